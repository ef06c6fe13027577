//! The owner-computes scatter: node-block offsets into the lower-triangle CSC pattern, the
//! split of the node range among threads, and the per-cell adds.
//!
//! DOF 3I + a belongs to node I. Every cell couples all three DOFs of each of its nodes, so the
//! pattern is node-blocked: column 3J + c holds rows 3J + c … 3J + 2 of the diagonal block, then
//! three rows 3I, 3I + 1, 3I + 2 for each neighbour I > J in increasing order. Hence
//!
//! pos(3I + a, 3J + c) = col_ptr[3J + c] − c + o(I, J) + a,  o(I, J) = 3·(rank of I among J's
//! nodes I ≥ J),
//!
//! one offset per node pair instead of one position per matrix entry: 400 `u32` (1.6 kB) per
//! Hex20 instead of 3 600 positions (57.6 kB), so the scatter streams from cache. Each cell
//! keeps them regrouped ([`pair_lists`]: 210 words per Hex20), per column node the pairs it
//! stores, then those it adds.
//!
//! The top bit of an offset ([`FIRST`]) marks the cell that is first, in the sweep, to reach
//! the node pair: it stores its block instead of adding it, so no value is zeroed beforehand
//! (zeroing the 56 MB tangent of a 90 k-DOF model cost a quarter of the scatter) and a cold
//! line is written without first being read. Node pairs of the pattern that no cell reaches
//! (tie couplings, nodes in no cell) are listed by [`mark_first`] and zeroed apart.
//!
//! The nodes are ranked by reverse Cuthill–McKee on the node graph (whatever the mesh's own
//! numbering), and cells are swept in order of their highest rank. Thread t owns the nodes
//! ranked in [s_t, s_{t+1}): their force entries, and the tangent entries (I, J) whose
//! higher-ranked node is one of them (`share.rs`). It evaluates the cells whose highest rank
//! is its own; a cell with nodes in lower parts as well is evaluated there once and the values
//! those parts own are handed over (`handover.rs`), so no cell is evaluated twice. Each thread
//! adds its own cells, then the handed-over ones, each in the global sweep order, which is the
//! order every entry receives its contributions in whatever the number of threads: the result
//! is bitwise independent of it. Where the range is split: `sweep.rs`.

use crate::AssemblyError;
use nonlin3d_solver::SymmetricPattern;

/// Flag in a node-pair offset: this cell is the first of the sweep to reach the pair (stores).
pub(crate) const FIRST: u32 = 1 << 31;

/// Checks that `pattern` (3·`nodes` DOFs) is node-blocked as described in the module docs.
pub(crate) fn check_node_blocked(
    pattern: &SymmetricPattern,
    nodes: usize,
) -> Result<(), AssemblyError> {
    let bad = |j: usize, why: &str| AssemblyError::Pattern {
        column: j,
        reason: why.to_string(),
    };
    if pattern.n() != 3 * nodes {
        return Err(bad(0, "the pattern's size is not three DOFs per node"));
    }
    for node in 0..nodes {
        let first = pattern.column(3 * node);
        if first.len() < 3 || first[..3] != [3 * node, 3 * node + 1, 3 * node + 2] {
            return Err(bad(3 * node, "the node's diagonal block is incomplete"));
        }
        for (k, t) in first[3..].chunks(3).enumerate() {
            if t.len() != 3 || t[1] != t[0] + 1 || t[2] != t[0] + 2 || t[0] % 3 != 0 {
                return Err(bad(
                    3 * node,
                    &format!("rows of neighbour {k} are not a triple"),
                ));
            }
        }
        for c in 1..3 {
            if pattern.column(3 * node + c) != &first[c..] {
                return Err(bad(
                    3 * node + c,
                    "the column differs from the node's first one",
                ));
            }
        }
    }
    Ok(())
}

/// o(I, J) for every ordered pair of the cell's nodes, j-major (`j·nn + i` for local nodes i, j,
/// `nn²` entries); pairs with I < J hold `u32::MAX` (they are added as their mirror).
pub(crate) fn block_offsets(
    pattern: &SymmetricPattern,
    nodes: &[usize],
) -> Result<Vec<u32>, AssemblyError> {
    let nn = nodes.len();
    let mut out = vec![u32::MAX; nn * nn];
    for (i, &ni) in nodes.iter().enumerate() {
        for (j, &nj) in nodes.iter().enumerate() {
            if ni < nj {
                continue;
            }
            let col = 3 * nj;
            let p = pattern
                .position(3 * ni, col)
                .ok_or(AssemblyError::Pattern {
                    column: col,
                    reason: format!("no entry for row {}", 3 * ni),
                })?;
            let o = p - pattern.col_ptr()[col];
            out[j * nn + i] =
                u32::try_from(o)
                    .ok()
                    .filter(|&o| o < FIRST)
                    .ok_or(AssemblyError::Pattern {
                        column: col,
                        reason: "column longer than 2³¹ entries".into(),
                    })?;
        }
    }
    Ok(out)
}

