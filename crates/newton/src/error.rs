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
        "no convergence towards λ = {target}: stopped at λ = {reached} after {cutbacks} cutbacks (last attempt Δλ = {last_step:e}: {reason})"
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
    /// Settings out of range (named).
    #[error("invalid setting {name}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Why.
        reason: String,
    },
}
