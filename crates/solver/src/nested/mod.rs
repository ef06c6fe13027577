//! Nested dissection (George 1973; multilevel bisection after Karypis & Kumar's METIS) on the
//! node graph of a finite-element pattern.
//!
//! Consecutive DOFs with the same closed neighbourhood (the 3 displacements of a node) are
//! merged into one supervariable first, so the graph is 3× smaller with 9× fewer edges. Each graph is bisected by
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
/// Parts larger than this are split between threads.
const PARALLEL_NODES: usize = 2000;
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
    Ok(nested_dissection_top(pattern)?.0)
}

/// Nested-dissection order and the DOF counts (n₀, n₁) of the top level's two sides: the
/// order is side 0 (n₀ DOFs), side 1 (n₁), then the top separator, and no entry of the
/// pattern couples the two sides. `None` when the top level was not dissected.
pub(crate) fn nested_dissection_top(
    pattern: &SymmetricPattern,
) -> Result<(Permutation, Option<(usize, usize)>), SolverError> {
    let (members, graph) = compress(pattern);
    let ids: Vec<usize> = (0..graph.n()).collect();
    let (order, sides) = dissect_counted(&graph, &ids)?;
    let dofs = |range: std::ops::Range<usize>| -> usize {
        order[range].iter().map(|&s| members[s].len()).sum()
    };
    let top = sides.map(|(a, b)| (dofs(0..a), dofs(a..a + b)));
    let forward: Vec<usize> = order
        .iter()
        .flat_map(|&s| members[s].iter().copied())
        .collect();
    Ok((Permutation::from_forward(forward)?, top))
}

/// Supervariables and their graph (vertex weight = DOF count, edge weight 1). Consecutive
/// DOFs i − 1, i join when their closed neighbourhoods are equal: the lower columns match
/// exactly (column i − 1 is {i − 1} ∪ column i) and the neighbours above are compared by an
/// order-independent hash (a collision could only merge two DOFs wrongly, which changes the
/// quality of the order, never its validity). A node's DOFs are consecutive in nonlin3d's
/// numbering; DOFs that are not stay apart.
pub(crate) fn compress(pattern: &SymmetricPattern) -> (Vec<Vec<usize>>, Graph) {
    let n = pattern.n();
    let mix = |v: usize| {
        (v as u64 + 1)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(17)
    };
    // Hash of the neighbours j < i of each i.
    let mut above = vec![0u64; n];
    for j in 0..n {
        for &i in &pattern.column(j)[1..] {
            above[i] = above[i].wrapping_add(mix(j));
        }
    }
    let mut sv = vec![0usize; n];
    let mut members: Vec<Vec<usize>> = Vec::new();
    for i in 0..n {
        let joins = i > 0 && {
            let (a, b) = (pattern.column(i - 1), pattern.column(i));
            a[1..] == *b && above[i] == above[i - 1].wrapping_add(mix(i - 1))
        };
        match members.last_mut() {
            Some(m) if joins => m.push(i),
            _ => members.push(vec![i]),
        }
        sv[i] = members.len() - 1;
    }
    // Edge S–T (first DOFs r_S < r_T) appears once: row r_T of column r_S.
    let ns = members.len();
    let edges = |f: &mut dyn FnMut(usize, usize)| {
        for (s, m) in members.iter().enumerate() {
            for &i in &pattern.column(m[0])[1..] {
                let t = sv[i];
                if t != s && members[t][0] == i {
                    f(s, t);
                }
            }
        }
    };
    let mut xadj = vec![0usize; ns + 1];
    edges(&mut |s, t| {
        xadj[s + 1] += 1;
        xadj[t + 1] += 1;
    });
    for s in 0..ns {
        xadj[s + 1] += xadj[s];
    }
    let mut fill = xadj.clone();
    let mut adj = vec![0usize; xadj[ns]];
    edges(&mut |s, t| {
        adj[fill[s]] = t;
        fill[s] += 1;
        adj[fill[t]] = s;
        fill[t] += 1;
    });
    let vw = members.iter().map(|m| m.len() as i64).collect();
    let ew = vec![1; adj.len()];
    (members, Graph { xadj, adj, ew, vw })
}

/// The order of `g`'s vertices (named `ids`): side 0, side 1, then the separator. The two
/// sides are ordered in parallel (rayon) above [`PARALLEL_NODES`]; each is a pure function of
/// its subgraph and they are joined in a fixed order, so the result is the same on any number
/// of threads.
fn dissect(g: &Graph, ids: &[usize]) -> Result<Vec<usize>, SolverError> {
    Ok(dissect_counted(g, ids)?.0)
}

/// An order and the sizes of its top level's two sides (`None`: not dissected).
type CountedOrder = (Vec<usize>, Option<(usize, usize)>);

/// [`dissect`] and the vertex counts of its two sides (`None` for a leaf).
fn dissect_counted(g: &Graph, ids: &[usize]) -> Result<CountedOrder, SolverError> {
    if g.n() <= LEAF_NODES {
        return Ok((leaf_order(g, ids)?, None));
    }
    let side = bisect(g);
    let count = |s: u8| side.iter().filter(|&&x| x == s).count();
    if count(0) == 0 || count(1) == 0 {
        // Nothing to dissect (a clique-like part): minimum degree on the whole.
        return Ok((leaf_order(g, ids)?, None));
    }
    let half = |s: u8| {
        let (sub, sub_ids) = subgraph(g, ids, &side, s);
        dissect(&sub, &sub_ids)
    };
    let (first, second) = if g.n() > PARALLEL_NODES {
        rayon::join(|| half(0), || half(1))
    } else {
        (half(0), half(1))
    };
    let mut out = first?;
    out.extend(second?);
    out.extend((0..g.n()).filter(|&v| side[v] == 2).map(|v| ids[v]));
    Ok((out, Some((count(0), count(1)))))
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
fn leaf_order(g: &Graph, ids: &[usize]) -> Result<Vec<usize>, SolverError> {
    let n = g.n();
    if n <= 2 {
        return Ok(ids.to_vec());
    }
    let columns: Vec<Vec<usize>> = (0..n)
        .map(|v| g.nbrs(v).map(|(w, _)| w).filter(|&w| w > v).collect())
        .collect();
    let p = SymmetricPattern::from_lower_columns(n, &columns)?;
    let perm = crate::approximate_minimum_degree(&p)?;
    Ok(perm.forward().iter().map(|&v| ids[v]).collect())
}

#[cfg(test)]
mod tests;
