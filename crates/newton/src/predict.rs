//! The tangent predictor of an increment whose prescribed values change (displacement
//! control): the free DOFs move with the prescribed ones before Newton starts.

use crate::session::StartTangent;
use crate::{NewtonError, NonlinearProblem, PathSolver};

/// Moves `u`, a state converged at `from`, to the start of the increment to `to`:
/// u ← u + Δu with Δu_c = u_c(to) − u_c(from) and K_ff Δu_f = −(r_f(u, from) + K_fc Δu_c −
/// Δf_ext) ([`NonlinearProblem::coupling_force`]): the first Newton step of eq. 2.1.3
/// linearised at `u` instead of at the state where only the prescribed DOFs jumped, whose
/// distorted cells can lead Newton to a spurious equilibrium. K is the factorisation `session`
/// holds for `u` — the last one of the increment that reached it, so no extra factorisation,
/// and r(u, from) is then taken as zero (that increment converged under the same loads) — or
/// one made at `u` with its residual ([`PathSolver::start_tangent`]: dead loads changed since,
/// e.g. a perturbation switched on, are then in r); with BFGS pairs the updated inverse.
/// With `apply` false `u` is left as it is: only whether the prescribed values change, and the
/// start's factorisation (hence its inertia, [`PathSolver::pivots_at`]) if they do.
pub(crate) fn tangent_predictor(
    problem: &mut dyn NonlinearProblem,
    u: &mut [f64],
    from: f64,
    to: f64,
    session: &mut PathSolver,
    apply: bool,
) -> Result<Prediction, NewtonError> {
    let mut c = vec![0.0; problem.n()];
    if !problem.coupling_force(u, from, to, &mut c)? {
        return Ok(Prediction::NoChange);
    }
    match session.start_tangent(problem, u, from)? {
        StartTangent::Singular => return Ok(Prediction::Changed),
        StartTangent::Kept => {}
        StartTangent::Made(r) => {
            for (c, r) in c.iter_mut().zip(&r) {
                *c += r;
            }
        }
    }
    if !apply {
        return Ok(Prediction::Changed);
    }
    let Ok(mut du) = session.cache.direction(&c, session.solver.as_mut(), None) else {
        session.cache.invalidate();
        return Ok(Prediction::Changed);
    };
    problem.expand(&mut du);
    if du.iter().any(|x| !x.is_finite()) {
        return Ok(Prediction::Changed);
    }
    for (x, d) in u.iter_mut().zip(&du) {
        *x += d;
    }
    problem.prescribe(u, to);
    Ok(Prediction::Moved)
}

/// An extrapolated start for [`predicted_increment`] ([`Extrapolation::predict`](crate::Extrapolation::predict)).
#[derive(Debug, Clone, Copy)]
pub struct Guess<'a> {
    /// The predicted state (prescribed DOFs are set by the problem at `to`).
    pub u: &'a [f64],
    /// Keep it only if ‖r(guess, to)‖∞ ≤ ‖r(u, to)‖∞, the plain start's (two residual
    /// evaluations, no factorisation); else start from the last converged state.
    pub guarded: bool,
}

/// One increment from the state `u` converged at `from` to `to`, for a driver that controls
/// its own increments (a deck step's automatic incrementation): the tangent predictor when the
/// prescribed values change (as [`follow_path_with`](crate::follow_path_with) does), else the
/// extrapolated `guess` when given (with its residual guard when asked), then Newton. `u` is
/// replaced by the converged state only if the attempt converged; the session then keeps its
/// factorisation for the next increment's predictor. No stepping and no inertia guard: a
/// failed attempt is the caller's to cut back. If the loads or the constrained DOFs change
/// between increments other than through the λ ramp, call [`PathSolver::invalidate`] first.
pub fn predicted_increment(
    problem: &mut dyn NonlinearProblem,
    u: &mut Vec<f64>,
    from: f64,
    to: f64,
    guess: Option<Guess<'_>>,
    settings: &crate::NewtonSettings,
    session: &mut PathSolver,
) -> Result<crate::IncrementReport, NewtonError> {
    session.fit(problem, settings.solver)?;
    let mut trial = u.clone();
    let apply = !session.cache.serves(settings);
    let prediction = tangent_predictor(problem, &mut trial, from, to, session, apply)?;
    let predicted = prediction == Prediction::Moved;
    if let (false, Some(g)) = (predicted, guess)
        && (!g.guarded || no_worse(problem, g.u, &trial, to)?)
    {
        trial.copy_from_slice(g.u);
    }
    let PathSolver {
        solver, k, cache, ..
    } = &mut *session;
    let report = crate::solve::iterate(
        problem,
        &mut trial,
        to,
        settings,
        (solver.as_mut(), k, cache),
        predicted,
    )?;
    if report.converged() {
        session.accept(&trial, report.negative_pivots());
        *u = trial;
    } else {
        session.invalidate();
    }
    Ok(report)
}

