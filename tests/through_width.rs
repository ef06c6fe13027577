//! Through-width scenes end to end (thesis §3.2, Fig. 3.2.3; results §5.2.1): the committed
//! scene `examples/scenes/fig_3_2_3_through_width.toml` runs from the command line and from
//! Rust, buckles within 10 % of the clamped column, releases more energy the further it is
//! compressed, and exports a deck that CalculiX 2.20 runs to the same deflections.
//!
//! Reference: a clamped–clamped column of length ℓ = 2a (x = 0 is the symmetry plane) buckles
//! at ε_c = π²h²/(3ℓ²). In plane strain (v = 0 on y = 0 and y = W) with σ_z = 0, membrane
//! stiffness E_ps·h and bending stiffness E_ps·h³/12 share the plane-strain modulus
//! E_ps = C11 − C13²/C33, which cancels: for the quasi-isotropic graphite/epoxy of the scene
//! E_ps = 57.98 GPa = 1.103·E (E = 1/S11 = 52.58 GPa), and ε_c has no material factor.
//!
//! CalculiX: as in tests/calculix.rs, skipped with a notice when `ccx` is missing outside CI;
//! in CI (`CI` set) a missing `ccx` fails.

mod common;

use nonlin3d::Scene;
use nonlin3d::analysis::{
    Analysis, build_model, deflections, perturbation_force, perturbation_loads, settings,
    solve_level,
};
use nonlin3d::newton::{
    DeadLoads, NonlinearProblem, PathSolver, negative_pivots_at, solve_increment,
};
use nonlin3d::scene::Geometry;
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENE: &str = include_str!("../examples/scenes/fig_3_2_3_through_width.toml");

fn tmp(name: &str) -> PathBuf {
    let d = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("through_width_{name}"));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// (h, ℓ = 2a, W) of a through-width scene, m.
fn dims(scene: &Scene) -> (f64, f64, f64) {
    match scene.geometry {
        Geometry::ThroughWidth {
            a_mm,
            width_mm,
            h_mm,
            ..
        } => (h_mm * 1e-3, 2.0 * a_mm * 1e-3, width_mm * 1e-3),
        _ => panic!("not a through-width scene"),
    }
}

/// ε_c = π²h²/(3ℓ²), the clamped–clamped column (module comment).
fn column_strain(scene: &Scene) -> f64 {
    let (h, l, _) = dims(scene);
    std::f64::consts::PI.powi(2) * h * h / (3.0 * l * l)
}

/// The plane-strain modulus E_ps = C11 − C13²/C33 (ε_y = 0, σ_z = 0) of the scene's material.
fn plane_strain_modulus(scene: &Scene) -> f64 {
    let c = scene.stiffnesses().unwrap()[0].matrix();
    c[(0, 0)] - c[(0, 2)] * c[(0, 2)] / c[(2, 2)]
}

/// A level of the pipeline's record, from results.json or from `Results`.
#[derive(Debug, Clone, Copy)]
struct Level {
    /// |ε|.
    strain: f64,
    /// Negative pivots of the tangent at the level.
    pivots: Option<u64>,
    /// Whether the §3.2 perturbation was applied at this level.
    perturbed: bool,
    /// Largest G_T, G_II and G_I along the front, J/m².
    g_t: f64,
    g_ii: f64,
    g_i: f64,
    /// w at the sublaminate's top centre, mm.
    centre_mm: f64,
}

fn levels_of_json(json: &serde_json::Value) -> Vec<Level> {
    let at = json["model"]["perturbed_at"].as_f64();
    json["levels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|l| {
            let max = |key: &str| {
                l["front"]
                    .as_array()
                    .unwrap()
                    .iter()
                    .map(|r| r[key].as_f64().unwrap())
                    .fold(f64::MIN, f64::max)
            };
            let value = l["value"].as_f64().unwrap();
            Level {
                strain: value.abs(),
                pivots: l["convergence"]["negative_pivots"].as_u64(),
                perturbed: at == Some(value),
                g_t: max("g_t"),
                g_ii: max("g_ii"),
                g_i: max("g_i"),
                centre_mm: l["centre_deflection_mm"].as_f64().unwrap(),
            }
        })
        .collect()
}

