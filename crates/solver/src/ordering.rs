//! Orderings: reverse Cuthill–McKee for the profile solver, approximate minimum degree (faer)
//! for the supernodal one, and the envelope statistics that decide between them.

use crate::{SolverError, SymmetricPattern};
use std::collections::VecDeque;

/// A permutation of 0..n: `forward[new] = old`, `inverse[old] = new`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Permutation {
    forward: Vec<usize>,
    inverse: Vec<usize>,
}

impl Permutation {
    /// The identity of size n.
    pub fn identity(n: usize) -> Self {
        Self {
            forward: (0..n).collect(),
            inverse: (0..n).collect(),
        }
    }

    /// From `forward[new] = old`; an entry out of range or repeated is an error.
    pub fn from_forward(forward: Vec<usize>) -> Result<Self, SolverError> {
        let n = forward.len();
        let mut inverse = vec![usize::MAX; n];
        for (new, &old) in forward.iter().enumerate() {
            if old >= n || inverse[old] != usize::MAX {
                return Err(SolverError::DimensionMismatch {
                    what: "permutation entry",
                    expected: n,
                    got: old,
                });
            }
            inverse[old] = new;
        }
        Ok(Self { forward, inverse })
    }

    /// `forward[new] = old`.
    pub fn forward(&self) -> &[usize] {
        &self.forward
    }

    /// `inverse[old] = new`.
    pub fn inverse(&self) -> &[usize] {
        &self.inverse
    }

    /// Size n.
    pub fn len(&self) -> usize {
        self.forward.len()
    }

    /// Whether n = 0.
    pub fn is_empty(&self) -> bool {
        self.forward.is_empty()
    }
}

/// Envelope (profile) statistics of a pattern under a permutation.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct EnvelopeStats {
    /// max over rows of (i − first column of row i).
    pub bandwidth: usize,
    /// Σ over rows of (i − first column of row i): the off-diagonal entries a profile
    /// factor stores (the "profile" of the thesis's solver).
    pub profile: usize,
}

/// First column (in the new order) of each row of the permuted lower triangle.
pub(crate) fn first_columns(pattern: &SymmetricPattern, perm: &Permutation) -> Vec<usize> {
    let n = pattern.n();
    let mut first: Vec<usize> = (0..n).collect();
    let inv = perm.inverse();
    for j in 0..n {
        for &i in pattern.column(j) {
            let (a, b) = (inv[i], inv[j]);
            let (row, col) = if a >= b { (a, b) } else { (b, a) };
            first[row] = first[row].min(col);
        }
    }
    first
}

/// Bandwidth and profile of `pattern` under `perm`.
pub fn envelope_stats(pattern: &SymmetricPattern, perm: &Permutation) -> EnvelopeStats {
    let first = first_columns(pattern, perm);
    let mut stats = EnvelopeStats {
        bandwidth: 0,
        profile: 0,
    };
    for (i, &f) in first.iter().enumerate() {
        stats.bandwidth = stats.bandwidth.max(i - f);
        stats.profile += i - f;
    }
    stats
}

/// Reverse Cuthill–McKee: breadth-first from a pseudo-peripheral node of each connected
/// component (George & Liu's search), neighbours in increasing degree, the whole order reversed
/// (which never enlarges the envelope and usually shrinks it).
pub fn reverse_cuthill_mckee(pattern: &SymmetricPattern) -> Permutation {
    let n = pattern.n();
    let (ptr, adj) = pattern.adjacency();
    let degree = |v: usize| ptr[v + 1] - ptr[v];
    let mut visited = vec![false; n];
    let mut order = Vec::with_capacity(n);
    let mut level = vec![usize::MAX; n];
    let mut queue = VecDeque::new();
    let mut scratch = Vec::new();
    for seed in 0..n {
        if visited[seed] {
            continue;
        }
        // Pseudo-peripheral start: repeat BFS from the min-degree node of the last level
        // while the eccentricity grows.
        let mut root = seed;
        let mut ecc = bfs_levels(root, &ptr, &adj, &mut level, &mut queue, &mut scratch);
        loop {
            let last = scratch
                .iter()
                .copied()
                .filter(|&v| level[v] == ecc)
                .min_by_key(|&v| (degree(v), v));
            for &v in &scratch {
                level[v] = usize::MAX;
            }
            let Some(cand) = last else { break };
            let e = bfs_levels(cand, &ptr, &adj, &mut level, &mut queue, &mut scratch);
            if e > ecc {
                root = cand;
                ecc = e;
            } else {
                for &v in &scratch {
                    level[v] = usize::MAX;
                }
                break;
            }
        }
        for &v in &scratch {
            level[v] = usize::MAX;
        }
        // Cuthill–McKee from the root.
        visited[root] = true;
        queue.push_back(root);
        let mut nbrs = Vec::new();
        while let Some(v) = queue.pop_front() {
            order.push(v);
            nbrs.clear();
            nbrs.extend(
                adj[ptr[v]..ptr[v + 1]]
                    .iter()
                    .copied()
                    .filter(|&w| !visited[w]),
            );
            nbrs.sort_unstable_by_key(|&w| (degree(w), w));
            for &w in &nbrs {
                visited[w] = true;
                queue.push_back(w);
            }
        }
    }
    order.reverse();
    let mut inverse = vec![0; n];
    for (new, &old) in order.iter().enumerate() {
        inverse[old] = new;
    }
    Permutation {
        forward: order,
        inverse,
    }
}

