//! Frictionless crack-face contact by active set for nonlin3d (thesis §2.7, Fig. 2.7.1–2.7.2,
//! §5.4).
//!
//! Where a postbuckled sublaminate closes onto its base, an analysis without constraints lets
//! the crack faces overlap (thesis §5.1, §5.4) and gives G_I > 0 where the front is closed.
//! Here the faces are node pairs (the generators' paired sets `crack_upper`/`crack_lower`):
//!
//! - gap g = n·(x_up − x_low), x = X + u, with n the normal of the deformed lower face at the
//!   lower node (the mean of its facets' unit outward normals: postbuckled faces rotate) —
//!   [`CrackFaces`];
//! - an active pair is held exactly by a tie n·(u_up − u_low) = −g₀, g₀ = n·(X_up − X_low)
//!   (the deformed gap is zero with n frozen over a pass), slave the upper node's component
//!   of largest |n_k|; its contact force is p = R_s/n_k, R_s the slave's reaction (the
//!   residual f_int − f_ext the fold moves onto the masters: p·n on the upper node, −p·n on
//!   the lower) — `tie`, [`contact_tie`], [`contact_force`];
//! - the release test reads the forces recovered with a face basis of positive integrals,
//!   f̂ = T f ([`CrackFaces::recovered`], [`CrackFaces::pressures`]): on quadratic faces the
//!   nodal forces of a uniform pressure are tensile at the corners, f̂ is not — `recover`;
//! - closing is tested in the same basis, on the weighted gaps g̃ = T⁻ᵀ g
//!   ([`CrackFaces::weighted_gaps`]: f̂·g̃ = f·g), and a closed mid-edge pair is held at
//!   g̃ = 0 (its tie reads its open end corners' gaps, [`weighted_tie`]): f̂ ≥ 0, g̃ ≥ 0,
//!   f̂·g̃ = 0 is one complementarity, so the stable set does not depend on the path;
//! - the active set changes by [`update`] (Fig. 2.7.2): inactive pairs with g̃ < −tol_g close,
//!   active pairs with f̂ < −tol_f open; the set is re-solved at the same load until it does not
//!   change, a repeated set being a cycle ([`ContactError::Cycle`]); a stable set whose held
//!   pairs overlap along the current normals is held again with them (a refresh) —
//!   [`Contact::solve_level`], [`Contact::continue_level`];
//! - all candidate pairs are reserved in the pattern once ([`Contact::reserve`]) and the ties
//!   are one replaced tie group, so a change of the set costs no new pattern and no new
//!   symbolic analysis;
//! - the thesis's own approximation (Fig. 2.7.1c: an upper node with w < 0 held at the base's
//!   height by an external force the base does not react) is [`Mode::External`].
//!
//! | item | what it is |
//! |---|---|
//! | [`Pair`], [`CrackFaces`] | node pairs, deformed normals, gaps |
//! | [`Tolerances`], [`Change`], [`update`] | the active-set update, a pure function |
//! | [`contact_tie`], [`contact_force`] | the constraint of a closed pair and its force |
//! | [`Contact`], [`ContactSettings`], [`LevelSettings`], [`Mode`], [`Resumed`] | the loop around a load level |
//! | [`ContactLevel`], [`PassReport`], [`ContactState`] | per-level report; gaps and forces as results |
//!
//! The active-set update alone: of three pairs, an open one overlapping by 2 µm closes, a held
//! one in tension (−5 N) opens, and an open one with a gap stays open.
//!
//! ```
//! use nonlin3d_contact::{Tolerances, update};
//!
//! let gaps = [-2e-6, 0.0, 1e-6]; // m
//! let forces = [0.0, -5.0, 0.0]; // N, compressive positive
//! let active = [false, true, false];
//! let change = update(&gaps, &forces, &active, Tolerances { gap: 1e-9, force: 1e-6 });
//! assert_eq!(change.added, [0]);
//! assert_eq!(change.released, [1]);
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

mod active;
mod driver;
mod error;
mod facet;
mod pairs;
mod recover;
mod tie;

pub use active::{Change, Tolerances, update};
pub use driver::{
    Contact, ContactLevel, ContactSettings, ContactState, Iterate, LevelSettings, Mode, PassReport,
    Reserve, Resumed,
};
pub use error::ContactError;
pub use pairs::{CrackFaces, Pair};
pub use recover::ALPHA;
pub use tie::{candidate_tie, contact_force, contact_tie, slave_component, weighted_tie};
