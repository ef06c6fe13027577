//! The error type of `nonlin3d-laminate`.

/// What can go wrong when building laminate properties. Every variant names the offending
/// constant, entry or ply so a user can fix the input.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LaminateError {
    /// A modulus (E or G) is zero, negative, NaN or infinite.
    #[error("modulus {name} = {value} must be positive and finite")]
    InvalidModulus {
        /// Name of the constant, e.g. `"E22"`.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A Poisson ratio is NaN or infinite.
    #[error("Poisson ratio {name} = {value} must be finite")]
    NonFinitePoisson {
        /// Name of the constant, e.g. `"nu12"`.
        name: &'static str,
        /// The value given.
        value: f64,
    },
    /// A Poisson ratio violates |ν_ij| < √(E_i/E_j), so the compliance is indefinite.
    #[error(
        "Poisson ratio {name} = {value} makes the compliance indefinite: |{name}| must be below {limit}"
    )]
    PoissonTooLarge {
        /// Name of the constant.
        name: &'static str,
        /// The value given.
        value: f64,
        /// The bound √(E_i/E_j) it has to stay under.
        limit: f64,
    },
    /// The three Poisson ratios together make the normal-compliance block indefinite:
    /// 1 − ν12ν21 − ν23ν32 − ν13ν31 − 2ν21ν32ν13 ≤ 0.
    #[error(
        "Poisson ratios nu12, nu23, nu13 together make the compliance indefinite (determinant factor {determinant} ≤ 0)"
    )]
    PoissonDeterminant {
        /// The determinant factor 1 − ν12ν21 − ν23ν32 − ν13ν31 − 2ν21ν32ν13.
        determinant: f64,
    },
    /// A stiffness entry is NaN or infinite.
    #[error("stiffness entry C[{row}][{col}] = {value} is not finite")]
    NonFiniteEntry {
        /// Zero-based row.
        row: usize,
        /// Zero-based column.
        col: usize,
        /// The value.
        value: f64,
    },
    /// The 6×6 matrix is not symmetric.
    #[error("stiffness is not symmetric: C[{row}][{col}] = {upper} but C[{col}][{row}] = {lower}")]
    NotSymmetric {
        /// Zero-based row of the upper entry.
        row: usize,
        /// Zero-based column of the upper entry.
        col: usize,
        /// C\[row\]\[col\].
        upper: f64,
        /// C\[col\]\[row\].
        lower: f64,
    },
    /// The Cholesky factorisation C = Q·Qᵀ met a non-positive pivot: C is not positive definite.
    #[error("stiffness is not positive definite: Cholesky pivot {index} is {pivot}")]
    NotPositiveDefinite {
        /// Zero-based index of the failing pivot (strain component).
        index: usize,
        /// The pivot value before the square root.
        pivot: f64,
    },
    /// A ply has a non-positive or non-finite thickness, or a non-finite angle.
    #[error("ply {index}: {reason}")]
    InvalidPly {
        /// Zero-based ply index in the stack.
        index: usize,
        /// What is wrong.
        reason: String,
    },
    /// A stack with no plies.
    #[error("a ply stack needs at least one ply")]
    EmptyStack,
}
