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
                ..Default::default()
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

#[path = "decks/dat.rs"]
mod dat;

/// The feature decks (tests/decks/README.md) against CalculiX's .dat output, block by block:
/// the same increments written (FREQUENCY, the end of each step, the automatic increments of
/// `static_control`), the same U, RF, totals and integration-point stresses.
#[test]
fn feature_decks_match_calculix_increment_by_increment() {
    // CalculiX prints 7 significant digits: ≤ 5e-7 of each value, so of a block's largest.
    // Both codes converge far below that: the decks ask CalculiX for R_n = 1e-7 of its average
    // force (≈ 1e-4 N here) and nonlin3d for 1e-7 of its largest force; a residual r moves the
    // solution by about r × the tip compliance (≈ 1.6e-6 m/N), 1e-10 m against millimetres.
    // 2e-6 of the block's largest value covers the printed digits with margin.
    let options = StepOptions {
        newton: NewtonSettings {
            force_tolerance: 1e-7,
            relative_tolerance: 1e-11,
            ..NewtonSettings::default()
        },
        initial_increment: None,
        ..Default::default()
    };
    for name in [
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
    ] {
        let dir = Path::new("tests/decks");
        let model = nonlin3d::mesh::read_inp_file(&dir.join(format!("{name}.inp"))).unwrap();
        let results = solve_deck(&model, &options).unwrap();
        let theirs =
            dat::parse_dat(&std::fs::read_to_string(dir.join(format!("{name}.ccx.dat"))).unwrap());
        assert!(!theirs.is_empty());
        let worst = dat::compare(name, &dat::our_blocks(&results), &theirs)
            .into_iter()
            .fold(
                (String::new(), 0.0f64),
                |a, b| if b.1 > a.1 { b } else { a },
            );
        eprintln!(
            "{name}: {} blocks, largest difference {:.1e} ({})",
            theirs.len(),
            worst.1,
            worst.0
        );
        assert!(worst.1 < 2e-6, "{name}: {worst:?}");
    }
}

/// The cylindrical `*ORIENTATION` of `ring_cylindrical.inp` matters: the same deck with its
/// cells left in global axes (hoop-stiff E = 134 GPa along global y instead of along the ring)
/// moves the end about twice as far (CalculiX: ux of node 121 −2.835e-4 m with the
/// orientation, −5.888e-4 m without). So agreement with CalculiX's oriented answer
/// (`feature_decks_match_calculix_increment_by_increment`) cannot come from ignoring it.
#[test]
fn a_cylindrical_orientation_changes_the_answer() {
    let path = Path::new("tests/decks/ring_cylindrical.inp");
    let model = nonlin3d::mesh::read_inp_file(path).unwrap();
    assert!(model.cylindrical.iter().all(Option::is_some));
    let mut global = model.clone();
    global.cylindrical.iter_mut().for_each(|c| *c = None);
    global.orientation_names.iter_mut().for_each(|c| *c = None);
    let options = StepOptions::default();
    let tip = |m: &nonlin3d::mesh::InpModel| {
        let r = solve_deck(m, &options).unwrap();
        let k = m.node_ids.iter().position(|&id| id == 121).unwrap();
        r.last().unwrap().displacements[k][0]
    };
    let (oriented, ignored) = (tip(&model), tip(&global));
    assert!(
        oriented < 0.0 && ignored < 1.5 * oriented,
        "{oriented} vs {ignored}"
    );
}

fn solve_cli(deck: &Path, out: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .arg("solve")
        .arg(deck)
        .arg("--out")
        .arg(out)
        .args(["--tolerance", "1e-7"])
        .output()
        .unwrap()
}

/// `nonlin3d solve` on a deck with includes, sets of sets and unused data: the output tables
/// per increment and the summary listing them and what was not used, with lines.
#[test]
fn the_solve_command_lists_outputs_and_unused_data() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("solve-amplitude");
    let _ = std::fs::remove_dir_all(&out);
    let o = solve_cli(Path::new("tests/decks/amplitude_cload.inp"), &out);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let step = &summary["steps"][0];
    // DIRECT 0.2 over the period 1: five increments; FREQUENCY=2 writes 2, 4 and the last.
    let converged: Vec<f64> = step["increments"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|i| i["converged"] == true)
        .map(|i| i["step_time"].as_f64().unwrap())
        .collect();
    assert_eq!(converged.len(), 5);
    assert!((converged[4] - 1.0).abs() < 1e-12);
    let outputs = step["outputs"].as_array().unwrap();
    assert_eq!(outputs.len(), 2);
    for o in outputs {
        assert_eq!(o["increments"], serde_json::json!([2, 4, 5]));
        assert!(out.join(o["file"].as_str().unwrap()).exists());
    }
    assert_eq!(outputs[0]["file"], "step-1/node-print-TIP.csv");
    assert_eq!(outputs[1]["file"], "step-1/node-print-x0-totals.csv");
    let csv = std::fs::read_to_string(out.join("step-1/node-print-TIP.csv")).unwrap();
    assert_eq!(
        csv.lines().next(),
        Some("increment,step_time,total_time,node,ux,uy,uz,rfx,rfy,rfz")
    );
    assert_eq!(csv.lines().count(), 4);
    let not_used = summary["not_used"].as_array().unwrap();
    let at: Vec<&str> = not_used.iter().map(|n| n["at"].as_str().unwrap()).collect();
    assert_eq!(at, ["line 1", "cantilever_mesh.inp line 283"]);
    assert!(
        String::from_utf8_lossy(&o.stdout)
            .contains("not used: cantilever_mesh.inp line 283, *SURFACE")
    );
}

