//! Element kernels of nonlin3d: Hex8/Hex20 shape functions, quadrature, and the two NONLIN3D
//! kernels **B0BL3D** (strains, stresses, internal forces) and **ESTIF3D** (tangent stiffness),
//! total Lagrangian, after J. D. Whitcomb, NASA TM-100655 (1988), §2.1–2.5 and the appendix.
//!
//! | item | what it is | thesis |
//! |---|---|---|
//! | [`ElementKind`] | Hex8 / Hex20, shape functions in Abaqus C3D8/C3D20 node order | §2.2, appendix |
//! | [`IntegrationRule`], [`Station`] | 2×2×2, 3×3×3, selective-reduced Hex8 | §2.3 |
//! | [`ShapeTable`] | shape data tabulated once per kind and rule | §2.4.1 eq. 2.4.1.2 |
//! | [`evaluate`], [`b0bl3d`], [`estif3d`] | one element: strains, stresses, forces, energy, tangent | eq. 2.1.4, 2.3.1–2.3.4, 2.4.2.6 |
//! | [`Kinematics::Linear`], [`linear_stiffness`] | small-strain variants | §2.6, §2.8 |
//! | [`evaluate_batch`], [`evaluate_batch_with`] | many elements of one kind, rayon across chunks; stored, or streamed to a consumer | §2.4 |
//! | [`evaluate_listed_with`], [`evaluate_listed_prefetching`], [`Prefetch`] | a listed run on the calling thread (owner-computes assembly), with cache-line hints for the consumer | — |
//! | [`Material`], [`CylindricalAxes`], [`AsMaterial`] | a stiffness uniform over the element, or in axes that vary with the position (turned to them at each station) | §2.1 eq. 2.1.5 |
//! | [`eigen_analysis`] | eigenvalues and zero-energy modes of an element stiffness | §2.5 |
//! | [`reference`](mod@reference) | a plain per-point nalgebra implementation (B explicit, Bᵀ C B): the oracle | — |
//! | `strategies` (feature `proptest`) | random distorted elements, SPD materials, displacements | — |
//!
//! Conventions: strains and stresses in the thesis order xx, yy, zz, γxy, γyz, γxz (engineering
//! shears); DOFs node-major (u, v, w per node); matrices row-major. Material stiffness enters
//! the tangent only as Σ TᵀT with T = Qᵀ B √(|J| W), C = Q Qᵀ (eq. 2.3.3–2.3.4).
//!
//! ```
//! use nonlin3d_element::{ElementKind, IntegrationRule, ShapeTable, b0bl3d, estif3d};
//! use nonlin3d_laminate::materials;
//! let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss2).unwrap();
//! let steel = materials::steel().stiffness().unwrap();
//! // A 1 mm cube stretched 0.1 % along x: u = 0.001·x.
//! let x: Vec<[f64; 3]> = ElementKind::Hex20
//!     .reference_nodes()
//!     .iter()
//!     .map(|p| [0.5e-3 * (p[0] + 1.0), 0.5e-3 * (p[1] + 1.0), 0.5e-3 * (p[2] + 1.0)])
//!     .collect();
//! let u: Vec<[f64; 3]> = x.iter().map(|p| [1e-3 * p[0], 0.0, 0.0]).collect();
//! let out = b0bl3d(&table, &x, &u, &steel).unwrap();
//! // Green–Lagrange εxx = u_x + u_x²/2 at every point.
//! assert!((out.strains[0][0] - (1e-3 + 0.5e-6)).abs() < 1e-15);
//! let k = estif3d(&table, &x, &u, &steel).unwrap();
//! assert_eq!(k.len(), 60 * 60);
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod batch;
mod eigen;
mod error;
mod kernel;
mod material;
mod prefetch;
mod quadrature;
pub mod reference;
mod shape;
mod simd;
#[cfg(feature = "proptest")]
pub mod strategies;
mod syrk;
mod table;

pub use batch::{
    BatchInput, BatchOutput, evaluate_batch, evaluate_batch_with, evaluate_listed_prefetching,
    evaluate_listed_with,
};
pub use eigen::{EigenReport, ZERO_MODE_THRESHOLD, eigen_analysis};
pub use error::ElementError;
pub use kernel::{
    ElementOutput, Kinematics, Workspace, b0bl3d, estif3d, evaluate, linear_stiffness,
};
pub use material::{AsMaterial, CylindricalAxes, Material};
pub use prefetch::{Prefetch, prefetch_line};
pub use quadrature::{IntegrationRule, Station, gauss_1d};
pub use shape::{ElementKind, HEX20_EDGES, HEX20_NODES, THESIS_NODE_HEX8, THESIS_NODE_HEX20};
pub use table::ShapeTable;
