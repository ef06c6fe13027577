//! Arc-length path following through limit points against closed forms: the shallow two-bar
//! (von Mises) truss, its snap-through and, with a soft spring in series, its snap-back.
//!
//! The truss: two bars of axial stiffness EA from supports at (±L, 0) to an apex at height h,
//! Green strain ε = (ℓ² − ℓ₀²)/(2ℓ₀²) and N = EA·ε (exact kinematics of a pin-jointed bar),
//! apex deflection w (down). Energy 2·½EA·ℓ₀·ε², so the vertical force is
//!
//! P(w) = EA·w·(h − w)·(2h − w)/ℓ₀³,  P′(w) = EA·(2h² − 6hw + 3w²)/ℓ₀³,
//!
//! with limit points at w = h(1 ∓ 1/√3), P = ±P_max, P_max = 2EA·h³/(3√3·ℓ₀³). With a spring
//! k between the apex and the load point (deflection v): P = k(v − w), so v = w + P(w)/k, and
//! v snaps back where dv/dw = 1 + P′(w)/k < 0, i.e. for k < EA·h²/ℓ₀³ (P′(h) = −EA·h²/ℓ₀³).

use approx::assert_relative_eq;
use nonlin3d_newton::{
    ArcConstraint, ArcLength, ArcStop, NewtonSettings, NonlinearProblem, SignRule, Stepping,
    follow_arc_length, follow_path_from,
};

mod common;
use common::*;

/// Snap-through: every converged point lies on the closed form, the path climbs to the first
/// limit point, falls through λ = −1 (the second, by the antisymmetry P(h + x) = −P(h − x)),
/// and ends past w = 2.5h; the tangent's inertia is 0, 1, 0 on the three branches and the
/// load factor turns exactly twice. The limit load from a parabola through the three points
/// around the computed maximum matches P_max within the interpolation error of a cubic by a
/// parabola: |P‴|/6·max|Π(w − wᵢ)| ≤ |P‴|/6·2Δ³ = 2EA·Δ³/ℓ₀³ (P‴ = 6EA/ℓ₀³, Δ the largest of
/// the two spacings).
#[test]
fn the_truss_snaps_through_both_limit_points_on_the_closed_form() {
    let (states, increments, report) = run(None, &to_far_side(SignRule::Inertia));
    assert_eq!(report.stop, ArcStop::Displacement);
    for (lambda, u) in &states {
        assert!(
            (lambda - force(u[0]) / p_max()).abs() <= ON_CURVE,
            "λ = {lambda} at w = {}",
            u[0]
        );
    }
    let w_last = states.last().unwrap().1[0];
    assert!(w_last >= 2.5 * H, "{w_last}");
    // The two limit points are passed: λ rises to ~1 (on w < h), falls to ~−1.
    let (imax, _) = states
        .iter()
        .enumerate()
        .filter(|s| s.1.1[0] < H)
        .max_by(|a, b| a.1.0.total_cmp(&b.1.0))
        .unwrap();
    let three: Vec<(f64, f64)> = (imax - 1..=imax + 1)
        .map(|i| (states[i].1[0], states[i].0))
        .collect();
    let (w_star, lambda_star) = vertex(&three);
    let spacing = (three[1].0 - three[0].0).max(three[2].0 - three[1].0);
    let bound = 2.0 * EA * spacing.powi(3) / l0().powi(3) / p_max();
    eprintln!(
        "limit point: λ* = {lambda_star:.9} (closed form 1), w* = {w_star:.9} m (closed form \
         {:.9} m), spacing {spacing:.4} m, bound {bound:.2e}; {} increments",
        H * (1.0 - 1.0 / 3f64.sqrt()),
        increments.len()
    );
    assert!((lambda_star - 1.0).abs() <= bound, "{lambda_star}");
    let min = states.iter().map(|s| s.0).fold(f64::INFINITY, f64::min);
    assert!(min < -0.9, "{min}");
    // Inertia by branch, and two turns of λ.
    let pivots: Vec<usize> = increments.iter().map(|i| i.negative_pivots).collect();
    let changes = pivots.windows(2).filter(|p| p[0] != p[1]).count();
    assert_eq!(changes, 2, "{pivots:?}");
    assert!(pivots.contains(&1));
    let turns = increments
        .windows(2)
        .filter(|p| p[0].delta_lambda.signum() != p[1].delta_lambda.signum())
        .count();
    assert_eq!(turns, 2);
    // The two sign rules agree on this path.
    assert!(increments.iter().all(|i| i.rules_agree));
    for i in &increments {
        eprintln!(
            "  inc {:3} λ = {:+.6} Δλ = {:+.5} s = {:.4} iterations {} cutbacks {} pivots {}",
            i.index, i.lambda, i.delta_lambda, i.arc, i.iterations, i.cutbacks, i.negative_pivots
        );
    }
}

