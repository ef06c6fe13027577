//! Multilevel bisection: heavy-edge coarsening, greedy growing, Fiduccia–Mattheyses on the
//! edge cut, then a vertex separator.

use super::separator::{refine_separator, separator};
use super::{BALANCE, COARSEST, FM_PASSES, FM_PATIENCE, Graph, SEEDS};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// Sides 0 and 1 and separator 2 of a multilevel bisection of `g`.
pub(crate) fn bisect(g: &Graph) -> Vec<u8> {
    // Coarsen: levels[k] holds the k-th coarser graph and the map onto it from the one before
    // (no copy of `g` itself).
    let mut levels: Vec<(Graph, Vec<usize>)> = Vec::new();
    loop {
        let fine = levels.last().map_or(g, |l| &l.0);
        if fine.n() <= COARSEST {
            break;
        }
        let (coarse, cmap) = coarsen(fine);
        if coarse.n() as f64 > 0.9 * fine.n() as f64 {
            break;
        }
        levels.push((coarse, cmap));
    }
    // Initial partition: the best of several grown ones.
    let mut part = initial_partition(levels.last().map_or(g, |l| &l.0));
    // Uncoarsen and refine.
    while let Some((_, cmap)) = levels.pop() {
        part = cmap.iter().map(|&c| part[c]).collect();
        refine(levels.last().map_or(g, |l| &l.0), &mut part);
    }
    let current = g;
    let mut part = separator(current, part);
    refine_separator(current, &mut part);
    part
}

/// Heavy-edge matching: each unmatched vertex (lightest degree first) joins its unmatched
/// neighbour over the heaviest edge. Returns the coarse graph and the fine → coarse map.
fn coarsen(g: &Graph) -> (Graph, Vec<usize>) {
    let n = g.n();
    let mut visit: Vec<usize> = (0..n).collect();
    visit.sort_by_key(|&v| (g.xadj[v + 1] - g.xadj[v], v));
    let mut mate = vec![usize::MAX; n];
    for &v in &visit {
        if mate[v] != usize::MAX {
            continue;
        }
        let best = g
            .nbrs(v)
            .filter(|&(w, _)| mate[w] == usize::MAX && w != v)
            .max_by_key(|&(w, e)| (e, Reverse(w)));
        match best {
            Some((w, _)) => {
                mate[v] = w;
                mate[w] = v;
            }
            None => mate[v] = v,
        }
    }
    let mut cmap = vec![usize::MAX; n];
    let mut nc = 0;
    for v in 0..n {
        if cmap[v] == usize::MAX {
            cmap[v] = nc;
            cmap[mate[v]] = nc;
            nc += 1;
        }
    }
    let mut xadj = Vec::with_capacity(nc + 1);
    let (mut adj, mut ew) = (Vec::new(), Vec::new());
    let mut vw = vec![0i64; nc];
    let mut slot = vec![usize::MAX; nc];
    xadj.push(0);
    let mut c = 0;
    for v in 0..n {
        if cmap[v] != c {
            continue;
        }
        let start = adj.len();
        let pair = if mate[v] == v {
            vec![v]
        } else {
            vec![v, mate[v]]
        };
        for &u in &pair {
            vw[c] += g.vw[u];
            for (w, e) in g.nbrs(u) {
                let cw = cmap[w];
                if cw == c {
                    continue;
                }
                if slot[cw] >= start && slot[cw] < adj.len() && adj[slot[cw]] == cw {
                    ew[slot[cw]] += e;
                } else {
                    slot[cw] = adj.len();
                    adj.push(cw);
                    ew.push(e);
                }
            }
        }
        xadj.push(adj.len());
        c += 1;
    }
    (Graph { xadj, adj, ew, vw }, cmap)
}

/// Weight of the edges between the sides.
fn cut(g: &Graph, part: &[u8]) -> i64 {
    (0..g.n())
        .map(|v| {
            g.nbrs(v)
                .filter(|&(w, _)| part[w] != part[v])
                .map(|(_, e)| e)
                .sum::<i64>()
        })
        .sum::<i64>()
        / 2
}

