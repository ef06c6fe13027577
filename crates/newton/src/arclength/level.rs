//! One level of a sweep by arc length: the path is followed by arc length (module docs of
//! [`crate::follow_arc_length`]) until λ passes the level, then Newton at the level's λ from
//! the state interpolated between the two increments around it lands on it; the stability test
//! and the perturbation protocol (thesis §2.5, §3.2) as [`solve_level`](crate::solve_level).

use super::{ArcIncrement, ArcLength, ArcStop, follow_arc_length};
use crate::level::perturbed_redo_with;
use crate::{
    DeadLoads, IncrementReport, LevelReport, NewtonError, NewtonSettings, NonlinearProblem,
    PathSolver, Stepping, Termination,
};

/// The record of a converged arc-length increment as an [`IncrementReport`].
fn report_of(inc: &ArcIncrement) -> IncrementReport {
    IncrementReport {
        lambda: inc.lambda,
        initial_residual: inc.initial_residual,
        tolerance: inc.tolerance,
        iterations: inc.records.clone(),
        termination: Termination::Converged,
        bifurcation: None,
    }
}

/// Solves one level from the converged state `u` at `from` to `to` (> `from`) by arc length
/// (`arc`; its first increment at most the level's step), landing on `to` by Newton at fixed λ
/// from the linear interpolation between the last increment below `to` and the first at or
/// past it (λ_a < to ≤ λ_b: u = u_a + (to − λ_a)/(λ_b − λ_a)·(u_b − u_a)), or, if that fails,
/// from u_b. A limit point below `to` is passed (the path turns and comes back, within
/// `arc.max_increments`). Past a bifurcation (negative pivots at `to`) with a `perturbation`,
/// the level is redone by the §3.2 protocol ([`perturbed_step`](crate::perturbed_step),
/// `stepping` its increments, on `session`'s analysis), as [`solve_level`](crate::solve_level)
/// does.
#[allow(clippy::too_many_arguments)]
pub fn solve_level_arc<P: NonlinearProblem + DeadLoads>(
    problem: &mut P,
    u: &mut Vec<f64>,
    from: f64,
    to: f64,
    perturbation: &[(usize, f64)],
    newton: &NewtonSettings,
    arc: &ArcLength,
    stepping: &Stepping,
    session: &mut PathSolver,
) -> Result<LevelReport, NewtonError> {
    if to.partial_cmp(&from) != Some(std::cmp::Ordering::Greater) {
        return Err(NewtonError::Setting {
            name: "arc-length level",
            reason: format!("from λ = {from} to {to}: levels must rise"),
        });
    }
    let start = u.clone();
    let arc = ArcLength {
        initial: arc.initial.min(to - from),
        min: arc.min.min(arc.initial.min(to - from)),
        max_lpf: None,
        monitor: None,
        ..arc.clone()
    };
    let mut attempts = Vec::new();
    let mut below = (from, u.clone());
    let mut past: Option<f64> = None;
    let report = follow_arc_length(problem, u, from, newton, &arc, &mut |inc, state, _| {
        attempts.push(report_of(inc));
        if inc.lambda >= to {
            past = Some(inc.lambda);
            return true;
        }
        below = (inc.lambda, state.to_vec());
        false
    })?;
    let Some(lambda_b) = past else {
        let last = report.increments.last().map_or(from, |i| i.lambda);
        return Err(NewtonError::ArcLength {
            increment: report.increments.len(),
            lambda: last,
            arc: report.increments.last().map_or(arc.initial, |i| i.arc),
            cutbacks: 0,
            reason: format!(
                "the level λ = {to} was not reached ({}, at λ = {last})",
                stopped(report.stop)
            ),
        });
    };
    let (lambda_a, u_a) = below;
    let t = (to - lambda_a) / (lambda_b - lambda_a);
    let mut landed: Vec<f64> = u_a
        .iter()
        .zip(u.iter())
        .map(|(a, b)| a + t * (b - a))
        .collect();
    let mut landing = session.solve_at(problem, &mut landed, to, newton)?;
    if !landing.converged() {
        attempts.push(landing);
        landed.clone_from(u);
        landing = session.solve_at(problem, &mut landed, to, newton)?;
    }
    if !landing.converged() {
        return Err(NewtonError::ArcLength {
            increment: report.increments.len(),
            lambda: lambda_b,
            arc: report.increments.last().map_or(arc.initial, |i| i.arc),
            cutbacks: 0,
            reason: format!(
                "landing on the level λ = {to} from λ = {lambda_b}: {}",
                landing.termination
            ),
        });
    }
    *u = landed;
    let mut pivots = match landing.negative_pivots() {
        Some(p) => Some(p),
        None => Some(session.inertia_at(problem, u, to)?),
    };
    attempts.push(landing);
    let mut perturbed = false;
    if pivots.is_some_and(|p| p > 0) && !perturbation.is_empty() {
        *u = start;
        attempts.extend(perturbed_redo_with(
            problem,
            u,
            (from, to),
            perturbation,
            newton,
            stepping,
            session,
        )?);
        perturbed = true;
        pivots = Some(session.inertia_at(problem, u, to)?);
    }
    Ok(LevelReport {
        attempts,
        perturbed,
        negative_pivots: pivots,
    })
}

