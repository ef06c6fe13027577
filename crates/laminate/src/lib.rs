//! Laminate properties for nonlin3d: orthotropic plies, their rotation about z, ply stacks,
//! homogenised stiffness and the Cholesky factor the element kernels use.
//!
//! Thesis: J. D. Whitcomb, NASA TM-100655 (1988), §2.1 (eq. 2.1.5) and §2.9 (eq. 2.9.1, Table 1).
//!
//! | type / function | what it is |
//! |---|---|
//! | [`Orthotropic`] | nine engineering constants (E11 … G13) of a ply in its material axes |
//! | [`Stiffness`] | a validated symmetric positive definite 6×6 C and its lower Cholesky factor Q (C = Q·Qᵀ, §2.3) |
//! | [`ShearCoupling`] | keep the exact C56 of a rotated ply, or drop it as the thesis did (§2.1) |
//! | [`Ply`], [`PlyStack`] | a ply (material, angle, thickness) and a stack of them |
//! | [`PlyStack::average_stiffness`] | the thesis's "homogeneous quasi-isotropic laminate" average (eq. 2.9.1) |
//! | [`PlyStack::smeared_stiffness`] | exact 3-D smearing: in-plane strains and out-of-plane stresses continuous |
//! | [`materials`] | Table 1 generic graphite/epoxy and IM7/8551-7, steel, aluminium |
//!
//! Strain order everywhere (thesis eq. 2.1.4): 1 = xx, 2 = yy, 3 = zz, 4 = γxy, 5 = γyz,
//! 6 = γxz, engineering shear strains; indices in code are zero-based (0 … 5).
//!
//! ```
//! use nonlin3d_laminate::{materials, ShearCoupling};
//! let ply = materials::generic_graphite_epoxy();
//! let c0 = ply.stiffness().unwrap();
//! let c45 = c0.rotated_about_z(45f64.to_radians(), ShearCoupling::Exact).unwrap();
//! // Rotation about z leaves C33 unchanged and couples γyz with γxz because G13 ≠ G23.
//! assert!((c45.c()[2][2] - c0.c()[2][2]).abs() < 1e-6 * c0.c()[2][2]);
//! assert!(c45.c()[4][5].abs() > 1e8);
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod error;
pub mod materials;
mod orthotropic;
mod rotation;
mod stack;
mod stiffness;

pub use error::LaminateError;
pub use orthotropic::Orthotropic;
pub use rotation::VOIGT_PAIRS;
pub use rotation::{rotate_voigt, rotation_about_z};
pub use stack::{Ply, PlyStack};
pub use stiffness::{ShearCoupling, Stiffness};
