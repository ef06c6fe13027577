//! Results that cannot be misread (issue: no silent wrong answers, part 5): front points whose
//! crack faces overlap are reported as overlapped — not physical without contact — in the
//! terminal table, results.json, the CSVs, the criterion and the plots; each quantity is named
//! for what it is; scene errors speak the scene's language.

use nonlin3d::Scene;
use nonlin3d::scene::THESIS_SCENE;
use std::path::Path;
use std::process::Command;

/// The reference scene on 4 slices at ε = −0.005, with a criterion: the faces overlap near the
/// x axis there (the thesis's dashed stretch), open at S = 0; contact off (with it, the
/// default, no point overlaps: tests/contact.rs). About a second.
fn overlapping_scene() -> String {
    let text = THESIS_SCENE.replace("slices = 8", "slices = 4").replace(
        "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
        "strains = [-0.002, -0.005]",
    );
    format!(
        "{text}\n[criterion]\nkind = \"power-law\"\ng_ic = 200.0\ng_iic = 800.0\n\n[contact]\ncrack_faces = \"off\"\n"
    )
}

fn tmp(name: &str) -> std::path::PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

#[test]
fn overlapped_points_are_reported_as_not_physical_everywhere() {
    let dir = tmp("overlap");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, overlapping_scene()).unwrap();
    let out = dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["run", "--out"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");

    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let last = &json["levels"][1];
    let front = last["front"].as_array().unwrap();
    let overlapped: Vec<&serde_json::Value> = front
        .iter()
        .filter(|r| r["faces"] == "overlapped")
        .collect();
    let open: Vec<&serde_json::Value> = front.iter().filter(|r| r["faces"] == "open").collect();
    assert_eq!(
        overlapped.len() + open.len(),
        front.len(),
        "faces is open or overlapped"
    );
    assert!(!overlapped.is_empty(), "the scene overlaps near the x axis");
    assert_eq!(front[0]["faces"], "open", "open at S = 0");
    // No failure index where the faces overlap; one everywhere else.
    assert!(overlapped.iter().all(|r| r["failure_index"].is_null()));
    assert!(open.iter().all(|r| r["failure_index"].is_number()));
    // The overlapped points' opening is negative, the open ones' not.
    assert!(
        overlapped
            .iter()
            .all(|r| r["opening_mm"].as_f64().unwrap() < 0.0)
    );

    // The table's G_I max is the largest over the open points, and the overlapped count shows.
    let gi_open = open
        .iter()
        .map(|r| r["g_i"].as_f64().unwrap())
        .fold(f64::MIN, f64::max);
    let row = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("-0.00500"))
        .unwrap();
    assert!(
        row.contains(&format!("{gi_open:.2} at")),
        "{row} vs {gi_open}"
    );
    assert!(
        row.contains(&format!("{}/{}", overlapped.len(), front.len())),
        "{row}"
    );
    assert!(stdout.contains("not physical"), "{stdout}");
    assert!(stdout.contains("max face separation (mm)"), "{stdout}");
    assert!(!stdout.contains("peak w"), "{stdout}");
    assert!(last["max_face_separation_mm"].as_f64().unwrap() > 0.0);

    // CSV: a `faces` column with the same words.
    let csv = std::fs::read_to_string(out.join("front_1.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "faces").unwrap();
    let words: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    assert_eq!(
        words.iter().filter(|w| **w == "overlapped").count(),
        overlapped.len()
    );

    // The plots explain the dashed, hollow stretches.
    let svg = std::fs::read_to_string(out.join("g_i.svg")).unwrap();
    assert!(svg.contains("G not physical"), "legend missing");
}

/// A front point with a large positive G_I where the faces overlap (75.8 J/m² at S = 23.5 mm on
/// the 8-slice reference at −0.005) must not set the growth onset: the critical strain comes
/// from the open points only.
#[test]
fn the_criterion_ignores_overlapped_points() {
    let scene = Scene::from_toml(&overlapping_scene()).unwrap();
    let results = nonlin3d::Analysis::new(scene).unwrap().run().unwrap();
    let last = results.levels.last().unwrap();
    // The largest S belongs to an overlapped point (near the x axis); `peak` skips it.
    assert!(!last.front.last().unwrap().is_open());
    let farthest_open = last.peak(|r| r.s_mm).unwrap();
    assert!(farthest_open.is_open());
    assert!(farthest_open.s_mm < last.front.last().unwrap().s_mm);
    assert!(last.peak(|r| r.g_i).unwrap().is_open());
    if let Some(c) = results.critical {
        let at = last
            .front
            .iter()
            .find(|r| (r.s_mm - c.s_mm).abs() < 1e-9)
            .unwrap();
        assert!(at.is_open(), "onset placed at an overlapped point");
    }
}

/// A delamination too large for the model is refused in the scene's terms (field names, mm),
/// not in the mesh generator's internal parameters in metres.
#[test]
fn a_geometry_error_names_the_scene_fields_in_mm() {
    let text = THESIS_SCENE
        .replace("a_mm = 15.0", "a_mm = 30.0")
        .replace("b_mm = 15.0", "b_mm = 60.0");
    let dir = tmp("geometry-error");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let run = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["run", "--out"])
        .arg(dir.join("out"))
        .arg(&scene)
        .output()
        .unwrap();
    assert!(!run.status.success());
    let err = String::from_utf8_lossy(&run.stderr);
    assert!(err.contains("geometry.w_mm = 50 mm"), "{err}");
    assert!(err.contains("84 mm"), "{err}");
    assert!(!err.contains("0.06"), "metres leaked: {err}");
}

