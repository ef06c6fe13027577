//! Assembly for nonlin3d (thesis §2.2–2.3): constraints, residual r(u, λ) = f_int(u) − λ·f_ext
//! and tangent K(u) = ∂f_int/∂u over all cells, in parallel and deterministically.
//!
//! | item | what it is |
//! |---|---|
//! | [`Contribution`] | a term of the unconstrained system: f_int,c, ∂f_int,c/∂u, E_c, its couplings, optional f_ext,c |
//! | [`Assembler`] | the solid, a contribution: per-cell materials (ply rotation), shape tables, pattern, scatter maps; `assemble` |
//! | [`System`] | Σ contributions on one union pattern (cells ∪ contributions ∪ reserved couplings), then the constraints applied once |
//! | [`Constraints`] | fixed and prescribed DOFs (values scaled by the load factor λ, releasable), linear ties ([`Tie`]) in replaceable groups ([`TieGroup`]), nodal loads |
//! | [`station_stresses`] | Cauchy (or small-strain) stresses at the integration points of listed cells, for output |
//!
//! Constraints are imposed by prescription: before each Newton solve the constrained entries of
//! u are set to their targets, so their increments are zero; the tangent gets identity rows
//! and columns there and the residual zeros. The internal force at a constrained DOF minus the
//! external load there is its reaction. A tie u_s = Σ c·u_m + λ·b eliminates its slave: the
//! residual and tangent are folded onto the masters (r′ = Tᵀr, K′ = TᵀKT, in place on a pattern
//! that holds the fill: [`System`]'s union, or one extended by [`Assembler::tie`]), the slave's
//! row becomes the identity, its value follows the masters ([`Constraints::apply`],
//! [`Constraints::expand_increment`]). [`Assembler::residual`] applies the constraints to the
//! solid alone exactly as a [`System`] holding only the solid does.
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod constrain;
mod constraints;
mod contribution;
mod error;
mod nodal;
mod solid;
mod stresses;
mod system;

pub use constraints::{Constraints, Tie, TieGroup};
pub use contribution::Contribution;
pub use error::AssemblyError;
pub use nodal::{NodalFields, extrapolation, nodal_fields};
pub use solid::{Assembler, Assembly};
pub use stresses::{StressRules, station_stresses};
pub use system::{Evaluation, System, SystemBuilder};
