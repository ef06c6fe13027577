//! CalculiX (`ccx`) for the cross-checks: whether it is installed (CI must have it) and a run of
//! a deck in a folder.

use std::path::Path;
use std::process::Command;

/// The feature decks of `tests/decks/` (docs/DECKS.md), each with its committed `.ccx.dat`.
pub const FEATURE_DECKS: [&str; 10] = [
    "amplitude_cload",
    "amplitude_total_time",
    "op_new",
    "static_control",
    "sets_and_not_used",
    "el_print_nlgeom",
    "ortho_tilted",
    "ortho_tilted_nlgeom",
    "ring_cylindrical",
    "time_reset_fixed",
];

/// Whether `ccx` runs here. Without it the cross-check is skipped with a note, except in CI
/// (`CI` set), where `.ci/run` installs calculix-ccx and its absence is a failure.
pub fn available() -> bool {
    let found = Command::new("ccx").arg("-v").output().is_ok();
    if !found {
        assert!(
            std::env::var_os("CI").is_none(),
            "CI must provide CalculiX (ccx); .ci/run installs calculix-ccx"
        );
        eprintln!(
            "ccx not found: CalculiX cross-check skipped (apt-get install calculix-ccx to run it)"
        );
    }
    found
}

/// Runs `ccx -i NAME` in `dir` (where NAME.inp is) and returns its `.dat` text; panics with
/// CalculiX's output if it fails.
pub fn run(dir: &Path, name: &str) -> String {
    let out = Command::new("ccx")
        .arg("-i")
        .arg(name)
        .current_dir(dir)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "ccx failed on {name} ({:?}): {}\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    std::fs::read_to_string(dir.join(format!("{name}.dat"))).unwrap()
}