/// With `perturbation_n = 0` the unbuckled path is followed past its bifurcation: each level
/// there is reported unstable (negative pivots, `stable = false`) in results.json, levels.csv
/// and the table, and the run says in a warning that it ends on an unstable state.
#[test]
fn unstable_levels_are_flagged_everywhere() {
    let text = THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.003]",
        )
        .replace("[loads]", "[loads]\nperturbation_n = 0.0");
    let dir = tmp("unstable");
    let scene = dir.join("scene.toml");
    std::fs::write(&scene, text).unwrap();
    let out = dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["run", "--out"])
        .arg(&out)
        .arg(&scene)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{stdout}");
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap();
    let levels = json["levels"].as_array().unwrap();
    // −0.001 is below the circle's bifurcation (≈ −0.0017), −0.003 above it.
    assert_eq!(levels[0]["convergence"]["stable"], true);
    assert_eq!(levels[1]["convergence"]["stable"], false);
    assert!(
        levels[1]["convergence"]["negative_pivots"]
            .as_u64()
            .unwrap()
            > 0
    );
    // The crossing is bracketed (the inertia guard cut the step) and reported, JSON and table.
    let b = &levels[1]["convergence"]["bifurcation"];
    let (from, to) = (b["from"].as_f64().unwrap(), b["to"].as_f64().unwrap());
    assert!(-0.001 >= from && from > to && to >= -0.003, "{b}");
    assert!(
        from - to <= 0.5 * 0.002,
        "bracket {from} … {to} not narrowed"
    );
    assert_eq!(b["negative_pivots_before"], 0);
    assert!(
        stdout.contains("bifurcation crossed between strain"),
        "{stdout}"
    );
    let warnings = json["warnings"].as_array().unwrap();
    assert!(
        warnings
            .iter()
            .any(|w| w.as_str().unwrap().contains("ends on an unstable state"))
    );
    let row = stdout
        .lines()
        .find(|l| l.trim_start().starts_with("-0.00300"))
        .unwrap();
    assert!(row.contains(" NO "), "{row}");
    assert!(
        stdout.contains("warning: the run ends on an unstable state"),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.join("levels.csv")).unwrap();
    let header: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let col = header.iter().position(|h| *h == "stable").unwrap();
    let stable: Vec<&str> = csv
        .lines()
        .skip(1)
        .map(|l| l.split(',').nth(col).unwrap())
        .collect();
    assert_eq!(stable, ["true", "false"]);
}

/// A criterion reached at the first buckled level after a flat one: G was zero until the
/// bifurcation somewhere between them, so the onset is reported as the bracket, not interpolated
/// (the √index interpolation from the flat level placed it below the bifurcation).
#[test]
fn an_onset_right_after_a_flat_level_is_bracketed() {
    let text = THESIS_SCENE.replace("slices = 8", "slices = 4").replace(
        "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
        "strains = [-0.001, -0.004]",
    );
    let text = format!("{text}\n[criterion]\nkind = \"power-law\"\ng_ic = 100.0\ng_iic = 400.0\n");
    let results = nonlin3d::Analysis::new(Scene::from_toml(&text).unwrap())
        .unwrap()
        .run()
        .unwrap();
    let c = results.critical.unwrap();
    assert_eq!(c.after, Some(-0.001));
    assert_eq!(c.strain, -0.004);
    let table = nonlin3d::report::table(&results);
    assert!(table.contains("between strain -0.001"), "{table}");
}
