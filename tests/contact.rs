//! Crack-face contact through the scene's `[contact]` section (thesis §2.7): the 30 mm circle
//! (§5.1) coarsened to slices = 4, whose faces overlap without contact from ε = −0.003 on.

use nonlin3d::contact::CrackFacesName;
use nonlin3d::results::{Faces, Results};
use nonlin3d::scene::Scene;
use std::path::Path;

/// The reference scene at slices = 4 with the given strains and `crack_faces`.
fn scene(strains: &[f64], faces: CrackFacesName) -> Scene {
    let path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/fig_5_1_3_circle_30mm.toml");
    let mut s = Scene::from_toml(&std::fs::read_to_string(path).unwrap()).unwrap();
    s.mesh.slices = Some(4);
    s.loads.strains = strains.to_vec();
    s.contact.crack_faces = faces;
    s
}

fn run(s: &Scene) -> Results {
    nonlin3d::analysis::run(s, &mut |_| Ok(())).unwrap()
}

/// G along the front of the last level and the centre deflection, as bits.
fn bits(r: &Results) -> Vec<[u64; 4]> {
    let l = r.levels.last().unwrap();
    l.front
        .iter()
        .map(|f| {
            [
                f.g_i.to_bits(),
                f.g_ii.to_bits(),
                f.g_iii.to_bits(),
                f.g_t.to_bits(),
            ]
        })
        .chain([[l.centre_deflection_mm.to_bits(), 0, 0, 0]])
        .collect()
}

const SWEEP: [f64; 5] = [-0.001, -0.002, -0.003, -0.004, -0.005];

#[test]
fn contact_removes_the_overlap_and_closed_points_have_no_mode_i() {
    let off = run(&scene(&SWEEP, CrackFacesName::Off));
    // The case: without contact, front points overlap at the last level.
    assert!(off.levels.last().unwrap().overlapped() > 0);
    // …and the run says so, naming the level (a G beside overlapped points can look plausible).
    let said = format!("level at strain {}: the crack faces pass through", SWEEP[4]);
    assert!(
        off.warnings.iter().any(|w| w.starts_with(&said)),
        "{:?}",
        off.warnings
    );
    for faces in [CrackFacesName::Auto, CrackFacesName::On] {
        let on = run(&scene(&SWEEP, faces));
        for l in &on.levels {
            assert_eq!(l.overlapped(), 0, "{faces:?} at ε = {}", l.value);
            // Closed points: G_I is set to 0 exactly (vcct::respect_contact).
            for f in l.front.iter().filter(|f| f.faces == Faces::Closed) {
                assert_eq!(f.g_i, 0.0);
            }
            // Overlap left after the loop, along the current normals: within the tolerance
            // (1e-6 mm) — held pairs whose normal turned are held again with the new one.
            if let Some(c) = &l.contact {
                assert!(c.max_penetration_mm <= 1e-6, "{c:?}");
                assert!(c.max_force_n >= 0.0 && c.max_pressure_mpa >= 0.0);
            }
        }
        assert!(
            !on.warnings
                .iter()
                .any(|w| w.contains("pass through each other")),
            "{:?}",
            on.warnings
        );
        let last = on.levels.last().unwrap().contact.clone().unwrap();
        assert!(last.pairs_closed > 0 && last.passes > 0, "{last:?}");
        // Where the faces touch (the points that overlap without contact, S ≥ 11.8 mm at
        // slices = 4) the front is closed: on Hex20 faces the corner pairs behind the points
        // stay in the set (the release test on the recovered forces; on the raw nodal forces,
        // tensile at corners, every front point came out open).
        let front = &on.levels.last().unwrap().front;
        assert!(front.iter().any(|f| f.faces == Faces::Closed), "{faces:?}");
        // `auto` solves the level where it engages once: the active-set passes start from the
        // overlapping state without contact, so that level's path following is off's (the same
        // iterations), not off's followed by a second one with the loop.
        if faces == CrackFacesName::Auto {
            let k = on.levels.iter().position(|l| l.contact.is_some()).unwrap();
            assert_eq!(
                on.levels[k].convergence.iterations, off.levels[k].convergence.iterations,
                "level {k}"
            );
        }
    }
}

