//! Nested iteration (`[analysis] start = "companion"`, the default; src/analysis_seed.rs): the
//! levels from the companion's perturbed level on start from the companion mesh's converged
//! states. They must reach the equilibria the path reaches (`start = "path"`): the same closed
//! contact pairs and negative pivots at every level, the same G and deflections to the
//! accuracy the contact loop defines them — a closed pair is held along the normal frozen at
//! its last refresh, so two runs reaching the same set along other passes agree to about 1e-5
//! of G_T max (3.4e-5 measured on the 30 × 60 mm ellipse, docs/PERFORMANCE.md), not to the
//! Newton tolerance — in fewer of this mesh's iterations; and a start that cannot be used (its
//! contact set far off, its Newton solve not converging, another branch) must be dropped for
//! the path, not reported.

mod common;

use nonlin3d::results::Results;
use nonlin3d::scene::{ErrorEstimateName, StartName};
use nonlin3d::{Analysis, Scene};

/// Bound on |ΔG| / G_T max between the two ways (see the module docs).
const G_AGREEMENT: f64 = 1e-4;

/// The reference circle on the tiny mesh (1 773 DOF, companion 513), three levels: below the
/// bifurcation, past it (the §3.2 protocol, contact `auto`) and one more with contact; the
/// error estimate on (the scene's default).
fn tiny() -> String {
    common::tiny_scene_text("[-0.001, -0.003, -0.004]")
}

/// `text` (a scene) run both ways on one thread: along the path, then nested.
fn both(text: &str) -> (Results, Results) {
    let run = |start| {
        let mut s = Scene::from_toml(text).unwrap();
        s.analysis.start = start;
        s.analysis.threads = 1;
        Analysis::new(s).unwrap().run().unwrap()
    };
    (run(StartName::Path), run(StartName::Companion))
}

/// A committed scene's text.
fn committed(name: &str) -> String {
    std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("examples/scenes")
            .join(name),
    )
    .unwrap()
}

/// The reference circle on the default mesh at the strains `strains` (a TOML array) instead of
/// its five levels.
fn reference_circle_at(strains: &str) -> String {
    let text = committed("reference_circle_30mm.toml").replace(
        "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
        &format!("strains = {strains}"),
    );
    assert!(text.contains(&format!("strains = {strains}")));
    text
}

/// This mesh's Newton iterations: each attempt's and each contact pass's (one factorisation
/// each; the first contact solve is among the attempts).
fn iterations(r: &Results) -> usize {
    r.levels
        .iter()
        .map(|l| {
            l.convergence.iterations
                + l.contact
                    .as_ref()
                    .map_or(0, |c| c.pass_log.iter().map(|p| p.iterations).sum())
        })
        .sum()
}

/// The two runs reach the same states: closed pairs, pivots, G to [`G_AGREEMENT`] of the
/// level's G_T max, centre deflection to 1e-4 of itself.
fn assert_same_states(path: &Results, nested: &Results) {
    assert_eq!(path.levels.len(), nested.levels.len());
    for (a, b) in path.levels.iter().zip(&nested.levels) {
        let closed =
            |l: &nonlin3d::results::LevelResult| l.contact.as_ref().map(|c| c.pairs_closed);
        assert_eq!(
            closed(a).unwrap_or(0),
            closed(b).unwrap_or(0),
            "level {}",
            a.value
        );
        assert_eq!(a.convergence.negative_pivots, b.convergence.negative_pivots);
        let g_max = a.front.iter().fold(0.0_f64, |m, r| m.max(r.g_t));
        for (x, y) in a.front.iter().zip(&b.front) {
            for (p, q) in [(x.g_i, y.g_i), (x.g_ii, y.g_ii), (x.g_iii, y.g_iii)] {
                assert!(
                    (p - q).abs() <= G_AGREEMENT * g_max + 1e-12,
                    "level {}, S = {} mm: {p} against {q} (G_T max {g_max})",
                    a.value,
                    x.s_mm
                );
            }
        }
        let w = a.centre_deflection_mm;
        assert!((w - b.centre_deflection_mm).abs() <= 1e-4 * w.abs() + 1e-9);
    }
}

