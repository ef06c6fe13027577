//! What a results file records about how it was made ([`Provenance`]): the program and its
//! version, the command line, the input file with its SHA-256, the scene as solved (every
//! default filled in), the linear solver and its ordering, the thread count, the wall time per
//! stage and the peak memory.

use crate::Error;
pub use crate::results::{InputFile, Provenance};
use nonlin3d_solver::SolverKind;
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::Path;
use std::time::{SystemTime, UNIX_EPOCH};

/// `path` as read: its SHA-256 (hex) and size.
pub fn input_file(path: &Path) -> Result<InputFile, Error> {
    let bytes = std::fs::read(path).map_err(|source| Error::Io {
        path: path.to_path_buf(),
        source,
    })?;
    Ok(InputFile {
        path: path.display().to_string(),
        sha256: sha256_hex(&bytes),
        bytes: bytes.len() as u64,
    })
}

/// SHA-256 of `bytes`, lower-case hex.
pub fn sha256_hex(bytes: &[u8]) -> String {
    Sha256::digest(bytes)
        .iter()
        .map(|b| format!("{b:02x}"))
        .collect()
}

/// The peak resident memory of this process so far (`VmHWM` of /proc/self/status), bytes;
/// None where there is no /proc.
pub fn peak_memory_bytes() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The solver's name and its ordering, in words.
pub fn solver_names(kind: SolverKind) -> (String, String) {
    // `FaerOrdering::Auto` (nonlin3d_solver::AUTO_METIS_ONLY_DOFS, AUTO_WITHOUT_AMD_DOFS).
    let auto = format!(
        "METIS from {} DOF; below, nested dissection or METIS (and AMD below {} DOF), \
         whichever needs the fewest flops",
        nonlin3d_solver::AUTO_METIS_ONLY_DOFS,
        nonlin3d_solver::AUTO_WITHOUT_AMD_DOFS
    );
    // `FaerSplit::Auto`, the solver's default (nonlin3d_solver::SPLIT_FROM_DOFS).
    let split = format!(
        "split at the top separator from {} DOF, the two halves side by side",
        nonlin3d_solver::SPLIT_FROM_DOFS
    );
    match kind {
        SolverKind::Profile => ("profile LDLᵀ".into(), "reverse Cuthill–McKee".into()),
        SolverKind::FaerLdlt => (format!("faer LDLᵀ ({split})"), auto.clone()),
        SolverKind::FaerLlt => ("faer LLᵀ".into(), auto.clone()),
        SolverKind::FaerLdltThreads(n) => {
            (format!("faer LDLᵀ on {n} threads ({split})"), auto.clone())
        }
        SolverKind::FaerLdltMixed(n) => (
            format!("faer LDLᵀ, f32 factor refined in f64, on {n} threads (0: all cores; {split})"),
            auto.clone(),
        ),
        SolverKind::FaerLdltAuto(n) => (
            format!(
                "faer LDLᵀ, f32 factor refined in f64 from {} DOF (f64 below), on {n} threads \
                 (0: all cores; {split})",
                nonlin3d_solver::MIXED_FROM_DOFS
            ),
            auto.clone(),
        ),
        SolverKind::FaerLdltKept(n) => (
            format!(
                "faer LDLᵀ, f32 factor refined in f64 from {} DOF (f64 below; after a refused \
                 f32 factor, f32 retried at the next factorisation), on {n} threads (0: all \
                 cores; {split})",
                nonlin3d_solver::KEPT_MIXED_FROM_DOFS
            ),
            auto.clone(),
        ),
    }
}

impl Provenance {
    /// The provenance of a command started now: this program, `std::env::args`, the working
    /// folder, `input` (None: the built-in scene), the resolved `scene` (None: a deck) and
    /// `solver`; the stage times and the peak memory are filled in by [`Provenance::stage`]
    /// and [`Provenance::finish`].
    pub fn new(
        input: Option<InputFile>,
        scene: Option<serde_json::Value>,
        solver: SolverKind,
    ) -> Self {
        let (solver, ordering) = solver_names(solver);
        Self {
            program: format!("nonlin3d {}", env!("CARGO_PKG_VERSION")),
            command: std::env::args().collect(),
            working_dir: std::env::current_dir()
                .map(|d| d.display().to_string())
                .unwrap_or_default(),
            input,
            scene,
            solver,
            ordering,
            threads: rayon::current_num_threads(),
            started_unix_s: SystemTime::now()
                .duration_since(UNIX_EPOCH)
                .map_or(0, |d| d.as_secs()),
            wall_s: BTreeMap::new(),
            peak_memory_bytes: peak_memory_bytes(),
        }
    }

    /// Records the wall time of a stage, s.
    pub fn stage(&mut self, name: &str, seconds: f64) {
        self.wall_s.insert(name.into(), seconds);
    }

    /// Records the total wall time and the peak memory now.
    pub fn finish(&mut self, total_s: f64) {
        self.stage("total", total_s);
        self.peak_memory_bytes = peak_memory_bytes();
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// FIPS 180-2's test vectors: "abc" and the empty message.
    #[test]
    fn sha256_matches_the_standard_vectors() {
        assert_eq!(
            sha256_hex(b"abc"),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad"
        );
        assert_eq!(
            sha256_hex(b""),
            "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855"
        );
    }

    /// On Linux the peak is at least what this test holds (a 64 MiB vector, touched).
    #[test]
    fn peak_memory_counts_what_was_touched() {
        let v = vec![1u8; 64 << 20];
        let peak = peak_memory_bytes();
        assert!(v.iter().all(|&b| b == 1));
        if cfg!(target_os = "linux") {
            assert!(peak.unwrap() >= 64 << 20, "{peak:?}");
        }
    }
}