/// Sets [`FIRST`] on the offset of every node pair at the first cell (in `cells`' order, the
/// sweep order) that reaches it, and returns the tangent positions of the pattern that no
/// cell reaches (their values are zeroed by the assembly). `cells` yields each cell's nodes
/// and its offsets from [`block_offsets`], flags cleared.
pub(crate) fn mark_first<'c>(
    pattern: &SymmetricPattern,
    cells: impl Iterator<Item = (&'c [usize], &'c mut [u32])>,
) -> Vec<usize> {
    let col_ptr = pattern.col_ptr();
    // Reached node pairs, by the position of their first entry (3I, 3J): one bit each.
    let mut reached: Vec<u64> = crate::zeroed_by_writing(pattern.nnz_lower().div_ceil(64));
    let bit = |p: usize| (p / 64, 1u64 << (p % 64));
    for (nodes, offsets) in cells {
        let nn = nodes.len();
        for (j, &nj) in nodes.iter().enumerate() {
            for (i, &ni) in nodes.iter().enumerate() {
                let o = &mut offsets[j * nn + i];
                if ni < nj {
                    continue;
                }
                let (word, mask) = bit(col_ptr[3 * nj] + *o as usize);
                if reached[word] & mask == 0 {
                    reached[word] |= mask;
                    *o |= FIRST;
                }
            }
        }
    }
    let mut unreached = Vec::new();
    for node in 0..pattern.n() / 3 {
        let col = 3 * node;
        let len = col_ptr[col + 1] - col_ptr[col];
        for o in (0..len).step_by(3) {
            let (word, mask) = bit(col_ptr[col] + o);
            if reached[word] & mask != 0 {
                continue;
            }
            for c in 0..3 {
                // Column 3J + c holds the pair's rows from 3I + c on when I = J, all three else.
                let first = if o == 0 { c } else { 0 };
                let base = col_ptr[col + c] - c + o;
                unreached.extend((first..3).map(|a| base + a));
            }
        }
    }
    unreached
}

/// Shared write access to a global array (forces or tangent values) for the parts of one
/// assembly. Each part writes only entries of the nodes it owns — forces 3v … 3v + 2, tangent
/// entries whose higher-ranked node is v — and every node has one owner, so no entry is
/// written by two threads.
pub(crate) struct Shared<'a> {
    ptr: *mut f64,
    len: usize,
    _borrow: std::marker::PhantomData<&'a mut [f64]>,
}

// SAFETY: a `Shared` is made from a `&mut [f64]` that stays borrowed (and so unaliased) for its
// whole life (`Shared::new` ties it to the borrow); concurrent use is confined to the parts of
// one assembly, which write disjoint entries (the owner-of-the-node rule above, enforced by the
// callers: `share::walk`, which checks the ranks of each pair, and the force loops, which check
// each node's).
unsafe impl Sync for Shared<'_> {}
// SAFETY: as for `Sync`: the pointer is only a borrowed slice.
unsafe impl Send for Shared<'_> {}

impl<'a> Shared<'a> {
    /// Shares `v` for the duration of the borrow.
    pub(crate) fn new(v: &'a mut [f64]) -> Self {
        Self {
            ptr: v.as_mut_ptr(),
            len: v.len(),
            _borrow: std::marker::PhantomData,
        }
    }

    /// The array's first element, for prefetch hints (never dereferenced through this).
    pub(crate) fn as_ptr(&self) -> *const f64 {
        self.ptr
    }

    /// v[p] += x.
    #[inline(always)]
    pub(crate) fn add(&self, p: usize, x: f64) {
        assert!(p < self.len);
        // SAFETY: in bounds (checked); written by the owner of its node only (type invariant).
        unsafe { *self.ptr.add(p) += x }
    }

    /// v[p..p + 3] += x.
    #[inline(always)]
    pub(crate) fn add3(&self, p: usize, x: &[f64]) {
        assert!(p + 3 <= self.len && x.len() >= 3);
        // SAFETY: in bounds (checked); written by the owner of its node only (type invariant).
        unsafe {
            *self.ptr.add(p) += x[0];
            *self.ptr.add(p + 1) += x[1];
            *self.ptr.add(p + 2) += x[2];
        }
    }