/// The vertex (x*, y*) of the parabola through three points.
fn vertex(p: &[(f64, f64)]) -> (f64, f64) {
    let [(x0, y0), (x1, y1), (x2, y2)] = [p[0], p[1], p[2]];
    let d01 = (y1 - y0) / (x1 - x0);
    let d12 = (y2 - y1) / (x2 - x1);
    let a = (d12 - d01) / (x2 - x0);
    let b = d01 - a * (x0 + x1);
    let c = y0 - a * x0 * x0 - b * x0;
    let x = -b / (2.0 * a);
    (x, a * x * x + b * x + c)
}

/// Load control and arc length agree before the limit point: at the load factors the arc
/// length converged to below λ = 0.9, load control (to those targets) finds the same w. Both
/// residuals are within 1e-8·F (F ≤ P_max), so |w_arc − w_load| ≤ 2e-8·P_max/P′(w) by the mean
/// value theorem with P′ ≥ its value at λ = 0.9 on the way; ×2 for the variation of P′
/// between the two. Load control cannot follow the limit: asked for λ = 1.05 it jumps to the
/// far stable branch (w > 2h), past the unstable part the arc length traces (h/2 < w < 2h).
#[test]
fn load_control_and_arc_length_agree_before_the_limit_point() {
    let (states, _, _) = run(None, &to_far_side(SignRule::Inertia));
    let before: Vec<&(f64, Vec<f64>)> = states.iter().take_while(|s| s.0 < 0.9).collect();
    assert!(before.len() >= 3);
    let targets: Vec<f64> = before.iter().map(|s| s.0).collect();
    let mut problem = Truss { spring: None };
    let mut u = vec![0.0];
    let path = follow_path_from(
        &mut problem,
        &mut u,
        0.0,
        &targets,
        &NewtonSettings::default(),
        &Stepping::default(),
    )
    .unwrap();
    for ((lambda, arc_u), (target, load_u)) in before.iter().zip(&path.states) {
        assert_eq!(lambda, target);
        let bound = 4e-8 * p_max() / stiffness(load_u[0]);
        assert!(
            (arc_u[0] - load_u[0]).abs() <= bound,
            "λ = {lambda}: {} against {}",
            arc_u[0],
            load_u[0]
        );
    }
    let mut u = vec![0.0];
    follow_path_from(
        &mut problem,
        &mut u,
        0.0,
        &[1.05],
        &NewtonSettings::default(),
        &Stepping::default(),
    )
    .unwrap();
    assert!(u[0] > 2.0 * H, "{}", u[0]);
    assert!(
        states
            .iter()
            .any(|s| s.1[0] > 0.5 * H && s.1[0] < 2.0 * H && s.0 < 1.0)
    );
}

/// Snap-back: with k = EA·h²/(2ℓ₀³) the load point's deflection v = w + P(w)/k turns back
/// (dv/dw = 1 + P′/k = −1 at w = h). Every converged point lies on the closed form (λ on P(w)
/// within [`ON_CURVE`], and v = w + λ·P_max/k, from the spring's residual row: |Δv| ≤
/// 1e-8·F/k), v decreases over some increments while the path goes on, and both sign rules
/// follow it to w = 2.5h with the same number of limit points (four turns of v or λ).
#[test]
fn the_truss_with_a_soft_spring_snaps_back_on_the_closed_form() {
    let k = soft().unwrap();
    for sign in [SignRule::Inertia, SignRule::Direction] {
        let (states, increments, report) = run(soft(), &to_far_side(sign));
        assert_eq!(report.stop, ArcStop::Displacement, "{sign:?}");
        for (lambda, u) in &states {
            assert!((lambda - force(u[0]) / p_max()).abs() <= ON_CURVE);
            let v = u[0] + lambda * p_max() / k;
            assert!((u[1] - v).abs() <= 1e-8 * 2.0 * p_max() / k, "{} {v}", u[1]);
        }
        let back = states.windows(2).filter(|p| p[1].1[1] < p[0].1[1]).count();
        assert!(back >= 2, "{sign:?}: v never decreased");
        let lambda_max = states
            .iter()
            .filter(|s| s.1[0] < H)
            .map(|s| s.0)
            .fold(f64::MIN, f64::max);
        assert!(lambda_max > 0.95 && lambda_max <= 1.0 + ON_CURVE);
        eprintln!(
            "{sign:?}: {} increments, {} with v decreasing, largest λ {lambda_max:.6}, \
             iterations {:?}",
            increments.len(),
            back,
            increments.iter().map(|i| i.iterations).collect::<Vec<_>>()
        );
    }
}