/// BFS levels from `root`; returns the eccentricity, leaves the visited nodes in `seen`
/// with their levels set (the caller resets them).
fn bfs_levels(
    root: usize,
    ptr: &[usize],
    adj: &[usize],
    level: &mut [usize],
    queue: &mut VecDeque<usize>,
    seen: &mut Vec<usize>,
) -> usize {
    seen.clear();
    queue.clear();
    level[root] = 0;
    seen.push(root);
    queue.push_back(root);
    let mut ecc = 0;
    while let Some(v) = queue.pop_front() {
        ecc = ecc.max(level[v]);
        for &w in &adj[ptr[v]..ptr[v + 1]] {
            if level[w] == usize::MAX {
                level[w] = level[v] + 1;
                seen.push(w);
                queue.push_back(w);
            }
        }
    }
    ecc
}

/// Approximate minimum degree (faer's port of SuiteSparse AMD): the fill-reducing ordering of
/// the supernodal path.
pub fn approximate_minimum_degree(pattern: &SymmetricPattern) -> Result<Permutation, SolverError> {
    use faer::dyn_stack::{MemBuffer, MemStack};
    use faer::sparse::SymbolicSparseColMatRef;
    use faer::sparse::linalg::amd;
    let n = pattern.n();
    let mut fwd = vec![0usize; n];
    let mut inv = vec![0usize; n];
    let a = SymbolicSparseColMatRef::new_checked(n, n, pattern.col_ptr(), None, pattern.row_idx());
    let mut buf = MemBuffer::try_new(amd::order_scratch::<usize>(n, pattern.nnz_lower()))
        .map_err(|_| SolverError::Faer("AMD workspace allocation failed".into()))?;
    amd::order(
        &mut fwd,
        &mut inv,
        a,
        amd::Control::default(),
        MemStack::new(&mut buf),
    )
    .map_err(|e| SolverError::Faer(format!("AMD: {e:?}")))?;
    Permutation::from_forward(fwd)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path graph numbered badly: RCM must bring its bandwidth to 1.
    #[test]
    fn rcm_finds_the_band_of_a_scrambled_path() {
        let n = 50;
        let label: Vec<usize> = (0..n).map(|k| (k * 17) % n).collect(); // 17 coprime to 50
        let lists: Vec<Vec<usize>> = (0..n - 1).map(|k| vec![label[k], label[k + 1]]).collect();
        let p = SymmetricPattern::from_dof_lists(n, &lists).unwrap();
        let before = envelope_stats(&p, &Permutation::identity(n));
        let perm = reverse_cuthill_mckee(&p);
        let after = envelope_stats(&p, &perm);
        assert!(before.bandwidth > 10);
        assert_eq!(after.bandwidth, 1);
        assert_eq!(after.profile, n - 1);
        let amd = approximate_minimum_degree(&p).unwrap();
        assert_eq!(amd.len(), n);
    }

    #[test]
    fn rcm_handles_disconnected_components() {
        let p = SymmetricPattern::from_dof_lists(6, &[vec![0, 3], vec![1, 4], vec![2, 5]]).unwrap();
        let perm = reverse_cuthill_mckee(&p);
        let mut seen = perm.forward().to_vec();
        seen.sort_unstable();
        assert_eq!(seen, (0..6).collect::<Vec<_>>());
        assert_eq!(envelope_stats(&p, &perm).bandwidth, 1);
    }
}