    /// v[p] = x.
    #[inline(always)]
    pub(crate) fn set(&self, p: usize, x: f64) {
        assert!(p < self.len);
        // SAFETY: in bounds (checked); written by the owner of its node only (type invariant).
        unsafe { *self.ptr.add(p) = x }
    }

    /// v[p..p + 3] = x.
    #[inline(always)]
    pub(crate) fn set3(&self, p: usize, x: &[f64]) {
        assert!(p + 3 <= self.len && x.len() >= 3);
        // SAFETY: in bounds (checked); written by the owner of its node only (type invariant).
        unsafe {
            *self.ptr.add(p) = x[0];
            *self.ptr.add(p + 1) = x[1];
            *self.ptr.add(p + 2) = x[2];
        }
    }
}

/// u32 words per cell of a [`pair_lists`] table for cells of `nn` nodes: a head per local
/// node, then one entry per node pair.
pub(crate) fn pair_stride(nn: usize) -> usize {
    nn + nn * nn.saturating_sub(1) / 2
}

/// Bit of a head word: the cell stores (rather than adds) the node's diagonal block.
const DIAG_FIRST: u32 = 1 << 31;

/// A cell's node pairs I > J regrouped for a branch-free scatter, from its flagged offsets
/// (j-major, as [`block_offsets`] and [`mark_first`] leave them) into `out` ([`pair_stride`]
/// words). Head j: segment start (bits 0–11), length (12–19), number of first-reached pairs
/// (20–27), [`DIAG_FIRST`]. Entry: local node i (bits 24–31) and o(I, J) (bits 0–23); in each
/// segment the first-reached pairs come first, then the others, each in increasing offset.
pub(crate) fn pair_lists(
    nodes: &[usize],
    offsets: &[u32],
    out: &mut [u32],
) -> Result<(), AssemblyError> {
    let nn = nodes.len();
    if pair_stride(nn) - nn > 0xfff {
        return Err(AssemblyError::Pattern {
            column: nodes.first().map_or(0, |&n| 3 * n),
            reason: format!("a cell of {nn} nodes has more node pairs than the scatter lists hold"),
        });
    }
    let (heads, entries) = out.split_at_mut(nn);
    let mut next = 0usize;
    let mut seg: Vec<(bool, u32, u32)> = Vec::with_capacity(nn);
    for (j, &nj) in nodes.iter().enumerate() {
        seg.clear();
        for (i, &ni) in nodes.iter().enumerate() {
            if ni > nj {
                let o = offsets[j * nn + i];
                let off = o & !FIRST;
                if off >= 1 << 24 {
                    return Err(AssemblyError::Pattern {
                        column: 3 * nj,
                        reason: "column longer than 2²⁴ entries".into(),
                    });
                }
                seg.push((o & FIRST == 0, off, ((i as u32) << 24) | off));
            }
        }
        seg.sort_unstable();
        let first = seg.iter().filter(|s| !s.0).count();
        heads[j] = next as u32
            | (seg.len() as u32) << 12
            | (first as u32) << 20
            | if offsets[j * nn + j] & FIRST != 0 {
                DIAG_FIRST
            } else {
                0
            };
        for (k, s) in seg.iter().enumerate() {
            entries[next + k] = s.2;
        }
        next += seg.len();
    }
    Ok(())
}

/// Where column 3J + c starts, less c, for c = 0, 1, 2: the triple of node I sits o(I, J) on.
pub(crate) fn column_bases(col_ptr: &[usize], nj: usize) -> [usize; 3] {
    [
        col_ptr[3 * nj],
        col_ptr[3 * nj + 1] - 1,
        col_ptr[3 * nj + 2] - 2,
    ]
}

/// Column node j's segment of a [`pair_lists`] table: whether it stores its diagonal block,
/// the entries it stores and the entries it adds.
pub(crate) fn segment(pairs: &[u32], nn: usize, j: usize) -> (bool, &[u32], &[u32]) {
    let (heads, entries) = pairs.split_at(nn);
    let head = heads[j];
    let start = (head & 0xfff) as usize;
    let len = ((head >> 12) & 0xff) as usize;
    let stores = ((head >> 20) & 0xff) as usize;
    let (stored, added) = entries[start..start + len].split_at(stores);
    (head & DIAG_FIRST != 0, stored, added)
}

#[cfg(test)]
mod tests {
    use super::super::share::{Count, Pack, Positions, Scatter, Unpack, walk};
    use super::*;

