//! One load level: Newton–Raphson iterations with line search (thesis §2.1, §4.4); full,
//! modified (a tangent kept for several iterations or increments) and quasi-Newton (BFGS
//! updates of a kept tangent, Matthies & Strang 1979).

use crate::line_search::line_search;
use crate::vector::norm_inf;
use crate::{NewtonError, NewtonSettings, NonlinearProblem, TangentCache};
use nonlin3d_solver::{LinearSolver, SolverKind, SymmetricMatrix};

/// One iteration.
#[derive(Debug, Clone, PartialEq)]
pub struct IterationRecord {
    /// ‖r‖∞ after the iteration, N.
    pub residual: f64,
    /// Line-search factor α accepted (1 = full step).
    pub step: f64,
    /// ‖Δu‖∞ of the accepted step.
    pub increment: f64,
    /// Negative pivots of the factorisation made for this iteration (None when an older one
    /// was used).
    pub negative_pivots: Option<usize>,
    /// BFGS pairs applied to the direction (0 for plain Newton steps).
    pub bfgs_pairs: usize,
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
    /// From [`NewtonSettings::divergence_check_from`] on, the residual stayed above the one two
    /// iterations back for two iterations (CalculiX's divergence test, cut back by D_F).
    Diverging,
    /// From [`NewtonSettings::slow_check_from`] on, the logarithmic estimate of the iterations
    /// to convergence exceeded the limit (CalculiX's "too slow convergence", cut back by D_C).
    TooSlow {
        /// The estimated total of iterations.
        estimate: usize,
    },
    /// The tangent could not be factored (zero pivot, …): the message names the DOF.
    Singular(String),
    /// The residual met the tolerance, but the tangent there has more negative pivots
    /// (`after`) than at the last accepted state (`before`) and the increment was larger than
    /// the inertia guard accepts ([`Stepping::inertia_guard`](crate::Stepping::inertia_guard)):
    /// possibly a spurious equilibrium a large step jumped to, so the increment is refused and
    /// cut back.
    InertiaChanged {
        /// Negative pivots at the last accepted state.
        before: usize,
        /// Negative pivots at the refused state.
        after: usize,
    },
}

impl std::fmt::Display for Termination {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Converged => write!(f, "converged"),
            Self::MaxIterations => write!(f, "no convergence within the iteration limit"),
            Self::Diverged => write!(f, "diverged (residual above 1e8 times its initial value)"),
            Self::NonFinite => write!(f, "a residual or displacement became NaN or infinite"),
            Self::Diverging => write!(
                f,
                "diverging (the residual stayed above the one two iterations back for two iterations)"
            ),
            Self::TooSlow { estimate } => write!(
                f,
                "too slow convergence (about {estimate} iterations estimated, more than allowed)"
            ),
            Self::Singular(why) => write!(f, "singular tangent: {why}"),
            Self::InertiaChanged { before, after } => write!(
                f,
                "refused: negative pivots rose from {before} to {after} over a large increment"
            ),
        }
    }
}

/// The smallest residual tolerance relative to the force scale that double precision reaches
/// (the residual is a sum of element forces of size F, each with rounding ≈1e-16·F,
/// over many terms; a cantilever of tests/newton.rs reaches 1e-13·F): a tolerance below
/// REACHABLE·F is refused, not raised.
pub const REACHABLE: f64 = 1e-14;

/// The force a Newton correction may leave unbalanced in its linear solve, as a fraction of
/// the force tolerance: K Δu = −r is solved to ‖K Δu + r‖∞ ≤ 0.01 · tol, so the next
/// residual differs from the exact step's by at most 1 % of the tolerance (a mixed-precision
/// solver stops refining there, [`LinearSolver::solve_to_residual`]).
pub const LINEAR_RESIDUAL: f64 = 0.01;

