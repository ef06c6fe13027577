//! Pivot checks and inertia shared by the unsplit, split and mixed-precision factors: the
//! pivots d_k of an LDLᵀ (thesis §3: the negative-pivot count is the number of negative
//! eigenvalues, Sylvester's law of inertia) judged against |a_kk| of the original matrix.

use crate::SolverError;
use faer::sparse::linalg::cholesky::supernodal;
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// A factorisation's outcome: the factor, or why it cannot be trusted (the caller takes
/// another path), or an error of A itself.
pub(super) type Attempt<T> = Result<Result<T, &'static str>, SolverError>;

/// How a pivot is judged.
#[derive(Debug, Clone, Copy)]
pub(super) enum PivotRule {
    /// An f64 factor: |d_k| ≤ tolerance·|a_kk| is a zero pivot of A (an error naming the DOF).
    Double { tolerance: f64 },
    /// An f32 factor: |d_k| < max(floor, tolerance)·|a_kk| means the sign could be rounding's,
    /// and the f64 factor must decide (a fallback, not an error).
    Single { tolerance: f64, floor: f64 },
}

impl PivotRule {
    /// The reason an f32 factor is refused, or the error of an f64 one, for pivot `d` of
    /// equation `equation` (DOF `dof`, |a_kk| = `scale`); `Ok(Ok(()))` when it is trusted.
    pub(super) fn judge(
        self,
        d: f64,
        equation: usize,
        dof: usize,
        scale: f64,
    ) -> Result<Result<(), &'static str>, SolverError> {
        match self {
            Self::Double { tolerance } => {
                if crate::profile::is_zero_pivot(d, tolerance, scale) {
                    return Err(SolverError::ZeroPivot {
                        equation,
                        dof,
                        pivot: d,
                        diagonal: scale,
                    });
                }
            }
            Self::Single { tolerance, floor } => {
                if !d.is_finite() || d.abs() < floor.max(tolerance) * scale {
                    return Ok(Err("an f32 pivot is too small to trust its sign"));
                }
            }
        }
        Ok(Ok(()))
    }

    /// Whether this rule is for an f32 factor.
    pub(super) fn single(self) -> bool {
        matches!(self, Self::Single { .. })
    }
}

/// Negative pivots among `pivots` (factor order, starting at equation `first`), each judged
/// by `rule` against `diag[dof(k)]`.
pub(super) fn negative_pivots(
    pivots: impl IntoIterator<Item = f64>,
    first: usize,
    dof: impl Fn(usize) -> usize,
    diag: &[f64],
    rule: PivotRule,
) -> Result<Result<usize, &'static str>, SolverError> {
    let mut negative = 0;
    for (k, d) in pivots.into_iter().enumerate() {
        let dof = dof(k);
        if let Err(reason) = rule.judge(d, first + k, dof, diag[dof].abs())? {
            return Ok(Err(reason));
        }
        if d < 0.0 {
            negative += 1;
        }
    }
    Ok(Ok(negative))
}

/// The diagonal D in factorisation order (LDLᵀ), or the diagonal of L (LLᵀ), of the factor
/// `values` (f64 or f32) on `symbolic`.
pub(super) fn factor_diagonal<T>(symbolic: &SymbolicCholesky<usize>, values: &[T]) -> Vec<f64>
where
    T: faer::traits::ComplexField + Copy + Into<f64>,
{
    let mut d = Vec::with_capacity(symbolic.nrows());
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            // Column k of the simplicial factor starts with its diagonal entry.
            let cp = s.col_ptr();
            for k in 0..s.nrows() {
                d.push(values[cp[k]].into());
            }
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let f = supernodal::SupernodalLdltRef::new(s, values);
            for k in 0..s.n_supernodes() {
                let v = f.supernode(k).val();
                for c in 0..v.ncols() {
                    d.push(v[(c, c)].into());
                }
            }
        }
    }
    d
}

/// The factor position of the pivot a faer factorisation failed at: its simplicial kernel
/// reports the position plus one (the count of columns done), the supernodal one the position.
pub(super) fn pivot_position(simplicial: bool, index: usize) -> usize {
    if simplicial {
        index.saturating_sub(1)
    } else {
        index
    }
}
