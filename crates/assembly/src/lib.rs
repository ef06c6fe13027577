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
//!
//! A steel bar 4 × 1 × 1 mm of four Hex8, fixed on x = 0 and stretched by 1 µm on x = 4 mm,
//! its residual and reactions assembled at that state: the element forces are
//! self-equilibrated, so residual and reactions sum to zero along x (to round-off of forces
//! of order E·A·ε = 207e9 · 1e-6 · 2.5e-4 ≈ 50 N).
//!
//! ```
//! use nonlin3d_assembly::{Assembler, Constraints};
//! use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
//! use nonlin3d_laminate::{ShearCoupling, materials};
//! use nonlin3d_mesh::{BoxParams, structured_box};
//!
//! let mesh = structured_box(&BoxParams::new(ElementKind::Hex8, [4, 1, 1], [4e-3, 1e-3, 1e-3]))?;
//! let steel = materials::steel().stiffness()?;
//! let assembler = Assembler::new(
//!     &mesh,
//!     &[steel],
//!     ShearCoupling::Exact,
//!     IntegrationRule::Gauss2,
//!     IntegrationRule::Gauss2,
//!     Kinematics::Linear,
//! )?;
//! let mut constraints = Constraints::new(assembler.n());
//! for r in 0..3 {
//!     constraints.fix_nodes(&mesh.node_sets["x0"], r)?;
//! }
//! let mut u = vec![0.0; assembler.n()];
//! for &node in &mesh.node_sets["x1"] {
//!     constraints.prescribe(3 * node, 1e-6)?;
//!     u[3 * node] = 1e-6;
//! }
//! let (residual, reactions, _) = assembler.residual(&u, 1.0, &constraints, None)?;
//! let sum_x: f64 = (0..assembler.n() / 3).map(|n| residual[3 * n] + reactions[3 * n]).sum();
//! assert!(sum_x.abs() < 1e-9, "{sum_x} N");
//! // Holding the end stretched takes a force along +x: the bar is in tension.
//! let pull: f64 = mesh.node_sets["x1"].iter().map(|&n| reactions[3 * n]).sum();
//! assert!(pull > 0.0);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
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

/// `len` copies of `T::default()` (zero), written one by one, for buffers that are summed
/// into (read, then written). A large `vec![0.0; len]` comes as untouched pages: each page's
/// first read maps the shared zero page, and its first write then flushes the TLBs of every
/// thread of the process (measured: 2.5 % of a model-6 run's samples, docs/PERFORMANCE.md).
/// Written first, a page is simply allocated.
#[allow(clippy::slow_vector_initialization)]
pub(crate) fn zeroed_by_writing<T: Clone + Default>(len: usize) -> Vec<T> {
    let mut v = Vec::new();
    v.resize(len, T::default());
    v
}
