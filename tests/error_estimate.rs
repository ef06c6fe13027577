//! The error estimate with every result (issue 25, docs/ACCURACY.md §3): results.json and
//! front_K.csv carry ±G per point, a target tighter than the estimate warns, and
//! `[mesh] accuracy` picks a finer mesh for a tighter target.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("error-estimate-{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn nonlin3d(dir: &Path, args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .current_dir(dir)
        .args(args)
        .output()
        .unwrap()
}

/// The reference circle on a tiny mesh (4 slices, 2 + 3 rings, 1 + 2 layers: 1 773 DOFs, its
/// companion 2 slices), one level past buckling, the scene's contact (`auto`: without it every
/// point of so coarse a mesh overlaps and no G is physical), with `extra` lines under `[mesh]`.
fn tiny_scene(extra: &str) -> String {
    nonlin3d::scene::THESIS_SCENE
        .replace(
            "slices = 8",
            &format!(
                "slices = 4\ninside = 2\noutside = 3\nsub_layers = 1\nbase_layers = 2\n{extra}"
            ),
        )
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.004]",
        )
}

/// Writes `text` as the scene of a fresh directory `name`, runs it on one thread into `out/`,
/// and returns the directory and the run's output (the run must succeed).
fn run_scene(name: &str, text: &str) -> (PathBuf, Output) {
    let dir = tmp(name);
    let s = dir.join("scene.toml");
    std::fs::write(&s, text).unwrap();
    let out = nonlin3d(
        &dir,
        &["run", s.to_str().unwrap(), "--out", "out", "--threads", "1"],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    (dir, out)
}

fn json(dir: &Path) -> serde_json::Value {
    serde_json::from_str(&std::fs::read_to_string(dir.join("out/results.json")).unwrap()).unwrap()
}

#[test]
fn results_and_csv_carry_the_estimate_and_a_tight_target_warns() {
    let (dir, out) = run_scene("tight", &tiny_scene("accuracy = 0.001"));
    let r = json(&dir);
    let acc = &r["accuracy"];
    assert_eq!(acc["error_estimate"], "companion");
    // The companion is the 2-slice mesh: fewer DOFs than the run.
    let dofs = r["model"]["dofs"].as_u64().unwrap();
    assert!(acc["companion_dofs"].as_u64().unwrap() < dofs / 2);
    // Every front point has ±G of every mode, non-negative, and G_T's is at least the floor
    // (1.2 × 0.2 of the difference at the G_T max, itself > 0 between meshes this coarse).
    let level = &r["levels"][0];
    let front = level["front"].as_array().unwrap();
    assert!(!front.is_empty());
    for p in front {
        for m in ["g_i", "g_ii", "g_iii", "g_t"] {
            assert!(p["error"][m].as_f64().unwrap() >= 0.0, "{p}");
        }
        assert!(p["error"]["g_t"].as_f64().unwrap() > 0.0);
    }
    let e = &level["error_estimate"];
    let rel = e["relative"].as_f64().unwrap();
    // The relative estimate is the largest ± over G_T max, as the report says.
    approx::assert_relative_eq!(
        rel,
        e["max_j_m2"].as_f64().unwrap() / e["g_t_max_j_m2"].as_f64().unwrap(),
        max_relative = 1e-12
    );
    // 0.001 is tighter than any mesh of the table reaches and than this estimate: not met,
    // and said so in results.json and on the terminal.
    assert!(rel > 0.001);
    assert_eq!(acc["met"], false);
    assert_eq!(acc["target"], 0.001);
    let warns = r["warnings"].as_array().unwrap();
    assert!(
        warns.iter().any(|w| w
            .as_str()
            .unwrap()
            .contains("exceeds the target mesh.accuracy = 0.001")),
        "{warns:?}"
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("exceeds the target"), "{stdout}");
    assert!(stdout.contains("± G max"), "{stdout}");
    // The explicit knobs override the table's, and results.json says which.
    let chosen = &acc["chosen_mesh"];
    assert_eq!(chosen["slices"], 4);
    assert_eq!(chosen["table_meets_target"], false);
    assert!(
        chosen["overridden"]
            .as_array()
            .unwrap()
            .iter()
            .any(|k| k == "slices")
    );
    // The CSV: the four ± columns appended after the old ones, one value per point.
    let csv = std::fs::read_to_string(dir.join("out/front_0.csv")).unwrap();
    let mut lines = csv.lines();
    let head: Vec<&str> = lines.next().unwrap().split(',').collect();
    assert_eq!(head[13], "failure_index");
    assert_eq!(
        head[14..].to_vec(),
        vec![
            "g_i_error_j_m2",
            "g_ii_error_j_m2",
            "g_iii_error_j_m2",
            "g_t_error_j_m2"
        ]
    );
    let first: Vec<&str> = lines.next().unwrap().split(',').collect();
    let g_t_err: f64 = first[17].parse().unwrap();
    approx::assert_relative_eq!(
        g_t_err,
        front[0]["error"]["g_t"].as_f64().unwrap(),
        max_relative = 1e-15
    );
}

#[test]
fn no_estimate_when_off() {
    let (dir, _) = run_scene("off", &tiny_scene("error_estimate = \"off\""));
    let r = json(&dir);
    assert!(r.get("accuracy").is_none());
    assert!(r["levels"][0].get("error_estimate").is_none());
    assert!(r["levels"][0]["front"][0].get("error").is_none());
}

#[test]
fn a_tighter_target_picks_a_finer_mesh() {
    // The model alone (no solve): DOFs of the mesh the target picks, no knob given.
    let dofs = |accuracy: f64| {
        let mut s = nonlin3d::Scene::from_toml(nonlin3d::scene::THESIS_SCENE).unwrap();
        s.mesh.slices = None;
        s.mesh.accuracy = Some(accuracy);
        let m = nonlin3d::Analysis::new(s).unwrap().model().unwrap();
        3 * m.mesh.nodes.len()
    };
    let (loose, mid, tight) = (dofs(0.1), dofs(0.03), dofs(0.01));
    // The table's rows on the reference circle: 5 940, 10 035, 14 919 DOFs (docs/ACCURACY.md).
    assert_eq!((loose, mid, tight), (5940, 10035, 14919));
    // A target that is not a fraction is refused, naming the field.
    let mut s = nonlin3d::Scene::from_toml(nonlin3d::scene::THESIS_SCENE).unwrap();
    s.mesh.accuracy = Some(2.0);
    let e = nonlin3d::Analysis::new(s).unwrap_err().to_string();
    assert!(e.contains("mesh.accuracy = 2"), "{e}");
}

/// Band mesh Q of docs/ACCURACY.md §2b (4 → 12 slices, 7 + 6 rings, 2 + 2 layers, e = 0.3 mm,
/// band 5 + 3; 10 035 DOFs), one level at ε = −0.004 without contact (§1's physics, whose
/// converged G_II at S = 0 is 84.55 ± 0.13 J/m²; Q gives 81.73, a true error of 2.82).
/// The old companion halved the two sublaminate and the two base layers to one each, and one
/// layer moves G_II(0) by 12–45 % whatever the rest: its ±G_II(0) was 37 J/m², 13× the true
/// error. The companion that keeps them gives a difference of 8.8 J/m² (3.1×), and the rule
/// for such a companion halves it (Richardson at p = 1.58: 4.4 J/m², 1.6×). Asserted: the
/// estimate brackets the true error and is at most 3× it (issue 25's bound), both over the
/// whole range the reference's uncertainty allows (the plain difference fails the second).
#[test]
fn a_band_mesh_companion_keeps_the_split_and_brackets_g_ii_within_a_few_times() {
    let text = nonlin3d::scene::THESIS_SCENE
        .replace(
            "slices = 8",
            "slices = 4\ninside = 7\noutside = 6\nsub_layers = 2\nbase_layers = 2\n\
             front_element_mm = 0.3\nfront_band = [5, 3]",
        )
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.004]",
        )
        + "\n[contact]\ncrack_faces = \"off\"\n";
    let (dir, _) = run_scene("band", &text);
    let r = json(&dir);
    assert_eq!(r["model"]["dofs"], 10035);
    let p0 = &r["levels"][0]["front"][0];
    assert_eq!(p0["s_mm"], 0.0);
    let g_ii = p0["g_ii"].as_f64().unwrap();
    let est = p0["error"]["g_ii"].as_f64().unwrap();
    let (reference, uncertainty) = (84.55, 0.13);
    let err = (g_ii - reference).abs();
    assert!(est >= err + uncertainty, "±{est} < |{g_ii} − {reference}|");
    assert!(
        est <= 3.0 * (err - uncertainty),
        "±{est} > 3 × |{g_ii} − {reference}|"
    );
}

