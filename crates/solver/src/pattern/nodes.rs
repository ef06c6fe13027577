//! The pattern's 3×3 node blocks, read off its columns, and y = A x over them.
//!
//! A pattern built from lists of whole nodes ([`SymmetricPattern::from_dof_lists`] on the
//! generators' cells) holds, for node b with DOFs 3b, 3b + 1, 3b + 2, the columns
//! {3b + k, …, 3b + 2} ∪ {3c, 3c + 1, 3c + 2 : c ∈ N(b), c > b}: one neighbour list serves
//! the three columns. The product then reads one node index per three values instead of one
//! DOF index per value, in exactly the column loop's order of operations, so that both give
//! the same bits.

use super::SymmetricPattern;

/// Each node's neighbours c > b, and whether its three columns have the node shape.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct NodeBlocks {
    /// Neighbours of node b: `next[next_ptr[b]..next_ptr[b + 1]]`, increasing.
    next_ptr: Vec<usize>,
    next: Vec<u32>,
    /// Node b couples its own three DOFs (a full diagonal block); false: three lone diagonals,
    /// no neighbour (a node no element touches).
    full: Vec<bool>,
}

impl NodeBlocks {
    /// The node blocks of `p`, or None when n is not a multiple of 3, a node index does not
    /// fit u32 or a column does not have the node shape.
    pub(crate) fn of(p: &SymmetricPattern) -> Option<Self> {
        let n = p.n();
        if !n.is_multiple_of(3) || n / 3 > u32::MAX as usize {
            return None;
        }
        let nodes = n / 3;
        let mut next_ptr = Vec::with_capacity(nodes + 1);
        next_ptr.push(0);
        let mut next = Vec::with_capacity(p.nnz_lower() / 9 + 1);
        let mut full = Vec::with_capacity(nodes);
        for b in 0..nodes {
            let j = 3 * b;
            let (c0, c1, c2) = (p.column(j), p.column(j + 1), p.column(j + 2));
            if c0 == [j] && c1 == [j + 1] && c2 == [j + 2] {
                full.push(false);
                next_ptr.push(next.len());
                continue;
            }
            let tail = c0.get(3..)?;
            if c0[..3] != [j, j + 1, j + 2]
                || c1.get(..2)? != [j + 1, j + 2]
                || c1.get(2..)? != tail
                || c2.get(..1)? != [j + 2]
                || c2.get(1..)? != tail
                || !tail.len().is_multiple_of(3)
            {
                return None;
            }
            for t in tail.chunks_exact(3) {
                if !t[0].is_multiple_of(3) || t[1] != t[0] + 1 || t[2] != t[0] + 2 {
                    return None;
                }
                next.push((t[0] / 3) as u32);
            }
            full.push(true);
            next_ptr.push(next.len());
        }
        Some(Self {
            next_ptr,
            next,
            full,
        })
    }

