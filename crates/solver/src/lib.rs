//! Sparse symmetric solvers for nonlin3d: the thesis's profile (skyline) LDLᵀ (§2.4, ref. 35)
//! and faer's supernodal Cholesky, behind one [`LinearSolver`] trait, with inertia.
//!
//! | item | what it is |
//! |---|---|
//! | [`SymmetricPattern`] | lower-triangle CSC pattern, built once from element DOF lists |
//! | [`SymmetricMatrix`] | values on a shared pattern: zero, scatter-add, matvec |
//! | [`reverse_cuthill_mckee`], [`approximate_minimum_degree`], [`nested_dissection`], [`metis_nested_dissection`], [`envelope_stats`] | orderings and their bandwidth/profile |
//! | [`ProfileLdlt`] | envelope LDLᵀ, RCM ordered, SIMD inner products |
//! | [`FaerSolver`], [`FaerOrdering`], [`FaerSplit`] | faer LDLᵀ / LLᵀ, AMD, nested-dissection or METIS ordered, supernodal or simplicial; LDLᵀ split at the top separator from 5 000 DOF (the halves side by side; the same bits on any thread count) |
//! | [`SchurComplement`], [`SchurOutcome`] | S = A_bb − A_bi A_ii⁻¹ A_ib from one partial LDLᵀ with the boundary last (static condensation), A_ii solves from the same factor |
//! | [`LinearSolver`], [`SolverKind`] | the common interface; [`Factorization::negative_pivots`] is the inertia |
//! | [`MemoryBudget`], [`set_memory_budget`] | the bytes a factorisation may take, checked by `analyze` before allocating |
//!
//! ```
//! use nonlin3d_solver::{LinearSolver, ProfileLdlt, SymmetricMatrix, SymmetricPattern};
//! use std::sync::Arc;
//! // Two springs in series, fixed at the left end (DOF 0 removed): [2 −1; −1 1] x = [0, 1].
//! let p = Arc::new(SymmetricPattern::from_dof_lists(2, &[vec![0], vec![0, 1]]).unwrap());
//! let mut a = SymmetricMatrix::zeros(p.clone());
//! a.scatter_add(&[0], &[1.0]).unwrap();
//! a.scatter_add(&[0, 1], &[1.0, -1.0, -1.0, 1.0]).unwrap();
//! let mut s = ProfileLdlt::new();
//! s.analyze(&p).unwrap();
//! let f = s.factorize(&a).unwrap();
//! assert_eq!(f.negative_pivots, 0);
//! let mut x = vec![0.0, 1.0];
//! s.solve_in_place(&mut x, 1).unwrap();
//! assert!((x[0] - 1.0).abs() < 1e-14 && (x[1] - 2.0).abs() < 1e-14);
//! ```
#![deny(missing_docs)]
#![cfg_attr(
    not(test),
    warn(clippy::unwrap_used, clippy::expect_used, clippy::panic)
)]

pub mod budget;
mod error;
mod faer_backend;
mod matrix;
mod metis;
mod nested;
mod ordering;
pub mod profile;
mod solver;

pub use budget::{MemoryBudget, set_memory_budget};
pub use error::SolverError;
pub use faer_backend::{
    AUTO_METIS_ONLY_DOFS, AUTO_WITHOUT_AMD_DOFS, FaerDirections, FaerMode, FaerOrdering,
    FaerPrecision, FaerSolver, FaerSplit, FaerStructure, KEPT_MIXED_FROM_DOFS,
    KEPT_RETRY_F32_AFTER, KERNEL_THREADS_FROM_DOFS, MAX_CONJUGATE_GRADIENT_STEPS,
    MAX_REFINEMENT_STEPS, MIXED_FROM_DOFS, MixedStats, SPLIT_FROM_DOFS, SchurComplement,
    SchurOutcome, TRUSTED_SHARE, UNCHECKED_IN_A_ROW,
};
pub use matrix::SymmetricMatrix;
pub use metis::{METIS_SEED, metis_nested_dissection};
pub use nested::{LEAF_NODES, nested_dissection};
pub use ordering::{
    EnvelopeStats, Permutation, approximate_minimum_degree, envelope_stats, reverse_cuthill_mckee,
};
pub use pattern::SymmetricPattern;
pub use profile::{ProfileLdlt, ProfileOrdering};
pub use solver::{Analysis, Factorization, LinearSolver, SolverKind, TreeWork, solve};

mod pattern;
