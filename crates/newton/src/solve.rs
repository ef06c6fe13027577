//! One load level: Newton–Raphson iterations with line search (thesis §2.1, §4.4).

use crate::{NewtonError, NonlinearProblem};
use nonlin3d_solver::{LinearSolver, SolverKind, SymmetricMatrix};

/// Settings of the Newton iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct NewtonSettings {
    /// Iterations per attempt.
    pub max_iterations: usize,
    /// Absolute residual tolerance in force units (N): the thesis used 1e-4 N (§4.4).
    pub force_tolerance: f64,
    /// Relative residual tolerance against the force scale (largest external or reaction force).
    /// Converged when ‖r‖∞ ≤ max(force_tolerance, relative_tolerance·scale).
    pub relative_tolerance: f64,
    /// Backtracking line search on the residual norm.
    pub line_search: bool,
    /// Refactor the tangent every this many iterations: 1 = full Newton, more = modified Newton.
    pub refactor_every: usize,
    /// Linear solver.
    pub solver: SolverKind,
    /// Also require ‖Δu‖∞ ≤ displacement_tolerance·‖u‖∞ of the last step (0 = residual only).
    pub displacement_tolerance: f64,
}

impl Default for NewtonSettings {
    fn default() -> Self {
        Self {
            max_iterations: 25,
            force_tolerance: 1e-4,
            relative_tolerance: 1e-8,
            line_search: true,
            refactor_every: 1,
            solver: SolverKind::FaerLdlt,
            displacement_tolerance: 0.0,
        }
    }
}

/// One iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationRecord {
    /// ‖r‖∞ after the iteration, N.
    pub residual: f64,
    /// Line-search factor α accepted (1 = full step).
    pub step: f64,
    /// ‖Δu‖∞ of the accepted step.
    pub increment: f64,
    /// Negative pivots of the factorisation used (None when the previous one was reused).
    pub negative_pivots: Option<usize>,
}

/// How an attempt ended.
#[derive(Debug, Clone, PartialEq)]
pub enum Termination {
    /// The residual met the tolerance.
    Converged,
    /// `max_iterations` reached.
    MaxIterations,
    /// The residual grew beyond 1e8 times its initial value.
    Diverged,
    /// A residual or displacement became NaN or infinite.
    NonFinite,
    /// The tangent could not be factored (zero pivot, …): the message names the DOF.
    Singular(String),
}

/// The record of one attempt at one load level.
#[derive(Debug, Clone, PartialEq)]
pub struct IncrementReport {
    /// Load factor.
    pub lambda: f64,
    /// ‖r‖∞ before the first iteration.
    pub initial_residual: f64,
    /// The tolerance applied, N.
    pub tolerance: f64,
    /// Iterations.
    pub iterations: Vec<IterationRecord>,
    /// How it ended.
    pub termination: Termination,
}

impl IncrementReport {
    /// Whether the attempt converged.
    pub fn converged(&self) -> bool {
        self.termination == Termination::Converged
    }

    /// Negative pivots of the last factorisation in this attempt.
    pub fn negative_pivots(&self) -> Option<usize> {
        self.iterations.iter().rev().find_map(|r| r.negative_pivots)
    }
}

fn norm_inf(v: &[f64]) -> f64 {
    v.iter().fold(
        0.0f64,
        |a, x| if x.is_nan() { f64::NAN } else { a.max(x.abs()) },
    )
}

/// Solves r(u, λ) = 0 from the current `u` (updated in place, also when not converged; the
/// caller keeps a copy to restart from). `solver` must have analysed the problem's pattern;
/// `k` is the tangent storage.
pub fn solve_increment(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    lambda: f64,
    settings: &NewtonSettings,
    solver: &mut dyn LinearSolver,
    k: &mut SymmetricMatrix,
) -> Result<IncrementReport, NewtonError> {
    if settings.refactor_every == 0 || settings.max_iterations == 0 {
        return Err(NewtonError::Setting {
            name: "refactor_every / max_iterations",
            reason: "must be ≥ 1".into(),
        });
    }
    let n = problem.n();
    problem.prescribe(u, lambda);
    let mut r = vec![0.0; n];
    let scale = problem.evaluate(u, lambda, &mut r, Some(k))?;
    let tolerance = settings
        .force_tolerance
        .max(settings.relative_tolerance * scale);
    let mut norm = norm_inf(&r);
    let mut report = IncrementReport {
        lambda,
        initial_residual: norm,
        tolerance,
        iterations: Vec::new(),
        termination: Termination::MaxIterations,
    };
    if !norm.is_finite() {
        report.termination = Termination::NonFinite;
        return Ok(report);
    }
    if norm <= tolerance {
        report.termination = Termination::Converged;
        return Ok(report);
    }
    let initial = norm;
    let mut trial_u = vec![0.0; n];
    let mut trial_r = vec![0.0; n];
    for it in 0..settings.max_iterations {
        let mut pivots = None;
        if it % settings.refactor_every == 0 {
            match solver.factorize(k) {
                Ok(f) => pivots = Some(f.negative_pivots),
                Err(e) => {
                    report.termination = Termination::Singular(e.to_string());
                    return Ok(report);
                }
            }
        }
        let mut du: Vec<f64> = r.iter().map(|x| -x).collect();
        if let Err(e) = solver.solve_in_place(&mut du, 1) {
            report.termination = Termination::Singular(e.to_string());
            return Ok(report);
        }
        problem.expand(&mut du);
        // The next iteration refactors: evaluate the tangent together with the residual.
        let need_k = (it + 1) % settings.refactor_every == 0;
        let mut alpha = 1.0;
        let mut accepted = false;
        for _ in 0..if settings.line_search { 6 } else { 1 } {
            for ((t, &x), &d) in trial_u.iter_mut().zip(u.iter()).zip(&du) {
                *t = x + alpha * d;
            }
            problem.evaluate(
                &trial_u,
                lambda,
                &mut trial_r,
                if need_k { Some(k) } else { None },
            )?;
            let trial = norm_inf(&trial_r);
            if trial.is_finite() && (trial < norm || !settings.line_search) {
                accepted = true;
                norm = trial;
                break;
            }
            alpha *= 0.5;
        }
        if !accepted {
            // No reduction along the Newton direction: take the full step anyway (the residual
            // of a buckling problem may rise before it falls) and let the iteration decide.
            alpha = 1.0;
            for ((t, &x), &d) in trial_u.iter_mut().zip(u.iter()).zip(&du) {
                *t = x + d;
            }
            problem.evaluate(
                &trial_u,
                lambda,
                &mut trial_r,
                if need_k { Some(k) } else { None },
            )?;
            norm = norm_inf(&trial_r);
        }
        u.copy_from_slice(&trial_u);
        r.copy_from_slice(&trial_r);
        report.iterations.push(IterationRecord {
            residual: norm,
            step: alpha,
            increment: alpha * norm_inf(&du),
            negative_pivots: pivots,
        });
        if !norm.is_finite() || u.iter().any(|x| !x.is_finite()) {
            report.termination = Termination::NonFinite;
            return Ok(report);
        }
        let step_small = settings.displacement_tolerance <= 0.0
            || alpha * norm_inf(&du) <= settings.displacement_tolerance * norm_inf(u);
        if norm <= tolerance && step_small {
            report.termination = Termination::Converged;
            return Ok(report);
        }
        if norm > 1e8 * initial {
            report.termination = Termination::Diverged;
            return Ok(report);
        }
    }
    Ok(report)
}
