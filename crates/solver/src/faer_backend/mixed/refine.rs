//! The f64 solution from the f32 factor: iterative refinement, and conjugate gradients
//! preconditioned by the same factor where refinement stalls. Carson & Higham (SIAM J. Sci.
//! Comput. 39, 2017) refine by GMRES preconditioned with the low-precision factors, which
//! still converges where cond(A)·ε₃₂ ≳ 1 stops plain refinement; with A and L̃D̃L̃ᵀ symmetric
//! positive definite, CG does that work with short recurrences.

use super::{MixedStats, max_abs};
use crate::{SolverError, SymmetricMatrix};

/// Refinement steps before falling back to f64 (cond(A)·ε₃₂ = 0.1 needs about 7 from
/// ε₃₂ to 1e-14).
pub const MAX_REFINEMENT_STEPS: usize = 20;

/// Conjugate-gradient steps after a stalled refinement before falling back to f64. With the
/// f32 factor as preconditioner, M⁻¹A = I + E with ‖E‖ ≈ cond(A)·ε₃₂ concentrated on a few
/// eigenvalues, so CG meets a target in a few steps where refinement's x ← x + M⁻¹r
/// oscillates (the thin plate deck at rest: 2 steps).
pub const MAX_CONJUGATE_GRADIENT_STEPS: usize = 20;

/// In a solve to a residual bound ([`LinearSolver::solve_to_residual`](crate::LinearSolver::solve_to_residual)) with an f32 factor:
/// a checked first solve whose residual ratio ρ₁ = ‖b − A x₁‖∞ / ‖b‖∞ was at most this share
/// of its bound's ratio τ = bound / ‖b‖∞ lets the next solves on the same factor skip the f64
/// product that checks them, while ρ₁ ≤ TRUSTED_SHARE·τ′ for their own bound ratio τ′ (the
/// reasons are in `mixed/refine.rs`, `Trust`; docs/PERFORMANCE.md has the measurements).
pub const TRUSTED_SHARE: f64 = 0.25;

/// Solves taken unchecked on one f32 factor after a check ([`TRUSTED_SHARE`]) before the
/// next one is checked again.
pub const UNCHECKED_IN_A_ROW: usize = 4;

/// Whether a solve to a residual bound may take the f32 solve x = C b without the f64 product
/// that checks ‖b − A x‖∞ ≤ bound (one pass over A, about an eighth of a direction's time
/// on the plate decks). The check measures the factor as much as b: on one factor, the first
/// solves of Newton's directions on the 24 k-DOF plate deck left ρ₁ = 0.5e-3 to 4e-3 of ‖b‖∞,
/// within 3× of each other, against bounds of 1e-2 to 5e-2 (KEPT_FORCING). So after a checked
/// solve whose first step met its bound with ρ₁ ≤ [`TRUSTED_SHARE`]·τ, up to
/// [`UNCHECKED_IN_A_ROW`] solves on that factor whose own bound ratio τ′ has ρ₁ ≤
/// TRUSTED_SHARE·τ′ are taken unchecked; every new factor, and every solve after those, is
/// checked. An unchecked solve that would have missed its bound (ρ₁ more than 4× the
/// checked one's) is a less exact inexact-Newton direction, not a wrong answer: the residual
/// that decides convergence is the f64 one of the next iteration.
#[derive(Debug, Default, Clone, Copy, PartialEq)]
pub(super) struct Trust {
    /// ρ₁ of the last checked solve on this factor, if its first step met the bound.
    checked: Option<f64>,
    /// Unchecked solves since.
    unchecked: usize,
}

impl Trust {
    /// Whether a solve whose bound is `ratio` of its ‖b‖∞ may go unchecked.
    fn allows(&self, ratio: f64) -> bool {
        self.checked
            .is_some_and(|rho| rho <= TRUSTED_SHARE * ratio && self.unchecked < UNCHECKED_IN_A_ROW)
    }
}

