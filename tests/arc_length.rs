//! Arc-length path following end to end: `*STATIC, RIKS` decks (the load proportionality
//! factor per increment, the stopping criteria, agreement with a load-controlled step) and
//! scenes with `[analysis] path = "arc-length"`.

use nonlin3d::deck::{StepOptions, solve_deck};
use nonlin3d::mesh::read_inp;
use std::path::Path;

/// The Hex20 cantilever of tests/decks (30×5×4 mm steel, 3 kN tip load, NLGEOM) with its
/// `*STATIC` line replaced by `riks` (keyword and data line).
fn cantilever(riks: &str) -> String {
    let deck = std::fs::read_to_string("tests/decks/cantilever_nlgeom.inp").unwrap();
    deck.replace("*STATIC\n0.1, 1.0, 1e-5, 1.0\n", riks)
}

/// The deck with every tip force scaled by `f` (a load-controlled step to λ·P_ref).
fn scaled(deck: &str, f: f64) -> String {
    deck.replace(
        "-142.85714285714286",
        &format!("{:e}", -142.85714285714286 * f),
    )
}

/// u_z at node 71 (a tip node), m.
fn tip(model: &nonlin3d::mesh::InpModel, d: &[[f64; 3]]) -> f64 {
    let i = model.node_ids.iter().position(|&id| id == 71).unwrap();
    d[i][2]
}

/// `*STATIC, RIKS` with λ_end = 1: every increment reports its LPF (rising here: the cantilever
/// has no limit point), the first is Δl_in/l_period = 0.1 off by the path's curvature only, the
/// step ends at the first increment with λ ≥ 1. A load-controlled step to the LPF reached
/// (the forces scaled by it) gives the same tip deflection: both meet ‖r‖∞ ≤ 1e-8·F, so the
/// displacements differ by about 1e-8·F/k_min ≤ 1e-8 × the largest displacement × the
/// stiffness ratio of the mesh (≲ 1e2 for 6×2×2 Hex20): 1e-6 relative.
#[test]
fn a_riks_deck_reports_the_lpf_and_agrees_with_load_control() {
    let riks = cantilever("*STATIC, RIKS\n0.1, 1.0, 1e-5, 0.5, 1.0\n");
    let model = read_inp(&riks).unwrap();
    let steps = solve_deck(&model, &StepOptions::default()).unwrap();
    let incs = &steps[0].increments;
    let lpf: Vec<f64> = incs.iter().map(|i| i.lpf.unwrap()).collect();
    eprintln!(
        "LPF {lpf:?}\narc {:?}\niterations {:?}",
        incs.iter()
            .map(|i| i.arc_length.unwrap())
            .collect::<Vec<_>>(),
        incs.iter().map(|i| i.iterations).collect::<Vec<_>>()
    );
    assert!((lpf[0] - 0.1).abs() < 0.01, "{}", lpf[0]);
    assert!(lpf.windows(2).all(|w| w[1] > w[0]));
    assert!(*lpf.last().unwrap() >= 1.0);
    assert!(lpf[..lpf.len() - 1].iter().all(|&l| l < 1.0));
    // The step time is the accumulated arc length.
    let total: f64 = incs.iter().map(|i| i.arc_length.unwrap()).sum();
    assert!((incs.last().unwrap().step_time - total).abs() <= 1e-12 * total);
    let end = *lpf.last().unwrap();
    let load = read_inp(&scaled(&cantilever("*STATIC\n0.1, 1.0, 1e-5, 1.0\n"), end)).unwrap();
    let reference = solve_deck(&load, &StepOptions::default()).unwrap();
    let (a, b) = (
        tip(&model, &steps[0].displacements),
        tip(&load, &reference[0].displacements),
    );
    eprintln!("tip u_z: Riks {a:e} m at LPF {end}, load control {b:e} m");
    assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} against {b}");
}