/// The 15 mm semicircular edge delamination on the default mesh (8, 4, 5, 1, 3; 6 789 DOFs),
/// one level at ε = −0.004 without contact: one sublaminate layer, so the companion halves
/// everything (the thesis's 4-slice mesh) and the split converges slowly (order ≈ 0.9):
/// G_II at S = 0 is 33.37 J/m² against the converged 59.29 ± 0.04 (docs/ACCURACY.md §3), a
/// true error of 25.9, and the companion's 9.27 gives a difference of 24.1 only — the plain
/// difference missed it. The rule for such a companion (a = 1.2, Richardson at p = 0.87)
/// gives 28.9: asserted, the estimate brackets the true error and is at most 3× it.
#[test]
fn a_one_layer_companion_brackets_the_slow_split_of_the_edge_delamination() {
    let text = include_str!("../examples/scenes/fig_5_5_1_edge_semicircle_15mm.toml")
        .replace("strains = [-0.002, -0.003, -0.004]", "strains = [-0.004]")
        + "\n[contact]\ncrack_faces = \"off\"\n";
    let (dir, _) = run_scene("edge", &text);
    let r = json(&dir);
    assert_eq!(r["model"]["dofs"], 6789);
    let p0 = &r["levels"][0]["front"][0];
    assert_eq!(p0["s_mm"], 0.0);
    let g_ii = p0["g_ii"].as_f64().unwrap();
    let est = p0["error"]["g_ii"].as_f64().unwrap();
    let (reference, uncertainty) = (59.29, 0.04);
    let err = (g_ii - reference).abs();
    assert!(est >= err + uncertainty, "±{est} < |{g_ii} − {reference}|");
    assert!(
        est <= 3.0 * (err - uncertainty),
        "±{est} > 3 × |{g_ii} − {reference}|"
    );
}

