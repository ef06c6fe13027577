//! The thesis's perturbation load (§3.2): a transverse force converged with a compression level
//! as a dead load, then removed at the same level, so the solution lands on the postbuckled
//! branch. Generic over [`DeadLoads`], so a problem that wraps another can use it.

use crate::{
    IncrementReport, NewtonError, NewtonSettings, NonlinearProblem, PathReport, PathSolver,
    Stepping, follow_path_from, follow_path_with, solve_increment,
};

/// A problem whose external force has a λ-independent part: r(u, λ) = f_int(u) − λ·f_ref −
/// f_dead. The perturbation protocol of thesis §3.2 applies its transverse load as f_dead
/// (converged with a level) and then removes it (f_dead = 0) at the same λ.
pub trait DeadLoads {
    /// Sets the dead force at DOF `dof` to `value` (N), replacing the one there (0 removes it).
    /// Errors name the DOF (out of range) or the value (not finite).
    fn set_dead_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError>;
}

/// Sets the dead loads `loads` (DOF, force), each times `scale`.
fn set_scaled<P: DeadLoads>(
    problem: &mut P,
    loads: &[(usize, f64)],
    scale: f64,
) -> Result<(), NewtonError> {
    loads
        .iter()
        .try_for_each(|&(dof, f)| problem.set_dead_load(dof, scale * f))
}

/// The thesis's way onto the postbuckled branch (§3.2) over a whole path: the transverse
/// `perturbation` loads (DOF, force) act as dead loads while the path is followed from λ = 0 to
/// the first target; then they are removed at that λ by [`perturbed_step`] (all at once, and in
/// parts with cutback if that fails); the path then continues through the remaining targets.
/// A removal that fails even in the smallest part is a located
/// [`NewtonError::Perturbation`] naming the level and the share of the load still on.
pub fn perturbed_path<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    perturbation: &[(usize, f64)],
    targets: &[f64],
    settings: &NewtonSettings,
    stepping: &Stepping,
) -> Result<PathReport, NewtonError> {
    let Some((&first, rest)) = targets.split_first() else {
        return Ok(PathReport::default());
    };
    let attempts = perturbed_step(problem, u, 0.0, first, perturbation, settings, stepping)?;
    let mut report = PathReport {
        attempts,
        states: vec![(first, u.clone())],
    };
    let more = follow_path_from(problem, u, first, rest, settings, stepping)?;
    report.attempts.extend(more.attempts);
    report.states.extend(more.states);
    Ok(report)
}

/// The §3.2 protocol over one step: from `u` converged at load factor `from` (a stable state,
/// e.g. the last level before the trivial path lost stability), the `perturbation` dead loads
/// (DOF, force) act while the path is followed to `to` (with cutback, so the response bends
/// smoothly onto a branch instead of snapping); then they are removed at the same λ: all at
/// once as in the thesis, and if that does not converge in parts with cutback (as the thesis
/// did once in four parts, §4.2): a part that fails is halved, down to [`MIN_REMOVAL_PART`]
/// (1/64) of the load, and after a success the part doubles again. `u` is updated only on
/// success, and the dead loads are off afterwards either way; errors name the stage, and for
/// the removal the fraction of the load still on.
pub fn perturbed_step<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    from: f64,
    to: f64,
    perturbation: &[(usize, f64)],
    settings: &NewtonSettings,
    stepping: &Stepping,
) -> Result<Vec<IncrementReport>, NewtonError> {
    let mut session = PathSolver::new(problem, settings.solver)?;
    perturbed_step_with(
        problem,
        u,
        (from, to),
        perturbation,
        settings,
        stepping,
        &mut session,
    )
}

/// [`perturbed_step`] with the caller's [`PathSolver`] (the level's): its symbolic analysis
/// serves the perturbed path and the removal (the pattern is the same; the dead loads change
/// only the right-hand side), no new one. What the session held is forgotten before and
/// after (its factorisation and last state belong to the unperturbed problem): the steps are
/// those of a new session, bitwise.
#[allow(clippy::too_many_arguments)]
pub fn perturbed_step_with<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    (from, to): (f64, f64),
    perturbation: &[(usize, f64)],
    settings: &NewtonSettings,
    stepping: &Stepping,
    session: &mut PathSolver,
) -> Result<Vec<IncrementReport>, NewtonError> {
    forget(session);
    let mut trial = u.clone();
    set_scaled(problem, perturbation, 1.0)?;
    let loaded = follow_path_with(
        problem,
        &mut trial,
        from,
        &[to],
        settings,
        stepping,
        session,
    );
    let mut attempts = match loaded {
        Ok(report) => report.attempts,
        Err(e) => {
            forget(session);
            set_scaled(problem, perturbation, 0.0)?;
            return Err(e);
        }
    };
    let removed = remove_in_parts(
        problem,
        &mut trial,
        to,
        perturbation,
        settings,
        &mut attempts,
        session,
    );
    forget(session);
    if let Err(e) = removed {
        set_scaled(problem, perturbation, 0.0)?;
        return Err(e);
    }
    *u = trial;
    Ok(attempts)
}

/// Leaves `session` as a new one would be, its analysis kept: no factorisation vouched for,
/// no last state (so no inertia known for any state).
fn forget(session: &mut PathSolver) {
    session.cache.invalidate();
    session.state.clear();
    session.pivots = None;
}

/// The smallest part of the perturbation load [`perturbed_step`] removes in one solve: 1/64.
pub const MIN_REMOVAL_PART: f64 = 1.0 / 64.0;

/// Takes the perturbation load `perturbation` from fully on to off at λ = `lambda`, `u`
/// converged with it fully on: parts of the load, each a Newton solve at the same λ with
/// f_dead = (1 − removed)·f_pert, the part halved after a failure and doubled after a success
/// (at most the whole remainder).
fn remove_in_parts<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut [f64],
    lambda: f64,
    perturbation: &[(usize, f64)],
    settings: &NewtonSettings,
    attempts: &mut Vec<IncrementReport>,
    session: &mut PathSolver,
) -> Result<(), NewtonError> {
    session.fit(problem, settings.solver)?;
    let PathSolver { solver, k, .. } = session;
    let (mut remaining, mut part, mut cutbacks) = (1.0f64, 1.0f64, 0);
    while remaining > 0.0 {
        part = part.min(remaining);
        // Parts are powers of two of the whole load: the remainder stays exact.
        let next = remaining - part;
        set_scaled(problem, perturbation, next)?;
        let mut trial = u.to_vec();
        let r = solve_increment(problem, &mut trial, lambda, settings, solver.as_mut(), k)?;
        let ok = r.converged();
        let reason = r.termination.to_string();
        attempts.push(r);
        if ok {
            u.copy_from_slice(&trial);
            remaining = next;
            part *= 2.0;
        } else if part * 0.5 >= MIN_REMOVAL_PART {
            part *= 0.5;
            cutbacks += 1;
        } else {
            return Err(NewtonError::Perturbation {
                lambda,
                remaining: 100.0 * remaining,
                part,
                cutbacks,
                reason,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
pub(crate) mod tests;