/// Refused through the command: a failing exit status and a message naming the line, the
/// keyword and the parameter, for a parameter `*STATIC, RIKS` does not take, `*CLOAD,
/// FOLLOWER` and an unknown parameter.
#[test]
fn the_solve_command_refuses_by_line() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("refusals");
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::fs::read_to_string("tests/decks/amplitude_cload.inp").unwrap();
    std::fs::copy(
        "tests/decks/cantilever_mesh.inp",
        dir.join("cantilever_mesh.inp"),
    )
    .unwrap();
    let line_of =
        |text: &str, start: &str| text.lines().position(|l| l.starts_with(start)).unwrap() + 1;
    for (from, to, what) in [
        (
            "*STATIC, DIRECT",
            "*STATIC, RIKS, TIME RESET",
            "*STATIC, TIME RESET",
        ),
        (
            "*CLOAD, AMPLITUDE=UPDOWN",
            "*CLOAD, FOLLOWER",
            "*CLOAD, FOLLOWER",
        ),
        (
            "*NSET, NSET=TIP",
            "*NSET, NSET=TIP, BOGUSPARAM=7",
            "*NSET, BOGUSPARAM",
        ),
    ] {
        let deck = base.replace(from, to);
        let path = dir.join("refused.inp");
        std::fs::write(&path, &deck).unwrap();
        let o = solve_cli(&path, &dir.join("out"));
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(!o.status.success());
        let want = format!("line {}, {what}", line_of(&deck, to));
        assert!(err.contains(&want), "{want} not in {err}");
    }
}

/// `INC=` is a limit, not a hint: a step that needs more increments stops with an error naming
/// the step, its line and the limit (CalculiX stops too).
#[test]
fn more_increments_than_inc_is_an_error() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("inc");
    std::fs::create_dir_all(&dir).unwrap();
    std::fs::copy(
        "tests/decks/cantilever_mesh.inp",
        dir.join("cantilever_mesh.inp"),
    )
    .unwrap();
    let deck = std::fs::read_to_string("tests/decks/static_control.inp")
        .unwrap()
        .replace("INC=20", "INC=4");
    std::fs::write(dir.join("deck.inp"), &deck).unwrap();
    let model = nonlin3d::mesh::read_inp_file(&dir.join("deck.inp")).unwrap();
    let e = solve_deck(&model, &StepOptions::default())
        .unwrap_err()
        .to_string();
    let line = deck.lines().position(|l| l.starts_with("*STEP")).unwrap() + 1;
    assert!(
        e.contains(&format!("step 1 (line {line})")) && e.contains("INC=4"),
        "{e}"
    );
    // Six increments are needed (0.1, 0.2, 0.35, 0.575, 0.875, 1): INC=6 passes.
    let model = read_inp(&deck.replace("INC=4", "INC=6").replace(
        "*INCLUDE, INPUT=cantilever_mesh.inp",
        &std::fs::read_to_string("tests/decks/cantilever_mesh.inp").unwrap(),
    ))
    .unwrap();
    assert!(solve_deck(&model, &StepOptions::default()).is_ok());
}

/// A checked deck is solved without checking it again, to the same bits as `solve_deck`; a
/// `Checked` of another deck (other node and element counts) is not trusted: that deck is
/// checked itself, and an inverted element in it is still refused.
#[test]
fn a_checked_deck_solves_as_solve_deck_and_another_decks_check_is_not_trusted() {
    use nonlin3d::deck::{check, solve_checked_with};
    let options = StepOptions::default();
    let text = std::fs::read_to_string("tests/decks/uniaxial_box.inp").unwrap();
    let model = read_inp(&text).unwrap();
    let plain = solve_deck(&model, &options).unwrap();
    let checked = check(&model, &options).unwrap();
    let solved = solve_checked_with(&model, &options, checked, &mut |_| Ok(())).unwrap();
    let bits = |r: &[nonlin3d::deck::StepResult]| -> Vec<u64> {
        r.iter()
            .flat_map(|s| s.displacements.iter().flatten().map(|v| v.to_bits()))
            .collect()
    };
    assert_eq!(bits(&solved), bits(&plain));
    // Another deck's check: the cantilever's elements, one of them turned inside out.
    let other = read_inp(&text).unwrap();
    let other_checked = check(&other, &options).unwrap();
    let cantilever = std::fs::read_to_string("tests/decks/cantilever_linear.inp").unwrap();
    let model = read_inp(&cantilever).unwrap();
    assert_ne!(model.mesh.nodes.len(), other.mesh.nodes.len());
    let mut inverted = model.clone();
    let cell = &mut inverted.mesh.cells[0];
    cell.nodes.swap(0, 4);
    cell.nodes.swap(1, 5);
    cell.nodes.swap(2, 6);
    cell.nodes.swap(3, 7);
    assert!(check(&inverted, &options).is_err());
    let e = solve_checked_with(&inverted, &options, other_checked, &mut |_| Ok(()))
        .err()
        .map(|e| e.to_string())
        .unwrap_or_default();
    assert!(
        e.contains("inverted"),
        "the inverted element was not found: {e}"
    );
}