/// The monitored displacement ends the step at the increment that crosses it; INC= ends it
/// after that many increments (a normal end, as in Abaqus).
#[test]
fn a_riks_step_stops_at_the_monitored_displacement_or_inc() {
    let base = cantilever("*STATIC, RIKS\n0.1, 1.0, 1e-5, 0.2, 1.0\n");
    let full = solve_deck(&read_inp(&base).unwrap(), &StepOptions::default()).unwrap();
    let model = read_inp(&base).unwrap();
    let half = 0.5 * tip(&model, &full[0].displacements);
    let deck = cantilever(&format!(
        "*STATIC, RIKS\n0.1, 1.0, 1e-5, 0.2, , 71, 3, {half:e}\n"
    ));
    let model = read_inp(&deck).unwrap();
    let steps = solve_deck(&model, &StepOptions::default()).unwrap();
    let end = tip(&model, &steps[0].displacements);
    assert!(end <= half, "{end} {half}");
    let lpf: Vec<f64> = steps[0].increments.iter().map(|i| i.lpf.unwrap()).collect();
    assert!(*lpf.last().unwrap() < 1.0 && lpf.len() >= 2, "{lpf:?}");
    let deck = cantilever("*STATIC, RIKS\n0.1, 1.0, 1e-5, 0.2, 1.0\n")
        .replace("*STEP, NLGEOM", "*STEP, NLGEOM, INC=3");
    let steps = solve_deck(&read_inp(&deck).unwrap(), &StepOptions::default()).unwrap();
    assert_eq!(steps[0].increments.len(), 3);
    assert!(steps[0].complete);
}

/// `nonlin3d solve` on a Riks deck: the LPF of every increment in summary.json and on the
/// standard output, as Abaqus's status file lists it.
#[test]
fn the_solve_command_lists_the_lpf_by_increment() {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("riks");
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("riks.inp");
    std::fs::write(
        &path,
        cantilever("*STATIC, RIKS\n0.25, 1.0, 1e-5, 0.5, 1.0\n"),
    )
    .unwrap();
    let out = dir.join("out");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .arg("solve")
        .arg(&path)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let summary: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out.join("summary.json")).unwrap()).unwrap();
    let incs = summary["steps"][0]["increments"].as_array().unwrap();
    assert!(incs.len() >= 2);
    for (k, i) in incs.iter().enumerate() {
        let lpf = i["lpf"].as_f64().unwrap();
        assert!(
            stdout.contains(&format!("increment {:3}: LPF {lpf:+.6e}", k + 1)),
            "{stdout}"
        );
    }
    // The arc-length corrector reports its iterations as Newton's do: one convergence.cvg record
    // per iteration of every increment (a header line first), so the log follows a RIKS step.
    let iterations: u64 = incs.iter().map(|i| i["iterations"].as_u64().unwrap()).sum();
    assert!(iterations > 0);
    let cvg = std::fs::read_to_string(out.join("convergence.cvg")).unwrap();
    assert_eq!(cvg.lines().count() as u64, iterations + 1, "{cvg}");
}

/// The reference scene on 4 slices at two strains (about a second a run), `path` as given.
fn coarse_scene(path: &str) -> nonlin3d::Scene {
    let text = nonlin3d::scene::THESIS_SCENE
        .replace("slices = 8", "slices = 4")
        .replace(
            "strains = [-0.001, -0.002, -0.003, -0.004, -0.005]",
            "strains = [-0.001, -0.003]",
        )
        .replace("[analysis]", &format!("[analysis]\npath = \"{path}\""));
    nonlin3d::Scene::from_toml(&text).unwrap()
}