fn levels_of_results(r: &nonlin3d::Results) -> Vec<Level> {
    r.levels
        .iter()
        .map(|l| {
            let max = |g: fn(&nonlin3d::results::FrontRow) -> f64| {
                l.front.iter().map(g).fold(f64::MIN, f64::max)
            };
            Level {
                strain: l.value.abs(),
                pivots: l.convergence.negative_pivots.map(|p| p as u64),
                perturbed: r.model.perturbed_at == Some(l.value),
                g_t: max(|f| f.g_t),
                g_ii: max(|f| f.g_ii),
                g_i: max(|f| f.g_i),
                centre_mm: l.centre_deflection_mm,
            }
        })
        .collect()
}

/// The bifurcation bracket (|ε| below, |ε| above) from the record, and the index of the first
/// level past it: the first level where the protocol fired or whose tangent has negative
/// pivots; the level before it must have had a positive definite tangent.
fn bracket(levels: &[Level]) -> (f64, f64, usize) {
    let k = levels
        .iter()
        .position(|l| l.perturbed || l.pivots.is_some_and(|p| p > 0))
        .expect("the path never lost stability");
    assert!(k > 0, "unstable at the first level: no bracket");
    assert_eq!(levels[k - 1].pivots, Some(0), "{levels:?}");
    (levels[k - 1].strain, levels[k].strain, k)
}

/// The checks on a run of the committed scene (from the CLI or from Rust).
fn check_sweep(scene: &Scene, levels: &[Level]) -> f64 {
    let eps_c = column_strain(scene);
    let (below, above, k) = bracket(levels);
    // ε_b is the bracket's midpoint, good to ± half the bracket: the scene's levels are 2e-5
    // apart near ε_c = 5.85e-4, ±1.7 % of ε_c. Against ε_c: the base is not a rigid clamp (its
    // root rotation lengthens the column; −2.5 % on the steel strip of tests/newton.rs) and
    // transverse shear lowers the load by E_ps·ε_c/(κ·G13) = 0.9 % (G13 = 4.48 GPa, κ = 5/6).
    // 10 % (the bound) covers both; measured 0.940·ε_c.
    assert!(above - below <= 0.05 * eps_c, "bracket {below}…{above}");
    let eps_b = 0.5 * (below + above);
    assert!(
        (eps_b / eps_c - 1.0).abs() < 0.10,
        "ε_b = {eps_b:.4e} vs ε_c = {eps_c:.4e}"
    );
    // Below the bifurcation the sublaminate stays flat: G_T is round-off (the faces do not
    // move apart: openings of the order of the 1e-4 N residual over the stiffness), far below
    // the 1 J/m² just past it.
    for l in &levels[..k] {
        assert!(l.g_t.abs() < 1e-2, "G_T = {} at {}", l.g_t, l.strain);
    }
    // Past it: buckled outward, and G_T and G_II grow with |ε| (Figs. 5.2.1.1a, 5.2.1.2a).
    for pair in levels[k..].windows(2) {
        assert!(pair[1].g_t > pair[0].g_t, "{pair:?}");
        assert!(pair[1].g_ii > pair[0].g_ii, "{pair:?}");
    }
    assert!(levels[k..].iter().all(|l| l.centre_mm > 0.0));
    // G_I "first increases very rapidly … then decreases" (§5.2.2): its peak is neither the
    // first buckled level nor the last, and it has fallen below half the peak at the last.
    let (peak, g_i_max) = levels[k..]
        .iter()
        .enumerate()
        .fold(
            (0, f64::MIN),
            |m, (i, l)| if l.g_i > m.1 { (i, l.g_i) } else { m },
        );
    let last = levels.len() - 1 - k;
    assert!(peak > 0 && peak < last, "G_I peak at level {}", k + peak);
    assert!(levels[k + last].g_i < 0.5 * g_i_max);
    // The thin-film (rigid substrate) one-dimensional blister, Hutchinson & Suo (1992):
    // G = (E_ps·h/2)·(ε − ε_b)·(ε + 3ε_b). The 4 mm base is not rigid and its compliance adds
    // to G (the same root rotation that lowers ε_b): measured +6.7 … +8.3 % from 2ε_b on;
    // asserted within 15 %.
    let (h, _, _) = dims(scene);
    let e_ps = plane_strain_modulus(scene);
    for l in levels[k..].iter().filter(|l| l.strain >= 2.0 * eps_b) {
        let film = 0.5 * e_ps * h * (l.strain - eps_b) * (l.strain + 3.0 * eps_b);
        assert!(
            (l.g_t / film - 1.0).abs() < 0.15,
            "G_T = {} vs thin film {film} at {}",
            l.g_t,
            l.strain
        );
    }
    eps_b
}