#[test]
fn auto_leaves_levels_without_overlap_alone() {
    // ε = −0.001: the sublaminate has not buckled, no pair overlaps. `auto` solves the one
    // level without contact in the loop's sub-levels (steps of at most `max_step` = 0.25,
    // where it checks the overlap), so it must give the bits of `off` run in levels at those
    // step ends (λ = 0.25, 0.5, 0.75, 1 exactly in both: −0.00025/−0.001 rounds to 0.25).
    let off = run(&scene(
        &[-0.00025, -0.0005, -0.00075, -0.001],
        CrackFacesName::Off,
    ));
    let auto = run(&scene(&[-0.001], CrackFacesName::Auto));
    assert!(auto.levels.iter().all(|l| l.contact.is_none()));
    assert_eq!(bits(&off), bits(&auto));
}

/// `auto` on one long level whose faces overlap from its middle on (ε = −0.005 at
/// slices = 4: the overlap appears in the second of the four steps of 0.25): the steps before
/// the overlap are solved once, without contact, and the loop starts from the first step that
/// overlaps, so the level follows `on`'s path (the same sub-levels; no step solved twice):
/// the same Newton iterations, the same closed pairs, and G within 1e-6 relative (the two
/// runs differ by the contact system's reserved couplings, which reorder the factorisation:
/// round-off on states converged to Newton's 1e-8 of the force scale). Solved whole without
/// contact first and then again from its start with the loop, as before, the level took 30
/// more Newton iterations.
#[test]
fn auto_on_a_long_level_follows_the_loops_path_once() {
    let on = run(&scene(&[-0.005], CrackFacesName::On));
    let auto = run(&scene(&[-0.005], CrackFacesName::Auto));
    let (a, o) = (&auto.levels[0], &on.levels[0]);
    let (ca, co) = (a.contact.as_ref().unwrap(), o.contact.as_ref().unwrap());
    eprintln!(
        "iterations auto {} on {}; passes {} {}",
        a.convergence.iterations, o.convergence.iterations, ca.passes, co.passes
    );
    assert_eq!(a.convergence.iterations, o.convergence.iterations);
    assert_eq!(closed_at_end(&auto), closed_at_end(&on));
    assert_eq!(ca.pairs_closed, co.pairs_closed);
    for (fa, fo) in a.front.iter().zip(&o.front) {
        approx::assert_relative_eq!(fa.g_t, fo.g_t, max_relative = 1e-6, epsilon = 1e-9);
        approx::assert_relative_eq!(fa.g_i, fo.g_i, max_relative = 1e-6, epsilon = 1e-9);
        approx::assert_relative_eq!(fa.g_ii, fo.g_ii, max_relative = 1e-6, epsilon = 1e-9);
    }
}

