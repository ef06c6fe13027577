//! The line search along a Newton direction (thesis §2.1's iteration, damped): the full step
//! when it lowers ‖r‖∞; else, far from convergence, Crisfield's energy line search on the
//! slope of the potential energy along the step; then halving on ‖r‖∞.

use crate::vector::{dot, norm_inf};
use crate::{NewtonError, NewtonSettings, NonlinearProblem};
use nonlin3d_solver::SymmetricMatrix;

/// The energy line search's acceptance (Crisfield 1991, Vol. 1 §9.3.2; Abaqus's s_tol): a step
/// α is taken once the slope of the potential energy along the Newton direction has fallen to
/// |s(α)| ≤ `ENERGY_SLOPE`·|s(0)|.
const ENERGY_SLOPE: f64 = 0.5;

/// Trials of a line search (either kind).
const TRIALS: usize = 6;

/// The energy line search serves only while ‖r‖∞ is above this many times the tolerance: far
/// from the solution, where Newton's full step may overshoot. Near it Newton is quadratic and
/// a full step that does not lower ‖r‖∞ meets the residual's rounding, where duᵀ·r is rounding
/// too (a Hex20 cantilever converged to 1e-8 N: s(0) ≈ −3e-25 N·m, and full steps taken on
/// s(1) ≤ 0 never reached the tolerance where the backtracking did).
const ENERGY_ABOVE: f64 = 1e3;

/// The line search along the Newton direction `du` from `u` (residual `r` there, ‖r‖∞ =
/// `norm`, the attempt's `tolerance`): the full step when `settings.line_search` is off or it
/// lowers ‖r‖∞; otherwise
/// 1. on the potential energy ([`energy_search`]) while ‖r‖∞ > [`ENERGY_ABOVE`]·`tolerance`,
///    where `du` descends: r is the gradient of the energy Π (elastic solid, dead loads,
///    linear constraints), so s(α) = duᵀ·r(u + α·du) = dΠ/dα along the step, s(0) =
///    −rᵀK⁻¹r < 0 for a positive definite tangent;
/// 2. then on the residual: α = ½, ¼, … until ‖r(u + α·du)‖∞ < `norm` ([`TRIALS`] in all),
///    else the full step anyway (the residual of a buckling problem may rise before it falls).
///
/// The energy comes before the residual's backtracking because the residual's norm may rise
/// on the way to the minimum: removing the §3.2 perturbation just past the bifurcation, the
/// backtracking took α = 1/8 in 16 of 19 iterations, the energy full steps in 5
/// (docs/PERFORMANCE.md, "The companion chain started first, and the energy line search"). A full step that lowers the residual is
/// taken as before, so near a solution Newton stays quadratic. The accepted state and its
/// residual are left in `trial`, the tangent there in `k` when given. Returns α and the force
/// scale at the accepted state.
pub(crate) fn line_search(
    problem: &mut dyn NonlinearProblem,
    (u, du, r, lambda, norm): (&[f64], &[f64], &[f64], f64, f64),
    (settings, tolerance): (&NewtonSettings, f64),
    mut k: Option<&mut SymmetricMatrix>,
    (trial_u, trial_r): (&mut [f64], &mut [f64]),
) -> Result<(f64, f64), NewtonError> {
    step_to(trial_u, u, du, 1.0);
    let scale = problem.evaluate(trial_u, lambda, trial_r, k.as_deref_mut())?;
    let trial = norm_inf(trial_r);
    if !settings.line_search || (trial.is_finite() && trial < norm) {
        return Ok((1.0, scale));
    }
    if norm > ENERGY_ABOVE * tolerance {
        let full = (&mut *trial_u, &mut *trial_r);
        let at = (u, du, r, lambda);
        if let Some(found) = energy_search(problem, at, (k.as_deref_mut(), scale), full)? {
            return Ok(found);
        }
    }
    let mut alpha = 0.5;
    for _ in 1..TRIALS {
        step_to(trial_u, u, du, alpha);
        let scale = problem.evaluate(trial_u, lambda, trial_r, k.as_deref_mut())?;
        let trial = norm_inf(trial_r);
        if trial.is_finite() && trial < norm {
            return Ok((alpha, scale));
        }
        alpha *= 0.5;
    }
    // No reduction along the Newton direction: take the full step anyway and let the
    // iteration decide.
    step_to(trial_u, u, du, 1.0);
    let scale = problem.evaluate(trial_u, lambda, trial_r, k)?;
    Ok((1.0, scale))
}

/// u + α·du into `trial_u`.
fn step_to(trial_u: &mut [f64], u: &[f64], du: &[f64], alpha: f64) {
    for ((t, &x), &d) in trial_u.iter_mut().zip(u).zip(du) {
        *t = x + alpha * d;
    }
}

/// The energy line search (Crisfield 1991, Vol. 1 §9.3) after a full step that raised the
/// residual, its state and residual in `trial` (tangent in `k`, force scale `scale`): s(α) =
/// duᵀ·r(u + α·du), the slope of the potential energy along `du`. None when `du` does not
/// descend (s(0) ≥ 0) or no trial fits in [`TRIALS`]. The full step is taken when the energy
/// still falls at its end (s(1) ≤ 0) or |s(1)| ≤ [`ENERGY_SLOPE`]·|s(0)|; otherwise α is the
/// regula-falsi root of s between the last trials below and above it, kept within the inner
/// 10–90 % of that bracket (a non-finite residual counts as above), until |s(α)| ≤
/// [`ENERGY_SLOPE`]·|s(0)|; the tangent is then evaluated again there.
fn energy_search(
    problem: &mut dyn NonlinearProblem,
    (u, du, r, lambda): (&[f64], &[f64], &[f64], f64),
    (k, scale): (Option<&mut SymmetricMatrix>, f64),
    (trial_u, trial_r): (&mut [f64], &mut [f64]),
) -> Result<Option<(f64, f64)>, NewtonError> {
    let s0 = dot(du, r);
    // (A NaN slope does not descend either.)
    if s0.is_nan() || s0 >= 0.0 {
        return Ok(None);
    }
    let fits = |s: f64| s.abs() <= ENERGY_SLOPE * s0.abs();
    let finite = |s: f64, r: &[f64]| s.is_finite() && norm_inf(r).is_finite();
    let s = dot(du, trial_r);
    if finite(s, trial_r) && (s <= 0.0 || fits(s)) {
        return Ok(Some((1.0, scale)));
    }
    // The bracket: s(below) < 0 < s(above) (NaN: the residual there was not finite).
    let (mut below, mut s_below) = (0.0, s0);
    let (mut above, mut s_above) = (1.0, if finite(s, trial_r) { s } else { f64::NAN });
    for _ in 1..TRIALS {
        let width = above - below;
        let alpha = if s_above.is_nan() {
            below + 0.5 * width
        } else {
            below + width * s_below / (s_below - s_above)
        }
        .clamp(below + 0.1 * width, below + 0.9 * width);
        step_to(trial_u, u, du, alpha);
        let scale = problem.evaluate(trial_u, lambda, trial_r, None)?;
        let s = dot(du, trial_r);
        let ok = finite(s, trial_r);
        if ok && fits(s) {
            return Ok(Some(match k {
                Some(k) => (alpha, problem.evaluate(trial_u, lambda, trial_r, Some(k))?),
                None => (alpha, scale),
            }));
        }
        if ok && s < 0.0 {
            (below, s_below) = (alpha, s);
        } else {
            (above, s_above) = (alpha, if ok { s } else { f64::NAN });
        }
    }
    Ok(None)
}