/// `[analysis] path = "arc-length"` on the reference scene (its delamination buckles at a
/// bifurcation, past which the perturbation protocol takes the buckled branch; no limit point
/// under strain control): each level lands on the same state as load control. Both meet
/// ‖r‖∞ ≤ 1e-8·F, which bounds the relative error of displacements and of the forces and
/// displacements VCCT multiplies at about 1e-8 × the conditioning of the buckled state; 1e-5
/// relative leaves room for that near-singular direction (G_T and the deflection).
#[test]
fn a_scene_by_arc_length_reproduces_load_control() {
    let load = nonlin3d::Analysis::new(coarse_scene("load"))
        .unwrap()
        .run()
        .unwrap();
    let arc = nonlin3d::Analysis::new(coarse_scene("arc-length"))
        .unwrap()
        .run()
        .unwrap();
    assert_eq!(load.levels.len(), arc.levels.len());
    let g = |l: &nonlin3d::results::LevelResult| l.front.iter().map(|r| r.g_t).fold(0.0, f64::max);
    // Scales: the largest G_T and separation of the sweep (below buckling both are rounding).
    let g_scale = load.levels.iter().map(g).fold(0.0, f64::max);
    let w_scale = load
        .levels
        .iter()
        .map(|l| l.max_face_separation_mm.abs())
        .fold(0.0, f64::max);
    for (a, b) in load.levels.iter().zip(&arc.levels) {
        eprintln!(
            "strain {}: G_T max {:e} / {:e} J/m², separation {:e} / {:e} mm, increments {} / {}, \
             iterations {} / {}",
            a.value,
            g(a),
            g(b),
            a.max_face_separation_mm,
            b.max_face_separation_mm,
            a.convergence.increments,
            b.convergence.increments,
            a.convergence.iterations,
            b.convergence.iterations,
        );
        assert_eq!(a.value, b.value);
        assert!((g(a) - g(b)).abs() <= 1e-5 * g_scale, "{} {}", g(a), g(b));
        assert!((a.max_face_separation_mm - b.max_face_separation_mm).abs() <= 1e-5 * w_scale);
    }
    assert!(arc.levels[1].max_face_separation_mm > 0.2);
    // The arc length did run: the first level (λ from 0 to 1/3, below buckling) takes two
    // load steps of at most 0.25 (0.25, then 1/12) by load control, and two arcs (λ ≈ 0.25,
    // ≈ 0.5 past the level) plus the landing Newton solve at λ = 1/3 by arc length.
    assert_eq!(load.levels[0].convergence.increments, 2);
    assert_eq!(arc.levels[0].convergence.increments, 3);
}

/// A shallow pinned arch as a deck: span 100 mm, sinusoidal rise 2 mm, 1 × 1 mm section of
/// steel, 40 × 2 C3D8 along the span and through the thickness, one through the width (held
/// in y: plane strain), pinned at the mid-thickness nodes of both ends, a point load of 1 N
/// per node on the two top nodes at mid-span; `procedure` is the `*STATIC` card and data
/// line, `load` the force per node (N). Node ids: 1 + 6i + 3j + k (i along, j across, k up).
fn arch(procedure: &str, load: f64) -> String {
    let (span, rise, t, n) = (0.1, 0.002, 0.001, 40);
    let id = |i: usize, j: usize, k: usize| 1 + 6 * i + 3 * j + k;
    let mut d = String::from("*HEADING\nshallow pinned arch\n*NODE, NSET=NALL\n");
    for i in 0..=n {
        let x = span * i as f64 / n as f64;
        let z0 = rise * (std::f64::consts::PI * x / span).sin();
        for j in 0..2 {
            for k in 0..3 {
                let z = z0 + t * (k as f64 / 2.0 - 0.5);
                d += &format!("{}, {x:e}, {:e}, {z:e}\n", id(i, j, k), 0.001 * j as f64);
            }
        }
    }
    d += "*ELEMENT, TYPE=C3D8, ELSET=ALL\n";
    for i in 0..n {
        for k in 0..2 {
            let c = [
                id(i, 0, k),
                id(i + 1, 0, k),
                id(i + 1, 1, k),
                id(i, 1, k),
                id(i, 0, k + 1),
                id(i + 1, 0, k + 1),
                id(i + 1, 1, k + 1),
                id(i, 1, k + 1),
            ];
            let c: Vec<String> = c.iter().map(|v| v.to_string()).collect();
            d += &format!("{}, {}\n", 1 + 2 * i + k, c.join(", "));
        }
    }
    d += &format!(
        "*NSET, NSET=PINS\n{}, {}, {}, {}\n*NSET, NSET=TOP\n{}, {}\n",
        id(0, 0, 1),
        id(0, 1, 1),
        id(n, 0, 1),
        id(n, 1, 1),
        id(n / 2, 0, 2),
        id(n / 2, 1, 2)
    );
    d += "*MATERIAL, NAME=STEEL\n*ELASTIC\n200e9, 0.3\n*SOLID SECTION, ELSET=ALL, MATERIAL=STEEL\n";
    d += &format!(
        "*STEP, NLGEOM, INC=100\n{procedure}*BOUNDARY\nPINS, 1, 1\nPINS, 3, 3\nNALL, 2, 2\n\
         *CLOAD\nTOP, 3, {load:e}\n*END STEP\n"
    );
    d
}

