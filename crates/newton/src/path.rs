//! Load stepping to a list of load-factor targets with cutback and regrowth.

use crate::guard::{InertiaGuard, Verdict};
use crate::predict::{Prediction, tangent_predictor};
use crate::solve::iterate;
use crate::{
    Bifurcation, IncrementReport, NewtonError, NewtonSettings, NonlinearProblem, PathSolver,
};

/// Increment control.
#[derive(Debug, Clone, PartialEq)]
pub struct Stepping {
    /// First increment Δλ.
    pub initial: f64,
    /// Smallest increment before giving up.
    pub min: f64,
    /// Largest increment.
    pub max: f64,
    /// Growth factor after an increment that converged in at most `easy` iterations.
    pub grow: f64,
    /// Iterations counted as easy.
    pub easy: usize,
    /// Cutback factor after a failed attempt.
    pub cutback: f64,
    /// Start each increment from the secant extrapolation of the last two converged states
    /// (u + (u − u_prev)·Δλ/Δλ_prev) instead of the last state. Used when the tangent
    /// predictor does not apply (no prescribed value changes): the tangent wins, its error is
    /// Δλ²/2·u″ against the secant's Δλ(Δλ + Δλ_prev)/2·u″, and it needs no history.
    pub secant_predictor: bool,
    /// When prescribed values change over an increment, move the free DOFs with them before
    /// Newton starts: K_ff Δu_f = −(K_fc Δu_c − Δf_ext) with the tangent of the last converged
    /// state (the factorisation its increment left; [`NonlinearProblem::coupling_force`]).
    /// Not when a kept tangent serves the increment's first iteration (modified Newton, BFGS):
    /// that iteration is linearised at or before the start already.
    pub tangent_predictor: bool,
    /// Inertia guard: an increment from a stable state (no negative pivot) over which the
    /// tangent gains negative pivots is refused and cut back while it is larger than this
    /// fraction of the increment that first showed the rise; at or below it the rise is
    /// accepted as a real bifurcation and recorded ([`IncrementReport::bifurcation`]). Rises on
    /// an unstable path are recorded without refusal. 0 = never refuse (rises are still
    /// recorded when the start's inertia is known: from the predictor's factorisation or an
    /// earlier increment's). The counts are those of each increment's last factorisation, so
    /// with a kept tangent (BFGS) only increments that refactor are judged.
    pub inertia_guard: f64,
    /// Most attempts (converged increments and cut-back tries together) towards one target;
    /// 0 = no limit. A path that would need more stops with [`NewtonError::Attempts`] instead
    /// of grinding on at the smallest increments (the thesis's scenes need at most about 10 a
    /// level).
    pub max_attempts: usize,
}

impl Default for Stepping {
    fn default() -> Self {
        Self {
            initial: 0.25,
            min: 1e-4,
            max: 1.0,
            grow: 1.5,
            easy: 4,
            cutback: 0.5,
            secant_predictor: true,
            tangent_predictor: true,
            inertia_guard: 0.25,
            max_attempts: 0,
        }
    }
}

/// The path: every attempt (converged or not) and the state at each target.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct PathReport {
    /// All attempts in order.
    pub attempts: Vec<IncrementReport>,
    /// (λ, u) at each target reached.
    pub states: Vec<(f64, Vec<f64>)>,
}

impl PathReport {
    /// The rises of the inertia accepted as real ([`IncrementReport::bifurcation`]), each with
    /// the load factor of the increment that recorded it: a bifurcation (or limit) point lies
    /// in (`from`, λ].
    pub fn bifurcations(&self) -> Vec<(f64, Bifurcation)> {
        self.attempts
            .iter()
            .filter_map(|a| a.bifurcation.map(|b| (a.lambda, b)))
            .collect()
    }

