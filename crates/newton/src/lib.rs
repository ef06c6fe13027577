//! Newton–Raphson path following for nonlin3d (thesis §2.1, §4.4).
//!
//! | item | what it is |
//! |---|---|
//! | [`NonlinearProblem`] | residual r(u, λ) and tangent K(u) of any model (§2.1) |
//! | [`StructuralProblem`] | the finite element model: [`Assembler`](nonlin3d_assembly::Assembler) + [`Constraints`](nonlin3d_assembly::Constraints), behind accessors |
//! | [`NewtonError`] | what stops path following; [`NewtonError::Problem`] carries a problem's own error |
//! | [`NewtonSettings`], [`solve_increment`] | one load level: full, modified or quasi-Newton (BFGS), line search, convergence records |
//! | [`TangentCache`], [`solve_increment_with`] | a factorised tangent (and BFGS pairs) kept across increments |
//! | [`Stepping`], [`follow_path`] | load stepping to a list of targets with cutback and regrowth |
//! | [`PathSolver`], [`follow_path_with`] | a solver, tangent and kept factorisation carried over the levels of a sweep |
//! | [`DeadLoads`], [`perturbed_path`], [`perturbed_step`] | the thesis's perturbation load (§3.2) as a dead load, converged with a level and then removed; any problem with dead loads |
//! | [`solve_level`], [`LevelReport`] | one level of a sweep: to the level, the stability test there (§2.5) and, past a bifurcation, the perturbation protocol |
//! | [`IncrementReport`], [`Termination`] | what happened, iteration by iteration, with the inertia |
//! | [`ArcLength`], [`follow_arc_length`] | arc-length path following through limit points (Crisfield 1981/1983): cylindrical or spherical constraint, predictor sign from the inertia, arc length adapted to the iterations |
//! | [`solve_level_arc`] | one level of a sweep by arc length, landed on the level by Newton, with the stability test and perturbation protocol |
//! | [`Bifurcation`] | a rise of the negative-pivot count the inertia guard accepted as real ([`Stepping::inertia_guard`]) |
//! | [`TRACE_TARGET`] | the `tracing` target of the per-iteration and per-attempt events (the door for progress bars and logs; nothing is printed) |
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

/// The `tracing` target of Newton's events: an `iteration` event per iteration and an `attempt`
/// event per attempt, inside a span `attempt` (fields in the doc of
/// [`solve_increment_with`]). A subscriber turns them into a progress bar, a log or a
/// convergence file; without one they cost a check per event.
pub const TRACE_TARGET: &str = "nonlin3d_newton";

mod arclength;
mod cache;
mod error;
mod guard;
mod level;
mod path;
mod perturb;
mod predict;
mod problem;
mod session;
mod solve;

pub use arclength::{
    ArcConstraint, ArcIncrement, ArcLength, ArcReport, ArcStop, SignRule, follow_arc_length,
    solve_level_arc,
};
pub use cache::TangentCache;
pub use error::NewtonError;
pub use level::{LevelReport, solve_level};
pub use path::{PathReport, Stepping, follow_path, follow_path_from, follow_path_with};
pub use perturb::{DeadLoads, MIN_REMOVAL_PART, perturbed_path, perturbed_step};
pub use predict::predicted_increment;
pub use problem::{NonlinearProblem, StructuralProblem};
pub use session::PathSolver;
pub use solve::{
    Bifurcation, IncrementReport, IterationRecord, NewtonSettings, REACHABLE, Termination,
    negative_pivots_at, residual_tolerance, solve_increment, solve_increment_with,
};