/// `col` (b in, x out) by one unchecked f32 solve if `trust` allows it for this bound, else
/// by [`refine_column`] (whose first step then sets `trust`); `false` if refinement stalled.
pub(super) fn solve_column(
    col: &mut [f64],
    system: System<'_>,
    stats: &mut MixedStats,
    trust: &mut Trust,
    mut correct: impl FnMut(&mut [f64]),
) -> Result<bool, SolverError> {
    let b_norm = max_abs(col);
    let bound = system.target.residual;
    if b_norm > 0.0 && bound > 0.0 && trust.allows(bound / b_norm) {
        correct(col);
        stats.unchecked_solves += 1;
        trust.unchecked += 1;
        return Ok(true);
    }
    let refined = refine_column(col, system, stats, correct)?;
    *trust = Trust {
        checked: refined.first_met.then_some(refined.first_ratio),
        unchecked: 0,
    };
    Ok(refined.met)
}

/// What [`refine_column`] did: whether it met its target, and its first step's residual
/// ratio ‖b − A x₁‖∞ / ‖b‖∞ and whether that step met the target already.
#[derive(Debug, Clone, Copy)]
pub(super) struct Refined {
    pub(super) met: bool,
    pub(super) first_ratio: f64,
    pub(super) first_met: bool,
}

/// Where [`refine_column`] stops: the first of the two reached.
#[derive(Debug, Clone, Copy)]
pub(super) struct Target {
    /// The normwise backward error ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞).
    pub(super) backward_error: f64,
    /// ‖b − A x‖∞ in b's units (0: none): what the caller can use
    /// ([`LinearSolver::solve_to_residual`](crate::LinearSolver::solve_to_residual)).
    pub(super) residual: f64,
}

/// What a refined solve needs besides b: A, ‖A‖∞, the target, and whether the f32 factor
/// L̃D̃L̃ᵀ is positive definite (all its pivots positive), so that it can precondition CG.
pub(super) struct System<'a> {
    pub(super) a: &'a SymmetricMatrix,
    pub(super) a_norm: f64,
    pub(super) target: Target,
    pub(super) definite: bool,
}

/// `col` (b in, x out) by iterative refinement, x ← x + C(b − A x) with `correct` applying
/// the approximate inverse C = (L̃D̃L̃ᵀ)⁻¹ in place, until the normwise backward error
/// ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) or the residual ‖b − A x‖∞ meets its target (`true`).
/// If refinement stalls (the backward error falls by less than half in a step, or
/// [`MAX_REFINEMENT_STEPS`] pass) and C is positive definite, preconditioned conjugate
/// gradients from x = 0 take over ([`conjugate_gradients`]); `met` false if they stall too.
pub(super) fn refine_column(
    col: &mut [f64],
    system: System<'_>,
    stats: &mut MixedStats,
    mut correct: impl FnMut(&mut [f64]),
) -> Result<Refined, SolverError> {
    let System {
        a,
        a_norm,
        target,
        definite,
    } = system;
    let n = col.len();
    let b = col.to_vec();
    let b_norm = max_abs(&b);
    col.fill(0.0);
    let mut refined = Refined {
        met: true,
        first_ratio: 0.0,
        first_met: true,
    };
    if b_norm == 0.0 {
        return Ok(refined);
    }
    let met = |residual: f64, x: &[f64]| {
        let omega = residual / (a_norm * max_abs(x) + b_norm);
        (
            omega,
            omega <= target.backward_error || residual <= target.residual,
        )
    };
    let mut r = b.clone();
    let mut ax = vec![0.0; n];
    let mut previous = f64::INFINITY;
    for step in 0..MAX_REFINEMENT_STEPS {
        correct(&mut r);
        for (xi, ci) in col.iter_mut().zip(&r) {
            *xi += ci;
        }
        a.matvec(col, &mut ax)?;
        for ((ri, bi), axi) in r.iter_mut().zip(&b).zip(&ax) {
            *ri = bi - axi;
        }
        let (omega, done) = met(max_abs(&r), col);
        stats.refinement_steps += 1;
        stats.last_backward_error = omega;
        if step == 0 {
            (refined.first_ratio, refined.first_met) = (max_abs(&r) / b_norm, done);
        }
        if done {
            return Ok(refined);
        }
        if !omega.is_finite() || omega > 0.5 * previous {
            break;
        }
        previous = omega;
    }
    refined.met = definite && conjugate_gradients(col, &b, a, stats, correct, met)?;
    Ok(refined)
}