/// The forcing term η of an iteration on a tangent not refreshed at every iteration (BFGS,
/// modified Newton: `keep_tangent` or `refactor_every` > 1). Its direction is solved to
/// ‖K₀ d + r‖∞ ≤ max(η‖r‖∞, [`LINEAR_RESIDUAL`]·tol): inexact Newton (Dembo, Eisenstat &
/// Steihaug 1982), the linear residual adds at most η‖r‖ to the next residual. K₀ is an older
/// tangent, so the direction is already off by ‖(K − K₀)d‖, far more than 1 % of ‖r‖; a
/// mixed-precision solver then stops after one f32 solve where cond(K₀)·ε₃₂ ≲ 0.01 instead of
/// refining to the tolerance. Full Newton keeps `LINEAR_RESIDUAL`·tol (its quadratic tail
/// needs the exact step). Measured on the plate decks in docs/PERFORMANCE.md ("f32 factors
/// for kept tangents").
pub const KEPT_FORCING: f64 = 0.01;

/// The residual bound of an iteration's direction: [`LINEAR_RESIDUAL`] of the force
/// tolerance, or on a tangent not refreshed at every iteration [`KEPT_FORCING`] of ‖r‖∞ if
/// that is larger.
pub(crate) fn direction_bound(settings: &NewtonSettings, tolerance: f64, norm: f64) -> f64 {
    let floor = LINEAR_RESIDUAL * tolerance;
    match settings.keep_tangent || settings.refactor_every > 1 {
        true => floor.max(KEPT_FORCING * norm),
        false => floor,
    }
}

/// The residual tolerance at a state of force scale `scale` (N): max(force_tolerance,
/// relative_tolerance·F), refused below [`REACHABLE`]·F. F = 0 (no load, no reaction) gives 0:
/// only an exactly zero residual converges then, which a zero-load increment has.
pub fn residual_tolerance(settings: &NewtonSettings, scale: f64) -> Result<f64, NewtonError> {
    let tolerance = settings
        .force_tolerance
        .max(settings.relative_tolerance * scale);
    if !(settings.force_tolerance >= 0.0 && settings.relative_tolerance >= 0.0) {
        return Err(NewtonError::Setting {
            name: "force_tolerance / relative_tolerance",
            reason: format!(
                "{} N / {} (must be ≥ 0)",
                settings.force_tolerance, settings.relative_tolerance
            ),
        });
    }
    if tolerance < REACHABLE * scale {
        return Err(NewtonError::Setting {
            name: "force_tolerance",
            reason: format!(
                "a residual tolerance of {tolerance:.3e} N cannot be reached for forces of \
                 {scale:.3e} N in double precision (the smallest is {:.3e} N, {REACHABLE:e} of them)",
                REACHABLE * scale
            ),
        });
    }
    Ok(tolerance)
}

/// A rise of the count of negative pivots accepted as real: it persisted down to the smallest
/// increment the inertia guard tries, so a bifurcation (or limit) point lies in (`from`, λ] of
/// the increment that records it (Sylvester's law of inertia on the symmetric tangent, eq.
/// 2.1.3: an eigenvalue of K_T crossed zero).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Bifurcation {
    /// Load factor of the last accepted state before the crossing.
    pub from: f64,
    /// Negative pivots there.
    pub before: usize,
    /// Negative pivots at the end of the increment.
    pub after: usize,
}