/// Whether ‖r(guess, λ)‖∞ ≤ ‖r(plain, λ)‖∞ (each with the prescribed values at λ): the guard
/// of an extrapolated start.
fn no_worse(
    problem: &mut dyn NonlinearProblem,
    guess: &[f64],
    plain: &[f64],
    lambda: f64,
) -> Result<bool, NewtonError> {
    let mut norms = [0.0; 2];
    let mut r = vec![0.0; problem.n()];
    for (norm, start) in norms.iter_mut().zip([guess, plain]) {
        let mut x = start.to_vec();
        problem.prescribe(&mut x, lambda);
        problem.evaluate(&x, lambda, &mut r, None)?;
        *norm = r.iter().fold(0.0f64, |m, v| m.max(v.abs()));
    }
    Ok(norms[0] <= norms[1])
}

/// What [`tangent_predictor`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Prediction {
    /// No prescribed value changes (or the problem has no coupling door): Newton's first
    /// iteration from the start state is the tangent step already.
    NoChange,
    /// Prescribed values change; `u` was not moved (not asked to, or the tangent at the start
    /// is singular).
    Changed,
    /// `u` moved to the predicted state.
    Moved,
}

#[cfg(test)]
mod tests {
    use crate::{
        NewtonError, NewtonSettings, NonlinearProblem, Stepping, Termination, follow_path,
    };
    use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
    use std::sync::Arc;

    /// One free DOF x pulled by one prescribed DOF c = λ·`reach` through a softening spring:
    /// r = g(x − c), g(s) = s − s³/3. Equilibria: s = 0 (K = 1, the path x = c, stable) and
    /// s = ±√3 (K = −2, unstable). Newton from x = 0 after a jump of c to 1.5 (s = −1.5,
    /// K = −1.25) goes to s = −√3; the tangent predictor moves x with c (K_ff Δx = −K_fc Δc =
    /// K Δc, so Δx = Δc) and lands on s = 0.
    struct Spring {
        reach: f64,
        pattern: Arc<SymmetricPattern>,
    }

    impl Spring {
        fn new(reach: f64) -> Self {
            let pattern = SymmetricPattern::from_dof_lists(2, &[vec![0, 1]]).unwrap();
            Self {
                reach,
                pattern: Arc::new(pattern),
            }
        }
    }

    fn g(s: f64) -> (f64, f64) {
        (s - s * s * s / 3.0, 1.0 - s * s)
    }

    impl NonlinearProblem for Spring {
        fn n(&self) -> usize {
            2
        }
        fn pattern(&self) -> Arc<SymmetricPattern> {
            self.pattern.clone()
        }
        fn prescribe(&self, u: &mut [f64], lambda: f64) {
            u[1] = lambda * self.reach;
        }
        fn coupling_force(
            &mut self,
            u: &[f64],
            from: f64,
            to: f64,
            out: &mut [f64],
        ) -> Result<bool, NewtonError> {
            let (_, k) = g(u[0] - u[1]);
            out[0] = -k * (to - from) * self.reach;
            out[1] = 0.0;
            Ok(to != from)
        }
        fn evaluate(
            &mut self,
            u: &[f64],
            _lambda: f64,
            r: &mut [f64],
            tangent: Option<&mut SymmetricMatrix>,
        ) -> Result<f64, NewtonError> {
            let (f, k) = g(u[0] - u[1]);
            r[0] = f;
            r[1] = 0.0;
            if let Some(t) = tangent {
                t.set_zero();
                t.add(0, 0, k).unwrap();
                t.add(1, 1, 1.0).unwrap();
            }
            Ok(1.0)
        }
    }