/// The thesis's 15 mm semicircular edge delamination (6 789 DOF, companion 1 773), its three
/// levels past the bifurcation: each seeded (the carried starts are within
/// `KEEP_SEEDING` = 0.15 of each level's step), contact closing 1 and 3 pairs on the way.
#[test]
fn every_level_of_the_edge_delamination_is_seeded_and_lands_on_the_path() {
    let (path, nested) = both(&committed("fig_5_5_1_edge_semicircle_15mm.toml"));
    assert_same_states(&path, &nested);
    assert!(nested.levels.iter().all(|l| l.convergence.seeded));
    // Its 1 773-DOF companion follows its own path (below `NESTED_FROM_DOFS`).
    let seeded = nested.accuracy.as_ref().map(|a| a.companion_seeded_levels);
    assert_eq!(seeded, Some(Some(0)));
    let closed: Vec<usize> = nested
        .levels
        .iter()
        .map(|l| l.contact.as_ref().map_or(0, |c| c.pairs_closed))
        .collect();
    assert_eq!(closed, [0, 1, 3]);
    let (a, b) = (iterations(&path), iterations(&nested));
    assert!(2 * b < a, "nested {b} iterations against the path's {a}");
    // The two contact levels: the carried set changes at the first solve's iterate after one
    // Newton iteration (src/contact.rs, `SEEDED_STEPS`), so the passes start there — the
    // first of them inexact — and the record ends with the converged state's check: two
    // attempts, one converged, the level's residual (below the Newton tolerance, 1e-8 of the
    // force scale of a few hundred N here), not the iterate's.
    for l in &nested.levels[1..] {
        let c = &l.convergence;
        let passes = &l.contact.as_ref().expect("contact acted").pass_log;
        assert_eq!(
            (c.attempts, c.increments, c.iterations),
            (2, 1, 1),
            "{}",
            l.value
        );
        assert!(passes.first().is_some_and(|p| p.inexact), "{}", l.value);
        assert!(c.residual_n < 1e-5, "{}: ‖r‖∞ {} N", l.value, c.residual_n);
    }
}

/// Turning the error estimate off keeps the nested iteration: the companion then runs for the
/// seeds alone (before, it did not run, and model 6 took 11 s instead of 5.5). The edge
/// delamination's levels are seeded as with the estimate and reach the same states bit for
/// bit; only the estimate is missing.
#[test]
fn without_the_estimate_the_levels_are_still_seeded_with_the_same_bits() {
    let text = committed("fig_5_5_1_edge_semicircle_15mm.toml");
    let run = |estimate| {
        let mut s = Scene::from_toml(&text).unwrap();
        s.mesh.error_estimate = Some(estimate);
        s.analysis.threads = 1;
        Analysis::new(s).unwrap().run().unwrap()
    };
    let (on, off) = (
        run(ErrorEstimateName::Companion),
        run(ErrorEstimateName::Off),
    );
    assert!(off.levels.iter().all(|l| l.convergence.seeded));
    assert_eq!(on.levels.len(), off.levels.len());
    for (a, b) in on.levels.iter().zip(&off.levels) {
        assert!(a.error_estimate.is_some() && b.error_estimate.is_none());
        assert_eq!(a.convergence.seeded, b.convergence.seeded);
        for (p, q) in a.front.iter().zip(&b.front) {
            assert_eq!(
                p.g_t.to_bits(),
                q.g_t.to_bits(),
                "{} at S = {}",
                a.value,
                p.s_mm
            );
            assert!(q.error.is_none());
        }
    }
}

