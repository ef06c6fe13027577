//! `solve --solver faer-mixed` records, per attempt, whether the f32 factor held
//! (`mixed_precision` in summary.json and a line per increment on the terminal); the f64
//! solver records nothing.

use std::path::Path;
use std::process::Command;

fn solve(solver: &str, name: &str) -> (String, serde_json::Value) {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/cantilever_nlgeom.inp");
    let o = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["solve", "--threads", "1", "--solver", solver, "--out"])
        .arg(&dir)
        .arg(&deck)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let text = std::fs::read_to_string(dir.join("summary.json")).unwrap();
    (
        String::from_utf8_lossy(&o.stdout).into_owned(),
        serde_json::from_str(&text).unwrap(),
    )
}

/// The NLGEOM cantilever (a well-conditioned Hex20 tangent: cond·ε₃₂ ≪ 0.5) keeps its f32
/// factors: every converged attempt made at least one of its factorisations in f32, none in
/// f64, and refined without a stall, each Newton correction until its residual was within 1 %
/// of Newton's force tolerance (`nonlin3d_newton::LINEAR_RESIDUAL`) or to the solver's
/// default backward-error target of 1e-14, whichever came first. The last correction of an
/// increment is small, so one f32 solve may already leave 1 % of the tolerance: its backward
/// error is then the f32 solve's (1.8e-8 measured; 1.8e-11 where a step refined), and a
/// refinement that failed to converge would have fallen back to f64.
#[test]
fn mixed_precision_statistics_are_recorded_per_attempt() {
    let (stdout, json) = solve("faer-mixed", "mixed-stats");
    let increments = json["steps"][0]["increments"].as_array().unwrap();
    assert!(!increments.is_empty());
    for i in increments.iter().filter(|i| i["converged"] == true) {
        let m = &i["mixed_precision"];
        assert!(m["f32_factorisations"].as_u64().unwrap() >= 1, "{i}");
        assert_eq!(m["f64_factorisations"], 0, "{i}");
        assert!(m["fallback"].is_null(), "{i}");
        assert!(m["refinement_steps"].as_u64().unwrap() >= 1, "{i}");
        assert!(m["backward_error"].as_f64().unwrap() <= 1e-6, "{i}");
    }
    assert!(stdout.contains("f32 factor held"), "{stdout}");
}

/// With the f64 solver there is nothing to say: no field, no line.
#[test]
fn the_f64_solver_records_no_mixed_statistics() {
    let (stdout, json) = solve("faer", "mixed-stats-f64");
    for i in json["steps"][0]["increments"].as_array().unwrap() {
        assert!(i.get("mixed_precision").is_none(), "{i}");
    }
    assert!(!stdout.contains("f32 factor"), "{stdout}");
}
