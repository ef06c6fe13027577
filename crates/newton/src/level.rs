//! One level of a load sweep: path following to the level, the stability test of the
//! converged state (thesis §2.5: the inertia of the tangent) and, past a bifurcation, the
//! perturbation protocol (§3.2) onto the buckled branch.

use crate::{
    DeadLoads, IncrementReport, NewtonError, NewtonSettings, NonlinearProblem, PathSolver,
    Stepping, follow_path_with, perturbed_step_with,
};

/// The perturbed step is taken in this many increments of the level's step: the perturbed
/// (imperfect) path is followed continuously onto the branch the perturbation favours (one
/// increment can land on the wrong branch: seen on the 60 mm circle; eighths cost 17 % more
/// time for the same answer on the reference models).
pub(crate) const PERTURBED_INCREMENTS: f64 = 4.0;

/// The perturbed step's iteration limit, in multiples of the level's: just past the
/// bifurcation the branch the force is removed onto is nearly flat (the amplitude's restoring
/// stiffness vanishes with ε − ε_b) and Newton, its line search cutting most steps, closes in
/// linearly: on the through-width example scene 56 iterations at 2.3 % past ε_b, about 5 at
/// 80 % past.
pub(crate) const PERTURBED_PATIENCE: usize = 4;

/// What [`solve_level`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct LevelReport {
    /// Every attempt, in order (those of a perturbed redo after the first pass's).
    pub attempts: Vec<IncrementReport>,
    /// Whether the perturbation was applied (and removed) on this level.
    pub perturbed: bool,
    /// Negative pivots of the tangent at the final state (None when no factorisation gave it).
    pub negative_pivots: Option<usize>,
}

/// Solves one level: from the converged state `u` at load factor `from` to `to`. If the
/// converged state is unstable (negative pivots of K_T: the trivial path past a bifurcation,
/// §2.5) and a `perturbation` is given, the step is redone from `from` by the §3.2 protocol
/// ([`perturbed_step`](crate::perturbed_step): perturbation on along the step, in quarters of
/// it with 4× the iterations, removed at `to`) to land on the buckled branch, on `session`'s
/// analysis ([`perturbed_redo_with`]); `perturbation` lists (DOF, force) pairs, empty for
/// none. The first increment is at most the level's step.
///
/// The thesis applied the perturbation at the first level and left it to the analyst to pick
/// that level above the buckling strain; here the change of inertia picks the level, so a
/// sweep may start below buckling (Fig. 5.1.1's flat part) and still find the branch. With a
/// kept tangent (BFGS) the last factorisation may belong to an older state, so the inertia is
/// then taken from one extra factorisation at the converged state
/// ([`PathSolver::inertia_at`]), which `session` keeps as the next level's starting tangent.
#[allow(clippy::too_many_arguments)]
pub fn solve_level<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    from: f64,
    to: f64,
    perturbation: &[(usize, f64)],
    newton: &NewtonSettings,
    stepping: &Stepping,
    session: &mut PathSolver,
) -> Result<LevelReport, NewtonError> {
    let stepping = Stepping {
        initial: stepping.initial.min((to - from).abs().max(stepping.min)),
        ..stepping.clone()
    };
    let start = u.clone();
    let mut attempts =
        follow_path_with(problem, u, from, &[to], newton, &stepping, session)?.attempts;
    let mut pivots = inertia(problem, u, to, newton, &attempts, session)?;
    let unstable = pivots.is_some_and(|p| p > 0);
    let mut perturbed = false;
    if unstable && !perturbation.is_empty() {
        *u = start;
        attempts.extend(perturbed_redo_with(
            problem,
            u,
            (from, to),
            perturbation,
            newton,
            &stepping,
            session,
        )?);
        perturbed = true;
        pivots = inertia(problem, u, to, newton, &attempts, session)?;
    }
    Ok(LevelReport {
        attempts,
        perturbed,
        negative_pivots: pivots,
    })
}

