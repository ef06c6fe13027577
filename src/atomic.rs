//! Files written atomically: under a temporary name in the same folder (`.NAME.partial`),
//! synced, then renamed over the target, so a reader — or a run killed at any instant — sees the
//! old file or the new one, never a part (docs/RELIABILITY.md).

use crate::Error;
use std::path::Path;

fn io(path: &Path) -> impl FnOnce(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Writes `path` through a temporary file in the same folder (`.NAME.partial`), synced, then
/// renamed over `path`: readers see the old file or the new one, never a part.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), Error> {
    atomically(path, |tmp| std::fs::write(tmp, bytes).map_err(io(tmp)))
}

/// Runs `write` on a temporary path beside `path`, syncs the result and renames it into place.
pub fn atomically(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), Error>,
) -> Result<(), Error> {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.partial"));
    write(&tmp)?;
    std::fs::File::open(&tmp)
        .and_then(|f| f.sync_all())
        .map_err(io(&tmp))?;
    std::fs::rename(&tmp, path).map_err(io(path))
}
