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
    /// Settings out of range (named).
    #[error("invalid setting {name}: {reason}")]
    Setting {
        /// The setting.
        name: &'static str,
        /// Why.
        reason: String,
    },
}

/// `x` rounded to 6 significant digits, printed in its shortest form (0.3, not
/// 0.30000000000000004).
pub(crate) fn sig6(x: f64) -> f64 {
    format!("{x:.5e}").parse().unwrap_or(x)
}
