//! Time incrementation of a static step, after CalculiX: increments of step time from the
//! `*STATIC` initial increment, cut back after a failed attempt and grown after easy ones,
//! between the `*STATIC` minimum and maximum, at most `INC=` increments; `DIRECT` fixes the
//! increment and allows no cutback. A linear step is one increment to the end of the period.
//!
//! Each increment is one Newton solve: the constraints take every value from step time t0
//! (λ = 0) to t1 (λ = 1) and Newton solves λ = 1 from the last state, moved first by the tangent
//! predictor when prescribed displacements change (K_ff Δu_f = −K_fc Δu_c, as CalculiX does for
//! displacement-controlled steps: without it a large increment can land on a spurious
//! equilibrium, docs/VALIDATION.md), else extrapolated in step time through the step's last
//! converged states (quadratic through three, linear through two: [`IncrementStart`](super::IncrementStart)). An
//! amplitude is evaluated only at
//! increment ends, so it is honoured however the increments fall (an elastic state does not
//! depend on the path).

use super::contact::{DeckContact, Settled};
use super::loads::{Frame, History};
use super::{IncrementSummary, MixedPrecision, StepOptions, Strategy};
use crate::Error;
use nonlin3d_mesh::{InpModel, ReadStep};
use nonlin3d_newton::{
    Extrapolation, Guess, NewtonSettings, PathSolver, StructuralProblem, Termination,
    predicted_increment,
};

/// The increment control in force in a step: `*CONTROLS, PARAMETERS=TIME INCREMENTATION` or
/// CalculiX's defaults.
struct Control {
    easy: usize,
    slow: usize,
    max_cutbacks: usize,
    diverged_cutback: f64,
    slow_cutback: f64,
    slow_shrink: f64,
    grow: f64,
}

impl Control {
    fn of(step: &ReadStep) -> Self {
        let c = &step.controls;
        Self {
            easy: c.easy_iterations.unwrap_or(4),
            slow: c.slow_iterations.unwrap_or(10),
            max_cutbacks: c.max_cutbacks.unwrap_or(5),
            diverged_cutback: c.diverged_cutback.unwrap_or(0.25),
            slow_cutback: c.slow_cutback.unwrap_or(0.5),
            slow_shrink: c.slow_shrink.unwrap_or(0.75),
            grow: c.grow.unwrap_or(1.5),
        }
    }
}

/// The Newton settings of a step: `base` with the deck's `*CONTROLS` (I_C → iterations, I_0 →
/// the divergence test, I_R → the logarithmic convergence test, R_n → relative residual
/// tolerance, C_n → displacement-correction tolerance) and `line_search`. Without I_0 and I_R
/// neither test is made (nonlin3d's default: an attempt runs to I_C).
pub(crate) fn newton_settings(
    base: &NewtonSettings,
    line_search: bool,
    step: &ReadStep,
) -> NewtonSettings {
    let c = &step.controls;
    NewtonSettings {
        max_iterations: c.max_iterations.unwrap_or(base.max_iterations),
        relative_tolerance: c.residual_ratio.unwrap_or(base.relative_tolerance),
        displacement_tolerance: c.correction_ratio.unwrap_or(base.displacement_tolerance),
        divergence_check_from: c.divergence_check.unwrap_or(base.divergence_check_from),
        slow_check_from: c.slow_check.unwrap_or(base.slow_check_from),
        line_search,
        ..base.clone()
    }
}

/// A converged increment, handed to the output writer.
pub(crate) struct Converged<'a> {
    pub increment: usize,
    pub step_time: f64,
    pub last: bool,
    pub u: &'a [f64],
    pub problem: &'a mut StructuralProblem,
    /// Every attempt of the step so far.
    pub attempts: &'a [IncrementSummary],
    /// What the step's solver analysis found (None where the step's path follower keeps
    /// its own solver: a Riks step).
    pub analysis: Option<nonlin3d_solver::Analysis>,
}

