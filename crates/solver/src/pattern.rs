//! The sparsity pattern of a symmetric matrix, built once from element connectivity.

use crate::SolverError;
use crate::budget::{try_filled, try_room};
use std::sync::OnceLock;

mod nodes;
pub(crate) use nodes::NodeBlocks;

/// The lower triangle (diagonal included) of a symmetric n×n sparsity pattern in compressed
/// sparse columns: column j holds rows `row_idx[col_ptr[j]..col_ptr[j + 1]]`, sorted, the first
/// being j itself. Every diagonal entry is present, so a DOF no element touches shows up as a
/// zero pivot, not as a malformed matrix.
///
/// Invariants (checked in every constructor): sorted unique rows ≥ j in each column, the
/// diagonal first, all indices < n.
#[derive(Debug, Clone)]
pub struct SymmetricPattern {
    n: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    /// The 3×3 node blocks, read off the columns at the first product (`nodes.rs`).
    nodes: OnceLock<Option<NodeBlocks>>,
}

/// Two patterns are equal when their entries are (the node blocks are derived from them).
impl PartialEq for SymmetricPattern {
    fn eq(&self, other: &Self) -> bool {
        self.n == other.n && self.col_ptr == other.col_ptr && self.row_idx == other.row_idx
    }
}

impl Eq for SymmetricPattern {}

impl SymmetricPattern {
    /// The pattern of Σ_e (DOFs of e) × (DOFs of e) for `n` DOFs, from one DOF list per element.
    ///
    /// Two passes over a DOF → elements index with a marker array: memory O(nnz), no sorting of
    /// duplicates, so a 150 000-DOF Hex20 model (~18 M entries) builds in a fraction of a second.
    ///
    /// When every list is made of whole nodes (the generators' cells and the ties' couplings),
    /// the pattern is built on the node graph and written out three columns a node: the same
    /// pattern, in about a third of the time.
    pub fn from_dof_lists<L: AsRef<[usize]>>(n: usize, lists: &[L]) -> Result<Self, SolverError> {
        match Self::from_node_lists(n, lists)? {
            Some(p) => Ok(p),
            None => Self::from_dof_lists_by_dof(n, lists),
        }
    }

