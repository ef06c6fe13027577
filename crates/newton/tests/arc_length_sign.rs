//! The arc length's sign rule (which way the predictor goes) through a bifurcation, where
//! the tangent's inertia changes with no limit point, and after an increment that converged
//! backwards along the truss of tests/arc_length.rs.

use nonlin3d_newton::{
    ArcLength, ArcStop, NewtonError, NewtonSettings, NonlinearProblem, SignRule, follow_arc_length,
};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

mod common;
use common::*;

/// A symmetric bifurcation on two DOFs: Π = ½u₁² + ½u₂² − ½u₁u₂² + ¼u₂⁴ − λu₁, so
/// r = (u₁ − ½u₂² − λ, u₂ − u₁u₂ + u₂³) and K_T = [[1, −u₂], [−u₂, 1 − u₁ + 3u₂²]]. The trivial
/// path u = (λ, 0) loses stability at λ = 1 (K₂₂ = 1 − λ), where the branch u₂² = u₁ − 1
/// bifurcates; the reference load q = (1, 0) is orthogonal to the mode (0, 1), so δu_t = (1, 0)
/// is continuous through it and λ goes on rising along the trivial path.
struct Fork;

impl NonlinearProblem for Fork {
    fn n(&self) -> usize {
        2
    }
    fn pattern(&self) -> Arc<SymmetricPattern> {
        Arc::new(SymmetricPattern::from_dof_lists(2, &[vec![0, 1]]).unwrap())
    }
    fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        r[0] = u[0] - 0.5 * u[1] * u[1] - lambda;
        r[1] = u[1] - u[0] * u[1] + u[1].powi(3);
        if let Some(t) = tangent {
            t.set_zero();
            t.add(0, 0, 1.0).unwrap();
            t.add(0, 1, -u[1]).unwrap();
            t.add(1, 1, 1.0 - u[0] + 3.0 * u[1] * u[1]).unwrap();
        }
        Ok(lambda.abs().max(1.0))
    }
}

/// Across the bifurcation of [`Fork`] (arcs 0.15 to 0.3, stop at λ = 2): det K_T's rule
/// turns back at the first increment past λ = 1 (one negative pivot, λ still rising) and
/// oscillates about the bifurcation until the increments run out; the direction rule and
/// the combined rule go on along the trivial path to λ = 2 in a few increments (7 at most
/// 0.3 each from 0.15, doubling), every point on it (u₁ = λ, u₂ = 0 to the residual test).
#[test]
fn the_sign_rule_goes_on_through_a_bifurcation() {
    let run = |sign| {
        let arc = ArcLength {
            initial: 0.15,
            max: 0.3,
            max_lpf: Some(2.0),
            max_increments: 60,
            sign,
            ..ArcLength::default()
        };
        let mut u = vec![0.0; 2];
        let mut states = Vec::new();
        let report = follow_arc_length(
            &mut Fork,
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
        (report, states)
    };
    let (inertia, states) = run(SignRule::Inertia);
    assert_eq!(inertia.stop, ArcStop::Increments);
    let top = states.iter().map(|s| s.0).fold(f64::MIN, f64::max);
    assert!(top < 1.5, "det K_T's rule reached λ = {top}");
    for sign in [SignRule::Direction, SignRule::Combined] {
        let (report, states) = run(sign);
        assert_eq!(report.stop, ArcStop::MaxLpf, "{sign:?}");
        assert!(
            report.increments.len() <= 10,
            "{sign:?}: {}",
            report.increments.len()
        );
        assert!(report.increments.iter().any(|i| i.negative_pivots == 1));
        for (lambda, u) in &states {
            // ‖r‖∞ ≤ 1e-8·max(|λ|, 1) and u₂ stays 0 by symmetry.
            assert!(
                (u[0] - lambda).abs() <= 1e-8 * lambda.max(1.0),
                "{lambda} {u:?}"
            );
            assert_eq!(u[1], 0.0);
        }
    }
}

/// A sharper snap-back, k = EA·h²/(10ℓ₀³) (dv/dw from 1 + P′(0)/k = 21 down to −9), with
/// arcs up to 0.5: one increment past the first limit point converges far back along the path,
/// with Δλ against its predictor (λ −0.82 → −0.79, w from 1.36h to −0.13h: the cylinder meets
/// the path again there). The direction rule takes that increment's orientation and descends
/// the w < 0 branch for good (λ → −∞, the monitor never reached); det K_T's rule, whose
/// orientation sign(det K_T)·sign(dλ/ds) does not depend on one increment, and the combined
/// rule (which keeps it over an increment whose Δλ turned against its predictor) come back up
/// and reach w = 2.5h, every point on the closed form.
#[test]
fn the_sign_rule_survives_an_increment_converged_backwards() {
    let spring = Some(EA * H * H / (10.0 * l0().powi(3)));
    let arc = |sign| ArcLength {
        max: 0.5,
        ..to_far_side(sign)
    };
    let (_, _, direction) = run(spring, &arc(SignRule::Direction));
    assert_eq!(direction.stop, ArcStop::Increments);
    for sign in [SignRule::Inertia, SignRule::Combined] {
        let (states, increments, report) = run(spring, &arc(sign));
        assert_eq!(report.stop, ArcStop::Displacement, "{sign:?}");
        assert!(increments.len() < 100, "{sign:?}: {}", increments.len());
        for (lambda, u) in &states {
            assert!(
                (lambda - force(u[0]) / p_max()).abs() <= ON_CURVE,
                "{sign:?}"
            );
        }
    }
}