/// The record of one attempt at one load level.
#[derive(Debug, Clone, PartialEq)]
pub struct IncrementReport {
    /// Load factor.
    pub lambda: f64,
    /// ‖r‖∞ before the first iteration.
    pub initial_residual: f64,
    /// The residual tolerance of the last state evaluated, N ([`residual_tolerance`]).
    pub tolerance: f64,
    /// Iterations.
    pub iterations: Vec<IterationRecord>,
    /// How it ended.
    pub termination: Termination,
    /// Set by path following on an accepted increment over which the count of negative pivots
    /// rose (see [`Bifurcation`]); None otherwise.
    pub bifurcation: Option<Bifurcation>,
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

/// Negative pivots of the tangent at (u, λ), from one assembly and one factorisation with a
/// new solver of `kind`: the stability test of a converged state (thesis §3.2: the trivial
/// path past a bifurcation has K_T with negative eigenvalues) for strategies whose last
/// factorisation belongs to an older state (a kept tangent, BFGS). `u` is taken as it is.
/// [`PathSolver::inertia_at`](crate::PathSolver::inertia_at) does the same with a solver kept
/// over the levels of a sweep, and keeps the factorisation for the next one.
pub fn negative_pivots_at(
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    lambda: f64,
    kind: SolverKind,
) -> Result<usize, NewtonError> {
    crate::PathSolver::new(problem, kind)?.inertia_at(problem, u, lambda)
}

/// Solves r(u, λ) = 0 from the current `u` (updated in place, also when not converged; the
/// caller keeps a copy to restart from). `solver` must have analysed the problem's pattern;
/// `k` is the tangent storage. Nothing is reused from earlier calls (see
/// [`solve_increment_with`]).
pub fn solve_increment(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    lambda: f64,
    settings: &NewtonSettings,
    solver: &mut dyn LinearSolver,
    k: &mut SymmetricMatrix,
) -> Result<IncrementReport, NewtonError> {
    let mut cache = TangentCache::new();
    solve_increment_with(problem, u, lambda, settings, solver, k, &mut cache)
}

/// [`solve_increment`] with a [`TangentCache`] carried between increments: with
/// `settings.keep_tangent` the factorisation `solver` holds (and the BFGS pairs) serve the next
/// increment too, until an iteration converges too slowly (`refactor_ratio`) or `refactor_every`
/// iterations have used it. Each iteration: direction d = −K⁻¹r (or −Hr with BFGS pairs),
/// the line search (line_search.rs: the full step, the energy, halving on ‖r‖∞), then the
/// convergence test.
///
/// Each attempt runs in a `tracing` span `attempt` (field `lambda`) and reports through
/// `tracing` events (target [`TRACE_TARGET`](crate::TRACE_TARGET), nothing is printed): one `iteration`
/// event per iteration (fields `lambda`, `iteration`, `residual` ‖r‖∞ in N, `correction`
/// ‖αΔu‖∞, `step` α, `negative_pivots`, −1 when no factorisation was made, `tolerance`) and
/// one `attempt` event at its end (`lambda`, `iterations`, `converged`, `termination`);
/// path following adds a `refused` event (`lambda`, `termination`) for an attempt the inertia
/// guard refuses.
pub fn solve_increment_with(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    lambda: f64,
    settings: &NewtonSettings,
    solver: &mut dyn LinearSolver,
    k: &mut SymmetricMatrix,
    cache: &mut TangentCache,
) -> Result<IncrementReport, NewtonError> {
    iterate(problem, u, lambda, settings, (solver, k, cache), false)
}

/// The Newton iterations of [`solve_increment_with`] (thesis §2.1: K_T(u)·Δu = −r(u, λ),
/// u ← u + α·Δu); with `iterate_once` at least one iteration even if the start already meets
/// the tolerance (after the tangent predictor, whose start may: the iteration's factorisation
/// gives the inertia of the converged state, which path following and the stability test
/// need). Each iteration: the tangent factorised when due ([`refactor`]), the direction, the
/// line search ([`line_search`]), the BFGS pair, the convergence tests.
pub(crate) fn iterate(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    lambda: f64,
    settings: &NewtonSettings,
    tangent: (
        &mut dyn LinearSolver,
        &mut SymmetricMatrix,
        &mut TangentCache,
    ),
    iterate_once: bool,
) -> Result<IncrementReport, NewtonError> {
    let span = tracing::debug_span!(target: crate::TRACE_TARGET, "attempt", lambda);
    let _entered = span.enter();
    let report = iterations(problem, u, lambda, settings, tangent, iterate_once)?;
    tracing::debug!(
        target: crate::TRACE_TARGET,
        event = "attempt",
        lambda,
        iterations = report.iterations.len(),
        converged = report.converged(),
        termination = %report.termination,
    );
    Ok(report)
}

/// The iterations of [`iterate`].
fn iterations(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    lambda: f64,
    settings: &NewtonSettings,
    (solver, k, cache): (
        &mut dyn LinearSolver,
        &mut SymmetricMatrix,
        &mut TangentCache,
    ),
    iterate_once: bool,
) -> Result<IncrementReport, NewtonError> {
    check_iteration(settings)?;
    if !settings.keep_tangent {
        cache.invalidate();
    }
    let n = problem.n();
    problem.prescribe(u, lambda);
    let mut r = vec![0.0; n];
    // The tangent at u is wanted with the first residual unless a kept one will do.
    let reuse = cache.serves(settings);
    let scale = problem.evaluate(u, lambda, &mut r, if reuse { None } else { Some(k) })?;
    let mut k_current = !reuse;
    // Judged against the force scale of each new state (after a predictor, the start's).
    let mut tolerance = residual_tolerance(settings, scale)?;
    let mut norm = norm_inf(&r);
    let mut report = IncrementReport {
        lambda,
        initial_residual: norm,
        tolerance,
        iterations: Vec::new(),
        termination: Termination::MaxIterations,
        bifurcation: None,
    };
    if !norm.is_finite() {
        report.termination = Termination::NonFinite;
        return Ok(report);
    }
    if norm <= tolerance && !iterate_once {
        report.termination = Termination::Converged;
        return Ok(report);
    }
    // (The start may meet the tolerance already with `iterate_once`.)
    let initial = norm.max(tolerance);
    let mut trial_u = vec![0.0; n];
    let mut trial_r = vec![0.0; n];
    for _ in 0..settings.max_iterations {
        let tangent: (&mut dyn LinearSolver, _, _) = (&mut *solver, &mut *k, &mut *cache);
        let pivots = match refactor(problem, u, lambda, &mut r, settings, tangent, k_current)? {
            Refactor::Kept => None,
            Refactor::Made(pivots) => Some(pivots),
            Refactor::Singular(why) => {
                report.termination = Termination::Singular(why);
                return Ok(report);
            }
        };
        cache.age += 1;
        let bfgs_pairs = cache.pairs.len();
        let bound = direction_bound(settings, tolerance, norm);
        let mut du = match cache.direction(&r, solver, Some(bound)) {
            Ok(d) => d,
            Err(e) => {
                cache.invalidate();
                report.termination = Termination::Singular(e.to_string());
                return Ok(report);
            }
        };
        problem.expand(&mut du);
        // The next iteration refactors by count: evaluate the tangent with the residual
        // (not after the last iteration allowed: no next iteration uses it).
        let last = report.iterations.len() + 1 >= settings.max_iterations;
        let need_k = cache.age >= settings.refactor_every && !last;
        let trial = (trial_u.as_mut_slice(), trial_r.as_mut_slice());
        let (alpha, trial_scale) = line_search(
            problem,
            (u, &du, &r, lambda, norm),
            (settings, tolerance),
            need_k.then_some(&mut *k),
            trial,
        )?;
        let previous = norm;
        norm = norm_inf(&trial_r);
        k_current = need_k;
        if settings.quasi_newton > 0 && norm.is_finite() {
            let s: Vec<f64> = trial_u.iter().zip(u.iter()).map(|(a, b)| a - b).collect();
            let y: Vec<f64> = trial_r.iter().zip(&r).map(|(a, b)| a - b).collect();
            cache.push_pair(s, y, settings.quasi_newton);
        }
        // An old tangent that no longer pulls the residual down is replaced next iteration.
        let pulled_down = norm <= settings.refactor_ratio * previous;
        cache.slow = pivots.is_none() && !pulled_down;
        u.copy_from_slice(&trial_u);
        r.copy_from_slice(&trial_r);
        report.iterations.push(IterationRecord {
            residual: norm,
            step: alpha,
            increment: alpha * norm_inf(&du),
            negative_pivots: pivots,
            bfgs_pairs,
        });
        tracing::debug!(
            target: crate::TRACE_TARGET,
            event = "iteration",
            lambda,
            iteration = report.iterations.len(),
            residual = norm,
            correction = alpha * norm_inf(&du),
            step = alpha,
            negative_pivots = pivots.map_or(-1, |p| p as i64),
            tolerance,
        );
        if !norm.is_finite() || u.iter().any(|x| !x.is_finite()) {
            cache.invalidate();
            report.termination = Termination::NonFinite;
            return Ok(report);
        }
        if trial_scale.is_finite() {
            tolerance = residual_tolerance(settings, trial_scale)?;
            report.tolerance = tolerance;
        }
        let step_small = settings.displacement_tolerance <= 0.0
            || alpha * norm_inf(&du) <= settings.displacement_tolerance * norm_inf(u);
        if norm <= tolerance && step_small {
            report.termination = Termination::Converged;
            return Ok(report);
        }
        if initial > 0.0 && norm > 1e8 * initial {
            cache.invalidate();
            report.termination = Termination::Diverged;
            return Ok(report);
        }
        if let Some(stop) = early_stop(settings, &report, tolerance) {
            cache.invalidate();
            report.termination = stop;
            return Ok(report);
        }
    }
    cache.invalidate();
    Ok(report)
}

/// CalculiX's checks of an unconverged attempt after its i-th iteration (checkconvergence):
/// from I_0 ([`NewtonSettings::divergence_check_from`]) on, r_{i−1} > r_{i−2} and r_i > r_{i−2}
/// (r_0 the initial residual) is divergence; from I_R
/// ([`NewtonSettings::slow_check_from`]) on, while the residual falls, the logarithmic
/// estimate i + ln(tol/r_i)/ln(r_i/r_{i−1}) of the iterations to convergence (linear
/// convergence at the last rate) above `max_iterations` is too slow.
fn early_stop(
    settings: &NewtonSettings,
    report: &IncrementReport,
    tolerance: f64,
) -> Option<Termination> {
    let i = report.iterations.len();
    let r = |k: usize| match k {
        0 => report.initial_residual,
        k => report.iterations[k - 1].residual,
    };
    let from = |n: usize| n > 0 && i >= n;
    if from(settings.divergence_check_from) && i >= 2 && r(i - 1) > r(i - 2) && r(i) > r(i - 2) {
        return Some(Termination::Diverging);
    }
    if from(settings.slow_check_from) && r(i) < r(i - 1) && tolerance > 0.0 {
        let more = (tolerance / r(i)).ln() / (r(i) / r(i - 1)).ln();
        let estimate = (i as f64 + more).ceil();
        if estimate > settings.max_iterations as f64 {
            return Some(Termination::TooSlow {
                estimate: estimate.min(1e9) as usize,
            });
        }
    }
    None
}

/// Refuses `refactor_every` or `max_iterations` of 0 and a `refactor_ratio` not above 0.
fn check_iteration(settings: &NewtonSettings) -> Result<(), NewtonError> {
    if settings.refactor_every == 0 || settings.max_iterations == 0 {
        return Err(NewtonError::Setting {
            name: "refactor_every / max_iterations",
            reason: "must be ≥ 1".into(),
        });
    }
    if settings.refactor_ratio.is_nan() || settings.refactor_ratio <= 0.0 {
        return Err(NewtonError::Setting {
            name: "refactor_ratio",
            reason: format!("{} (must be > 0)", settings.refactor_ratio),
        });
    }
    Ok(())
}

/// What [`refactor`] did.
enum Refactor {
    /// The kept factorisation serves this iteration.
    Kept,
    /// A factorisation made at u, with its negative pivots.
    Made(usize),
    /// The tangent at u could not be factorised (the solver's message); the cache is empty.
    Singular(String),
}

/// Factorises K_T(u) when the cache holds no factorisation, or one used `refactor_every`
/// times, or one that stopped pulling the residual down; the tangent is evaluated first
/// (with the residual into `r`) unless the last evaluation made it (`k_current`).
fn refactor(
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    lambda: f64,
    r: &mut [f64],
    settings: &NewtonSettings,
    (solver, k, cache): (
        &mut dyn LinearSolver,
        &mut SymmetricMatrix,
        &mut TangentCache,
    ),
    k_current: bool,
) -> Result<Refactor, NewtonError> {
    if cache.factored && cache.age < settings.refactor_every && !cache.slow {
        return Ok(Refactor::Kept);
    }
    if !k_current {
        problem.evaluate(u, lambda, r, Some(k))?;
    }
    match solver.factorize(k) {
        Ok(f) => {
            *cache = TangentCache::factored_now();
            Ok(Refactor::Made(f.negative_pivots))
        }
        Err(e) => {
            cache.invalidate();
            Ok(Refactor::Singular(e.to_string()))
        }
    }
}
