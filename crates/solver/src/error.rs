//! The error type of `nonlin3d-solver`.

use crate::budget::format_bytes;

/// What can go wrong building, assembling, ordering or factoring a sparse system. Variants
/// name the equation (position in the factor's order) and the DOF (the caller's index).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolverError {
    /// A DOF index in an element list is outside 0..n.
    #[error("element list {list}: DOF {dof} is out of range (n = {n})")]
    DofOutOfRange {
        /// Index of the DOF list (element).
        list: usize,
        /// The offending DOF.
        dof: usize,
        /// Matrix dimension.
        n: usize,
    },
    /// An entry (row, col) that the pattern does not hold.
    #[error("entry ({row}, {col}) is not in the sparsity pattern")]
    PatternMismatch {
        /// Row (DOF).
        row: usize,
        /// Column (DOF).
        col: usize,
    },
    /// A matrix, vector or element block of the wrong size, or a matrix on another pattern.
    #[error("{what}: expected {expected}, got {got}")]
    DimensionMismatch {
        /// Which input.
        what: &'static str,
        /// Size required.
        expected: usize,
        /// Size given.
        got: usize,
    },
    /// A NaN or infinite matrix entry or right-hand side.
    #[error("non-finite value {value} at ({row}, {col})")]
    NonFinite {
        /// Row (DOF).
        row: usize,
        /// Column (DOF; the right-hand-side column for vectors).
        col: usize,
        /// The value.
        value: f64,
    },
    /// A zero or tiny pivot: |d| ≤ tolerance·|a_ii|. For a stiffness matrix this is usually a
    /// missing support (a rigid-body mode) or a mechanism; the DOF says where.
    #[error("zero pivot at equation {equation} (DOF {dof}): d = {pivot:e}, |a_ii| = {diagonal:e}")]
    ZeroPivot {
        /// Position in the factorisation order.
        equation: usize,
        /// The caller's DOF index.
        dof: usize,
        /// The pivot found.
        pivot: f64,
        /// |a_ii| of that DOF, the scale of the test.
        diagonal: f64,
    },
    /// A Cholesky (LLᵀ) factorisation met a non-positive pivot: the matrix is not positive
    /// definite (for a tangent: past a bifurcation or limit point).
    #[error(
        "matrix not positive definite: pivot at equation {equation} (DOF {dof}) is not positive"
    )]
    NotPositiveDefinite {
        /// Position in the factorisation order.
        equation: usize,
        /// The caller's DOF index.
        dof: usize,
    },
    /// `solve` before `factorize`, or `factorize` before `analyze`.
    #[error("{0}")]
    NotReady(&'static str),
    /// A DOF list of a block partition (interior and boundary of a Schur complement) that
    /// names a DOF outside the matrix or twice.
    #[error("DOF {dof} of a {n}-DOF matrix: {reason}")]
    BlockDof {
        /// The offending DOF.
        dof: usize,
        /// Matrix dimension.
        n: usize,
        /// What is wrong with it.
        reason: &'static str,
    },
    /// The envelope or factor would not fit in memory (entries counted).
    #[error("{what} needs {entries} entries, more than the allowed {limit}")]
    TooLarge {
        /// What was being allocated.
        what: &'static str,
        /// Entries needed.
        entries: usize,
        /// The limit.
        limit: usize,
    },
    /// The factor, its workspace and the matrix it factors would exceed the memory budget
    /// (`crate::budget`); found by the symbolic analysis, before anything is allocated.
    #[error(
        "the {what} needs {entries} entries ({}) plus {} of workspace and {} for the matrix it \
         factors: {} in all, more than the {} allowed by {limit}",
        format_bytes(*factor_bytes as u128),
        format_bytes(*workspace_bytes as u128),
        format_bytes(*matrix_bytes as u128),
        format_bytes(*factor_bytes as u128 + *workspace_bytes as u128 + *matrix_bytes as u128),
        format_bytes(*budget as u128)
    )]
    OverBudget {
        /// Which factor.
        what: &'static str,
        /// Stored entries of the factor.
        entries: usize,
        /// Bytes of the factor's values.
        factor_bytes: usize,
        /// Bytes of workspace.
        workspace_bytes: usize,
        /// Bytes of the matrix of values on the pattern.
        matrix_bytes: usize,
        /// The budget, bytes.
        budget: usize,
        /// What sets the budget, in words.
        limit: String,
    },
    /// The system refused memory for an allocation (a `try_reserve` failed, or faer's
    /// symbolic analysis ran out of memory).
    #[error("out of memory: the system refused the {} asked for {what}", format_bytes(*bytes as u128))]
    OutOfMemory {
        /// What was being allocated.
        what: &'static str,
        /// Bytes asked for (for faer's symbolic analysis: its index arrays, a lower bound).
        bytes: usize,
    },
    /// faer reported a failure outside the cases above.
    #[error("faer: {0}")]
    Faer(String),
    /// METIS failed (other than out of memory).
    #[error("METIS: {0}")]
    Metis(String),
}