/// The perturbation protocol's redo of a level (thesis §3.2) from the level's start `u`: the
/// perturbed step in 4 equal increments with 4 times the iteration limit, the perturbation applied and removed
/// ([`perturbed_step`](crate::perturbed_step)), with a solver of its own. Shared by the
/// callers that follow a perturbed level again (the contact loop's fallback);
/// [`perturbed_redo_with`] is the same on the caller's session.
pub fn perturbed_redo<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    (from, to): (f64, f64),
    perturbation: &[(usize, f64)],
    newton: &NewtonSettings,
    stepping: &Stepping,
) -> Result<Vec<IncrementReport>, NewtonError> {
    let mut session = PathSolver::new(problem, newton.solver)?;
    perturbed_redo_with(
        problem,
        u,
        (from, to),
        perturbation,
        newton,
        stepping,
        &mut session,
    )
}

/// [`perturbed_redo`] with `session`'s solver (the level's: [`solve_level`], the arc-length
/// level) through [`perturbed_step_with`]: no new symbolic analysis (fill-reducing orderings
/// compared, symbolic factorisation) for the perturbed path nor for the removal; the steps are
/// bitwise those of new solvers.
#[allow(clippy::too_many_arguments)]
pub fn perturbed_redo_with<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    (from, to): (f64, f64),
    perturbation: &[(usize, f64)],
    newton: &NewtonSettings,
    stepping: &Stepping,
    session: &mut PathSolver,
) -> Result<Vec<IncrementReport>, NewtonError> {
    let part = ((to - from) / PERTURBED_INCREMENTS).abs().max(stepping.min);
    let fine = Stepping {
        initial: part,
        max: part,
        ..stepping.clone()
    };
    let patient = NewtonSettings {
        max_iterations: PERTURBED_PATIENCE * newton.max_iterations,
        ..newton.clone()
    };
    perturbed_step_with(
        problem,
        u,
        (from, to),
        perturbation,
        &patient,
        &fine,
        session,
    )
}

/// Negative pivots at the converged state `u` at λ = `to`: with a kept tangent (BFGS, or
/// modified Newton's `refactor_every` > 1, whose last factorisation may be several iterations
/// old) one extra factorisation there ([`PathSolver::inertia_at`]), else those of the last
/// converged attempt's last factorisation.
fn inertia(
    problem: &mut dyn NonlinearProblem,
    u: &[f64],
    to: f64,
    newton: &NewtonSettings,
    attempts: &[IncrementReport],
    session: &mut PathSolver,
) -> Result<Option<usize>, NewtonError> {
    if newton.keep_tangent || newton.refactor_every > 1 {
        session.inertia_at(problem, u, to).map(Some)
    } else {
        Ok(attempts
            .iter()
            .rev()
            .find(|a| a.converged())
            .and_then(IncrementReport::negative_pivots))
    }
}

#[cfg(test)]
mod tests {
    use crate::perturb::tests::compressed;
    use crate::{NewtonSettings, NonlinearProblem, PathSolver, Stepping, solve_level};

    /// One level from 0 to 1.3·ε_c on the through-width model: without a perturbation the
    /// converged state is the trivial path past the bifurcation (negative pivots); with one,
    /// the level is redone through the §3.2 protocol and ends on the buckled branch, stable
    /// (no negative pivot) and lifted (above 0.3·h; the derivation in
    /// `perturb::tests::a_wrapped_problem_follows_the_protocol_bitwise_like_the_bare_one`).
    #[test]
    fn an_unstable_level_is_redone_with_the_perturbation() {
        let newton = NewtonSettings::default();
        let stepping = Stepping {
            initial: 0.25,
            max: 0.25,
            ..Stepping::default()
        };
        let run = |perturbation: &[(usize, f64)]| {
            let (mut problem, top, h) = compressed();
            let mut session = PathSolver::new(&problem, newton.solver).unwrap();
            let mut u = vec![0.0; problem.n()];
            let level = solve_level(
                &mut problem,
                &mut u,
                0.0,
                1.0,
                perturbation,
                &newton,
                &stepping,
                &mut session,
            )
            .unwrap();
            (level, u[3 * top + 2] / h)
        };
        let (plain, w) = run(&[]);
        assert!(!plain.perturbed);
        assert!(plain.negative_pivots.is_some_and(|p| p > 0), "{plain:?}");
        assert!(w.abs() < 0.3, "w/h = {w}");
        let (_, top, _) = compressed();
        let (level, w) = run(&[(3 * top + 2, 0.5)]);
        assert!(level.perturbed);
        assert_eq!(level.negative_pivots, Some(0));
        assert!(w > 0.3, "w/h = {w}");
        assert!(level.attempts.len() > plain.attempts.len());
    }
}
