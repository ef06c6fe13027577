//! Virtual crack closure for nonlin3d (thesis §2.8): strain-energy release rates G_I, G_II,
//! G_III and G_T at each corner node of a delamination front from one solution, and
//! mixed-mode growth criteria.
//!
//! | item | what it is | thesis |
//! |---|---|---|
//! | [`release_rates`] | G per mode at the front corners: eq. 2.8.1 weighting, eq. 2.8.2 local frame | §2.8 |
//! | [`cells_above`] | the cells whose internal forces give the forces at c and d | §2.8 |
//! | [`closure_energy`] | Σ G_T·area, the VCCT estimate of −ΔU | — |
//! | [`respect_contact`], [`FaceState`] | G_I = 0 where contact holds the faces behind a point; open/closed/overlap per point | §5.4 |
//! | [`MixedMode`] | power law (Wu and Reuter 1965) and Benzeggagh–Kenane (1996) failure indices, mode mix | — |
//! | [`estimate`] | the discretisation error of G per point from a coarser companion mesh (in-plane counts halved; the layers that set the mode split kept) | — |
//! | [`critical_strain`] | onset strain of a strain sweep by interpolation | — |
//!
//! The front topology (c, d ahead; a, a′, b, b′ behind), local frames and S come with the mesh
//! ([`nonlin3d_mesh::Front`]); the forces of the cells above the plane from the assembly
//! (`Assembler::partial_internal`, linear or nonlinear strain–displacement relations). This
//! crate is pure arithmetic on those arrays.
//!
//! The failure index and mode mix of one front point with G = (60, 30, 10) J/m² by
//! Benzeggagh–Kenane (G_Ic = 200, G_IIc = 800 J/m², η = 2): mode mix 40/100 = 0.4,
//! G_c = 200 + 600·0.4² = 296 J/m², index 100/296:
//!
//! ```
//! use nonlin3d_vcct::{FrontRelease, MixedMode};
//!
//! let bk = MixedMode::BenzeggaghKenane { g_ic: 200.0, g_iic: 800.0, eta: 2.0 };
//! bk.validate()?;
//! let point = FrontRelease {
//!     node: 0, s: 0.0, theta_deg: 0.0, x: 0.0, y: 0.0, delta_a: 1e-3, area: 1e-6,
//!     g_i: 60.0, g_ii: 30.0, g_iii: 10.0, g_t: 100.0, opening: 1e-6,
//! };
//! assert!((MixedMode::mode_mix(&point) - 0.4).abs() < 1e-15);
//! assert!((bk.index(&point) - 100.0 / 296.0).abs() < 1e-15);
//! # Ok::<(), nonlin3d_vcct::VcctError>(())
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod contact;
mod criteria;
mod error;
pub mod estimate;
mod release;

pub use contact::{FaceState, respect_contact};
pub use criteria::{CriticalStrain, MixedMode, critical_strain};
pub use error::VcctError;
pub use release::{FrontRelease, OPEN_ALLOWANCE, cells_above, closure_energy, release_rates};