/// On the tiny mesh the buckling level is seeded; its carried start is farther than
/// `KEEP_SEEDING` of the level's step (a 513-DOF companion), so the next level is followed.
#[test]
fn seeded_levels_reach_the_paths_states_in_fewer_iterations() {
    let (path, nested) = both(&tiny());
    assert_same_states(&path, &nested);
    // Below the bifurcation the level is followed; the perturbed level seeded; the next
    // followed.
    let seeded: Vec<bool> = nested.levels.iter().map(|l| l.convergence.seeded).collect();
    assert_eq!(seeded, [false, true, false]);
    assert!(path.levels.iter().all(|l| !l.convergence.seeded));
    // The path perturbs at −0.003 on this mesh; the nested run reports the companion's
    // perturbation and bifurcation there, and does not perturb itself.
    assert!(path.levels[1].convergence.perturbed);
    assert!(!nested.levels[1].convergence.perturbed);
    assert_eq!(nested.model.perturbed_at, Some(-0.003));
    assert!(nested.levels[1].convergence.bifurcation.is_some());
    let (a, b) = (iterations(&path), iterations(&nested));
    assert!(b < a, "nested {b} iterations against the path's {a}");
    // The error estimate is the same companion's either way.
    for (x, y) in path.levels.iter().zip(&nested.levels) {
        let e = |l: &nonlin3d::results::LevelResult| l.error_estimate.as_ref().map(|e| e.max_j_m2);
        // (No summary on the unbuckled level, in either run.)
        let (p, q) = (e(x), e(y));
        assert_eq!(p.is_some(), q.is_some(), "{}", x.value);
        if let (Some(p), Some(q)) = (p, q) {
            assert!((p - q).abs() <= 1e-3 * p.abs().max(1e-9), "{p} against {q}");
        }
    }
}

/// Model 6's companion mesh (3 951 DOF) as a scene: its own companion (1 365 DOF) is too coarse
/// for the buckling level — the contact set carried from it would change at 95 of 96 pairs
/// (src/contact.rs, `SEEDED_CHANGE`) — so that level is followed on this mesh (the §3.2
/// protocol on this mesh), and the next, seeded, agrees with the path.
#[test]
fn a_start_the_companion_cannot_give_is_dropped_for_the_path() {
    let text = committed("table_2_model_6_size.toml")
        .replace("slices = 8", "slices = 4")
        .replace("inside = 10", "inside = 5")
        .replace("outside = 11", "outside = 6")
        .replace("base_layers = 4", "base_layers = 2")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.002, -0.003]",
        );
    let (path, nested) = both(&text);
    assert_eq!(path.model.dofs, 3951);
    let seeded: Vec<bool> = nested.levels.iter().map(|l| l.convergence.seeded).collect();
    assert_eq!(seeded, [false, false, true]);
    assert!(nested.levels[1].convergence.perturbed);
    assert_eq!(nested.model.perturbed_at, Some(-0.002));
    assert_same_states(&path, &nested);
}