    /// Converged increments where the count of negative pivots changed from the previous one:
    /// (λ before, λ after, pivots before, pivots after). On a symmetric tangent a change marks a
    /// bifurcation or limit point between the two load factors (Sylvester's law of inertia).
    pub fn inertia_changes(&self) -> Vec<(f64, f64, usize, usize)> {
        let mut out = Vec::new();
        let mut last: Option<(f64, usize)> = None;
        for a in self.attempts.iter().filter(|a| a.converged()) {
            // The first factorisation of an increment is at the start state (λ set, previous u);
            // the last one is closest to the converged state.
            let Some(p) = a.negative_pivots() else {
                continue;
            };
            if let Some((l0, p0)) = last
                && p0 != p
            {
                out.push((l0, a.lambda, p0, p));
            }
            last = Some((a.lambda, p));
        }
        out
    }
}

/// Follows the equilibrium path from λ = 0 (`u` the starting state, updated to the last
/// converged one) through `targets` in order.
pub fn follow_path(
    problem: &mut dyn NonlinearProblem,
    u: &mut Vec<f64>,
    targets: &[f64],
    settings: &NewtonSettings,
    stepping: &Stepping,
) -> Result<PathReport, NewtonError> {
    follow_path_from(problem, u, 0.0, targets, settings, stepping)
}

/// [`follow_path`] from a converged state `u` at load factor `start`.
pub fn follow_path_from(
    problem: &mut dyn NonlinearProblem,
    u: &mut Vec<f64>,
    start: f64,
    targets: &[f64],
    settings: &NewtonSettings,
    stepping: &Stepping,
) -> Result<PathReport, NewtonError> {
    check_stepping(stepping)?;
    let mut session = PathSolver::new(problem, settings.solver)?;
    follow_path_with(problem, u, start, targets, settings, stepping, &mut session)
}

