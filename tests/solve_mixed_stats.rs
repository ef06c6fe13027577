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

/// `solve`'s default solver (`auto`) on a kept tangent: the clamped plate of issue 20 at
/// n = 8 (`tests/decks/plate_n8.inp`, 4 263 DOF, ten `*STATIC, DIRECT` increments run by BFGS,
/// written by `cargo bench --bench plate_decks -- n=8 write=tests/decks/plate_n8.inp`) is at
/// least `KEPT_MIXED_FROM_DOFS`, so its factorisations are f32 (`SolverKind::FaerLdltKept`).
/// Each direction is solved to 1 % of the residual (`nonlin3d_newton::KEPT_FORCING`): one f32
/// solve each, checked by an f64 product until a check on the same factor met its bound at a
/// quarter of it or better, then up to four unchecked (`nonlin3d_solver::TRUSTED_SHARE`,
/// `UNCHECKED_IN_A_ROW`; 26 refinement steps and 62 unchecked solves in 86 iterations
/// measured, against 88 refinement steps with every solve checked; to 1 % of the force
/// tolerance it took 4–5 a direction). The same negative pivots as the f64 solver at every
/// increment, and the same answer: both stop at ‖r‖∞ ≤ 1e-8 of the largest force (≈ 2.8 kN,
/// so ≤ 3e-5 N), which with a tangent compliance below 3e-3 mm/N moves u by < 1e-7 mm, 1e-7 of
/// w₀ ≈ 1.3 mm: 1e-6 of max |u| (as in tests/decks_strategy.rs).
#[test]
fn the_default_solver_factorises_a_kept_tangent_in_f32_for_the_same_answer() {
    let run = |solver: &str, name: &str| {
        let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
        let _ = std::fs::remove_dir_all(&dir);
        let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/plate_n8.inp");
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_nonlin3d"));
        cmd.args(["solve", "-q", "--threads", "1", "--out"])
            .arg(&dir);
        if !solver.is_empty() {
            cmd.args(["--solver", solver]);
        }
        let o = cmd.arg(&deck).output().unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(dir.join("summary.json")).unwrap())
                .unwrap();
        let u: Vec<f64> = std::fs::read_to_string(dir.join("displacements.csv"))
            .unwrap()
            .lines()
            .skip(1)
            .flat_map(|l| {
                l.split(',')
                    .skip(1)
                    .map(|v| v.trim().parse::<f64>().unwrap())
                    .collect::<Vec<_>>()
            })
            .collect();
        (json, u)
    };
    let (auto, u_auto) = run("", "kept-auto");
    let (f64_run, u_f64) = run("faer", "kept-f64");
    assert!(
        auto["provenance"]["solver"]
            .as_str()
            .unwrap()
            .contains("f32 factor refined in f64 from 4000 DOF"),
        "{}",
        auto["provenance"]["solver"]
    );
    let increments =
        |j: &serde_json::Value| j["steps"][0]["increments"].as_array().unwrap().clone();
    let (a, f) = (increments(&auto), increments(&f64_run));
    assert_eq!((a.len(), f.len()), (10, 10));
    let sum = |v: &[serde_json::Value], key: &str| -> u64 {
        v.iter()
            .map(|i| i["mixed_precision"][key].as_u64().unwrap())
            .sum()
    };
    let (iterations, factorisations): (u64, u64) = a.iter().fold((0, 0), |(n, m), i| {
        (
            n + i["iterations"].as_u64().unwrap(),
            m + i["factorisations"].as_u64().unwrap(),
        )
    });
    assert!(sum(&a, "f32_factorisations") + 2 >= factorisations, "{a:?}");
    let (steps, unchecked) = (sum(&a, "refinement_steps"), sum(&a, "unchecked_solves"));
    assert!(
        10 * (steps + unchecked) <= 11 * iterations && steps + unchecked >= iterations,
        "{steps} steps and {unchecked} unchecked solves in {iterations} iterations"
    );
    // Each increment's first direction is on a new factor, so it is checked; most are not.
    assert!(
        steps >= 10 && unchecked > steps,
        "{steps} checked, {unchecked} unchecked"
    );
    for (x, y) in a.iter().zip(&f) {
        assert_eq!(x["converged"], true, "{x}");
        assert_eq!(x["negative_pivots"], 0, "{x}");
        assert_eq!(x["negative_pivots"], y["negative_pivots"], "{x} {y}");
    }
    assert_eq!(u_auto.len(), u_f64.len());
    let scale = u_f64.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    let diff = u_auto
        .iter()
        .zip(&u_f64)
        .fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
    assert!(diff <= 1e-6 * scale, "{diff} against {scale}");
}
