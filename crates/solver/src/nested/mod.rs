//! Nested dissection (George 1973; multilevel bisection after Karypis & Kumar's METIS) on the
//! node graph of a finite-element pattern.
//!
//! DOFs with the same closed neighbourhood (the 3 displacements of a node) are merged into one
//! supervariable first, so the graph is 3× smaller with 9× fewer edges. Each graph is bisected by
//! heavy-edge-matching coarsening, greedy graph growing from several seeds on the coarsest graph
//! and Fiduccia–Mattheyses refinement on the way back; the cut edges give a vertex separator as
//! a minimum vertex cover of their bipartite graph (König). The two halves are ordered
//! recursively, the separator last; parts of at most [`LEAF_NODES`] nodes get approximate minimum
//! degree. No randomness: the same pattern gives the same order on every call and thread count.

mod bisect;
mod separator;

use crate::{Permutation, SolverError, SymmetricPattern};
use bisect::bisect;

/// Parts of at most this many nodes are ordered by AMD instead of being dissected further.
pub const LEAF_NODES: usize = 120;
/// Coarsening stops at this many vertices.
pub(crate) const COARSEST: usize = 80;
/// Seeds of the greedy growing on the coarsest graph.
pub(crate) const SEEDS: usize = 8;
/// Largest side allowed, as a fraction of the total weight (METIS's default imbalance is 1.2
/// for separators; 0.55 keeps the tree balanced).
pub(crate) const BALANCE: f64 = 0.55;
/// A refinement pass stops after this many moves without improvement.
pub(crate) const FM_PATIENCE: usize = 60;
/// Refinement passes per level.
pub(crate) const FM_PASSES: usize = 6;

/// A weighted undirected graph in compressed rows (no self loops).
#[derive(Debug, Clone)]
pub(crate) struct Graph {
    pub(crate) xadj: Vec<usize>,
    pub(crate) adj: Vec<usize>,
    pub(crate) ew: Vec<i64>,
    pub(crate) vw: Vec<i64>,
}

impl Graph {
    pub(crate) fn n(&self) -> usize {
        self.vw.len()
    }
    pub(crate) fn nbrs(&self, v: usize) -> impl Iterator<Item = (usize, i64)> + '_ {
        let r = self.xadj[v]..self.xadj[v + 1];
        self.adj[r.clone()]
            .iter()
            .copied()
            .zip(self.ew[r].iter().copied())
    }
    pub(crate) fn total(&self) -> i64 {
        self.vw.iter().sum()
    }
}

/// Nested-dissection order of `pattern`'s DOFs (`forward[new] = old`).
pub fn nested_dissection(pattern: &SymmetricPattern) -> Result<Permutation, SolverError> {
    let (members, graph) = compress(pattern);
    let mut order = Vec::with_capacity(graph.n());
    let ids: Vec<usize> = (0..graph.n()).collect();
    dissect(&graph, &ids, &mut order)?;
    let forward: Vec<usize> = order
        .iter()
        .flat_map(|&s| members[s].iter().copied())
        .collect();
    Permutation::from_forward(forward)
}