/// The default mesh's companion keeps the rings outside the front band and halves the rest
/// (docs/ACCURACY.md §3b; 7 581 DOFs against 18 444), with a = 0.4, c = 1, and its own coarser
/// companion (3 345 DOFs) adds b = 0.27 times their difference (§3d): at S = 0 on the
/// reference circle and the 15 mm edge delamination, one level at ε = −0.004 with contact
/// `auto` (the scenes' own), the estimate of G_I, G_II and G_T brackets the true error
/// against the converged families of §2f (circle 135.03 / 86.84 / 220.99 J/m², edge
/// 217.43 / 59.29 / 275.85) and is at most 3× it, counting errors below 1 % of the
/// converged G_T max as 1 % (issue 25's measure, §2f). Measured with the band curved (§3c):
/// ±4.71 / 3.81 / 5.64 against 2.62 / 0.69 / 2.41 (circle, at most 2.34×) and ±6.91 / 4.62 /
/// 6.40 against 2.44 / 0.71 / 2.24 (edge, at most 2.86×); the companion with the rings halved
/// gave ±G_T(0) 11.0 and 11.9, 3.7× and 4.3× (not ≤ 3×).
#[test]
fn the_default_meshs_estimate_brackets_g_at_s0_within_three_times() {
    let circle = nonlin3d::scene::DEFAULT_SCENE.replace(
        "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
        "strains = [-0.004]",
    );
    let edge = include_str!("../examples/scenes/fig_5_5_1_edge_semicircle_15mm.toml")
        .replace("slices = 8\n", "")
        .replace("strains = [-0.002, -0.003, -0.004]", "strains = [-0.004]");
    for (name, text, reference, g_t_max) in [
        ("default-circle", circle, [135.03, 86.84, 220.99], 220.99),
        ("default-edge", edge, [217.43, 59.29, 275.85], 275.85),
    ] {
        let (dir, _) = run_scene(name, &text);
        let r = json(&dir);
        assert_eq!(r["model"]["dofs"], 18444, "{name}");
        assert_eq!(r["accuracy"]["companion_dofs"], 7581, "{name}");
        assert_eq!(r["accuracy"]["coarser_companion_dofs"], 3345, "{name}");
        let p0 = &r["levels"][0]["front"][0];
        assert_eq!(p0["s_mm"], 0.0);
        for (mode, want) in ["g_i", "g_ii", "g_t"].into_iter().zip(reference) {
            let g = p0[mode].as_f64().unwrap();
            let est = p0["error"][mode].as_f64().unwrap();
            let err = (g - want).abs();
            assert!(est >= err, "{name} {mode}: ±{est} < |{g} − {want}|");
            assert!(
                est <= 3.0 * err.max(0.01 * g_t_max),
                "{name} {mode}: ±{est} > 3 × max(|{g} − {want}|, 1 % of {g_t_max})"
            );
        }
    }
}