/// What the terminal says: the companion's bifurcation and perturbation labelled as the
/// companion's, and the seeded levels listed; `start = "path"` says neither.
#[test]
fn the_terminal_names_the_companions_crossing_and_the_seeded_levels() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-nested-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let summary = |start: &str| {
        // The key as a user writes it in the scene's [analysis] table.
        let text = tiny().replace(
            "integration = \"gauss2\"",
            &format!("integration = \"gauss2\"\nstart = \"{start}\""),
        );
        assert!(text.contains(&format!("start = \"{start}\"")));
        let file = dir.join(format!("{start}.toml"));
        std::fs::write(&file, text).unwrap();
        let out = dir.join(start);
        let o = common::nonlin3d_ok([
            "run".as_ref(),
            file.as_os_str(),
            "--out".as_ref(),
            out.as_os_str(),
        ]);
        String::from_utf8(o.stdout).unwrap()
    };
    let nested = summary("companion");
    // status.sta holds this mesh's attempts only: the companion's (run first on one thread,
    // or beside) were numbered as this run's first level before they were left out.
    let sta = std::fs::read_to_string(dir.join("companion").join("status.sta")).unwrap();
    let first_level = sta.lines().filter(|l| l.starts_with("1,")).count();
    assert_eq!(first_level, 1, "{sta}");
    assert!(
        nested.contains("(negative pivots 0 → 1) on the companion mesh"),
        "{nested}"
    );
    assert!(nested.contains("perturbation applied at strain -0.003 on the companion mesh"));
    assert!(nested.contains("nested iteration, [analysis] start): strain -0.003\n"));
    let path = summary("path");
    assert!(!path.contains("on the companion mesh") && !path.contains("nested iteration"));
    assert!(path.contains("perturbation applied at strain -0.003 (§3.2 protocol)"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// The 15 mm edge delamination on mesh S (docs/ACCURACY.md §2d: 18 444 DOF, e = 0.2 mm, four
/// base layers at the front; companion 7 581 DOF), one level at ε = −0.004: the companion
/// needs no contact there, this mesh closes 3 pairs. The carried start converges with this
/// mesh's faces overlapping and the inertia the companion has, so the contact loop starts
/// from it (before, such a start was dropped and the level followed: 36 iterations, 8 s
/// against 2.4 s) and lands on the path's state.
#[test]
fn a_seeded_level_that_overlaps_where_the_companion_did_not_goes_on_in_the_contact_loop() {
    let text = committed("fig_5_5_1_edge_semicircle_15mm.toml")
        .replace(
            "[mesh]\nslices = 8",
            "[mesh]\nslices = 6\ninside = 7\noutside = 6\nsub_layers = 2\nbase_layers = 4\n\
             front_element_mm = 0.2\nfront_band = [5, 3]\nlayer_band = [3, 2]",
        )
        .lines()
        .map(|l| match l.starts_with("strains") {
            true => "strains = [-0.004]",
            false => l,
        })
        .collect::<Vec<_>>()
        .join("\n");
    let (path, nested) = both(&text);
    assert_eq!(nested.model.dofs, 18_444);
    assert_same_states(&path, &nested);
    let (level, companion) = (&nested.levels[0], nested.accuracy.as_ref());
    assert!(level.convergence.seeded);
    assert_eq!(level.contact.as_ref().map(|c| c.pairs_closed), Some(3));
    assert!(companion.is_some_and(|a| a.companion_dofs == Some(7_581)));
    // Nested companions: the 7 581-DOF companion started its level from its own (the slices
    // halved, and its rings with them), and the states are still the path's.
    assert_eq!(companion.and_then(|a| a.companion_seeded_levels), Some(1));
    let (a, b) = (iterations(&path), iterations(&nested));
    assert!(3 * b < a, "nested {b} iterations against the path's {a}");
}

/// Nested companions on the default mesh, as a user runs it: `nonlin3d run` on the reference
/// circle without mesh knobs, one level at ε = −0.004 (18 444 DOF; companion 7 581, which
/// starts from its own companion, 4 → 2 slices and 7 + 6 → 4 + 3 rings). The `-v` lines name
/// the coarser companion apart from the companion, `results.json` counts the companion's
/// seeded level, and one and two threads give the same bits (the companions wait for each
/// other's levels, whatever runs when).
#[test]
fn nested_companions_serve_the_default_mesh_with_the_same_bits_on_any_thread_count() {
    let dir = std::env::temp_dir().join(format!("nonlin3d-nested-3-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = reference_circle_at("[-0.004]");
    let file = dir.join("circle.toml");
    std::fs::write(&file, text).unwrap();
    let run = |threads: &str| {
        let out = dir.join(threads);
        let args = [
            "run",
            file.to_str().unwrap(),
            "-v",
            "--threads",
            threads,
            "--out",
        ];
        let o = common::nonlin3d_ok(args.iter().map(|a| a.as_ref()).chain([out.as_os_str()]));
        (
            common::results_json(&out),
            String::from_utf8_lossy(&o.stderr).to_string(),
        )
    };
    let (two, log) = run("2");
    let (one, _) = run("1");
    let lines = |prefix: &str| log.lines().filter(|l| l.starts_with(prefix)).count();
    assert!(lines("coarser companion: ") > 20, "{log}");
    assert!(lines("companion mesh: ") > 0, "{log}");
    assert_eq!(two["model"]["dofs"], 18_444);
    assert_eq!(two["accuracy"]["companion_dofs"], 7_581);
    assert_eq!(two["accuracy"]["companion_seeded_levels"], 1);
    assert_eq!(two["levels"][0]["convergence"]["seeded"], true);
    // The same bits: every front point's G and its estimate.
    assert_eq!(two["levels"][0]["front"], one["levels"][0]["front"]);
    assert_eq!(
        two["levels"][0]["error_estimate"],
        one["levels"][0]["error_estimate"]
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Two levels of the default mesh in a row, both seeded: the reference circle at ε = −0.002
/// and −0.003 reaches the path's states — the same closed pairs, pivots, G and deflections —
/// in fewer of this mesh's iterations, and on two threads (the companion beside the sweep)
/// gives the one-thread bits. Since the companion keeps the rings outside the front band
/// (docs/ACCURACY.md §3b) its start at −0.002 is close enough that −0.003 is seeded too; with
/// the rings-halved companion before, −0.003 was followed from the companion's contact set
/// (src/analysis_seed.rs `Seeds::followed_set`), which no committed scene reaches now.
#[test]
fn two_seeded_levels_of_the_default_mesh_reach_the_paths_states() {
    let text = reference_circle_at("[-0.002, -0.003]");
    let (path, nested) = both(&text);
    assert_same_states(&path, &nested);
    let flags: Vec<(bool, bool)> = nested
        .levels
        .iter()
        .map(|l| (l.convergence.seeded, l.convergence.companion_set))
        .collect();
    assert_eq!(flags, [(true, false), (true, false)]);
    assert!(path.levels.iter().all(|l| !l.convergence.companion_set));
    let (a, b) = (iterations(&path), iterations(&nested));
    assert!(b < a, "nested {b} iterations against the path's {a}");
    let mut s = Scene::from_toml(&text).unwrap();
    s.analysis.threads = 2;
    let two = Analysis::new(s).unwrap().run().unwrap();
    for (x, y) in nested.levels.iter().zip(&two.levels) {
        assert_eq!(x.front, y.front, "level {}", x.value);
        assert_eq!(x.convergence.companion_set, y.convergence.companion_set);
    }
}

/// A level followed on this mesh from the companion's contact set (`Seeds::followed_set`): the
/// 60 mm circle on its default mesh (24 546 DOF, companion 7 581), five levels. The first four
/// are seeded; seeding stops paying there, and −0.005 is followed from the companion's set at
/// −0.005 mapped onto this mesh's pairs (`convergence.companion_set`). It reaches the path's
/// states: the same closed pairs (135, 194, 228, 242, 256) and pivots, G within 1.8e-8 of G_T
/// max measured (asserted: `G_AGREEMENT`). Before the band was curved the path closed one
/// boundary pair more at −0.005 (258 against 257, docs/PERFORMANCE.md).
#[test]
fn a_level_followed_from_the_companions_set_reaches_the_paths_state() {
    let text = committed("fig_5_1_5_circle_60mm.toml").replace("slices = 8\n", "");
    assert!(!text.contains("slices"));
    let run = |start| {
        let mut s = Scene::from_toml(&text).unwrap();
        s.analysis.start = start;
        Analysis::new(s).unwrap().run().unwrap()
    };
    let (path, nested) = (run(StartName::Path), run(StartName::Companion));
    assert_eq!(nested.model.dofs, 24_546);
    let flags: Vec<(bool, bool)> = nested
        .levels
        .iter()
        .map(|l| (l.convergence.seeded, l.convergence.companion_set))
        .collect();
    assert_eq!(flags[4], (false, true), "{flags:?}");
    assert!(flags[..4].iter().all(|f| f.0), "{flags:?}");
    assert_same_states(&path, &nested);
}

/// A seeded level reads its contact set on this mesh's own pairs at the carried state where the
/// companion has 3 000 DOF or more (src/analysis_seed.rs, `CARRIED_SET_FROM_DOFS`): the
/// reference circle on the default mesh (companion 7 581 DOF) at ε = −0.003 and −0.005 reaches
/// the path's states with 3 contact iterations a level, where the companion's set mapped pair by
/// pair took 4 (it closed this mesh's pairs out to the coarse zone's edge, opened again pass by
/// pass).
#[test]
fn a_seeded_level_reads_its_set_on_this_meshs_pairs() {
    let text = reference_circle_at("[-0.003, -0.005]");
    let (path, nested) = both(&text);
    assert_eq!(nested.model.dofs, 18_444);
    assert_eq!(
        nested.accuracy.as_ref().and_then(|a| a.companion_dofs),
        Some(7_581)
    );
    assert_same_states(&path, &nested);
    for level in &nested.levels {
        assert!(level.convergence.seeded, "level {}", level.value);
        let contact = level.contact.as_ref().map(|c| c.iterations);
        assert!(
            contact.is_some_and(|i| i <= 3),
            "level {}: {contact:?}",
            level.value
        );
    }
}