/// What an early stop of the path means here.
fn stopped(stop: ArcStop) -> &'static str {
    match stop {
        ArcStop::MaxLpf => "the maximum load factor was reached",
        ArcStop::Displacement => "the monitored displacement was reached",
        ArcStop::Increments => "the increments ran out",
        ArcStop::Observer => "stopped",
    }
}

#[cfg(test)]
mod tests {
    use crate::perturb::tests::compressed;
    use crate::{
        ArcLength, NewtonSettings, NonlinearProblem, PathSolver, Stepping, solve_level,
        solve_level_arc,
    };

    /// The through-width model from 0 to 1.3·ε_c in one level (its bifurcation inside): by arc
    /// length as by load control, the first pass ends on the trivial path (negative pivots),
    /// the perturbation protocol then lands both on the same stable buckled branch. The two
    /// final states meet ‖r‖∞ ≤ 1e-8·F each and the protocol after the first pass is the same
    /// (the same start, the same steps), so they agree to rounding of the landing: w/h within
    /// 1e-6.
    #[test]
    fn a_level_by_arc_length_lands_where_load_control_does() {
        let newton = NewtonSettings::default();
        let stepping = Stepping {
            initial: 0.25,
            max: 0.25,
            ..Stepping::default()
        };
        let (_, top, h) = compressed();
        let perturbation = [(3 * top + 2, 0.5)];
        let (mut a, mut b) = (compressed().0, compressed().0);
        let mut session = PathSolver::new(&a, newton.solver).unwrap();
        let mut ua = vec![0.0; a.n()];
        let load = solve_level(
            &mut a,
            &mut ua,
            0.0,
            1.0,
            &perturbation,
            &newton,
            &stepping,
            &mut session,
        )
        .unwrap();
        let mut session = PathSolver::new(&b, newton.solver).unwrap();
        let mut ub = vec![0.0; b.n()];
        let arc = ArcLength {
            initial: 0.25,
            ..ArcLength::default()
        };
        let by_arc = solve_level_arc(
            &mut b,
            &mut ub,
            0.0,
            1.0,
            &perturbation,
            &newton,
            &arc,
            &stepping,
            &mut session,
        )
        .unwrap();
        assert!(load.perturbed && by_arc.perturbed);
        assert_eq!(by_arc.negative_pivots, Some(0));
        let (wa, wb) = (ua[3 * top + 2] / h, ub[3 * top + 2] / h);
        assert!(wb > 0.3, "w/h = {wb}");
        assert!((wa - wb).abs() <= 1e-6, "{wa} against {wb}");
    }
}
