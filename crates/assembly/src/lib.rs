//! Assembly for nonlin3d (thesis §2.2–2.3): constraints, residual r(u, λ) = f_int(u) − λ·f_ext
//! and tangent K(u) = ∂f_int/∂u over all cells, in parallel and deterministically.
//!
//! | item | what it is |
//! |---|---|
//! | [`Constraints`] | fixed and prescribed DOFs (values scaled by the load factor λ), linear ties ([`Tie`]), nodal loads |
//! | [`Assembler`] | per-cell materials (ply rotation), shape tables, pattern, scatter maps; `assemble` |
//! | [`station_stresses`] | Cauchy (or small-strain) stresses at the integration points of listed cells, for output |
//!
//! Constraints are imposed by prescription: before each Newton solve the constrained entries of
//! u are set to their targets, so their increments are zero; the tangent gets identity rows
//! and columns there and the residual zeros. The internal force at a constrained DOF minus the
//! external load there is its reaction. A tie u_s = Σ c·u_m + λ·b eliminates its slave: the
//! residual and tangent are folded onto the masters (r′ = Tᵀr, K′ = TᵀKT, in place on a pattern
//! extended by [`Assembler::tie`]), the slave's row becomes the identity, its value follows the
//! masters ([`Constraints::apply`], [`Constraints::expand_increment`]).
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod assembler;
mod constraints;
mod error;
mod handover;
mod prefetch;
mod scatter;
mod share;
mod stresses;

pub use assembler::{Assembler, Assembly};
pub use constraints::{Constraints, Tie};
pub use error::AssemblyError;
pub use stresses::{StressRules, station_stresses};