fn run_cli(scene: &Path, out: &Path) -> serde_json::Value {
    let o = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["run", "--quiet", "--out"])
        .arg(out)
        .arg(scene)
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "{}\n{}",
        String::from_utf8_lossy(&o.stdout),
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(&std::fs::read_to_string(out.join("results.json")).unwrap()).unwrap()
}

/// `nonlin3d run` on the committed scene (1 s in release): bifurcation within 10 % of ε_c,
/// G_T growing past it, the thesis's G_I/G_II trends; the CSVs give S = W − y along the
/// straight front (from y = W to y = 0) and the plots are drawn. With `perturbation_n = 0` the
/// trivial path is followed and its negative-pivot count changes in the same bracket.
#[test]
fn cli_runs_the_fig_3_2_3_scene_and_it_buckles_as_the_clamped_column() {
    let dir = tmp("cli");
    let path = dir.join("scene.toml");
    std::fs::write(&path, SCENE).unwrap();
    let scene = Scene::from_toml(SCENE).unwrap();
    let json = run_cli(&path, &dir.join("out"));
    let levels = levels_of_json(&json);
    let eps_b = check_sweep(&scene, &levels);
    eprintln!(
        "ε_b = {eps_b:.4e} = {:.3} ε_c",
        eps_b / column_strain(&scene)
    );
    let (_, _, w) = dims(&scene);
    for k in 0..levels.len() {
        let csv = std::fs::read_to_string(dir.join(format!("out/front_{k}.csv"))).unwrap();
        let mut lines = csv.lines();
        let head: Vec<&str> = lines.next().unwrap().split(',').collect();
        let col = |name: &str| head.iter().position(|h| *h == name).unwrap();
        let rows: Vec<Vec<f64>> = lines
            .map(|l| {
                l.split(',')
                    .take(col("node"))
                    .map(|v| v.parse::<f64>().unwrap_or(f64::NAN))
                    .collect()
            })
            .collect();
        assert_eq!(rows.len(), 2, "one row per front corner: y = W and y = 0");
        for r in &rows {
            assert!((r[col("s_mm")] - (w * 1e3 - r[col("y_mm")])).abs() < 1e-9);
            assert_eq!(r[col("theta_deg")], -90.0);
        }
    }
    for f in ["g_i.svg", "g_ii.svg", "g_t.svg", "deflection.svg"] {
        let svg = std::fs::read_to_string(dir.join("out").join(f)).unwrap();
        assert!(svg.starts_with("<svg") && svg.contains("<polyline"), "{f}");
    }

    // No perturbation: no force is looked up, and the path stays trivial (G_T = 0) with the
    // tangent indefinite from the same level on.
    let flat = dir.join("flat.toml");
    std::fs::write(
        &flat,
        SCENE.replace("[loads]\n", "[loads]\nperturbation_n = 0.0\n"),
    )
    .unwrap();
    let json = run_cli(&flat, &dir.join("flat"));
    assert!(json["model"]["perturbed_at"].is_null());
    let trivial = levels_of_json(&json);
    assert_eq!(bracket(&trivial), bracket(&levels));
    assert!(trivial.iter().all(|l| l.g_t.abs() < 1e-2));
}

