//! Vertex separators: König's cover of the cut edges, then node-based Fiduccia–Mattheyses.

use super::{BALANCE, FM_PASSES, FM_PATIENCE, Graph};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// A vertex separator from the edge cut: a minimum vertex cover of the bipartite graph of cut
/// edges (maximum matching by augmenting paths, then König's construction).
pub(crate) fn separator(g: &Graph, mut part: Vec<u8>) -> Vec<u8> {
    let n = g.n();
    let left: Vec<usize> = (0..n)
        .filter(|&v| part[v] == 0 && g.nbrs(v).any(|(w, _)| part[w] == 1))
        .collect();
    let mut mate = vec![usize::MAX; n];
    let mut stamp = vec![usize::MAX; n];
    for (round, &u) in left.iter().enumerate() {
        augment(g, &part, u, round, &mut mate, &mut stamp);
    }
    // Alternating reachability from unmatched left vertices.
    let mut reached = vec![false; n];
    let mut stack: Vec<usize> = left
        .iter()
        .copied()
        .filter(|&u| mate[u] == usize::MAX)
        .collect();
    for &u in &stack {
        reached[u] = true;
    }
    while let Some(u) = stack.pop() {
        for (w, _) in g.nbrs(u) {
            if part[w] == 1 && !reached[w] {
                reached[w] = true;
                let m = mate[w];
                if m != usize::MAX && !reached[m] {
                    reached[m] = true;
                    stack.push(m);
                }
            }
        }
    }
    let right: Vec<usize> = (0..n)
        .filter(|&v| part[v] == 1 && g.nbrs(v).any(|(w, _)| part[w] == 0))
        .collect();
    for &u in &left {
        if !reached[u] {
            part[u] = 2;
        }
    }
    for &w in &right {
        if reached[w] {
            part[w] = 2;
        }
    }
    part
}

/// Fiduccia–Mattheyses on the vertex separator (METIS's two-sided node refinement): a
/// separator vertex v moves into side s and pulls its neighbours on the other side into the
/// separator; gain = w(v) − w(those neighbours). Moves past the lightest separator are undone.
pub(crate) fn refine_separator(g: &Graph, part: &mut [u8]) {
    let n = g.n();
    let total = g.total();
    let max_side = ((BALANCE * total as f64) as i64).max((total + 1) / 2);
    let gain_into = |part: &[u8], v: usize, s: u8| -> i64 {
        g.vw[v]
            - g.nbrs(v)
                .filter(|&(u, _)| part[u] == 1 - s)
                .map(|(u, _)| g.vw[u])
                .sum::<i64>()
    };
    for _ in 0..FM_PASSES {
        let mut weight = [0i64; 3];
        for v in 0..n {
            weight[part[v] as usize] += g.vw[v];
        }
        let mut heaps: [BinaryHeap<(i64, Reverse<usize>)>; 2] =
            [BinaryHeap::new(), BinaryHeap::new()];
        let mut gain = [vec![0i64; n], vec![0i64; n]];
        for v in (0..n).filter(|&v| part[v] == 2) {
            for s in 0..2 {
                gain[s][v] = gain_into(part, v, s as u8);
                heaps[s].push((gain[s][v], Reverse(v)));
            }
        }
        let mut locked = vec![false; n];
        // (vertex, its side before the move), in order.
        let mut log: Vec<(usize, u8)> = Vec::new();
        let (start, mut best_sep, mut best_len, mut since) = (weight[2], weight[2], 0, 0);
        let best_imb = |w: &[i64; 3]| (w[0] - w[1]).abs();
        let mut best_balance = best_imb(&weight);
        loop {
            let mut top = [None, None];
            for s in 0..2 {
                while let Some(&(gn, Reverse(v))) = heaps[s].peek() {
                    if locked[v] || part[v] != 2 || gain[s][v] != gn {
                        heaps[s].pop();
                    } else {
                        top[s] = Some((gn, v));
                        break;
                    }
                }
            }
            let fits = |s: usize, v: usize| weight[s] + g.vw[v] <= max_side;
            let candidates =
                (0..2).filter_map(|s| top[s].filter(|&(_, v)| fits(s, v)).map(|t| (s, t)));
            // Highest gain; on ties, into the lighter side.
            let Some((s, (gn, v))) =
                candidates.max_by_key(|&(s, (gn, _))| (gn, Reverse(weight[s])))
            else {
                break;
            };
            debug_assert_eq!(gn, gain[s][v]);
            heaps[s].pop();
            locked[v] = true;
            log.push((v, 2));
            part[v] = s as u8;
            weight[2] -= g.vw[v];
            weight[s] += g.vw[v];
            let other = 1 - s as u8;
            let pulled: Vec<usize> = g
                .nbrs(v)
                .filter(|&(u, _)| part[u] == other)
                .map(|(u, _)| u)
                .collect();
            for &u in &pulled {
                log.push((u, other));
                part[u] = 2;
                weight[other as usize] -= g.vw[u];
                weight[2] += g.vw[u];
            }
            // Gains change for the pulled vertices and the separator vertices next to them.
            let mut touched: Vec<usize> = pulled.clone();
            for &u in &pulled {
                touched.extend(g.nbrs(u).map(|(w, _)| w).filter(|&w| part[w] == 2));
            }
            touched.extend(g.nbrs(v).map(|(w, _)| w).filter(|&w| part[w] == 2));
            touched.sort_unstable();
            touched.dedup();
            for &w in &touched {
                if locked[w] || part[w] != 2 {
                    continue;
                }
                for t in 0..2 {
                    gain[t][w] = gain_into(part, w, t as u8);
                    heaps[t].push((gain[t][w], Reverse(w)));
                }
            }
            let imb = best_imb(&weight);
            if weight[2] < best_sep || (weight[2] == best_sep && imb < best_balance) {
                best_sep = weight[2];
                best_balance = imb;
                best_len = log.len();
                since = 0;
            } else {
                since += 1;
                if since > FM_PATIENCE {
                    break;
                }
            }
        }
        for &(v, old) in log[best_len..].iter().rev() {
            part[v] = old;
        }
        if best_sep >= start {
            break;
        }
    }
}

/// One augmenting-path search (iterative depth-first) from left vertex `root`.
fn augment(
    g: &Graph,
    part: &[u8],
    root: usize,
    round: usize,
    mate: &mut [usize],
    stamp: &mut [usize],
) {
    // Stack of (left vertex, next neighbour position, right vertex taken to reach it).
    let mut stack: Vec<(usize, usize, usize)> = vec![(root, g.xadj[root], usize::MAX)];
    stamp[root] = round;
    while let Some(top) = stack.last_mut() {
        let u = top.0;
        if top.1 == g.xadj[u + 1] {
            stack.pop();
            continue;
        }
        let w = g.adj[top.1];
        top.1 += 1;
        if part[w] != 1 || stamp[w] == round {
            continue;
        }
        stamp[w] = round;
        if mate[w] == usize::MAX {
            // Flip the path: each left vertex on the stack takes the right vertex after it.
            let mut right = w;
            while let Some((l, _, via)) = stack.pop() {
                mate[right] = l;
                mate[l] = right;
                right = via;
            }
            return;
        }
        let m = mate[w];
        if stamp[m] != round {
            stamp[m] = round;
            stack.push((m, g.xadj[m], w));
        }
    }
}
