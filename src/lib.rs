//! nonlin3d: geometrically nonlinear 3-D finite element analysis of delaminated composite
//! laminates, after J. D. Whitcomb, NASA TM-100655 (1988).
//!
//! This facade re-exports the layers under `crates/`:
//!
//! | module | crate | owns |
//! |---|---|---|
//! | [`laminate`] | `nonlin3d-laminate` | ply stiffness, rotation, stacks, Cholesky factor (§2.1, §2.9) |
//! | [`element`] | `nonlin3d-element` | Hex8/Hex20, quadrature, B0BL3D / ESTIF3D kernels, eigen-analysis (§2.1–2.5) |
#![deny(missing_docs)]

pub use nonlin3d_element as element;
pub use nonlin3d_laminate as laminate;
