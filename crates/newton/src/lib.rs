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
//! | [`Extrapolation`], [`predicted_increment`], [`Guess`] | an increment's start extrapolated from the last converged states (linear or quadratic in step time), kept only if its residual is not larger than the plain start's |
//! | [`PathSolver`], [`follow_path_with`] | a solver, tangent and kept factorisation carried over the levels of a sweep |
//! | [`DeadLoads`], [`perturbed_path`], [`perturbed_step`], [`perturbed_redo`], [`perturbed_step_with`], [`perturbed_redo_with`] | the thesis's perturbation load (§3.2) as a dead load, converged with a level and then removed; any problem with dead loads; a level redone by the protocol (`_with`: on the caller's [`PathSolver`], no new analysis) |
//! | [`solve_level`], [`LevelReport`] | one level of a sweep: to the level, the stability test there (§2.5) and, past a bifurcation, the perturbation protocol |
//! | [`IncrementReport`], [`Termination`] | what happened, iteration by iteration, with the inertia |
//! | [`ArcLength`], [`follow_arc_length`] | arc-length path following through limit points (Crisfield 1981/1983): cylindrical or spherical constraint, predictor sign from the inertia, arc length adapted to the iterations |
//! | [`solve_level_arc`] | one level of a sweep by arc length, landed on the level by Newton, with the stability test and perturbation protocol |
//! | [`Bifurcation`] | a rise of the negative-pivot count the inertia guard accepted as real ([`Stepping::inertia_guard`]) |
//! | [`TRACE_TARGET`] | the `tracing` target of the per-iteration and per-attempt events (the door for progress bars and logs; nothing is printed) |
//!
//! A steel bar 4 × 1 × 1 mm of four Hex8 (E = 207 GPa), clamped on x = 0 and pulled by
//! F = 100 N on x = 4 mm with nonlinear kinematics, followed to the full load: the end moves
//! by about F·L/(E·A) = 1.93 µm (the clamp's Poisson constraint stiffens the short bar by a
//! few per cent: within 10 %), and the clamp's reactions balance F.
//!
//! ```
//! use nonlin3d_assembly::{Assembler, Constraints};
//! use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
//! use nonlin3d_laminate::{ShearCoupling, materials};
//! use nonlin3d_mesh::{BoxParams, structured_box};
//! use nonlin3d_newton::{NewtonSettings, NonlinearProblem, Stepping, StructuralProblem, follow_path};
//!
//! let mesh = structured_box(&BoxParams::new(ElementKind::Hex8, [4, 1, 1], [4e-3, 1e-3, 1e-3]))?;
//! let steel = materials::steel().stiffness()?;
//! let assembler = Assembler::new(
//!     &mesh,
//!     &[steel],
//!     ShearCoupling::Exact,
//!     IntegrationRule::Gauss2,
//!     IntegrationRule::Gauss2,
//!     Kinematics::Nonlinear,
//! )?;
//! let mut constraints = Constraints::new(assembler.n());
//! for r in 0..3 {
//!     constraints.fix_nodes(&mesh.node_sets["x0"], r)?;
//! }
//! let mut problem = StructuralProblem::new(assembler, constraints)?;
//! let end: Vec<usize> = mesh.node_sets["x1"].iter().map(|&n| 3 * n).collect();
//! for &d in &end {
//!     problem.add_load(d, 100.0 / end.len() as f64)?;
//! }
//! let mut u = vec![0.0; problem.n()];
//! let report = follow_path(&mut problem, &mut u, &[1.0], &NewtonSettings::default(), &Stepping::default())?;
//! let stretch = end.iter().map(|&d| u[d]).sum::<f64>() / end.len() as f64;
//! let bar = 100.0 * 4e-3 / (207e9 * 1e-6);
//! assert!((stretch / bar - 1.0).abs() < 0.1, "{stretch} m against {bar} m");
//! let clamp: f64 = mesh.node_sets["x0"].iter().map(|&n| problem.reactions()[3 * n]).sum();
//! assert!((clamp + 100.0).abs() < 1e-4, "{clamp} N");
//! # let _ = report;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
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
mod extrapolate;
mod guard;
mod level;
mod line_search;
mod path;
mod perturb;
mod predict;
mod problem;
mod session;
mod settings;
mod solve;
mod vector;

pub use arclength::{
    ArcConstraint, ArcIncrement, ArcLength, ArcReport, ArcStop, SignRule, follow_arc_length,
    solve_level_arc,
};
pub use cache::TangentCache;
pub use error::NewtonError;
pub use extrapolate::Extrapolation;
pub use level::{LevelReport, perturbed_redo, perturbed_redo_with, solve_level};
pub use path::{PathReport, Stepping, follow_path, follow_path_from, follow_path_with};
pub use perturb::{
    DeadLoads, MIN_REMOVAL_PART, perturbed_path, perturbed_step, perturbed_step_with,
};
pub use predict::{Guess, predicted_increment};
pub use problem::{NonlinearProblem, StructuralProblem};
pub use session::PathSolver;
pub use settings::{BFGS_REFACTOR_RATIO, NewtonSettings};
pub use solve::{
    Bifurcation, IncrementReport, IterationRecord, KEPT_FORCING, LINEAR_RESIDUAL, REACHABLE,
    Termination, negative_pivots_at, residual_tolerance, solve_increment, solve_increment_with,
};
