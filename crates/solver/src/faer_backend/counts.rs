//! What a symbolic factorisation costs: the factor's column counts and the numeric phase's
//! flops (the ordering choice between AMD and nested dissection compares them).

use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};

/// Flops of the numeric phase: Σ_k c_k² over the factor's column counts c_k.
pub(super) fn factor_flops(symbolic: &SymbolicCholesky<usize>) -> f64 {
    column_counts(symbolic)
        .iter()
        .map(|&c| (c * c) as f64)
        .sum()
}

/// Entries per column of the factor (diagonal included), in factorisation order.
pub(super) fn column_counts(symbolic: &SymbolicCholesky<usize>) -> Vec<usize> {
    match symbolic.raw() {
        SymbolicCholeskyRaw::Simplicial(s) => {
            let cp = s.col_ptr();
            (0..s.nrows()).map(|k| cp[k + 1] - cp[k]).collect()
        }
        SymbolicCholeskyRaw::Supernodal(s) => {
            let mut counts = Vec::with_capacity(s.nrows());
            for k in 0..s.n_supernodes() {
                let sn = s.supernode(k);
                let (start, end) = (s.supernode_begin()[k], s.supernode_end()[k]);
                let width = end - start;
                for c in 0..width {
                    counts.push(width - c + sn.pattern().len());
                }
            }
            counts
        }
    }
}