/// [`follow_path_from`] with a [`PathSolver`] kept by the caller over several calls (the levels
/// of a sweep): no new symbolic analysis, and with `settings.keep_tangent` the first increment
/// starts from the session's factorisation (the last increment's, or the one
/// [`PathSolver::inertia_at`] left) instead of factoring anew. A session made for another
/// pattern or solver kind is made anew.
///
/// Each increment whose prescribed values change starts from the tangent predictor
/// ([`Stepping::tangent_predictor`]) with the factorisation the session holds for the start
/// state when it has one (the residual there is then taken as converged: after changing dead
/// loads between calls, [`PathSolver::invalidate`] so that the start is evaluated anew), else
/// one made there; other increments from the secant extrapolation. A converged increment that
/// makes a stable path unstable is judged by the inertia guard ([`Stepping::inertia_guard`]):
/// refused and cut back ([`Termination::InertiaChanged`](crate::Termination)), or accepted
/// with its [`Bifurcation`] recorded ([`PathReport::bifurcations`]).
pub fn follow_path_with(
    problem: &mut dyn NonlinearProblem,
    u: &mut Vec<f64>,
    start: f64,
    targets: &[f64],
    settings: &NewtonSettings,
    stepping: &Stepping,
    session: &mut PathSolver,
) -> Result<PathReport, NewtonError> {
    check_stepping(stepping)?;
    session.fit(problem, settings.solver)?;
    let mut report = PathReport::default();
    let mut lambda = start;
    let mut step = stepping.initial.min(stepping.max);
    let mut cutbacks = 0;
    // The previous converged state and its increment, for the secant predictor.
    let mut previous: Option<(Vec<f64>, f64)> = None;
    // The factorised tangent (and BFGS pairs) carried between increments when
    // `settings.keep_tangent`; a failed attempt clears it, so its retry starts afresh.
    let mut guard = InertiaGuard::new(stepping.inertia_guard, session.pivots_at(u));
    for &target in targets {
        let mut attempts = 0;
        while (target - lambda).abs() > 1e-12 * target.abs().max(1.0) {
            let dir = (target - lambda).signum();
            let delta = step.min((target - lambda).abs());
            let to = lambda + dir * delta;
            let mut trial = u.clone();
            // The tangent predictor, unless a kept tangent serves the first iteration (which is
            // then linearised at or before the start already); or, when the guard lacks the
            // start's inertia, whether the prescribed values change (then the start's tangent
            // is factorised for its inertia).
            let apply = stepping.tangent_predictor && !session.cache.serves(settings);
            let prediction = if apply || guard.needs_reference() {
                tangent_predictor(problem, &mut trial, lambda, to, session, apply)?
            } else {
                Prediction::NoChange
            };
            if prediction != Prediction::NoChange {
                guard.know(session.pivots_at(u));
            }
            let predicted = prediction == Prediction::Moved;
            let secant = !predicted && stepping.secant_predictor && previous.is_some();
            if let (true, Some((u_prev, d_prev))) = (secant, &previous) {
                let f = dir * delta / d_prev;
                for ((t, &a), &b) in trial.iter_mut().zip(u.iter()).zip(u_prev) {
                    *t = a + f * (a - b);
                }
            }
            let PathSolver {
                solver, k, cache, ..
            } = &mut *session;
            let mut attempt = iterate(
                problem,
                &mut trial,
                to,
                settings,
                (solver.as_mut(), k, cache),
                predicted,
            )?;
            if prediction == Prediction::NoChange && !secant {
                // Started at u itself: the first factorisation, if one was made, is u's.
                guard.know(attempt.iterations.first().and_then(|i| i.negative_pivots));
            }
            let mut converged = attempt.converged();
            let iterations = attempt.iterations.len();
            if converged {
                let next = delta * stepping.cutback;
                if guard.judge(&mut attempt, lambda, delta, next, stepping.min) == Verdict::Refuse {
                    // Its factorisation belongs to the refused state: not the retry's tangent.
                    session.invalidate();
                    converged = false;
                    tracing::debug!(
                        target: crate::TRACE_TARGET,
                        event = "refused",
                        lambda = to,
                        termination = %attempt.termination,
                    );
                }
            }
            let reason = attempt.termination.to_string();
            let pivots = attempt.negative_pivots();
            report.attempts.push(attempt);
            attempts += 1;
            if converged {
                session.accept(&trial, pivots);
                previous = Some((std::mem::replace(u, trial), dir * delta));
                lambda = to;
                if iterations <= stepping.easy && !guard.pending() {
                    step = (step * stepping.grow).min(stepping.max);
                }
                if stepping.max_attempts > 0
                    && attempts >= stepping.max_attempts
                    && (target - lambda).abs() > 1e-12 * target.abs().max(1.0)
                {
                    return Err(NewtonError::Attempts {
                        target,
                        reached: lambda,
                        attempts,
                        last_step: delta,
                        reason,
                    });
                }
            } else {
                cutbacks += 1;
                step = delta * stepping.cutback;
                if step < stepping.min {
                    return Err(NewtonError::Cutback {
                        target,
                        reached: lambda,
                        cutbacks,
                        last_step: delta,
                        reason,
                    });
                }
                if stepping.max_attempts > 0 && attempts >= stepping.max_attempts {
                    return Err(NewtonError::Attempts {
                        target,
                        reached: lambda,
                        attempts,
                        last_step: delta,
                        reason,
                    });
                }
            }
        }
        report.states.push((target, u.clone()));
    }
    Ok(report)
}

/// Refuses increments that are not finite and positive, a largest step below the smallest, a
/// cutback outside (0, 1) and a growth below 1.
fn check_stepping(stepping: &Stepping) -> Result<(), NewtonError> {
    let ok = |v: f64| v.is_finite() && v > 0.0;
    if ok(stepping.initial)
        && ok(stepping.min)
        && stepping.max >= stepping.min
        && stepping.cutback > 0.0
        && stepping.cutback < 1.0
        && stepping.grow >= 1.0
    {
        Ok(())
    } else {
        Err(NewtonError::Setting {
            name: "stepping",
            reason: format!("{stepping:?}"),
        })
    }
}
