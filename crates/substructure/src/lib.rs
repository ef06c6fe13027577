//! Substructuring for nonlin3d (thesis §2.6, Fig. 3.2.2, §4.5): a linear region of the mesh is
//! condensed once onto its interface with the rest, as a superelement — "just another element"
//! — and the nonlinear region is solved by Newton with it as one more
//! [`Contribution`](nonlin3d_assembly::Contribution); afterwards the linear region is
//! recovered from the interface displacements.
//!
//! With b the interface DOFs, i the linear region's free interior DOFs and p its prescribed
//! ones (u_p = base + λ v), the region's small-strain equilibrium K u = f eliminates u_i:
//!
//! - K_red = K_bb − K_bi K_ii⁻¹ K_ib (§2.6: column j holds the restraint forces on Γ for
//!   u_b = e_j, the interior free and unloaded);
//! - f_c(λ) = −K_bi K_ii⁻¹ (f_i(λ) − K_ip u_p(λ)) − K_bp u_p(λ) (§2.6: "the negative of the
//!   restraint forces" with u_b = 0 and the region's own loads), linear in λ: a strain sweep
//!   (u = W·ε on x = W) needs no new condensation;
//! - the linear region's internal force on Γ is then K_red u_b − f_c(λ): the superelement adds
//!   f_int += K_red u_b, K_T += K_red, E += ½ u_bᵀ K_red u_b and f_ext += f_c(λ);
//! - recovery: u_i = K_ii⁻¹ (f_i(λ) − K_ib u_b − K_ip u_p(λ)), exact for the linear region.
//!
//! K is the linear region's tangent at u = 0, the small-strain stiffness (no stress, so no
//! geometric stiffness). The result is exact when the linear region stays small-strain (§4.5
//! found G_I and G_II barely changed with the front in the linear region, ℓ ≈ h).
//!
//! | item | what it is |
//! |---|---|
//! | [`Partition`], [`Region`] | linear and nonlinear cells, the interface Γ, interior nodes, the two sub-meshes and their node maps; [`Partition::nonlinear_constraints`] |
//! | [`condense`], [`CondenseSettings`], [`Condensed`], [`CondensationReport`] | K_red and f_c by one partial LDLᵀ with the interface last (or K_ii's factor and blocked multi-RHS solves) |
//! | [`Superelement`], [`CondensedLoad`] | K_red and f_c(λ) as a contribution on the nonlinear sub-mesh's DOFs |
//! | [`Recovery`], [`Recovered`] | u_i from u_b; the region's nodal forces K u and reactions, in the full mesh's numbering |
//! | [`mtx_text`] | K_red as the `.mtx` text CalculiX's `*SUBSTRUCTURE MATRIX OUTPUT` writes |
//! | [`SubstructureError`] | typed errors: empty region, no interface, singular interior (the DOF) |
//!
//! ```
//! use nonlin3d_assembly::{Assembler, Constraints};
//! use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
//! use nonlin3d_laminate::ShearCoupling;
//! use nonlin3d_mesh::{BoxParams, names, structured_box};
//! use nonlin3d_substructure::{CondenseSettings, Partition, condense};
//! let mesh = structured_box(&BoxParams::new(ElementKind::Hex8, [4, 1, 1], [4.0, 1.0, 1.0])).unwrap();
//! let steel = nonlin3d_laminate::materials::steel().stiffness().unwrap();
//! let build = |m: &nonlin3d_mesh::Mesh| Assembler::new(m, &[steel], ShearCoupling::Exact,
//!     IntegrationRule::Gauss2, IntegrationRule::Gauss2, Kinematics::Nonlinear);
//! // The two cells nearest x = 0 are linear, clamped there; the others are solved on top.
//! let p = Partition::from_linear_cells(&mesh, &[0, 1]).unwrap();
//! let mut c = Constraints::new(3 * mesh.nodes.len());
//! for r in 0..3 { c.fix_nodes(&mesh.node_sets[names::X0], r).unwrap(); }
//! let done = condense(&p, &build(p.linear_mesh()).unwrap(), &c, &CondenseSettings::default()).unwrap();
//! assert_eq!(done.report.interface_dofs, 3 * 4);
//! assert!(done.report.asymmetry < 1e-12);
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod condense;
mod dofs;
mod error;
mod mtx;
mod partition;
mod recover;
mod reduce;
mod superelement;

pub use condense::{CondensationReport, CondenseSettings, Condensed, condense};
pub use error::SubstructureError;
pub use mtx::mtx_text;
pub use partition::{INTERFACE, Partition, Region};
pub use recover::{Recovered, Recovery};
pub use superelement::{CondensedLoad, Superelement};