/// The same sweep through the Rust API, then ε_b resolved by bisection on the inertia of the
/// trivial path's tangent inside the run's bracket, and the perturbation force checked
/// against the h/4 it is sized for.
#[test]
fn rust_api_runs_the_scene_and_the_inertia_pins_the_bifurcation() {
    let scene = Scene::from_toml(SCENE).unwrap();
    let analysis = Analysis::new(scene.clone()).unwrap();
    let results = analysis.run().unwrap();
    let levels = levels_of_results(&results);
    check_sweep(&scene, &levels);
    let (below, above, _) = bracket(&levels);

    let model = analysis.model().unwrap();
    let mut problem = analysis.problem(&model).unwrap();
    let (newton, stepping) = settings(&scene);
    let reference = -0.005; // the scene's largest strain: λ = ε/reference
    assert_eq!(
        scene.loads.strains.iter().copied().fold(0.0, f64::min),
        reference
    );
    let mut session = PathSolver::new(&problem, newton.solver).unwrap();
    let mut unstable = |strain: f64| {
        let lambda = -strain / reference;
        let mut u = vec![0.0; problem.assembler().n()];
        solve_level(
            &mut problem,
            &mut u,
            0.0,
            lambda,
            &[],
            &newton,
            &stepping,
            &mut session,
        )
        .unwrap();
        negative_pivots_at(&mut problem, &u, lambda, newton.solver).unwrap() > 0
    };
    let (mut lo, mut hi) = (below, above);
    assert!(!unstable(lo) && unstable(hi));
    for _ in 0..8 {
        let mid = 0.5 * (lo + hi);
        if unstable(mid) { hi = mid } else { lo = mid }
    }
    // Bracket 2e-5 / 2⁸ = 8e-8 = 0.013 % of ε_c; the 10 % as in `check_sweep`.
    let eps_c = column_strain(&scene);
    let eps_b = 0.5 * (lo + hi);
    eprintln!(
        "inertia: ε_b = {eps_b:.5e} = {:.4} ε_c (±{:.1e})",
        eps_b / eps_c,
        0.5 * (hi - lo)
    );
    assert!((eps_b / eps_c - 1.0).abs() < 0.10);

    // The force alone, at zero strain: the clamped–clamped beam formula sizes it for w = h/4.
    // The base's compliant clamp (the column above is ~3 % longer in effect: +9 % on ℓ³) and
    // shear (+1 %) add deflection, membrane stretching at w = h/4 takes a little away;
    // measured w = 0.260·h, asserted within 15 %.
    let mut problem = analysis.problem(&model).unwrap();
    let force = perturbation_force(&scene, &model).unwrap();
    for (dof, f) in perturbation_loads(&model, force).unwrap() {
        problem.set_dead_load(dof, f).unwrap();
    }
    let mut u = vec![0.0; problem.assembler().n()];
    let mut solver = newton.solver.build();
    solver.analyze(&problem.pattern()).unwrap();
    let mut k = nonlin3d::solver::SymmetricMatrix::zeros(problem.pattern());
    let r = solve_increment(&mut problem, &mut u, 0.0, &newton, solver.as_mut(), &mut k).unwrap();
    assert!(r.converged());
    let (centre, _) = deflections(&model, &u);
    let (h, l, w) = dims(&scene);
    assert!(
        (centre / (0.25 * h) - 1.0).abs() < 0.15,
        "w/h = {}",
        centre / h
    );
    // … and it is P/2 = 2·E_ps·W·h⁴/ℓ³ on the half model.
    let expected = 2.0 * plane_strain_modulus(&scene) * w * h.powi(4) / l.powi(3);
    assert!(
        (force / expected - 1.0).abs() < 1e-9,
        "{force} vs {expected}"
    );
}