    /// One DOF under a dead load, r = x + x³ − λ, K = 1 + 3x² (no prescribed values, so the
    /// guess decides the start). From x = 0 to λ = 1 the plain start has |r| = 1; a guess
    /// x = 2 has r = 9 (the guard drops it), x = 0.6 has |r| = 0.184 (kept).
    struct Cubic(Arc<SymmetricPattern>);

    impl NonlinearProblem for Cubic {
        fn n(&self) -> usize {
            1
        }
        fn pattern(&self) -> Arc<SymmetricPattern> {
            self.0.clone()
        }
        fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
        fn evaluate(
            &mut self,
            u: &[f64],
            lambda: f64,
            r: &mut [f64],
            tangent: Option<&mut SymmetricMatrix>,
        ) -> Result<f64, NewtonError> {
            let x = u[0];
            r[0] = x + x * x * x - lambda;
            if let Some(t) = tangent {
                t.set_zero();
                t.add(0, 0, 1.0 + 3.0 * x * x).unwrap();
            }
            Ok(1.0)
        }
    }

    #[test]
    fn the_guard_keeps_a_better_guess_and_drops_a_worse_one() {
        let pattern = Arc::new(SymmetricPattern::from_dof_lists(1, &[vec![0]]).unwrap());
        let settings = NewtonSettings::default();
        for (guess, guarded, start) in [(2.0, true, 1.0), (2.0, false, 9.0), (0.6, true, 0.184)] {
            let mut problem = Cubic(pattern.clone());
            let mut session = crate::PathSolver::new(&problem, settings.solver).unwrap();
            let mut u = vec![0.0];
            let g = [guess];
            let report = crate::predicted_increment(
                &mut problem,
                &mut u,
                0.0,
                1.0,
                Some(crate::Guess { u: &g, guarded }),
                &settings,
                &mut session,
            )
            .unwrap();
            assert!(
                (report.initial_residual - start).abs() < 1e-12,
                "{guess} {guarded}: {report:?}"
            );
            assert!(report.converged());
            // x + x³ = 1: x = 0.6823278038280193.
            assert!((u[0] - 0.6823278038280193).abs() < 1e-8, "{u:?}");
        }
    }

    fn one_step(stepping: Stepping) -> (Vec<f64>, crate::PathReport) {
        let settings = NewtonSettings {
            force_tolerance: 1e-12,
            ..NewtonSettings::default()
        };
        let stepping = Stepping {
            initial: 1.0,
            ..stepping
        };
        let mut problem = Spring::new(1.5);
        let mut u = vec![0.0; 2];
        let path = follow_path(&mut problem, &mut u, &[1.0], &settings, &stepping).unwrap();
        (u, path)
    }

    #[test]
    fn the_predictor_moves_the_free_dof_with_the_prescribed_one() {
        let (u, path) = one_step(Stepping::default());
        assert_eq!(path.attempts.len(), 1);
        // Exact here (Δx = Δc keeps s = 0): one iteration, made for the end state's inertia.
        assert_eq!(path.attempts[0].iterations.len(), 1);
        assert_eq!(path.attempts[0].initial_residual, 0.0);
        assert!((u[0] - 1.5).abs() < 1e-12);
        assert_eq!(path.attempts[0].negative_pivots(), Some(0));
    }

    #[test]
    fn without_the_predictor_the_guard_refuses_the_unstable_state() {
        let bare = Stepping {
            tangent_predictor: false,
            ..Stepping::default()
        };
        let (u, path) = one_step(Stepping {
            inertia_guard: 0.0,
            ..bare.clone()
        });
        // The premise: one step lands on s = −√3 (one negative pivot).
        assert!((u[0] - u[1] + 3f64.sqrt()).abs() < 1e-9, "{u:?}");
        assert_eq!(path.attempts[0].negative_pivots(), Some(1));
        let (u, path) = one_step(bare);
        assert_eq!(
            path.attempts[0].termination,
            Termination::InertiaChanged {
                before: 0,
                after: 1
            }
        );
        assert!((u[0] - 1.5).abs() < 1e-9, "{u:?}");
        assert!(path.bifurcations().is_empty());
    }
}