    /// y = A x for the lower-triangle values `v` of a matrix on the pattern these blocks were
    /// read from (`cp` its column pointers; lengths checked by the caller). Node by node, its
    /// three columns one after the other, each read as the column loop reads it but with one
    /// node index per three rows: y(i) receives column j's a_ij·x_j in increasing j, and
    /// column j's own sum a_jj·x_j + Σ_{i>j} a_ij·x_i runs in increasing i, so the result is
    /// bit for bit the column loop's. (Taking the three columns together, one neighbour block
    /// at a time, was 2.2× slower than the column loop on the AMD EPYC of 2026-11-30 at
    /// 53 847 DOF; one column at a time is 1.14–1.37× faster: docs/PERFORMANCE.md.)
    pub(crate) fn matvec(&self, cp: &[usize], v: &[f64], x: &[f64], y: &mut [f64]) {
        y.fill(0.0);
        for (b, &full) in self.full.iter().enumerate() {
            let j = 3 * b;
            if !full {
                for k in 0..3 {
                    y[j + k] += v[cp[j + k]] * x[j + k];
                }
                continue;
            }
            let neighbours = &self.next[self.next_ptr[b]..self.next_ptr[b + 1]];
            // Column j + q: its diagonal, the 2 − q rows below it in the diagonal block, then
            // three rows per neighbour, as the column loop takes them.
            for q in 0..3 {
                let col = j + q;
                let s = cp[col];
                let xj = x[col];
                let mut acc = v[s] * xj;
                for d in 1..3 - q {
                    y[col + d] += v[s + d] * xj;
                    acc += v[s + d] * x[col + d];
                }
                let tail = &v[s + 3 - q..s + 3 - q + 3 * neighbours.len()];
                for (a, &c) in tail.chunks_exact(3).zip(neighbours) {
                    let i = 3 * c as usize;
                    let (xi, yi) = (&x[i..i + 3], &mut y[i..i + 3]);
                    yi[0] += a[0] * xj;
                    acc += a[0] * xi[0];
                    yi[1] += a[1] * xj;
                    acc += a[1] * xi[1];
                    yi[2] += a[2] * xj;
                    acc += a[2] * xi[2];
                }
                y[col] += acc;
            }
        }
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use crate::pattern::tests::node_lists;
    use crate::{SymmetricMatrix, SymmetricPattern};
    use std::sync::Arc;

    proptest::proptest! {
        /// On patterns of whole nodes (nodes in no list among them) the node-block product
        /// gives the column loop's bits; one DOF more, coupled to DOF 0, takes the blocks away
        /// and the product is the column loop itself.
        #[test]
        fn node_blocks_give_the_column_loops_bits(
            nodes in 1usize..30,
            raw in proptest::collection::vec(proptest::collection::vec(0usize..1000, 1..9), 0..20),
            loose in proptest::bool::ANY,
            seed in 0u64..u64::MAX,
        ) {
            let mut lists = node_lists(nodes, &raw);
            let n = 3 * nodes + usize::from(loose);
            if loose {
                lists.push(vec![0, n - 1]);
            }
            let p = Arc::new(SymmetricPattern::from_dof_lists(n, &lists).unwrap());
            proptest::prop_assert_eq!(p.nodes().is_some(), !loose);
            // Values and x of mixed signs and magnitudes (a fixed-seed LCG): rounding differs
            // with any change of the order of operations.
            let mut state = seed | 1;
            let mut next = || {
                state = state.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10f64.powi((state % 7) as i32 - 3)
            };
            let values: Vec<f64> = (0..p.nnz_lower()).map(|_| next()).collect();
            let x: Vec<f64> = (0..n).map(|_| next()).collect();
            let a = SymmetricMatrix::from_values(p, values).unwrap();
            let (mut y, mut reference) = (vec![f64::NAN; n], vec![f64::NAN; n]);
            a.matvec(&x, &mut y).unwrap();
            a.matvec_by_columns(&x, &mut reference).unwrap();
            for (u, w) in y.iter().zip(&reference) {
                proptest::prop_assert_eq!(u.to_bits(), w.to_bits());
            }
        }
    }

    #[test]
    fn columns_not_in_threes_have_no_node_blocks() {
        // n not a multiple of 3.
        let p = SymmetricPattern::from_dof_lists(4, &[vec![0, 1, 2, 3]]).unwrap();
        assert!(p.nodes().is_none());
        // Node 0 couples to DOF 4 alone (half a neighbour block).
        let p = SymmetricPattern::from_dof_lists(6, &[vec![0, 1, 2, 4], vec![3, 4, 5]]).unwrap();
        assert!(p.nodes().is_none());
        // Whole nodes: blocks, node 1 its own neighbour-free diagonal block.
        let p = SymmetricPattern::from_dof_lists(6, &[vec![0, 1, 2], vec![3, 4, 5]]).unwrap();
        let blocks = p.nodes().unwrap();
        assert_eq!(blocks.full, [true, true]);
        assert!(blocks.next.is_empty());
    }
}
