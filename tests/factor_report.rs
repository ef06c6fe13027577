//! The factor a run and a solve report (issue 20: what the flop counts and the supernode tree
//! say about threads): results.json `timings.factor` and summary.json `steps[].factor` give
//! each system's equations, ordering, factor entries and flops, and where the factor is
//! supernodal its tree's critical path; the terminal prints the same line.

mod common;

use std::path::{Path, PathBuf};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("factor-report-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Everything the program printed, stdout then stderr.
fn terminal(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned() + &String::from_utf8_lossy(&o.stderr)
}

/// One factor entry's numbers hold together: L's lower nonzeros within the stored entries,
/// the f64 size their 8 bytes, and a supernodal tree's critical path within its work, with
/// W / cp as the parallelism; returns the equations.
fn check_factor(f: &serde_json::Value) -> u64 {
    let entries = f["factor_entries"].as_u64().unwrap();
    let lower = f["lower_nonzeros"].as_u64().unwrap();
    let equations = f["equations"].as_u64().unwrap();
    assert!(equations <= lower && lower <= entries, "{f}");
    let mib = f["factor_mib"].as_f64().unwrap();
    assert!((mib - entries as f64 * 8.0 / 1048576.0).abs() < 1e-9, "{f}");
    let gflop = f["gflop"].as_f64().unwrap();
    // Σ c² ≥ Σ c: at least one flop an entry of L.
    assert!(gflop * 1e9 >= lower as f64, "{f}");
    assert!(
        ["AMD", "nested dissection", "METIS", "RCM"].contains(&f["ordering"].as_str().unwrap())
    );
    if let Some(cp) = f["critical_path_gflop"].as_f64() {
        assert!(cp > 0.0 && cp <= gflop * (1.0 + 1e-12), "{f}");
        let p = f["tree_parallelism"].as_f64().unwrap();
        assert!((p - gflop / cp).abs() < 1e-9 * p, "{f}");
        let widest = f["widest_supernode"].as_u64().unwrap();
        let supernodes = f["supernodes"].as_u64().unwrap();
        assert!(
            widest >= 1 && supernodes >= 1 && supernodes <= equations,
            "{f}"
        );
    }
    equations
}

/// The reference scene on 4 slices at ε = −0.002 (past buckling, the contact loop engaged):
/// results.json lists the level loop's system and the contact loop's, both of the model's DOFs,
/// supernodal; the contact system reserves every candidate pair, so its factor is larger.
/// The terminal's summary prints one line for each.
#[test]
fn a_run_reports_its_systems_factors() {
    let dir = tmp("run");
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.002]",
        );
    let (scene, out) = (dir.join("scene.toml"), dir.join("out"));
    std::fs::write(&scene, text).unwrap();
    let o = common::nonlin3d_ok([
        "run".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
        scene.as_os_str(),
    ]);
    let v = common::results_json(&out);
    let dofs = v["model"]["dofs"].as_u64().unwrap();
    let factors = v["timings"]["factor"].as_array().unwrap();
    let systems: Vec<&str> = factors
        .iter()
        .map(|f| f["system"].as_str().unwrap())
        .collect();
    assert_eq!(systems, ["solid", "contact"], "{factors:?}");
    for f in factors {
        assert_eq!(check_factor(f), dofs);
        assert!(f["supernodes"].as_u64().is_some(), "{f}");
    }
    assert!(factors[1]["factor_entries"].as_u64() > factors[0]["factor_entries"].as_u64());
    let terminal = terminal(&o);
    for system in systems {
        assert!(
            terminal.contains(&format!("  {system} system: {dofs} equations, ")),
            "{terminal}"
        );
    }
}

/// A deck's steps each report their factor: the uniaxial box, as many equations as
/// three DOFs a node, and the terminal's step lines name it.
#[test]
fn a_solve_reports_each_steps_factor() {
    let dir = tmp("solve");
    let deck = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/decks/uniaxial_box.inp");
    let out = dir.join("out");
    let o = common::nonlin3d_ok([
        "solve".as_ref(),
        "--out".as_ref(),
        out.as_os_str(),
        deck.as_os_str(),
    ]);
    let v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let text = std::fs::read_to_string(&deck).unwrap();
    let nodes = text
        .split("*NODE")
        .nth(1)
        .unwrap()
        .lines()
        .skip(1)
        .take_while(|l| !l.starts_with('*'))
        .filter(|l| !l.trim().is_empty())
        .count() as u64;
    let steps = v["steps"].as_array().unwrap();
    assert!(!steps.is_empty());
    for step in steps {
        assert_eq!(check_factor(&step["factor"]), 3 * nodes);
        assert_eq!(step["factor"]["system"], "solid");
    }
    let terminal = terminal(&o);
    assert!(
        terminal.contains(&format!("  solid system: {} equations, ", 3 * nodes)),
        "{terminal}"
    );
}
