//! Committed decks against CalculiX 2.20's committed answers (`tests/decks/README.md`): the deck
//! reader, step semantics, assembly, Newton and solver, through the library and the
//! `nonlin3d solve` command.

use nonlin3d::deck::{StepOptions, solve_deck};
use nonlin3d::mesh::read_inp;
use nonlin3d::newton::NewtonSettings;
use std::collections::HashMap;
use std::path::Path;

fn reference(name: &str) -> HashMap<usize, [f64; 3]> {
    let text =
        std::fs::read_to_string(Path::new("tests/decks").join(format!("{name}.ccx.csv"))).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().unwrap(),
                [
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                    f[3].parse().unwrap(),
                ],
            )
        })
        .collect()
}

/// max |u_nonlin3d − u_ccx| / max |u| by deck node id.
fn difference(ids: &[usize], ours: &[[f64; 3]], theirs: &HashMap<usize, [f64; 3]>) -> f64 {
    assert_eq!(theirs.len(), ids.len());
    let scale = ours.iter().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    let mut diff = 0.0f64;
    for (id, u) in ids.iter().zip(ours) {
        let t = theirs[id];
        for r in 0..3 {
            diff = diff.max((u[r] - t[r]).abs());
        }
    }
    diff / scale
}

#[test]
fn decks_match_calculix() {
    // CalculiX prints 7 significant digits (≤ 5e-7 relative) and converges NLGEOM steps to its
    // own default residual criterion; 2e-6 of the largest displacement covers both.
    let settings = NewtonSettings {
        force_tolerance: 1e-7,
        relative_tolerance: 1e-11,
        ..NewtonSettings::default()
    };
    for name in [
        "cantilever_linear",
        "cantilever_nlgeom",
        "cantilever_nlgeom_2steps",
        "ortho_block_30deg",
    ] {
        let model = read_inp(
            &std::fs::read_to_string(Path::new("tests/decks").join(format!("{name}.inp"))).unwrap(),
        )
        .unwrap();
        let results = solve_deck(
            &model,
            &StepOptions {
                newton: settings.clone(),
                initial_increment: None,
            },
        )
        .unwrap();
        let last = results.last().unwrap();
        let rel = difference(&model.node_ids, &last.displacements, &reference(name));
        eprintln!(
            "{name}: {} steps, max relative difference to CalculiX {rel:.2e}",
            results.len()
        );
        assert!(rel < 2e-6, "{name}: {rel:e}");
        for r in &results {
            assert!(r.increments.iter().filter(|i| i.converged).count() >= 1);
            if !r.nlgeom {
                // Linear steps: one iteration solves them to round-off.
                assert!(
                    r.increments.iter().all(|i| i.iterations <= 2),
                    "{name}: {:?}",
                    r.increments
                );
            }
        }
    }
    // Elastic, so path independent: two steps end where one step does.
    let one = reference("cantilever_nlgeom");
    let two = reference("cantilever_nlgeom_2steps");
    let scale = one.values().flatten().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        one.iter()
            .all(|(id, u)| (0..3).all(|r| (u[r] - two[id][r]).abs() < 2e-6 * scale))
    );
}

#[test]
fn the_solve_command_writes_csv_and_json() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("solve-2steps");
    let _ = std::fs::remove_dir_all(&out);
    let status = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["solve", "tests/decks/cantilever_nlgeom_2steps.inp", "--out"])
        .arg(&out)
        .args(["--tolerance", "1e-7"])
        .status()
        .unwrap();
    assert!(status.success());
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let steps = summary["steps"].as_array().unwrap();
    assert_eq!(steps.len(), 2);
    assert!(
        steps
            .iter()
            .all(|s| s["nlgeom"] == true
                && s["increments"].as_array().is_some_and(|i| !i.is_empty()))
    );
    let csv = std::fs::read_to_string(out.join("displacements.csv")).unwrap();
    let ours: Vec<(usize, [f64; 3])> = csv
        .lines()
        .skip(1)
        .map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (
                f[0].parse().unwrap(),
                [
                    f[1].parse().unwrap(),
                    f[2].parse().unwrap(),
                    f[3].parse().unwrap(),
                ],
            )
        })
        .collect();
    let ids: Vec<usize> = ours.iter().map(|p| p.0).collect();
    let u: Vec<[f64; 3]> = ours.iter().map(|p| p.1).collect();
    let rel = difference(&ids, &u, &reference("cantilever_nlgeom_2steps"));
    assert!(rel < 2e-6, "{rel:e}");
    assert!(
        out.join("step-1/displacements.csv").exists()
            && out.join("step-2/displacements.csv").exists()
    );
    // A malformed deck is a located error on stderr and a failing exit status.
    let bad = Path::new(env!("CARGO_TARGET_TMPDIR")).join("bad.inp");
    std::fs::write(&bad, "*NODE\n1, 0, 0, x\n").unwrap();
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .arg("solve")
        .arg(&bad)
        .output()
        .unwrap();
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("line 2"));
}