/// Supervariables (DOFs with equal closed neighbourhoods, in increasing DOF order) and their
/// graph, vertex weight = DOF count, edge weight 1.
fn compress(pattern: &SymmetricPattern) -> (Vec<Vec<usize>>, Graph) {
    let n = pattern.n();
    let (ptr, adj) = pattern.adjacency();
    // Order-independent hash of the closed neighbourhood.
    let mix = |v: usize| {
        (v as u64 + 1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(17)
    };
    let hash: Vec<u64> = (0..n)
        .map(|v| {
            adj[ptr[v]..ptr[v + 1]]
                .iter()
                .fold(mix(v), |h, &w| h.wrapping_add(mix(w)))
        })
        .collect();
    let mut by_hash: Vec<usize> = (0..n).collect();
    by_hash.sort_unstable_by_key(|&v| (hash[v], v));
    let closed = |v: usize| {
        let mut c: Vec<usize> = adj[ptr[v]..ptr[v + 1]].to_vec();
        c.push(v);
        c.sort_unstable();
        c
    };
    let mut sv = vec![usize::MAX; n];
    let mut members: Vec<Vec<usize>> = Vec::new();
    let mut i = 0;
    while i < n {
        let mut j = i;
        while j < n && hash[by_hash[j]] == hash[by_hash[i]] {
            j += 1;
        }
        // Within a run of equal hashes, group the equal neighbourhoods (runs are short).
        let run = &by_hash[i..j];
        let mut heads: Vec<(usize, Vec<usize>)> = Vec::new();
        for &v in run {
            let c = closed(v);
            match heads.iter().find(|(_, hc)| *hc == c) {
                Some(&(s, _)) => members[s].push(v),
                None => {
                    heads.push((members.len(), c));
                    members.push(vec![v]);
                }
            }
        }
        i = j;
    }
    // Number the supervariables by their smallest DOF, so the graph does not depend on hashes.
    members.sort_unstable_by_key(|m| m[0]);
    for (s, m) in members.iter().enumerate() {
        for &v in m {
            sv[v] = s;
        }
    }
    let ns = members.len();
    let mut xadj = Vec::with_capacity(ns + 1);
    let mut nadj = Vec::new();
    let mut mark = vec![usize::MAX; ns];
    xadj.push(0);
    for (s, m) in members.iter().enumerate() {
        mark[s] = s;
        let start = nadj.len();
        for &w in &adj[ptr[m[0]]..ptr[m[0] + 1]] {
            let t = sv[w];
            if mark[t] != s {
                mark[t] = s;
                nadj.push(t);
            }
        }
        nadj[start..].sort_unstable();
        xadj.push(nadj.len());
    }
    let vw = members.iter().map(|m| m.len() as i64).collect();
    let ew = vec![1; nadj.len()];
    (
        members,
        Graph {
            xadj,
            adj: nadj,
            ew,
            vw,
        },
    )
}

/// Appends the order of `g`'s vertices (named `ids`) to `out`: halves, then separator.
fn dissect(g: &Graph, ids: &[usize], out: &mut Vec<usize>) -> Result<(), SolverError> {
    if g.n() <= LEAF_NODES {
        return leaf_order(g, ids, out);
    }
    let side = bisect(g);
    let count = |s: u8| side.iter().filter(|&&x| x == s).count();
    if count(0) == 0 || count(1) == 0 {
        // Nothing to dissect (a clique-like part): minimum degree on the whole.
        return leaf_order(g, ids, out);
    }
    for s in [0u8, 1] {
        let (sub, sub_ids) = subgraph(g, ids, &side, s);
        dissect(&sub, &sub_ids, out)?;
    }
    out.extend((0..g.n()).filter(|&v| side[v] == 2).map(|v| ids[v]));
    Ok(())
}

/// The subgraph of the vertices with `side[v] == s`.
fn subgraph(g: &Graph, ids: &[usize], side: &[u8], s: u8) -> (Graph, Vec<usize>) {
    let mut local = vec![usize::MAX; g.n()];
    let keep: Vec<usize> = (0..g.n()).filter(|&v| side[v] == s).collect();
    for (k, &v) in keep.iter().enumerate() {
        local[v] = k;
    }
    let mut xadj = Vec::with_capacity(keep.len() + 1);
    let (mut adj, mut ew) = (Vec::new(), Vec::new());
    xadj.push(0);
    for &v in &keep {
        for (w, e) in g.nbrs(v) {
            if local[w] != usize::MAX {
                adj.push(local[w]);
                ew.push(e);
            }
        }
        xadj.push(adj.len());
    }
    let vw = keep.iter().map(|&v| g.vw[v]).collect();
    let sub_ids = keep.iter().map(|&v| ids[v]).collect();
    (Graph { xadj, adj, ew, vw }, sub_ids)
}

/// Approximate minimum degree on a small part.
fn leaf_order(g: &Graph, ids: &[usize], out: &mut Vec<usize>) -> Result<(), SolverError> {
    let n = g.n();
    if n <= 2 {
        out.extend_from_slice(ids);
        return Ok(());
    }
    let columns: Vec<Vec<usize>> = (0..n)
        .map(|v| g.nbrs(v).map(|(w, _)| w).filter(|&w| w > v).collect())
        .collect();
    let p = SymmetricPattern::from_lower_columns(n, &columns)?;
    let perm = crate::approximate_minimum_degree(&p)?;
    out.extend(perm.forward().iter().map(|&v| ids[v]));
    Ok(())
}

#[cfg(test)]
mod tests;