/// Without a force the `center_top` set is not needed, by the pipeline or the deck; with one,
/// its absence is an error that names it.
#[test]
fn no_force_needs_no_centre_set() {
    let mut scene = Scene::from_toml(SCENE).unwrap();
    scene.loads.perturbation_n = Some(0.0);
    let mut model = build_model(&scene).unwrap();
    model.mesh.node_sets.remove("center_top");
    assert!(perturbation_loads(&model, 0.0).unwrap().is_empty());
    let e = perturbation_loads(&model, 0.1).unwrap_err().to_string();
    assert!(e.contains("center_top"), "{e}");
    let deck = nonlin3d::export::deck_of(&scene, &model).unwrap();
    assert!(!deck.contains("*CLOAD"));
}

/// w of `node` (1-based) at the ends of the steps (times 1, 2, …) in a CalculiX .dat file.
fn ccx_w(dat: &str, node: usize) -> Vec<(f64, f64)> {
    let mut out = Vec::new();
    for block in dat.split("displacements").skip(1) {
        let mut lines = block.lines();
        let time = lines
            .next()
            .and_then(|h| h.split_whitespace().last())
            .and_then(|t| t.parse::<f64>().ok())
            .unwrap_or(f64::NAN);
        for line in lines {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.len() == 4 && f[0].parse::<usize>().ok() == Some(node) {
                out.push((time, f[3].parse::<f64>().unwrap_or(f64::NAN)));
                break;
            }
        }
    }
    out
}

/// `nonlin3d export` of a two-level copy of the scene (ε = −0.001, −0.002): the perturbation
/// as a CLOAD on the `center_top` node; CalculiX runs the deck and, at the end of each level's
/// second step (force removed), has the sublaminate on the same buckled branch as
/// `nonlin3d run` of the same copy (measured: equal to the 5 digits results.json is compared
/// at; asserted 0.5 %, as for the embedded scene in tests/calculix.rs).
#[test]
fn export_writes_a_deck_calculix_runs_to_the_same_branch() {
    let dir = tmp("export");
    let text = SCENE.replace(
        "strains = [-0.0005, -0.00052, -0.00054, -0.00056, -0.00058, -0.0006,\n           \
         -0.001, -0.002, -0.003, -0.004, -0.005]",
        "strains = [-0.001, -0.002]",
    );
    assert_ne!(text, SCENE, "the scene's strains line changed");
    let path = dir.join("two.toml");
    std::fs::write(&path, &text).unwrap();
    let inp = dir.join("tw.inp");
    let o = Command::new(env!("CARGO_BIN_EXE_nonlin3d"))
        .args(["export"])
        .arg(&path)
        .arg("--inp")
        .arg(&inp)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let deck = std::fs::read_to_string(&inp).unwrap();
    assert_eq!(deck.matches("*STEP, NLGEOM").count(), 4);
    let top: usize = deck
        .split("*NSET, NSET=center_top\n")
        .nth(1)
        .and_then(|s| s.lines().next())
        .and_then(|l| l.trim().trim_end_matches(',').parse().ok())
        .unwrap();
    assert!(
        deck.contains(&format!("*CLOAD\n{top}, 3,")),
        "no CLOAD on node {top}"
    );
    if !common::ccx::available() {
        return;
    }
    let dat = common::ccx::run(&dir, "tw");
    let w = ccx_w(&dat, top);
    let json = run_cli(&path, &dir.join("out"));
    for (k, level) in json["levels"].as_array().unwrap().iter().enumerate() {
        let ours = level["centre_deflection_mm"].as_f64().unwrap();
        let end = (2 * k + 2) as f64;
        let theirs = w
            .iter()
            .find(|(t, _)| (t - end).abs() < 1e-9)
            .map(|p| p.1 * 1e3)
            .unwrap_or_else(|| panic!("no CalculiX output at time {end}"));
        assert!(
            (theirs / ours - 1.0).abs() < 5e-3,
            "level {k}: CalculiX w = {theirs} mm, nonlin3d {ours} mm"
        );
    }
}