/// Just past buckling (ε = −0.002, 1.25× the circle's buckling strain) the default mesh's error
/// is its buckling strain's, which its companion shares (docs/ACCURACY.md §3b): the companion's
/// term alone gives ±0.14 J/m² at S = 0 against true errors of 0.23 / 0.21 / 0.43 (G_I, G_II,
/// G_T; converged 7.533 ± 0.092, 4.813 ± 0.033, 12.337 ± 0.115 J/m², §3d). The coarser
/// companion halves the rings and sees it: with it the estimate brackets all three at S = 0
/// (measured ±0.53 / 0.24 / 0.77). Following the path on the run's own mesh
/// (`start = "path"`) runs no coarser companion: the term is absent, G_T(0) is not bracketed,
/// and a warning says so.
#[test]
fn near_buckling_the_coarser_companion_brackets_the_circles_s0() {
    let circle = nonlin3d::scene::DEFAULT_SCENE.replace(
        "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
        "strains = [-0.002]",
    );
    let reference = [7.533, 4.813, 12.337];
    let (dir, _) = run_scene("near-buckling", &circle);
    let r = json(&dir);
    assert_eq!(r["accuracy"]["coarser_companion_dofs"], 3345);
    let p0 = &r["levels"][0]["front"][0];
    assert_eq!(p0["s_mm"], 0.0);
    for (mode, want) in ["g_i", "g_ii", "g_t"].into_iter().zip(reference) {
        let g = p0[mode].as_f64().unwrap();
        let est = p0["error"][mode].as_f64().unwrap();
        assert!(est >= (g - want).abs(), "{mode}: ±{est} < |{g} − {want}|");
    }
    let path = circle.replace("[analysis]\n", "[analysis]\nstart = \"path\"\n");
    assert!(path.contains("start = \"path\""));
    let (dir, _) = run_scene("near-buckling-path", &path);
    let r = json(&dir);
    assert!(r["accuracy"]["coarser_companion_dofs"].is_null());
    let warned = r["warnings"].as_array().unwrap().iter().any(|w| {
        w.as_str()
            .is_some_and(|w| w.contains("lacks its coarser companion's term"))
    });
    assert!(warned, "{}", r["warnings"]);
    let p0 = &r["levels"][0]["front"][0];
    let (g, est) = (
        p0["g_t"].as_f64().unwrap(),
        p0["error"]["g_t"].as_f64().unwrap(),
    );
    assert!(
        est < (g - reference[2]).abs(),
        "±{est} against |{g} − {}|",
        reference[2]
    );
}