/// Greedy graph growing from `SEEDS` seeds, each refined; the smallest cut wins (first on ties).
fn initial_partition(g: &Graph) -> Vec<u8> {
    let n = g.n();
    let total = g.total();
    let mut best: Option<(i64, Vec<u8>)> = None;
    let seeds: Vec<usize> = (0..SEEDS.min(n)).map(|k| k * n / SEEDS.min(n)).collect();
    for &seed in &seeds {
        // Side 0 grows from the seed; side 1 holds the rest.
        let mut part = vec![1u8; n];
        let mut conn = vec![0i64; n];
        let deg: Vec<i64> = (0..n).map(|v| g.nbrs(v).map(|(_, e)| e).sum()).collect();
        let mut weight = 0;
        // Frontier by gain (lazy heap: an entry is current while its gain matches), then the
        // first vertex left for a graph in several pieces: O(E log n) however it is shaped.
        let mut heap: BinaryHeap<(i64, Reverse<usize>)> = BinaryHeap::new();
        let mut cursor = 0;
        let mut next = Some(seed);
        while let Some(v) = next {
            if 2 * (weight + g.vw[v]) > total + g.vw[v] {
                break;
            }
            part[v] = 0;
            weight += g.vw[v];
            for (w, e) in g.nbrs(v) {
                if part[w] == 1 {
                    conn[w] += e;
                    heap.push((2 * conn[w] - deg[w], Reverse(w)));
                }
            }
            // The frontier vertex whose move cuts least (smallest index on ties).
            next = loop {
                match heap.pop() {
                    Some((gain, Reverse(w))) if part[w] == 1 && gain == 2 * conn[w] - deg[w] => {
                        break Some(w);
                    }
                    Some(_) => continue,
                    None => {
                        while cursor < n && part[cursor] != 1 {
                            cursor += 1;
                        }
                        break (cursor < n).then_some(cursor);
                    }
                }
            };
        }
        refine(g, &mut part);
        let c = cut(g, &part);
        if best.as_ref().is_none_or(|(bc, _)| c < *bc) {
            best = Some((c, part));
        }
    }
    best.map_or_else(|| vec![0; n], |(_, p)| p)
}

/// Fiduccia–Mattheyses passes on the edge cut, each side at most `BALANCE` of the weight
/// (or half plus the heaviest vertex, on coarse graphs); moves past the best point are undone.
fn refine(g: &Graph, part: &mut [u8]) {
    let n = g.n();
    let total = g.total();
    let heaviest = g.vw.iter().copied().max().unwrap_or(0);
    let max_side = ((BALANCE * total as f64) as i64).max((total + 1) / 2 + heaviest);
    let mut weight = [0i64; 2];
    for v in 0..n {
        weight[part[v] as usize] += g.vw[v];
    }
    // gain[v]: cut decrease if v changes side = external − internal weight.
    let mut gain = vec![0i64; n];
    for pass in 0..FM_PASSES {
        for v in 0..n {
            gain[v] = g
                .nbrs(v)
                .map(|(w, e)| if part[w] != part[v] { e } else { -e })
                .sum();
        }
        let mut heaps: [BinaryHeap<(i64, Reverse<usize>)>; 2] =
            [BinaryHeap::new(), BinaryHeap::new()];
        for v in 0..n {
            if g.nbrs(v).any(|(w, _)| part[w] != part[v]) {
                heaps[part[v] as usize].push((gain[v], Reverse(v)));
            }
        }
        let mut locked = vec![false; n];
        let mut moves: Vec<usize> = Vec::new();
        let imbalance = |w: &[i64; 2]| (w[0] - w[1]).abs();
        let (mut delta, mut best_delta, mut best_len) = (0i64, 0i64, 0usize);
        let mut best_imb = imbalance(&weight);
        loop {
            // Valid tops of both heaps.
            let mut top = [None, None];
            for s in 0..2 {
                while let Some(&(gn, Reverse(v))) = heaps[s].peek() {
                    if locked[v] || part[v] as usize != s || gain[v] != gn {
                        heaps[s].pop();
                    } else {
                        top[s] = Some((gn, v));
                        break;
                    }
                }
            }
            let feasible = |s: usize, v: usize| weight[1 - s] + g.vw[v] <= max_side;
            let pick = match (top[0], top[1]) {
                (Some((g0, v0)), Some((g1, v1))) => {
                    let (f0, f1) = (feasible(0, v0), feasible(1, v1));
                    match (f0, f1) {
                        (true, true) => {
                            if g0 > g1 || (g0 == g1 && weight[0] >= weight[1]) {
                                Some(0)
                            } else {
                                Some(1)
                            }
                        }
                        (true, false) => Some(0),
                        (false, true) => Some(1),
                        _ => None,
                    }
                }
                (Some((_, v0)), None) => feasible(0, v0).then_some(0),
                (None, Some((_, v1))) => feasible(1, v1).then_some(1),
                (None, None) => None,
            };
            let Some(s) = pick else { break };
            let (gn, v) = top[s].unwrap_or_default();
            heaps[s].pop();
            locked[v] = true;
            part[v] = 1 - s as u8;
            weight[s] -= g.vw[v];
            weight[1 - s] += g.vw[v];
            delta -= gn;
            moves.push(v);
            for (w, e) in g.nbrs(v) {
                gain[w] += if part[w] == part[v] { -2 * e } else { 2 * e };
                if !locked[w] {
                    heaps[part[w] as usize].push((gain[w], Reverse(w)));
                }
            }
            let imb = imbalance(&weight);
            if delta < best_delta || (delta == best_delta && imb < best_imb) {
                best_delta = delta;
                best_len = moves.len();
                best_imb = imb;
            } else if moves.len() - best_len > FM_PATIENCE {
                break;
            }
        }
        for &v in moves[best_len..].iter().rev() {
            let s = part[v] as usize;
            part[v] = 1 - s as u8;
            weight[s] -= g.vw[v];
            weight[1 - s] += g.vw[v];
        }
        if best_len == 0 && pass > 0 {
            break;
        }
    }
}