#[test]
fn cli_writes_the_contact_record() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-contact-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/fig_5_1_3_circle_30mm.toml"),
    )
    .unwrap()
    .replace("slices = 8", "slices = 4")
        + "\n[contact]\ncrack_faces = \"auto\"\ntolerance_mm = 1e-6\n";
    let path = dir.join("scene.toml");
    std::fs::write(&path, text).unwrap();
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["run", "--out"])
        .arg(dir.join("out"))
        .arg(&path)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    // The terminal table carries the contact column.
    assert!(String::from_utf8_lossy(&out.stdout).contains("contact: pairs closed"));
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.join("out/results.json")).unwrap())
            .unwrap();
    let last = &json["levels"][4];
    for key in [
        "passes",
        "pairs_closed",
        "max_force_n",
        "max_pressure_mpa",
        "max_penetration_mm",
        "iterations",
        "first_s",
    ] {
        assert!(last["contact"][key].is_number(), "{key}: {last}");
    }
    // One record per pass: pairs closed and opened, whether a refresh, iterations, time.
    let log = last["contact"]["pass_log"].as_array().unwrap();
    assert_eq!(
        log.len() as u64,
        last["contact"]["passes"].as_u64().unwrap()
    );
    for pass in log {
        for key in ["closed", "opened", "iterations", "seconds"] {
            assert!(pass[key].is_number(), "{key}: {pass}");
        }
        assert!(pass["refresh"].is_boolean());
        assert!(pass["inexact"].is_boolean());
    }
    assert!(
        last["front"]
            .as_array()
            .unwrap()
            .iter()
            .all(|f| f["faces"] != "overlapped")
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_negative_tolerance_is_refused_by_name() {
    let text = format!(
        "{}\n[contact]\ntolerance_mm = -1.0\n",
        include_str!("../examples/scenes/fig_5_1_3_circle_30mm.toml")
    );
    let e = Scene::from_toml(&text).unwrap_err();
    assert!(e.to_string().contains("contact.tolerance_mm"), "{e}");
}

#[test]
fn the_thesis_external_force_also_removes_the_overlap() {
    let mut s = scene(&SWEEP, CrackFacesName::On);
    s.contact.mode = nonlin3d::contact::ContactModeName::Thesis;
    let r = run(&s);
    assert!(r.levels.iter().all(|l| l.overlapped() == 0));
    assert!(
        r.levels
            .last()
            .unwrap()
            .contact
            .as_ref()
            .unwrap()
            .pairs_closed
            > 0
    );
}

/// The 30 mm circle on a front-resolving mesh (e = 0.1 mm; 6 slices, 6 and 5 rings, 2 and 2
/// layers: 5 901 DOF) whose faces overlap without contact by up to 0.029 mm behind the front
/// near the load axis at ε = −0.004.
fn graded(strains: &[f64], faces: CrackFacesName) -> Scene {
    let mut s = scene(strains, faces);
    s.mesh.slices = Some(6);
    s.mesh.inside = Some(6);
    s.mesh.outside = Some(5);
    s.mesh.sub_layers = Some(2);
    s.mesh.base_layers = Some(2);
    s.mesh.front_element_mm = Some(0.1);
    s
}

#[test]
fn one_level_with_contact_lands_on_the_loading_paths_solution() {
    // Reference: contact followed along the load in steps of 0.001 (steps of 0.00025 give the
    // same centre deflection within 0.0003 mm, 0.05 %). One level ε = −0.004 with `auto`
    // engages on a state that overlaps by 0.029 mm; its passes used to settle there on another
    // equilibrium (centre deflection 0.721 mm against the path's 0.674, +7 %, a dozen pairs
    // carrying up to 12.5 N). The bound, 1 %, is 20× the spread of the stepped solutions and
    // a seventh of the error.
    let path = run(&graded(
        &[-0.001, -0.002, -0.003, -0.004],
        CrackFacesName::On,
    ));
    let one = run(&graded(&[-0.004], CrackFacesName::Auto));
    let w = |r: &Results| r.levels.last().unwrap().centre_deflection_mm;
    approx::assert_relative_eq!(w(&one), w(&path), max_relative = 0.01);
    let g = |r: &Results| r.levels.last().unwrap().front[0].g_t;
    // G_T at S = 0 moves with the deflection (210.8 against 194.5 J/m² before, +8 %).
    approx::assert_relative_eq!(g(&one), g(&path), max_relative = 0.01);
}

/// The closed pairs at the last level: weighted gap g̃ (the contact test's basis, zero at a
/// closed pair) within the contact tolerance, 1e-9 m (open pairs are ≥ 3e-7 m apart here).
fn closed_at_end(r: &Results) -> Vec<usize> {
    let model = r.model_data.as_ref().unwrap();
    let faces = nonlin3d_contact::CrackFaces::from_mesh(&model.mesh).unwrap();
    let u = &r.levels.last().unwrap().displacements;
    let n = faces.normals(u).unwrap();
    let g = faces.weighted_gaps(&faces.gaps(u, &n));
    (0..g.len()).filter(|&i| g[i].abs() <= 1e-9).collect()
}

/// One closed set whatever the path (issue 19, defect 1: closing on nodal gaps and releasing
/// on recovered forces left two stable sets, and a level in one go held 2 more edge pairs than
/// small increments at −0.003, 3 more at −0.005). At ε = −0.005: one level (followed in the
/// contact's sub-levels of at most `max_step`, 4 × 0.00125 — without them, max_step = 1, the
/// same 12 pairs were measured), the sweep in levels of 0.001 and in levels of 0.0005 close
/// the same pairs, and the centre deflections agree to 1e-4 (relative: each run is converged
/// to Newton's 1e-8 of the force scale, the measured spread is 5e-7; a pair more or less moves
/// it by 1e-4 … 6e-4). The deck's increments close the same pairs as `run` at every level
/// (tests/calculix_contact.rs).
#[test]
fn the_closed_set_does_not_depend_on_the_load_path() {
    let fine: Vec<f64> = (1..=10).map(|k| -0.0005 * k as f64).collect();
    let runs = [
        run(&scene(&[-0.005], CrackFacesName::On)),
        run(&scene(&SWEEP, CrackFacesName::On)),
        run(&scene(&fine, CrackFacesName::On)),
    ];
    let sets: Vec<Vec<usize>> = runs.iter().map(closed_at_end).collect();
    let w: Vec<f64> = runs
        .iter()
        .map(|r| r.levels.last().unwrap().centre_deflection_mm)
        .collect();
    eprintln!("closed at −0.005: {sets:?}; centre w {w:?} mm");
    assert!(!sets[0].is_empty());
    for (k, r) in runs.iter().enumerate() {
        let c = r.levels.last().unwrap().contact.as_ref().unwrap();
        assert_eq!(c.pairs_closed, sets[k].len(), "run {k}");
        assert_eq!(sets[k], sets[0], "run {k}");
        approx::assert_relative_eq!(w[k], w[0], max_relative = 1e-4);
    }
}

/// The thesis's approximation (`mode = "thesis"`, Fig. 2.7.1c) on the graded mesh: a held
/// upper node 0.05 mm behind the front drags its lower node along through the front cell, so
/// holding it at the lower node's height again and again (refresh passes) contracts the
/// overlap by a few per cent a pass. The loop ends in an error that names the level, the pair
/// and the overlaps, and says why and what to use instead (it used to run 50 passes and
/// report only that the set still changed).
#[test]
fn the_thesis_approximation_on_a_graded_mesh_ends_in_a_located_error() {
    let mut s = graded(&[-0.001, -0.002], CrackFacesName::On);
    s.contact.mode = nonlin3d::contact::ContactModeName::Thesis;
    let e = nonlin3d::analysis::run(&s, &mut |_| Ok(())).unwrap_err();
    let m = e.to_string();
    eprintln!("{m}");
    assert!(
        m.contains("refresh passes") && m.contains("nodes ") && m.contains("two_body"),
        "{m}"
    );
}

/// Stability is counted on the pairs that hold (`Contact::holding_inertia`). Hex8 with the
/// selective-reduced rule on the default 8-slice circle: the perturbation at −0.002 sends the
/// sublaminate towards the base, all 52 pairs close with zero force and hold it flat
/// (w ≈ 0.003 mm, G = 0 everywhere). Counted with every closed pair tied, that state looked
/// stable; a pair without compressive force would open, so without their ties the tangent has
/// the negative pivots of the buckling modes the bifurcation at −0.0016 brought, and the levels
/// must say unstable (and the run warn), not report a flat, stable, G-free laminate.
#[test]
fn faces_that_touch_without_force_do_not_make_a_buckled_state_stable() {
    use nonlin3d::scene::{ElementName, RuleName};
    let mut s = scene(&[-0.001, -0.002, -0.003], CrackFacesName::Auto);
    s.mesh.slices = None;
    s.mesh.element = Some(ElementName::Hex8);
    s.analysis.integration = RuleName::SelectiveReduced;
    let r = run(&s);
    let after: Vec<_> = r.levels.iter().skip(1).collect();
    for l in &after {
        let c = l.contact.as_ref().expect("contact engaged");
        assert!(c.pairs_closed > 0 && c.max_force_n < 1e-6, "{c:?}");
        assert_eq!(l.convergence.stable, Some(false), "level {}", l.value);
    }
    assert!(
        r.stability_warnings()
            .iter()
            .any(|w| w.contains("the run ends on an unstable state")),
        "{:?}",
        r.stability_warnings()
    );
}

/// Modified Newton (an option) against full Newton (the default) on the contact sweep: the same negative
/// pivots, bifurcation bracket and closed pairs at every level, and G
/// within 1e-6 of the level's G_T max at every point and mode. Both states are converged to
/// ‖r‖∞ ≤ 1e-8·F; G is a product of nodal forces and openings, each off by about that
/// tolerance relative, so the two differ by a few 1e-8 (measured 6.6e-8 on the 8-slice
/// scene); 1e-6 leaves room for the flat branch just past a bifurcation, where a residual
/// moves the state most (4.4e-6 on the through-width scene, docs/PERFORMANCE.md).
#[test]
fn modified_newton_reaches_full_newtons_levels() {
    use nonlin3d::scene::NewtonName;
    let mut full = scene(&SWEEP, CrackFacesName::Auto);
    assert_eq!(full.analysis.newton, NewtonName::Full);
    // Along the path on this mesh: a level started from the companion's state is solved by
    // full Newton whatever the scene's strategy (tests/nested.rs).
    full.analysis.start = nonlin3d::scene::StartName::Path;
    let mut modified = full.clone();
    modified.analysis.newton = NewtonName::Modified;
    let (m, f) = (run(&modified), run(&full));
    for (a, b) in m.levels.iter().zip(&f.levels) {
        assert_eq!(a.convergence.negative_pivots, b.convergence.negative_pivots);
        assert_eq!(a.convergence.bifurcation, b.convergence.bifurcation);
        let closed =
            |r: &nonlin3d::results::LevelResult| r.contact.as_ref().map(|c| c.pairs_closed);
        assert_eq!(closed(a), closed(b), "level {}", a.value);
        let g_max = b.front.iter().fold(0.0_f64, |m, r| m.max(r.g_t.abs()));
        for (p, q) in a.front.iter().zip(&b.front) {
            assert_eq!(p.faces, q.faces);
            for (x, y) in [
                (p.g_i, q.g_i),
                (p.g_ii, q.g_ii),
                (p.g_iii, q.g_iii),
                (p.g_t, q.g_t),
            ] {
                assert!(
                    (x - y).abs() <= 1e-6 * g_max.max(1e-12),
                    "level {}: {x} {y}",
                    a.value
                );
            }
        }
    }
}

/// A run asked for all cores (`threads = 0`) reports the pool's threads, also on a small model
/// (the solver itself keeps faer's kernels on one thread below `KERNEL_THREADS_FROM_DOFS`;
/// the bits do not depend on the count); one that names its threads reports them.
#[test]
fn a_run_reports_the_threads_it_was_given() {
    let mut s = scene(&[-0.001], CrackFacesName::Off);
    s.analysis.threads = 0;
    let r = run(&s);
    assert!(r.model.dofs < nonlin3d::solver::KERNEL_THREADS_FROM_DOFS);
    assert_eq!(r.timings.threads, rayon::current_num_threads());
    s.analysis.threads = 2;
    assert_eq!(run(&s).timings.threads, 2);
}

/// `[contact] inexact_passes` as a user sets it: 0 gives the exact loop of Fig. 2.7.2 (no pass
/// read at a Newton iterate), the default reads the set at iterates near equilibrium. Both end
/// on converged states of the same set: the same closed pairs per level and G within 1e-6 of
/// the level's G_T max (measured ≤ 3.4e-7 on three meshes; both states meet ‖r‖∞ ≤ 1e-8·F,
/// so their G differ by the solution's tolerance, not by the set), the default in no more
/// Newton iterations. The key is refused when misspelt (unknown fields are).
#[test]
fn cli_inexact_passes_zero_is_the_exact_loop_with_the_same_answer() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-inexact-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/scenes/fig_5_1_3_circle_30mm.toml"),
    )
    .unwrap()
    .replace("slices = 8", "slices = 4\nerror_estimate = \"off\"");
    let run = |name: &str, contact: &str| -> (serde_json::Value, bool) {
        let path = dir.join(format!("{name}.toml"));
        std::fs::write(&path, format!("{base}\n[contact]\n{contact}\n")).unwrap();
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
            .args(["run", "-q", "--threads", "1", "--out"])
            .arg(dir.join(name))
            .arg(&path)
            .output()
            .unwrap();
        if !out.status.success() {
            return (
                serde_json::Value::String(String::from_utf8_lossy(&out.stderr).into()),
                false,
            );
        }
        let text = std::fs::read_to_string(dir.join(name).join("results.json")).unwrap();
        (serde_json::from_str(&text).unwrap(), true)
    };
    let (exact, ok) = run("exact", "inexact_passes = 0");
    assert!(ok, "{exact}");
    let (inexact, ok) = run("inexact", "crack_faces = \"auto\"");
    assert!(ok, "{inexact}");
    let passes = |r: &serde_json::Value, inexact: bool| -> usize {
        r["levels"]
            .as_array()
            .unwrap()
            .iter()
            .filter_map(|l| l["contact"]["pass_log"].as_array())
            .flatten()
            .filter(|p| p["inexact"].as_bool() == Some(inexact))
            .count()
    };
    assert_eq!(passes(&exact, true), 0, "the exact loop read an iterate");
    assert!(passes(&inexact, true) > 0, "no pass read at an iterate");
    let levels = |r: &serde_json::Value| r["levels"].as_array().unwrap().clone();
    let (a, b) = (levels(&exact), levels(&inexact));
    assert_eq!(a.len(), b.len());
    let mut iterations = [0u64; 2];
    for (la, lb) in a.iter().zip(&b) {
        assert_eq!(la["contact"]["pairs_closed"], lb["contact"]["pairs_closed"]);
        iterations[0] += la["contact"]["iterations"].as_u64().unwrap_or(0);
        iterations[1] += lb["contact"]["iterations"].as_u64().unwrap_or(0);
        let front = |l: &serde_json::Value| -> Vec<[f64; 4]> {
            l["front"]
                .as_array()
                .unwrap()
                .iter()
                .map(|f| ["g_i", "g_ii", "g_iii", "g_t"].map(|k| f[k].as_f64().unwrap_or(0.0)))
                .collect()
        };
        let (fa, fb) = (front(la), front(lb));
        let gt_max = fa.iter().fold(0.0f64, |m, g| m.max(g[3]));
        for (ga, gb) in fa.iter().zip(&fb) {
            for k in 0..4 {
                assert!(
                    (ga[k] - gb[k]).abs() <= 1e-6 * gt_max.max(1e-12),
                    "G differs: {ga:?} against {gb:?} (G_T max {gt_max})"
                );
            }
        }
    }
    assert!(
        iterations[1] <= iterations[0],
        "inexact {} against exact {} iterations",
        iterations[1],
        iterations[0]
    );
    let (refused, ok) = run("misspelt", "inexact_pass = 0");
    assert!(
        !ok && refused.as_str().unwrap().contains("inexact_pass"),
        "{refused}"
    );
}
