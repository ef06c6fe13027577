//! The error type of `nonlin3d-newton`.

/// Failures that stop path following (non-convergence of one attempt is a reported outcome,
/// see [`crate::Termination`]; running out of cutbacks is this error).
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum NewtonError {
    /// Assembly failed (e.g. an element inverted): names the cell; also invalid loads.
    #[error(transparent)]
    Assembly(#[from] nonlin3d_assembly::AssemblyError),
    /// A linear solve failed outside what cutback can cure (e.g. a pattern mismatch).
    #[error(transparent)]
    Solver(#[from] nonlin3d_solver::SolverError),
    /// The load step was cut back to the minimum and still did not converge.
    #[error(
        "no convergence towards λ = {}: stopped at λ = {} after {cutbacks} cutbacks (last attempt Δλ = {}: {reason})",
        sig6(*.target), sig6(*.reached), sig6(*.last_step)
    )]
    Cutback {
        /// Target load factor.
        target: f64,
        /// Last converged load factor.
        reached: f64,
        /// Cutbacks made.
        cutbacks: usize,
        /// The last step tried.
        last_step: f64,
        /// Why the last attempt failed.
        reason: String,
    },
    /// The attempts allowed towards one target ([`crate::Stepping::max_attempts`]) were used up:
    /// a path that needs more is not progressing at a useful rate (CalculiX and Abaqus bound
    /// the increments of a step the same way, 100 by default).
    #[error(
        "no convergence towards λ = {}: stopped at λ = {} after {attempts} increment attempts, \
         the limit for one target (last attempt Δλ = {}: {reason})",
        sig6(*.target), sig6(*.reached), sig6(*.last_step)
    )]
    Attempts {
        /// Target load factor.
        target: f64,
        /// Last converged load factor.
        reached: f64,
        /// Attempts made towards the target (converged and cut back).
        attempts: usize,
        /// The last step tried.
        last_step: f64,
        /// How the last attempt ended.
        reason: String,
    },
    /// An arc-length increment was cut back below the smallest arc length
    /// ([`crate::ArcLength::min`]) and still did not converge.
    #[error(
        "arc-length increment {increment} from λ = {}: no convergence after {cutbacks} cutbacks \
         (last arc length {}: {reason})",
        sig6(*.lambda), sig6(*.arc)
    )]
    ArcLength {
        /// The increment (1-based).
        increment: usize,
        /// The load factor it started from.
        lambda: f64,
        /// The last arc length tried.
        arc: f64,
        /// Cutbacks made.
        cutbacks: usize,
        /// Why the last attempt failed.
        reason: String,
    },
    /// Removing the perturbation load at the end of a perturbed step failed even in the
    /// smallest part ([`crate::perturbed_step`]).
    #[error(
        "removing the perturbation load at λ = {}: stopped at {} % of it remaining after {cutbacks} cutbacks (removing a part of 1/{} of it did not converge: {reason})",
        sig6(*.lambda), sig6(*.remaining), (1.0 / .part).round()
    )]
    Perturbation {
        /// The load factor of the step.
        lambda: f64,
        /// Percentage of the perturbation load still on at the last converged state.
        remaining: f64,
        /// The last part tried, as a fraction of the whole load.
        part: f64,
        /// Halvings of the part made.
        cutbacks: usize,
        /// Why the last attempt failed.
        reason: String,
    },
    /// An error of the problem's own, from a crate above this one (its typed error, boxed),
    /// passed through [`NonlinearProblem::evaluate`](crate::NonlinearProblem::evaluate) and
    /// path following untouched: shown as its own message, and given back by `source()` (or
    /// [`NewtonError::problem_error`]) for the caller to downcast. Made with
    /// [`NewtonError::problem`].
    #[error("{0}")]
    Problem(#[source] Box<dyn std::error::Error + Send + Sync + 'static>),
    /// Settings out of range (named).
    #[error("invalid setting {name}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Why.
        reason: String,
    },
}

impl NewtonError {
    /// A problem's own error, boxed as [`NewtonError::Problem`].
    pub fn problem(error: impl Into<Box<dyn std::error::Error + Send + Sync + 'static>>) -> Self {
        Self::Problem(error.into())
    }

    /// The problem's own error of type `E` this carries ([`NewtonError::Problem`]), if any.
    pub fn problem_error<E: std::error::Error + 'static>(&self) -> Option<&E> {
        match self {
            Self::Problem(e) => e.downcast_ref::<E>(),
            _ => None,
        }
    }
}

/// `x` rounded to 6 significant digits, printed in its shortest form (0.3, not
/// 0.30000000000000004).
pub(crate) fn sig6(x: f64) -> f64 {
    format!("{x:.5e}").parse().unwrap_or(x)
}

#[cfg(test)]
mod tests {
    use crate::{NewtonError, NewtonSettings, NonlinearProblem, Stepping, follow_path};
    use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
    use std::error::Error;
    use std::sync::Arc;

    /// A typed error of a crate above newton.
    #[derive(Debug, PartialEq)]
    struct Stop {
        evaluation: usize,
    }

    impl std::fmt::Display for Stop {
        fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
            write!(
                f,
                "the model's own check failed at evaluation {}",
                self.evaluation
            )
        }
    }

    impl Error for Stop {}

    /// r = u − λ on one DOF, failing with [`Stop`] at the second evaluation.
    struct Failing {
        evaluations: usize,
    }

    impl NonlinearProblem for Failing {
        fn n(&self) -> usize {
            1
        }
        fn pattern(&self) -> Arc<SymmetricPattern> {
            Arc::new(SymmetricPattern::from_dof_lists(1, &[vec![0]]).unwrap())
        }
        fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
        fn evaluate(
            &mut self,
            u: &[f64],
            lambda: f64,
            r: &mut [f64],
            tangent: Option<&mut SymmetricMatrix>,
        ) -> Result<f64, NewtonError> {
            self.evaluations += 1;
            if self.evaluations == 2 {
                return Err(NewtonError::problem(Stop {
                    evaluation: self.evaluations,
                }));
            }
            r[0] = u[0] - lambda;
            if let Some(k) = tangent {
                k.set_zero();
                k.add(0, 0, 1.0).unwrap();
            }
            Ok(1.0)
        }
    }

    /// The problem's typed error comes out of path following as itself: its message, its
    /// type behind `source()`, no string in between.
    #[test]
    fn a_problem_error_passes_through_path_following_typed() {
        let mut problem = Failing { evaluations: 0 };
        let mut u = vec![0.0];
        let e = follow_path(
            &mut problem,
            &mut u,
            &[1.0],
            &NewtonSettings::default(),
            &Stepping::default(),
        )
        .unwrap_err();
        assert_eq!(e.problem_error::<Stop>(), Some(&Stop { evaluation: 2 }));
        assert_eq!(
            e.to_string(),
            "the model's own check failed at evaluation 2"
        );
        let source = e.source().and_then(|s| s.downcast_ref::<Stop>());
        assert_eq!(source, Some(&Stop { evaluation: 2 }));
        // Another variant carries none.
        let other = NewtonError::Setting {
            name: "x",
            reason: "y".into(),
        };
        assert_eq!(other.problem_error::<Stop>(), None);
    }
}