/// The committed scene against the closed form of the straight-sided blister (Hutchinson & Suo
/// 1992, `nonlin3d_testkit::blister`): its mode-mix angle ψ and G from beam theory, with the
/// run's own buckling strain ε_b (the bracket's midpoint) and the thin-film ω = 52.07°, at the
/// levels from 2ε_b to the family's strain −0.004 (below ε/ε_b = 1 + 4 tan²ω = 7.59, where the
/// closed form's K_I reaches 0 and the faces start to touch at the tip).
///
/// ψ of the model from its VCCT split, ψ = −atan(√(G_II/G_I)) (one material across the
/// delamination plane: no oscillatory index, G_I ∝ K_I², G_II ∝ K_II²). Allowance, 5°:
/// - discretisation: 1.5° (at −0.004, where G_I/G_T = 0.2 % is the mesh-sensitive part, the
///   family of examples/studies/through_width.toml gives ψ = −88.2, −86.95, −86.46° on its 16-,
///   32- and 64-element members and −85.9° with G_I extrapolated: the scene's −87.24° is 1.3°
///   from that; at −0.002 and −0.003 a mesh with 2.8× the DOF moves ψ by ≤ 0.3°,
///   docs/VALIDATION.md);
/// - the clamp: ε_b from the run (0.94 ε_c, the base's root rotation) instead of the rigid
///   clamp's ε_c moves the closed form's ψ by 1.0–1.5° at these levels;
/// - ω: 52.07° is the isotropic thin film's; the base here is finite (η = h/H = 0.1) and the
///   quasi-isotropic laminate is orthotropic in the x–z plane (E_z/E_x ≈ 0.2), each of which
///   moves ω; dψ/dω ≈ 1 at these ξ, and 2° of ω is allowed.
///
/// G: the thin-film G with the same ε_b, from below: the compliant base only adds (measured
/// +7.3 … +8.4 %), asserted within [0, +15 %] as in `check_sweep`. A one-layer sublaminate
/// (tw-16-sub1 of examples/studies/through_width.toml, G_I/G_T = 1.5 % at −0.004) would be
/// 6.3° off and fail; measured here: +2.1 … +2.8° (docs/VALIDATION.md).
#[test]
fn mode_mix_and_g_follow_the_hutchinson_suo_blister() {
    use nonlin3d_testkit::blister::{OMEGA_THIN_FILM_DEG, straight_blister};
    let scene = Scene::from_toml(SCENE).unwrap();
    let results = Analysis::new(scene.clone()).unwrap().run().unwrap();
    let levels = levels_of_results(&results);
    let (below, above, k) = bracket(&levels);
    let eps_b = 0.5 * (below + above);
    let (h, _, _) = dims(&scene);
    let e_ps = plane_strain_modulus(&scene);
    let closing = 1.0 + 4.0 * OMEGA_THIN_FILM_DEG.to_radians().tan().powi(2);
    let mut compared = 0;
    for l in levels[k..]
        .iter()
        .filter(|l| l.strain >= 2.0 * eps_b && l.strain < closing * eps_b)
    {
        let b = straight_blister(e_ps, h, l.strain, eps_b, OMEGA_THIN_FILM_DEG);
        assert!(
            l.g_i > 0.0,
            "G_I = {} at {}: the faces open",
            l.g_i,
            l.strain
        );
        let psi = -(l.g_ii / l.g_i).sqrt().atan();
        let off = (psi - b.psi).to_degrees();
        eprintln!(
            "ε = {:.4}: ψ = {:.2}° (closed form {:.2}°, Δ {off:+.2}°), G_II/G_T = {:.4} ({:.4}), \
             G_T = {:.2} J/m² ({:.2}, ratio {:.3})",
            l.strain,
            psi.to_degrees(),
            b.psi.to_degrees(),
            l.g_ii / l.g_t,
            b.mode_ii_share(),
            l.g_t,
            b.g,
            l.g_t / b.g
        );
        assert!(off.abs() < 5.0, "ψ = {psi} vs {} at {}", b.psi, l.strain);
        assert!(
            l.g_t >= b.g && l.g_t <= 1.15 * b.g,
            "G_T = {} vs {} at {}",
            l.g_t,
            b.g,
            l.strain
        );
        compared += 1;
    }
    // −0.002, −0.003, −0.004 (ε_b ≈ 5.5e-4).
    assert_eq!(compared, 3);
}