/// The arch snaps through: by `*STATIC, RIKS` (Δl_in 0.5, Δl_max 2, stop when the top node
/// at mid-span, id 123, has moved down 2.5 × the rise) the LPF rises to a limit point, falls
/// to less than half of it on the unstable branch (the tangent has a negative pivot there),
/// rises again on the inverted arch, and the step ends at the increment that crosses the
/// monitored deflection. Below the limit point a load-controlled step to an increment's LPF
/// lands on the same state (both within ‖r‖∞ ≤ 1e-8·F: 1e-6 relative, as for the cantilever).
#[test]
fn a_riks_deck_follows_a_shallow_arch_through_snap_through() {
    let model = read_inp(&arch(
        "*STATIC, RIKS\n0.5, 1., , 2., , 123, 3, -0.005\n",
        -1.0,
    ))
    .unwrap();
    let steps = solve_deck(&model, &StepOptions::default()).unwrap();
    let incs = &steps[0].increments;
    let lpf: Vec<f64> = incs.iter().map(|i| i.lpf.unwrap()).collect();
    eprintln!("LPF {lpf:?}");
    let top = |d: &[[f64; 3]]| d[model.node_ids.iter().position(|&i| i == 123).unwrap()][2];
    let (peak, at) =
        lpf.iter().enumerate().fold(
            (f64::MIN, 0),
            |m, (k, &l)| if l > m.0 && k < 20 { (l, k) } else { m },
        );
    let valley = lpf[at..].iter().copied().fold(f64::MAX, f64::min);
    assert!(
        at > 0 && valley < 0.5 * peak,
        "peak {peak} at {at}, valley {valley}"
    );
    assert!(*lpf.last().unwrap() > peak, "{lpf:?}");
    assert!(
        incs.iter()
            .any(|i| i.negative_pivots.is_some_and(|p| p > 0))
    );
    assert!(top(&steps[0].displacements) <= -0.005);
    assert!(incs.len() < 100, "the monitor ended the step, not INC");
    // Load control to the LPF of an increment below the limit point (the Riks step stopped
    // there by λ_end, a hair below so that the same increment ends it).
    let k = at / 2;
    let riks = read_inp(&arch(
        &format!("*STATIC, RIKS\n0.5, 1., , 2., {}\n", lpf[k] * (1.0 - 1e-12)),
        -1.0,
    ))
    .unwrap();
    let first = solve_deck(&riks, &StepOptions::default()).unwrap();
    let load = read_inp(&arch("*STATIC\n0.25, 1.\n", -lpf[k])).unwrap();
    let reference = solve_deck(&load, &StepOptions::default()).unwrap();
    let (a, b) = (
        top(&first[0].displacements),
        top(&reference[0].displacements),
    );
    eprintln!("at LPF {}: Riks {a:e} m, load control {b:e} m", lpf[k]);
    assert!((a - b).abs() <= 1e-6 * b.abs(), "{a} against {b}");
}
