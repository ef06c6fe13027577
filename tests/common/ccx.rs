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

/// The displacements (u, v, w of each node in turn) at the ends of the steps in a CalculiX .dat
/// file: (total time, displacements by DOF).
pub fn displacements(dat: &str, nodes: usize) -> Vec<(f64, Vec<f64>)> {
    let mut out = Vec::new();
    for block in dat.split("displacements").skip(1) {
        let mut lines = block.lines();
        let time = lines
            .next()
            .and_then(|h| h.split_whitespace().last())
            .and_then(|t| t.parse::<f64>().ok())
            .unwrap_or(f64::NAN);
        let mut u = vec![f64::NAN; 3 * nodes];
        for line in lines {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.len() != 4 {
                if !f.is_empty() {
                    break;
                }
                continue;
            }
            let Ok(id) = f[0].parse::<usize>() else { break };
            for k in 0..3 {
                u[3 * (id - 1) + k] = f[k + 1].parse::<f64>().unwrap_or(f64::NAN);
            }
        }
        out.push((time, u));
    }
    out
}