/// The spherical constraint follows the same curve; its first increment meets the constraint
/// (Δw/ℓ)² + ψ²Δλ² = s₀², s₀ = initial·√(1 + ψ²), to rounding (the corrector solves it
/// exactly each iteration; ℓ = |dw/dλ| at rest = P_max/P′(0)).
#[test]
fn the_spherical_constraint_follows_the_same_curve() {
    let arc = ArcLength {
        constraint: ArcConstraint::Spherical { psi: 1.0 },
        ..to_far_side(SignRule::Inertia)
    };
    let (states, increments, report) = run(None, &arc);
    assert_eq!(report.stop, ArcStop::Displacement);
    let first = &increments[0];
    let dw = states[0].1[0] / (p_max() / stiffness(0.0));
    assert_relative_eq!(report.scale, p_max() / stiffness(0.0), max_relative = 1e-12);
    assert_relative_eq!(
        dw * dw + first.delta_lambda.powi(2),
        0.02,
        max_relative = 1e-12
    );
    assert_relative_eq!(first.arc, 0.1 * 2f64.sqrt(), max_relative = 1e-15);
    for (lambda, u) in &states {
        assert!((lambda - force(u[0]) / p_max()).abs() <= ON_CURVE);
    }
}

/// The arc length adapts to the iterations: after an increment of I iterations,
/// s ← s·min(√(I_d/max(I, 1)), growth), within [min, max]; a failed attempt (here: more than
/// 2 iterations needed) is cut back and counted; the maximum load factor stops the path.
#[test]
fn the_arc_length_adapts_and_cuts_back() {
    let arc = ArcLength {
        initial: 0.5,
        max: 0.6,
        target_iterations: 3,
        max_lpf: Some(0.95),
        ..ArcLength::default()
    };
    let mut problem = Truss { spring: soft() };
    let mut u = vec![0.0; 2];
    let settings = NewtonSettings {
        max_iterations: 2,
        ..NewtonSettings::default()
    };
    let report = follow_arc_length(
        &mut problem,
        &mut u,
        0.0,
        &settings,
        &arc,
        &mut |_, _, _| false,
    )
    .unwrap();
    assert_eq!(report.stop, ArcStop::MaxLpf);
    assert!(report.increments.last().unwrap().lambda >= 0.95);
    let incs = &report.increments;
    for p in incs.windows(2) {
        let (a, b) = (&p[0], &p[1]);
        let ratio = (3.0 / a.iterations.max(1) as f64).sqrt().min(arc.growth);
        let expected =
            (a.arc * ratio).clamp(arc.min, arc.max) * arc.cutback.powi(b.cutbacks as i32);
        assert_relative_eq!(b.arc, expected, max_relative = 1e-12);
    }
    assert!(incs.iter().any(|i| i.cutbacks > 0), "no cutback: {incs:?}");
}

/// An arc that cannot converge stops with an error naming the increment and the reason.
#[test]
fn a_hopeless_arc_stops_with_a_located_error() {
    let arc = ArcLength {
        initial: 0.5,
        min: 0.3,
        ..ArcLength::default()
    };
    let settings = NewtonSettings {
        max_iterations: 1,
        ..NewtonSettings::default()
    };
    let mut problem = Truss { spring: soft() };
    let mut u = vec![0.0; 2];
    let e = follow_arc_length(
        &mut problem,
        &mut u,
        0.0,
        &settings,
        &arc,
        &mut |_, _, _| false,
    )
    .unwrap_err();
    let text = e.to_string();
    assert!(
        text.starts_with("arc-length increment 1 from λ = 0: no convergence after 1 cutbacks"),
        "{text}"
    );
    assert!(
        text.contains("no convergence within 1 iterations"),
        "{text}"
    );
}