/// Preconditioned conjugate gradients on A x = b from x = 0 (into `x`), C = (L̃D̃L̃ᵀ)⁻¹ applied by
/// `correct`: z = C r, p = z + β p, α = rᵀz / pᵀAp, x += α p, r −= α A p, with
/// β = zₖ₊₁ᵀ(rₖ₊₁ − rₖ) / zₖᵀrₖ (the flexible form, which tolerates the f32 rounding that
/// makes C slightly nonlinear). The updated r drifts from b − A x by rounding, so when it
/// meets the target the true residual is formed: `true` if that meets it too (`met`), else
/// CG restarts from it. `false` after [`MAX_CONJUGATE_GRADIENT_STEPS`], or at a step whose
/// pᵀAp or backward error is not positive and finite (A not positive definite).
fn conjugate_gradients(
    x: &mut [f64],
    b: &[f64],
    a: &SymmetricMatrix,
    stats: &mut MixedStats,
    mut correct: impl FnMut(&mut [f64]),
    met: impl Fn(f64, &[f64]) -> (f64, bool),
) -> Result<bool, SolverError> {
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(p, q)| p * q).sum::<f64>();
    let mut ap = vec![0.0; x.len()];
    // r = b − A x: each restart's true residual (the start, from x = 0, has r = b).
    let restart = |x: &[f64], r: &mut [f64], ap: &mut [f64]| -> Result<(), SolverError> {
        a.matvec(x, ap)?;
        for ((ri, bi), axi) in r.iter_mut().zip(b).zip(ap.iter()) {
            *ri = bi - axi;
        }
        Ok(())
    };
    x.fill(0.0);
    let mut r = b.to_vec();
    let mut z = r.clone();
    correct(&mut z);
    let mut p = z.clone();
    let mut rz = dot(&r, &z);
    let mut r_old = r.clone();
    for _ in 0..MAX_CONJUGATE_GRADIENT_STEPS {
        a.matvec(&p, &mut ap)?;
        let pap = dot(&p, &ap);
        if pap <= 0.0 || !pap.is_finite() {
            return Ok(false);
        }
        let alpha = rz / pap;
        r_old.copy_from_slice(&r);
        for ((xi, ri), (pi, api)) in x.iter_mut().zip(r.iter_mut()).zip(p.iter().zip(&ap)) {
            *xi += alpha * pi;
            *ri -= alpha * api;
        }
        stats.refinement_steps += 1;
        stats.conjugate_gradient_steps += 1;
        let (omega, done) = met(max_abs(&r), x);
        stats.last_backward_error = omega;
        if !omega.is_finite() {
            return Ok(false);
        }
        if done {
            restart(x, &mut r, &mut ap)?;
            let (omega, met_now) = met(max_abs(&r), x);
            stats.last_backward_error = omega;
            if met_now {
                return Ok(true);
            }
        }
        z.copy_from_slice(&r);
        correct(&mut z);
        // β = 0 after a restart from the true residual.
        let beta = match done {
            true => 0.0,
            false => {
                let dz = z.iter().zip(r.iter().zip(&r_old));
                dz.map(|(zi, (ri, oi))| zi * (ri - oi)).sum::<f64>() / rz
            }
        };
        rz = dot(&r, &z);
        for (pi, zi) in p.iter_mut().zip(&z) {
            *pi = zi + beta * *pi;
        }
    }
    Ok(false)
}
