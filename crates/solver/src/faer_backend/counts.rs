//! What a symbolic factorisation costs: the factor's column counts, the numeric phase's flops
//! (the ordering choice between AMD and nested dissection compares them) and how that work
//! lies on the supernode tree (how far threads can take it).

use crate::TreeWork;
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

/// The supernode tree's work (`None` for a simplicial factor, which has no supernodes).
///
/// Supernode s of width w with p rows below its diagonal block costs
/// f_s = Σ_{i<w} (w − i + p)² flops (its columns' counts squared, as [`factor_flops`]); its
/// parent is the supernode holding the first of those p rows. The critical path is the
/// largest Σ f_s along a leaf-to-root chain, cp(s) = f_s + max over children cp(c): with
/// unlimited threads that only run supernodes side by side (tree-level parallelism), one
/// factorisation still takes cp/W of its one-thread time.
pub(super) fn tree_work(symbolic: &SymbolicCholesky<usize>) -> Option<TreeWork> {
    let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() else {
        return None;
    };
    let count = s.n_supernodes();
    let begin = s.supernode_begin();
    let end = s.supernode_end();
    // Column → supernode, to find each supernode's parent from its first row below.
    let mut owner = vec![0usize; s.nrows()];
    for k in 0..count {
        owner[begin[k]..end[k]].fill(k);
    }
    let mut below = vec![0.0f64; count]; // the largest cp among the children so far
    let (mut total, mut critical, mut largest, mut widest) = (0.0f64, 0.0f64, 0.0f64, 0usize);
    for k in 0..count {
        let width = end[k] - begin[k];
        let rows = s.supernode(k).pattern();
        let p = rows.len();
        let flops: f64 = (0..width).map(|i| ((width - i + p) as f64).powi(2)).sum();
        let path = flops + below[k];
        total += flops;
        largest = largest.max(flops);
        widest = widest.max(width);
        match rows.first() {
            // Supernodes are numbered children first (faer's postorder): the parent lies ahead.
            Some(&r) => below[owner[r]] = below[owner[r]].max(path),
            None => critical = critical.max(path),
        }
    }
    Some(TreeWork {
        supernodes: count,
        widest,
        critical_path_flops: critical,
        largest_supernode_flops: largest,
        flops: total,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SymmetricPattern;
    use faer::sparse::SymbolicSparseColMatRef;
    use faer::sparse::linalg::cholesky::{
        CholeskySymbolicParams, SymmetricOrdering, factorize_symbolic_cholesky,
    };
    use faer::sparse::linalg::{SupernodalThreshold, SymbolicSupernodalParams};

    /// faer's supernodal symbolic factor of `pattern` in its own numbering (a custom identity
    /// order: `SymmetricOrdering::Identity` reads the lower triangle as the upper one).
    fn supernodal(pattern: &SymmetricPattern) -> SymbolicCholesky<usize> {
        let n = pattern.n();
        let identity: Vec<usize> = (0..n).collect();
        let ordering =
            SymmetricOrdering::Custom(faer::perm::PermRef::new_checked(&identity, &identity, n));
        let a =
            SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
        let params = CholeskySymbolicParams {
            supernodal_flop_ratio_threshold: SupernodalThreshold::FORCE_SUPERNODAL,
            // Fundamental supernodes only: the expected counts below assume no merging.
            supernodal_params: SymbolicSupernodalParams { relax: None },
            ..Default::default()
        };
        factorize_symbolic_cholesky(a, faer::Side::Lower, ordering, params).unwrap()
    }

    /// Two independent dense 3×3 blocks, each coupled to one shared last DOF (an arrow): the
    /// tree is two leaves under a root. With the identity order the leaves are {0,1,2} and
    /// {3,4,5} (counts 4,3,2 each: 16 + 9 + 4 = 29 flops) and the root {6} (1 flop): W = 59,
    /// the critical path 29 + 1 = 30, the largest supernode 29.
    #[test]
    fn an_arrow_of_two_blocks_has_half_its_work_on_the_critical_path() {
        let mut lists = vec![vec![0, 1, 2, 6], vec![3, 4, 5, 6]];
        lists.push(vec![6]);
        let pattern = SymmetricPattern::from_dof_lists(7, &lists).unwrap();
        let symbolic = supernodal(&pattern);
        let tree = tree_work(&symbolic).unwrap();
        assert_eq!(tree.flops, factor_flops(&symbolic));
        assert_eq!(tree.flops, 59.0);
        assert_eq!(tree.critical_path_flops, 30.0);
        assert_eq!(tree.largest_supernode_flops, 29.0);
        assert_eq!(tree.widest, 3);
        assert!((tree.parallelism() - 59.0 / 30.0).abs() < 1e-15);
    }

    /// A chain (a tridiagonal matrix) has no tree-level parallelism: every supernode lies on
    /// the one path, so cp = W.
    #[test]
    fn a_chain_has_all_its_work_on_the_critical_path() {
        let lists: Vec<Vec<usize>> = (0..40).map(|i| vec![i, i + 1]).collect();
        let pattern = SymmetricPattern::from_dof_lists(41, &lists).unwrap();
        let symbolic = supernodal(&pattern);
        let tree = tree_work(&symbolic).unwrap();
        assert_eq!(tree.critical_path_flops, tree.flops);
        assert_eq!(tree.parallelism(), 1.0);
    }
}