    /// [`from_dof_lists`](Self::from_dof_lists) on the DOF graph (any lists).
    fn from_dof_lists_by_dof<L: AsRef<[usize]>>(
        n: usize,
        lists: &[L],
    ) -> Result<Self, SolverError> {
        // DOF → lists containing it (CSR).
        let mut count = try_filled(n + 1, 0usize, "the pattern's DOF index")?;
        for (list, dofs) in lists.iter().enumerate() {
            for &dof in dofs.as_ref() {
                if dof >= n {
                    return Err(SolverError::DofOutOfRange { list, dof, n });
                }
                count[dof + 1] += 1;
            }
        }
        for i in 0..n {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut lists_of = try_filled(count[n], 0usize, "the pattern's DOF index")?;
        for (list, dofs) in lists.iter().enumerate() {
            for &dof in dofs.as_ref() {
                lists_of[fill[dof]] = list;
                fill[dof] += 1;
            }
        }
        drop(fill);
        let mut marker = try_filled(n, usize::MAX, "the pattern's markers")?;
        let mut col_ptr = Vec::new();
        try_room(&mut col_ptr, n + 1, "the pattern's column pointers")?;
        let mut row_idx: Vec<usize> = Vec::new();
        col_ptr.push(0);
        for j in 0..n {
            let start = row_idx.len();
            // Room for the whole column before it is filled: at most the DOFs of its lists.
            let most = 1 + lists_of[count[j]..count[j + 1]]
                .iter()
                .map(|&l| lists[l].as_ref().len())
                .sum::<usize>();
            if row_idx.capacity() - row_idx.len() < most {
                let grow = most.max(row_idx.len() / 2);
                try_room(&mut row_idx, grow, "the pattern's row indices")?;
            }
            row_idx.push(j);
            marker[j] = j;
            for &list in &lists_of[count[j]..count[j + 1]] {
                for &i in lists[list].as_ref() {
                    if i > j && marker[i] != j {
                        marker[i] = j;
                        row_idx.push(i);
                    }
                }
            }
            row_idx[start + 1..].sort_unstable();
            col_ptr.push(row_idx.len());
        }
        row_idx.shrink_to_fit();
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            nodes: OnceLock::new(),
        })
    }

    /// The pattern of [`from_dof_lists`](Self::from_dof_lists) when n = 3·nodes and every list
    /// is made of whole nodes (DOFs 3a, 3a + 1, 3a + 2 in a row, a < nodes); None otherwise.
    /// Node b's neighbours c > b are gathered once with a marker (a ninth of the DOF path's
    /// checks, a third of its sorts), and its three DOF columns 3b + k are then
    /// {3b + k, …, 3b + 2} ∪ {3c, 3c + 1, 3c + 2 : c} (the diagonal alone for a node in no
    /// list): the rows a list shares with DOF 3b + k are exactly those of the nodes it shares
    /// with b.
    fn from_node_lists<L: AsRef<[usize]>>(
        n: usize,
        lists: &[L],
    ) -> Result<Option<Self>, SolverError> {
        let blocked = |d: &[usize]| {
            d.len().is_multiple_of(3)
                && d.chunks_exact(3)
                    .all(|t| t[0] % 3 == 0 && t[0] < n && t[1] == t[0] + 1 && t[2] == t[0] + 2)
        };
        if !n.is_multiple_of(3) || !lists.iter().all(|l| blocked(l.as_ref())) {
            return Ok(None);
        }
        let nodes = n / 3;
        // Node → lists containing it (CSR).
        let mut count = try_filled(nodes + 1, 0usize, "the pattern's node index")?;
        for dofs in lists {
            for t in dofs.as_ref().chunks_exact(3) {
                count[t[0] / 3 + 1] += 1;
            }
        }
        for b in 0..nodes {
            count[b + 1] += count[b];
        }
        let mut fill = count.clone();
        let mut lists_of = try_filled(count[nodes], 0usize, "the pattern's node index")?;
        for (list, dofs) in lists.iter().enumerate() {
            for t in dofs.as_ref().chunks_exact(3) {
                lists_of[fill[t[0] / 3]] = list;
                fill[t[0] / 3] += 1;
            }
        }
        drop(fill);
        // Neighbours c > b of each node b, sorted (CSR).
        let mut marker = try_filled(nodes, usize::MAX, "the pattern's markers")?;
        let mut next_ptr = try_filled(nodes + 1, 0usize, "the pattern's node columns")?;
        let mut next: Vec<usize> = Vec::new();
        for b in 0..nodes {
            let start = next.len();
            marker[b] = b;
            for &list in &lists_of[count[b]..count[b + 1]] {
                for t in lists[list].as_ref().chunks_exact(3) {
                    let c = t[0] / 3;
                    if c > b && marker[c] != b {
                        marker[c] = b;
                        if next.len() == next.capacity() {
                            let grow = 64.max(next.len() / 2);
                            try_room(&mut next, grow, "the pattern's node columns")?;
                        }
                        next.push(c);
                    }
                }
            }
            next[start..].sort_unstable();
            next_ptr[b + 1] = next.len();
        }
        drop((lists_of, marker));
        // Each node column written out as its three DOF columns.
        let mut col_ptr = Vec::new();
        try_room(&mut col_ptr, n + 1, "the pattern's column pointers")?;
        let mut row_idx: Vec<usize> = Vec::new();
        try_room(
            &mut row_idx,
            6 * nodes + 9 * next.len(),
            "the pattern's row indices",
        )?;
        col_ptr.push(0);
        for b in 0..nodes {
            // A node in no list keeps its three diagonals only.
            let listed = count[b + 1] > count[b];
            for k in 0..3 {
                row_idx.push(3 * b + k);
                if listed {
                    row_idx.extend(3 * b + k + 1..3 * b + 3);
                }
                for &c in &next[next_ptr[b]..next_ptr[b + 1]] {
                    row_idx.extend([3 * c, 3 * c + 1, 3 * c + 2]);
                }
                col_ptr.push(row_idx.len());
            }
        }
        Ok(Some(Self {
            n,
            col_ptr,
            row_idx,
            nodes: OnceLock::new(),
        }))
    }

    /// A pattern from explicit lower-triangle columns (rows ≥ j; the diagonal is added if
    /// missing; order and duplicates are fixed).
    pub fn from_lower_columns(n: usize, columns: &[Vec<usize>]) -> Result<Self, SolverError> {
        if columns.len() != n {
            return Err(SolverError::DimensionMismatch {
                what: "columns",
                expected: n,
                got: columns.len(),
            });
        }
        let mut col_ptr = vec![0];
        let mut row_idx = Vec::new();
        for (j, col) in columns.iter().enumerate() {
            let mut rows: Vec<usize> = col.clone();
            rows.push(j);
            rows.sort_unstable();
            rows.dedup();
            if let Some(&bad) = rows.iter().find(|&&i| i < j || i >= n) {
                return Err(SolverError::PatternMismatch { row: bad, col: j });
            }
            row_idx.extend(rows);
            col_ptr.push(row_idx.len());
        }
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            nodes: OnceLock::new(),
        })
    }

    /// A pattern from its lower triangle in compressed columns: `row_idx[col_ptr[j]..col_ptr[j +
    /// 1]]` the rows of column j, increasing, the first of them j (the diagonal). Errors: a
    /// column not so.
    pub(crate) fn from_sorted_lower(
        n: usize,
        col_ptr: Vec<usize>,
        row_idx: Vec<usize>,
    ) -> Result<Self, SolverError> {
        if col_ptr.len() != n + 1 || col_ptr[n] != row_idx.len() {
            return Err(SolverError::DimensionMismatch {
                what: "column pointers",
                expected: n + 1,
                got: col_ptr.len(),
            });
        }
        for j in 0..n {
            let rows = &row_idx[col_ptr[j]..col_ptr[j + 1]];
            let sorted = rows.windows(2).all(|w| w[0] < w[1]);
            if rows.first() != Some(&j) || !sorted || rows.last().is_some_and(|&i| i >= n) {
                let bad = rows.first().copied().unwrap_or(j);
                return Err(SolverError::PatternMismatch { row: bad, col: j });
            }
        }
        Ok(Self {
            n,
            col_ptr,
            row_idx,
            nodes: OnceLock::new(),
        })
    }

    /// Dimension n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Stored entries of the lower triangle (diagonal included).
    pub fn nnz_lower(&self) -> usize {
        self.row_idx.len()
    }

    /// Column pointers (length n + 1).
    pub fn col_ptr(&self) -> &[usize] {
        &self.col_ptr
    }

    /// Row indices, column after column.
    pub fn row_idx(&self) -> &[usize] {
        &self.row_idx
    }

    /// The node blocks, when the columns come in threes of the node shape (`nodes.rs`).
    pub(crate) fn nodes(&self) -> Option<&NodeBlocks> {
        self.nodes.get_or_init(|| NodeBlocks::of(self)).as_ref()
    }

    /// Rows of column j (sorted, j first).
    pub fn column(&self, j: usize) -> &[usize] {
        &self.row_idx[self.col_ptr[j]..self.col_ptr[j + 1]]
    }

    /// Position of entry (i, j) in the value array, either triangle; `None` if not stored.
    pub fn position(&self, i: usize, j: usize) -> Option<usize> {
        let (r, c) = if i >= j { (i, j) } else { (j, i) };
        if c >= self.n {
            return None;
        }
        let col = self.column(c);
        col.binary_search(&r).ok().map(|k| self.col_ptr[c] + k)
    }

    /// For an element with global DOFs `dofs`, the value position of each entry (a, b) of its
    /// row-major dense matrix whose global row ≥ global column, `None` for the others (they are
    /// the mirror images). Compute once per element; [`crate::SymmetricMatrix::scatter_add_mapped`]
    /// then adds without searching.
    pub fn scatter_map(&self, dofs: &[usize]) -> Result<Vec<Option<usize>>, SolverError> {
        let ne = dofs.len();
        let mut map = vec![None; ne * ne];
        for (a, &i) in dofs.iter().enumerate() {
            for (b, &j) in dofs.iter().enumerate() {
                if i >= j {
                    let p = self
                        .position(i, j)
                        .ok_or(SolverError::PatternMismatch { row: i, col: j })?;
                    map[a * ne + b] = Some(p);
                }
            }
        }
        Ok(map)
    }

    /// Neighbour lists of the graph of the pattern (both triangles, no self loops).
    pub fn adjacency(&self) -> (Vec<usize>, Vec<usize>) {
        let mut deg = vec![0usize; self.n + 1];
        for j in 0..self.n {
            for &i in &self.column(j)[1..] {
                deg[i + 1] += 1;
                deg[j + 1] += 1;
            }
        }
        for i in 0..self.n {
            deg[i + 1] += deg[i];
        }
        let mut fill = deg.clone();
        let mut adj = vec![0usize; deg[self.n]];
        for j in 0..self.n {
            for &i in &self.column(j)[1..] {
                adj[fill[i]] = j;
                fill[i] += 1;
                adj[fill[j]] = i;
                fill[j] += 1;
            }
        }
        (deg, adj)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pattern_from_two_elements() {
        let p = SymmetricPattern::from_dof_lists(5, &[vec![0, 2, 1], vec![3, 2, 4]]).unwrap();
        assert_eq!(p.column(0), &[0, 1, 2]);
        assert_eq!(p.column(1), &[1, 2]);
        assert_eq!(p.column(2), &[2, 3, 4]);
        assert_eq!(p.column(3), &[3, 4]);
        assert_eq!(p.column(4), &[4]);
        assert_eq!(p.position(0, 2), p.position(2, 0));
        assert_eq!(p.position(0, 3), None);
        assert!(matches!(
            SymmetricPattern::from_dof_lists(3, &[vec![0, 3]]),
            Err(SolverError::DofOutOfRange {
                list: 0,
                dof: 3,
                n: 3
            })
        ));
    }

    /// Lists of whole nodes (DOFs 3b, 3b + 1, 3b + 2) of `nodes` nodes from raw node numbers
    /// (taken modulo `nodes`); shared with `nodes.rs`'s tests.
    pub(super) fn node_lists(nodes: usize, raw: &[Vec<usize>]) -> Vec<Vec<usize>> {
        raw.iter()
            .map(|l| {
                l.iter()
                    .flat_map(|&a| {
                        let b = a % nodes;
                        [3 * b, 3 * b + 1, 3 * b + 2]
                    })
                    .collect()
            })
            .collect()
    }

    proptest::proptest! {
        /// Lists of whole nodes (some repeated, some nodes in no list) give the DOF path's
        /// pattern on the node path; one loose DOF sends them back to the DOF path.
        #[test]
        fn node_lists_give_the_dof_path_pattern(
            nodes in 1usize..40,
            raw in proptest::collection::vec(proptest::collection::vec(0usize..1000, 1..9), 0..30),
            loose in proptest::bool::ANY,
        ) {
            let mut lists = node_lists(nodes, &raw);
            if loose {
                lists.push(vec![3 * nodes - 1]);
            }
            let n = 3 * nodes;
            let by_dof = SymmetricPattern::from_dof_lists_by_dof(n, &lists).unwrap();
            let by_node = SymmetricPattern::from_node_lists(n, &lists).unwrap();
            proptest::prop_assert_eq!(by_node.is_none(), loose);
            if let Some(p) = by_node {
                proptest::prop_assert_eq!(&p, &by_dof);
            }
            proptest::prop_assert_eq!(SymmetricPattern::from_dof_lists(n, &lists).unwrap(), by_dof);
        }
    }

    #[test]
    fn isolated_dof_keeps_its_diagonal() {
        let p = SymmetricPattern::from_dof_lists(3, &[vec![0, 1]]).unwrap();
        assert_eq!(p.column(2), &[2]);
        assert_eq!(p.nnz_lower(), 4);
    }
}
