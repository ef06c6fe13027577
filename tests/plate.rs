//! Thesis §4.1: the transversely loaded plate. The thesis's own model: a circular debond of
//! radius a = 15 mm under a sublaminate h = 0.4 mm thick, base H = 4 mm, quarter model W = 50 mm,
//! steel (E = 207 GPa, ν = 0.3), a central transverse load P at (0, 0, H + h) (P/4 on the quarter
//! model). The debonded sublaminate is a plate clamped by the base at r = a; its central
//! deflection against eq. 4.1.1, w₀/h + 0.443 (w₀/h)³ = 0.217 P a²/(E h⁴) (ref. 43: exact in
//! the linear range, approximate for large deflections).

mod common;

use common::structural_problem;
use nonlin3d::element::IntegrationRule;
use nonlin3d::element::Kinematics;
use nonlin3d::laminate::materials;
use nonlin3d::mesh::{EmbeddedParams, embedded_delamination_with_front};
use nonlin3d::newton::{NewtonSettings, Stepping, follow_path};
use nonlin3d::vcct::{cells_above, release_rates};

/// w₀/h from eq. 4.1.1 for a given load (Newton on the cubic).
fn closed_form(load: f64, e: f64, h: f64, a: f64) -> f64 {
    let k = 0.217 * load * a * a / (e * h.powi(4));
    let mut x = k;
    for _ in 0..50 {
        x -= (x + 0.443 * x.powi(3) - k) / (1.0 + 3.0 * 0.443 * x * x);
    }
    x
}

#[test]
fn clamped_plate_centre_deflection_follows_eq_4_1_1() {
    let p = EmbeddedParams::thesis_reference();
    let (a, h) = (p.a, p.h);
    let (mesh, front) = embedded_delamination_with_front(&p).unwrap();
    let steel = materials::steel();
    let e = steel.e11;
    let mut problem = structural_problem(
        &mesh,
        steel.stiffness().unwrap(),
        IntegrationRule::Gauss2,
        &[("x0", 0), ("y0", 1), ("z0", 2)],
    );
    // The load needed for w₀/h = 2 by eq. 4.1.1; a quarter of it on the quarter model.
    let p_max = (2.0 + 0.443 * 8.0) * e * h.powi(4) / (0.217 * a * a);
    let top = mesh.node_sets["center_top"][0];
    problem.add_load(3 * top + 2, 0.25 * p_max).unwrap();
    // The plate's mid-plane deflection is read at its lower face (the upper crack face node on
    // the axis), free of the local indentation under the point load.
    let bottom = mesh.node_sets["crack_upper"]
        .iter()
        .copied()
        .find(|&n| mesh.nodes[n][0] == 0.0 && mesh.nodes[n][1] == 0.0)
        .unwrap();
    let mut u = vec![0.0; problem.assembler().n()];
    let ratios = [0.1, 0.25, 0.5, 1.0, 1.5, 2.0];
    let targets: Vec<f64> = ratios
        .iter()
        .map(|&r| (r + 0.443 * r * r * r) * e * h.powi(4) / (0.217 * a * a) / p_max)
        .collect();
    let path = follow_path(
        &mut problem,
        &mut u,
        &targets,
        &NewtonSettings::default(),
        &Stepping {
            initial: 0.05,
            max: 0.25,
            ..Stepping::default()
        },
    )
    .unwrap();
    // Eq. 4.1.4: G_T of the clamped plate from its centre deflection.
    let g_closed = |w0: f64| {
        e * h * w0 * w0 / (2.0 * std::f64::consts::PI * a.powi(4))
            * (h * h / 0.217 + 1.02 * w0 * w0)
    };
    let above = cells_above(&front);
    eprintln!(
        "| P (N) | w₀/h eq. 4.1.1 | w₀/h nonlin3d | difference | G_T eq. 4.1.4 at w₀ (J/m²) | G_T VCCT mean | difference | spread along front |"
    );
    for (&(lambda, ref state), &expected) in path.states.iter().zip(&ratios) {
        let load = lambda * p_max;
        let w = state[3 * bottom + 2] / h;
        assert!((closed_form(load, e, h, a) - expected).abs() < 1e-9);
        let diff = w / expected - 1.0;
        // VCCT with the nonlinear strain–displacement relations (the plate is a nonlinear
        // region, §2.8); the load is axisymmetric, so G_T is uniform along the front.
        let f = problem
            .assembler()
            .partial_internal(&above, state, Kinematics::Nonlinear)
            .unwrap();
        let r = release_rates(&front, &mesh.nodes, state, &f).unwrap();
        let g = r.iter().map(|x| x.g_t).sum::<f64>() / r.len() as f64;
        let (lo, hi) = r.iter().fold((f64::MAX, f64::MIN), |m, x| {
            (m.0.min(x.g_t), m.1.max(x.g_t))
        });
        let gc = g_closed(w * h);
        let gdiff = g / gc - 1.0;
        eprintln!(
            "| {load:.1} | {expected:.3} | {w:.4} | {:+.2} % | {gc:.4} | {g:.4} | {:+.2} % | {:.2} % |",
            100.0 * diff,
            100.0 * gdiff,
            100.0 * (hi - lo) / g
        );
        // Eq. 4.1.4 within 5 % for w₀/h ≤ 1 (the bound; the closed form is an
        // approximate plate solution, ref. 43).
        if expected <= 1.0 {
            assert!(gdiff.abs() < 0.05, "G_T at w₀/h = {w:.3}: {g} vs {gc}");
        }
        assert!(r.iter().all(|x| x.g_t.is_finite() && x.open()));
        // 2 % where eq. 4.1.1 is exact or nearly (w₀/h ≤ 0.5), 6 % beyond (the closed form's
        // own error grows with w₀/h; the thesis found 10 % at its highest load).
        let tol = if expected <= 0.5 { 0.02 } else { 0.06 };
        assert!(
            diff.abs() < tol,
            "w₀/h = {expected}: nonlin3d {w:.4}, difference {:.2} %",
            100.0 * diff
        );
    }
}