/// Runs step `k` (0-based) from `u` (updated to its end), appending every attempt to
/// `attempts` and calling `on_increment` with each converged increment.
#[allow(clippy::too_many_arguments)]
pub(crate) fn run_step(
    model: &InpModel,
    k: usize,
    history: &History,
    frame: Frame,
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    options: &StepOptions,
    mut contact: Option<&mut DeckContact>,
    attempts: &mut Vec<IncrementSummary>,
    on_increment: &mut dyn FnMut(Converged<'_>) -> Result<(), Error>,
) -> Result<(), Error> {
    let step = &model.steps[k];
    let p = &step.procedure;
    let strategy = options.strategy.in_step(p.direct || !step.nlgeom);
    let mut base = newton_settings(&options.newton, options.start.line_search, step);
    // An NLGEOM step that keeps a tangent takes `kept_solver`, its full-Newton redos too (one
    // solver per step: a different kind would be analysed anew). A linear step solves once,
    // exactly: `newton.solver`.
    if let (Some(kind), true) = (
        options.kept_solver,
        step.nlgeom && strategy != Strategy::Full,
    ) {
        base.solver = kind;
    }
    let full = Strategy::Full.apply(&base);
    // A kept-tangent attempt stops at CalculiX's divergence test from its fourth iteration
    // (CalculiX's default I_0) unless the deck sets I_0, and the increment is then redone by
    // full Newton (docs/PERFORMANCE.md: from the second iteration, the plate's second
    // increment was redone for nothing).
    let quick = (strategy != Strategy::Full).then(|| NewtonSettings {
        divergence_check_from: match base.divergence_check_from {
            0 => 4,
            n => n,
        },
        ..strategy.apply(&base)
    });
    let settings = quick.as_ref().unwrap_or(&full);
    let control = Control::of(step);
    let period = frame.period;
    let eps = 1e-12 * period;
    // One session per step: its kept factorisation serves the next increment's predictor while
    // the loads run continuously; a new step may change them at once (OP=NEW).
    let mut session = PathSolver::new(problem, settings.solver)?;
    let mut t = 0.0;
    let mut dt = match (step.nlgeom, options.initial_increment) {
        (false, _) => period,
        (true, None) => p.initial,
        (true, Some(f)) if p.direct => f * period,
        (true, Some(f)) => (f * period).clamp(p.min, p.max),
    };
    let mut increment = 0;
    let mut easy_before = false;
    let mut cutbacks = 0;
    // The converged states of the step (from its start) for the extrapolated start.
    let mut path = Extrapolation::new(options.start.extrapolation);
    path.push(0.0, u);
    let guarded = options.start.guarded;
    let fail = |reason: String| Error::Step {
        step: k + 1,
        line: step.line,
        reason,
    };
    while period - t > eps {
        let size = if period - t - dt < eps {
            period - t
        } else {
            dt
        };
        problem.set_constraints(history.constraints(model, frame, t, t + size)?)?;
        if let Some(c) = contact.as_deref_mut() {
            c.reinstall(problem, u, &mut session)?;
        }
        let start = u.clone();
        let mixed_before = session.mixed_stats();
        let predicted = path.predict(t + size);
        let guess = predicted.as_deref().map(|g| Guess { u: g, guarded });
        let mut report = predicted_increment(problem, u, 0.0, 1.0, guess, settings, &mut session)?;
        if quick.is_some() && !report.converged() {
            // The kept tangent failed: the same increment by full Newton from the same start
            // (`u` is left as it was), before any cutback.
            let mut failed = IncrementSummary::of(&report, increment + 1, t + size, frame.start);
            failed.termination = format!("{}; redone by full Newton", failed.termination);
            attempts.push(failed);
            session.invalidate();
            report = predicted_increment(problem, u, 0.0, 1.0, guess, &full, &mut session)?;
        }
        let iterations = report.iterations.len();
        let mut converged = report.converged();
        let mut summary = IncrementSummary::of(&report, increment + 1, t + size, frame.start);
        // Contact (thesis §2.7): the active-set passes at the converged state; a failure of
        // theirs is a failed attempt, cut back as one.
        let mut contact_failure = None;
        if let (true, Some(c)) = (converged, contact.as_deref_mut()) {
            match c.settle(problem, u, &start, &full, &mut session)? {
                Settled::Stable(s) => summary.contact = Some(s),
                Settled::Failed(why) => {
                    converged = false;
                    summary.converged = false;
                    summary.termination = why.clone();
                    contact_failure = Some(why);
                }
            }
        }
        // A kept tangent's last iteration made no factorisation: the inertia of the converged
        // state from one made there (the next increment's tangent), where full Newton's last
        // factorisation gives it (docs/PERFORMANCE.md, "Fewer factorisations in deck steps").
        let unfactored = report
            .iterations
            .last()
            .is_some_and(|i| i.negative_pivots.is_none());
        if converged && unfactored {
            summary.negative_pivots = Some(session.inertia_at(problem, u, 1.0)?);
            summary.factorisations += 1;
        }
        summary.mixed_precision = session
            .mixed_stats()
            .map(|now| MixedPrecision::between(mixed_before, now));
        attempts.push(summary);
        if converged {
            increment += 1;
            if increment > step.max_increments {
                return Err(fail(format!(
                    "more than INC={} increments needed (step time {t:.6} of {period})",
                    step.max_increments
                )));
            }
            t += size;
            path.push(t, u);
            cutbacks = 0;
            on_increment(Converged {
                increment,
                step_time: t,
                last: period - t <= eps,
                u,
                problem,
                attempts,
                analysis: session.analysis(),
            })?;
            if p.direct || !step.nlgeom {
                continue;
            }
            let easy = iterations <= control.easy;
            if iterations > control.slow {
                dt = size * control.slow_shrink;
            } else if easy && easy_before {
                dt = (dt * control.grow).min(p.max);
            }
            dt = dt.max(p.min);
            easy_before = easy;
        } else {
            let reason = match (&contact_failure, &report.termination) {
                (Some(why), _) => why.clone(),
                (None, Termination::MaxIterations) => {
                    format!("no convergence in {iterations} iterations")
                }
                (None, other) => other.to_string(),
            };
            if p.direct || !step.nlgeom {
                return Err(fail(format!(
                    "increment {} (step time {:.6} → {:.6}) did not converge ({reason}){}",
                    increment + 1,
                    t,
                    t + size,
                    if p.direct {
                        "; DIRECT allows no cutback"
                    } else {
                        ""
                    }
                )));
            }
            cutbacks += 1;
            easy_before = false;
            let factor = match report.termination {
                _ if contact_failure.is_some() => control.slow_cutback,
                Termination::MaxIterations | Termination::TooSlow { .. } => control.slow_cutback,
                _ => control.diverged_cutback,
            };
            dt = size * factor;
            if cutbacks > control.max_cutbacks || dt < p.min {
                return Err(fail(format!(
                    "increment {} from step time {t:.6} did not converge after {cutbacks} \
                     attempts ({reason}; next size {dt:.3e}, minimum {:.3e}, I_A = {})",
                    increment + 1,
                    p.min,
                    control.max_cutbacks
                )));
            }
        }
    }
    Ok(())
}