    /// The DOFs 3n, 3n + 1, 3n + 2 of each node, node after node.
    fn dofs(nodes: &[usize]) -> Vec<usize> {
        nodes
            .iter()
            .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
            .collect()
    }

    /// Two Hex8-like cells sharing a face in a 1-D chain of node pairs: the offsets give the
    /// positions `SymmetricPattern::position` gives, for every entry of every pair.
    #[test]
    fn offsets_give_the_pattern_positions() {
        let cells = [vec![0usize, 1, 2, 3], vec![2, 3, 4, 5], vec![5, 1, 6, 0]];
        let lists: Vec<Vec<usize>> = cells.iter().map(|c| dofs(c)).collect();
        let pattern = SymmetricPattern::from_dof_lists(21, &lists).unwrap();
        check_node_blocked(&pattern, 7).unwrap();
        for nodes in &cells {
            let o = block_offsets(&pattern, nodes).unwrap();
            let nn = nodes.len();
            for (i, &ni) in nodes.iter().enumerate() {
                for (j, &nj) in nodes.iter().enumerate() {
                    if ni < nj {
                        assert_eq!(o[j * nn + i], u32::MAX);
                        continue;
                    }
                    for c in 0..3 {
                        for a in 0..3 {
                            let (r, col) = (3 * ni + a, 3 * nj + c);
                            if r < col {
                                continue;
                            }
                            let p = pattern.col_ptr()[col] - c + o[j * nn + i] as usize + a;
                            assert_eq!(Some(p), pattern.position(r, col), "({r}, {col})");
                        }
                    }
                }
            }
        }
        // A pattern that couples single DOFs is not node-blocked.
        let loose = SymmetricPattern::from_dof_lists(6, &[vec![0, 4]]).unwrap();
        assert!(check_node_blocked(&loose, 2).is_err());
    }

    /// Every node pair of the cells is flagged at exactly one cell, the first to reach it, and
    /// the positions no cell reaches are exactly those of a coupling the cells lack (nodes 4
    /// and 0, as a tie makes) and of a node in no cell (7): the assembly zeroes these alone.
    #[test]
    fn first_flags_cover_each_pair_once() {
        let cells = [vec![0usize, 1, 2, 3], vec![2, 3, 4, 5], vec![5, 1, 6, 0]];
        let mut lists: Vec<Vec<usize>> = cells.iter().map(|c| dofs(c)).collect();
        lists.push(dofs(&[0, 4]));
        lists.push(dofs(&[7]));
        let pattern = SymmetricPattern::from_dof_lists(24, &lists).unwrap();
        check_node_blocked(&pattern, 8).unwrap();
        let mut offsets: Vec<Vec<u32>> = cells
            .iter()
            .map(|c| block_offsets(&pattern, c).unwrap())
            .collect();
        let unreached = mark_first(
            &pattern,
            cells
                .iter()
                .map(|c| &c[..])
                .zip(offsets.iter_mut().map(|o| &mut o[..])),
        );
        let mut seen = std::collections::BTreeMap::new();
        for (k, (c, o)) in cells.iter().zip(&offsets).enumerate() {
            for (j, &nj) in c.iter().enumerate() {
                for (i, &ni) in c.iter().enumerate() {
                    let o = o[j * c.len() + i];
                    if ni < nj {
                        assert_eq!(o, u32::MAX);
                    } else if o & FIRST != 0 {
                        assert!(seen.insert((ni, nj), k).is_none(), "({ni}, {nj}) twice");
                    } else {
                        let first = seen.get(&(ni, nj)).copied();
                        assert!(first.is_some_and(|f| f < k), "({ni}, {nj}) not first");
                    }
                }
            }
        }
        let mut expected: Vec<usize> = (0..3)
            .flat_map(|c| (0..3).map(move |a| (3 * 4 + a, c)))
            .chain((0..3).flat_map(|c| (c..3).map(move |a| (21 + a, 21 + c))))
            .map(|(r, col)| pattern.position(r, col).unwrap())
            .collect();
        expected.sort_unstable();
        let mut got = unreached;
        got.sort_unstable();
        assert_eq!(got, expected);
    }