/// A steel bar 4×1×1 mm of 4 Hex8 (nonlinear kinematics) fixed on x = 0 and pulled on
/// x = 4 mm by a prescribed u_x = λ·4 µm: the arc length (ℓ and q from the prescribed values,
/// [`NonlinearProblem::coupling_force`]) and load control to the same load factors agree.
/// Both meet ‖r‖∞ ≤ 1e-8·F with F the largest reaction; the free DOFs then differ by at most
/// ~1e-8·F/k_min, and F/k_min is of the order of the largest displacement (4 µm) times the
/// stiffness ratio of the bar (≤ 1e2 for 4 elements): 1e-8·4e-6·1e2 = 4e-12 m. The first
/// increment's Δλ is the initial 0.25 (the corrector keeps the arc, λ moves with the path's
/// curvature).
#[test]
fn arc_length_follows_prescribed_displacements_as_load_control_does() {
    use nonlin3d_assembly::{Assembler, Constraints};
    use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
    use nonlin3d_laminate::{ShearCoupling, materials};
    use nonlin3d_mesh::{BoxParams, structured_box};
    use nonlin3d_newton::StructuralProblem;
    let problem = || {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [4, 1, 1],
            [4e-3, 1e-3, 1e-3],
        ))
        .unwrap();
        let steel = materials::steel().stiffness().unwrap();
        let assembler = Assembler::new(
            &mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap();
        let mut c = Constraints::new(assembler.n());
        for r in 0..3 {
            c.fix_nodes(&mesh.node_sets["x0"], r).unwrap();
        }
        for &n in &mesh.node_sets["x1"] {
            c.prescribe(3 * n, 4e-6).unwrap();
        }
        StructuralProblem::new(assembler, c).unwrap()
    };
    let mut p = problem();
    let mut u = vec![0.0; p.n()];
    let mut states = Vec::new();
    let arc = ArcLength {
        initial: 0.25,
        max_lpf: Some(1.0),
        ..ArcLength::default()
    };
    let report = follow_arc_length(
        &mut p,
        &mut u,
        0.0,
        &NewtonSettings::default(),
        &arc,
        &mut |i, u, _| {
            states.push((i.lambda, u.to_vec()));
            false
        },
    )
    .unwrap();
    assert_eq!(report.stop, ArcStop::MaxLpf);
    // ℓ = ‖du/dλ‖ counts the prescribed rates too: at least ‖ū_c‖ = 4 µm·√4 = 8 µm (the free
    // DOFs alone, x-rates of 1, 2, 3 µm on 4 nodes each plus Poisson's, give 7.5–7.6 µm).
    assert!(report.scale > 8e-6 * (1.0 + 1e-9), "{}", report.scale);
    // The corrector moves the first λ off the predictor's 0.25 by the path's curvature, of
    // the order of the strain (1e-3).
    assert_relative_eq!(states[0].0, 0.25, max_relative = 1e-3);
    let targets: Vec<f64> = states.iter().map(|s| s.0).collect();
    let mut q = problem();
    let mut v = vec![0.0; q.n()];
    let path = follow_path_from(
        &mut q,
        &mut v,
        0.0,
        &targets,
        &NewtonSettings::default(),
        &Stepping::default(),
    )
    .unwrap();
    for ((l, a), (_, b)) in states.iter().zip(&path.states) {
        let diff = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        assert!(diff <= 4e-12, "λ = {l}: {diff:e} m");
    }
}

/// A level above the limit load (λ = 1.05 > 1) by arc length: the path climbs to the limit
/// point, turns, comes back through the unstable branch and the far stable one up to λ = 1.05,
/// and Newton lands there: on the closed form (|1.05 − P(w)/P_max| ≤ [`ON_CURVE`]), on the far
/// branch (w > 2h, where P(w) = 1.05·P_max has its only stable root), with no negative pivot;
/// the increments went down in λ on the way (the two limit points were passed).
#[test]
fn a_level_past_the_limit_point_is_reached_through_it() {
    let mut problem = Truss { spring: None };
    let mut u = vec![0.0];
    let mut session = nonlin3d_newton::PathSolver::new(&problem, Default::default()).unwrap();
    let level = nonlin3d_newton::solve_level_arc(
        &mut problem,
        &mut u,
        0.0,
        1.05,
        &[],
        &NewtonSettings::default(),
        &ArcLength {
            initial: 0.1,
            max: 0.2,
            max_increments: 200,
            ..ArcLength::default()
        },
        &Stepping::default(),
        &mut session,
    )
    .unwrap();
    assert!((1.05 - force(u[0]) / p_max()).abs() <= ON_CURVE);
    assert!(u[0] > 2.0 * H, "{}", u[0]);
    assert_eq!(level.negative_pivots, Some(0));
    let lambdas: Vec<f64> = level.attempts.iter().map(|a| a.lambda).collect();
    assert!(lambdas.windows(2).any(|w| w[1] < w[0]), "{lambdas:?}");
    assert!(lambdas.iter().any(|&l| l < -0.9));
}
