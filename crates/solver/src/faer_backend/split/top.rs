//! The top separator of an elimination order that does not say where it is (METIS's: its
//! nested dissection numbers the first part, then the second, then their separator, but
//! returns only the order).
//!
//! For a cut n₀ of the order, the DOFs at positions < n₀ are coupled to later ones only at
//! positions ≥ R(n₀) = min{ pos(j) : a_ij ≠ 0, pos(i) < n₀ ≤ pos(j) }, so positions
//! [0, n₀) and [n₀, R(n₀)) are two halves that do not touch and [R(n₀), n) separates them.
//! On a nested-dissection order the cut between the first and second part of the top level
//! gives the largest R (the shortest separator): a cut inside a part meets that part's own
//! separator earlier, a cut inside the separator leaves no second half. So the cut kept is the
//! one with the largest R(n₀) among those whose halves each hold at least [`MIN_SHARE`] of
//! the interior; ties go to the more even halves. Deterministic (no randomness, no threads).

use crate::SymmetricPattern;
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The smaller half must hold at least this share of the interior DOFs: a cut that leaves a
/// few DOFs on one side has nothing to run beside the other half.
pub(crate) const MIN_SHARE: f64 = 0.2;

/// (n₀, n₁) for the order `forward` (`forward[new] = old`) of `pattern`'s DOFs: the halves
/// `forward[..n₀]` and `forward[n₀..n₀ + n₁]` share no entry of A, the rest is the separator
/// (module docs). `None` when no cut leaves two halves of at least [`MIN_SHARE`] and a
/// non-empty separator. O(nnz + n log n): one pass over the entries, then a sweep of the cuts
/// with a heap of at most n later ends.
pub(crate) fn top_split(pattern: &SymmetricPattern, forward: &[usize]) -> Option<(usize, usize)> {
    let n = pattern.n();
    if forward.len() != n || n < 3 {
        return None;
    }
    let mut pos = vec![0usize; n];
    for (k, &d) in forward.iter().enumerate() {
        pos[d] = k;
    }
    // A cut n₀ is crossed by entry (lo, h) when lo < n₀ ≤ h, so the later ends that cross it
    // are {h ≥ n₀ : first(h) < n₀}, first(h) the earliest position coupled to h: one number
    // per DOF instead of one per entry.
    let mut first: Vec<usize> = (0..n).collect();
    for j in 0..n {
        for &i in pattern.column(j) {
            let (lo, hi) = (pos[i].min(pos[j]), pos[i].max(pos[j]));
            first[hi] = first[hi].min(lo);
        }
    }
    drop(pos);
    // The later ends bucketed by first(h) (those with first(h) = h cross no cut).
    let mut start = vec![0usize; n + 1];
    for (h, &f) in first.iter().enumerate() {
        if f < h {
            start[f + 1] += 1;
        }
    }
    for k in 0..n {
        start[k + 1] += start[k];
    }
    let mut ends = vec![0usize; start[n]];
    let mut fill = start.clone();
    for (h, &f) in first.iter().enumerate() {
        if f < h {
            ends[fill[f]] = h;
            fill[f] += 1;
        }
    }
    drop(fill);
    // Sweep the cut: the heap holds the later ends h that a cut at n₀ may cross, R(n₀) the least
    // of those not behind it.
    let mut heap = BinaryHeap::new();
    let mut best: Option<(usize, usize)> = None;
    let mut best_key = (0usize, Reverse(usize::MAX));
    for n0 in 1..n {
        heap.extend(ends[start[n0 - 1]..start[n0]].iter().map(|&h| Reverse(h)));
        while heap.peek().is_some_and(|&Reverse(h)| h < n0) {
            heap.pop();
        }
        let r = heap.peek().map_or(n, |&Reverse(h)| h);
        if r >= n {
            continue;
        }
        let small = n0.min(r - n0);
        if (small as f64) < MIN_SHARE * r as f64 {
            continue;
        }
        let key = (r, Reverse((2 * n0).abs_diff(r)));
        if key > best_key {
            best_key = key;
            best = Some((n0, r - n0));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A path 0–1–…–(n−1), ordered as nested dissection would: the middle vertex last.
    #[test]
    fn a_path_splits_at_its_middle_vertex() {
        let n = 9;
        let lists: Vec<Vec<usize>> = (0..n - 1).map(|i| vec![i, i + 1]).collect();
        let p = SymmetricPattern::from_dof_lists(n, &lists).unwrap();
        // Left 0..4, right 5..9, separator 4.
        let forward = vec![0, 1, 2, 3, 5, 6, 7, 8, 4];
        assert_eq!(top_split(&p, &forward), Some((4, 4)));
        // The natural order of a path has no separator at its end that leaves two halves.
        let natural: Vec<usize> = (0..n).collect();
        assert_eq!(top_split(&p, &natural), None);
    }

    /// A 5 × 5 grid ordered [left columns, right columns, middle column]: the middle column
    /// is the separator, and cuts inside the left part (whose own separator comes earlier)
    /// are not taken.
    #[test]
    fn a_grid_splits_at_its_middle_column() {
        let (w, h) = (5, 5);
        let id = |x: usize, y: usize| y * w + x;
        let mut lists = Vec::new();
        for y in 0..h {
            for x in 0..w {
                if x + 1 < w {
                    lists.push(vec![id(x, y), id(x + 1, y)]);
                }
                if y + 1 < h {
                    lists.push(vec![id(x, y), id(x, y + 1)]);
                }
            }
        }
        let p = SymmetricPattern::from_dof_lists(w * h, &lists).unwrap();
        let column = |x: usize| (0..h).map(move |y| id(x, y));
        let forward: Vec<usize> = [0, 1, 3, 4, 2].into_iter().flat_map(column).collect();
        assert_eq!(top_split(&p, &forward), Some((10, 10)));
    }

    /// The cut straight from the definition: R(n₀) = min{pos(j) : a_ij ≠ 0, pos(i) < n₀ ≤
    /// pos(j)}, the same choice rule; O(n · nnz).
    fn top_split_by_definition(
        pattern: &SymmetricPattern,
        forward: &[usize],
    ) -> Option<(usize, usize)> {
        let n = pattern.n();
        let mut pos = vec![0usize; n];
        for (k, &d) in forward.iter().enumerate() {
            pos[d] = k;
        }
        let mut best = None;
        let mut best_key = (0usize, Reverse(usize::MAX));
        for n0 in 1..n {
            let mut r = n;
            for j in 0..n {
                for &i in pattern.column(j) {
                    let (lo, hi) = (pos[i].min(pos[j]), pos[i].max(pos[j]));
                    if lo < n0 && n0 <= hi {
                        r = r.min(hi);
                    }
                }
            }
            if r >= n || (n0.min(r - n0) as f64) < MIN_SHARE * r as f64 {
                continue;
            }
            let key = (r, Reverse((2 * n0).abs_diff(r)));
            if key > best_key {
                best_key = key;
                best = Some((n0, r - n0));
            }
        }
        best
    }

    /// On grids with holes (some edges left out) under orders that end with a middle column,
    /// scrambled orders and the natural order, the sweep picks the cut the definition picks.
    #[test]
    fn the_sweep_agrees_with_the_definition() {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move |m: usize| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state % m as u64) as usize
        };
        let mut found = 0;
        for case in 0..40 {
            let (w, h) = (3 + case % 5, 2 + case % 4);
            let id = |x: usize, y: usize| y * w + x;
            let mut lists = Vec::new();
            for y in 0..h {
                for x in 0..w {
                    if x + 1 < w && next(5) > 0 {
                        lists.push(vec![id(x, y), id(x + 1, y)]);
                    }
                    if y + 1 < h && next(5) > 0 {
                        lists.push(vec![id(x, y), id(x, y + 1)]);
                    }
                }
            }
            let p = SymmetricPattern::from_dof_lists(w * h, &lists).unwrap();
            let mid = w / 2;
            let mut forward: Vec<usize> = (0..w)
                .filter(|&x| x != mid)
                .chain([mid])
                .flat_map(|x| (0..h).map(move |y| id(x, y)))
                .collect();
            match case % 3 {
                1 => {
                    for k in (1..forward.len()).rev() {
                        forward.swap(k, next(k + 1));
                    }
                }
                2 => forward = (0..w * h).collect(),
                _ => {}
            }
            let sweep = top_split(&p, &forward);
            assert_eq!(
                sweep,
                top_split_by_definition(&p, &forward),
                "case {case}: {w} × {h}, order {forward:?}"
            );
            found += usize::from(sweep.is_some());
        }
        // Both kinds of answer were compared.
        assert!((5..35).contains(&found), "{found} of 40 split");
    }
}