    /// The regrouped pair lists scatter each cell's share exactly as the plain sum K = Σ Ke
    /// does on the entries whose higher-ranked node is in the range (the first cell of a pair
    /// storing, later ones adding), from the full tangent and through a hand-over pack alike;
    /// each segment lists its stores before its adds, each in increasing offset; and the
    /// `Positions` walk visits exactly the positions the scatter writes.
    #[test]
    fn pair_lists_scatter_the_plain_sum_and_positions_match() {
        let cells = [vec![0usize, 1, 2, 3], vec![2, 3, 4, 5], vec![5, 1, 6, 0]];
        let lists: Vec<Vec<usize>> = cells.iter().map(|c| dofs(c)).collect();
        let pattern = SymmetricPattern::from_dof_lists(21, &lists).unwrap();
        let mut offsets: Vec<Vec<u32>> = cells
            .iter()
            .map(|c| block_offsets(&pattern, c).unwrap())
            .collect();
        let unreached = mark_first(
            &pattern,
            cells
                .iter()
                .map(|c| &c[..])
                .zip(offsets.iter_mut().map(|o| &mut o[..])),
        );
        assert!(unreached.is_empty());
        let pairs: Vec<Vec<u32>> = cells
            .iter()
            .zip(&offsets)
            .map(|(c, o)| {
                let mut out = vec![0; pair_stride(c.len())];
                pair_lists(c, o, &mut out).unwrap();
                out
            })
            .collect();
        for (c, p) in cells.iter().zip(&pairs) {
            for j in 0..c.len() {
                let (_, stored, added) = segment(p, c.len(), j);
                let off = |e: &u32| e & 0xff_ffff;
                assert!(stored.is_sorted_by_key(off) && added.is_sorted_by_key(off));
            }
        }
        // Ke(a, b) = 1 + a + 100·b on and below the diagonal (mirrored), distinct per cell.
        let ke = |k: usize| -> Vec<f64> {
            (0..144)
                .map(|e| {
                    let (a, b) = (e / 12, e % 12);
                    let (a, b) = (a.max(b), a.min(b));
                    (1 + a + 100 * b + 10_000 * k) as f64
                })
                .collect()
        };
        // Ranks scrambled against the mesh numbers, so shares cut across columns.
        let rank: Vec<usize> = vec![3, 0, 5, 1, 6, 2, 4];
        let col_ptr = pattern.col_ptr();
        let ranges = [(0, 7), (0, 3), (3, 7), (2, 5), (0, 3), (3, 7), (2, 5)];
        for (case, (lo, hi)) in ranges.into_iter().enumerate() {
            let packed = case >= 4;
            let mut values = vec![f64::NAN; pattern.nnz_lower()];
            let mut visited = Vec::new();
            {
                let shared = Shared::new(&mut values);
                for (k, (c, p)) in cells.iter().zip(&pairs).enumerate() {
                    let full = ke(k);
                    if packed {
                        let mut count = Count::default();
                        walk(c, p, &rank, (lo, hi), &mut count);
                        let mut pack = vec![f64::NAN; count.0];
                        walk(c, p, &rank, (lo, hi), &mut Pack::new(&full, 12, &mut pack));
                        assert!(pack.iter().all(|x| !x.is_nan()));
                        let mut from = Unpack::new(&pack, col_ptr, &shared);
                        walk(c, p, &rank, (lo, hi), &mut from);
                    } else {
                        let mut to = Scatter::new(&full, 12, col_ptr, &shared);
                        walk(c, p, &rank, (lo, hi), &mut to);
                    }
                    let mut at = Positions::new(col_ptr, |q| visited.push(q));
                    walk(c, p, &rank, (lo, hi), &mut at);
                }
            }
            let mut expected = vec![f64::NAN; pattern.nnz_lower()];
            for (k, c) in cells.iter().enumerate() {
                let ke = ke(k);
                for (i, &ni) in c.iter().enumerate() {
                    for (j, &nj) in c.iter().enumerate() {
                        for (a, cc) in (0..3).flat_map(|a| (0..3).map(move |cc| (a, cc))) {
                            let (r, col) = (3 * ni + a, 3 * nj + cc);
                            let owner = rank[ni].max(rank[nj]);
                            if r < col || owner < lo || owner >= hi {
                                continue;
                            }
                            let q = pattern.position(r, col).unwrap();
                            let v = ke[(3 * i + a) * 12 + 3 * j + cc];
                            expected[q] = if expected[q].is_nan() {
                                v
                            } else {
                                expected[q] + v
                            };
                        }
                    }
                }
            }
            for (q, (g, e)) in values.iter().zip(&expected).enumerate() {
                assert!(
                    g == e || (g.is_nan() && e.is_nan()),
                    "{lo}..{hi} at {q}: {g} vs {e}"
                );
            }
            let mut written: Vec<usize> =
                (0..values.len()).filter(|&q| !values[q].is_nan()).collect();
            visited.sort_unstable();
            visited.dedup();
            written.sort_unstable();
            assert_eq!(visited, written, "{lo}..{hi}");
        }
    }
}
