//! The split of the rank range among the parts of an owner-computes assembly (`scatter.rs`):
//! each part's cost from the cells it evaluates, the hand-overs it reads and those it packs,
//! and the split that minimises the largest part's cost.

/// Cost of a cell in a part, in units of [`COST_READ`]: evaluating it (the part owns its
/// highest rank) …
pub(crate) const COST_EVAL: u64 = 16;
/// … scattering a cell handed over from a higher part (its evaluation is done there) …
pub(crate) const COST_READ: u64 = 5;
/// … and packing an evaluated cell for a lower part (measured: docs/PERFORMANCE.md).
pub(crate) const COST_SEND: u64 = 1;

/// Where the rank range can be split: how many cells have their lowest rank below s, and how
/// many their highest, for every s. The part [a, b) evaluates the cells whose highest rank is
/// there, `hi_below[b] − hi_below[a]`; it scatters, from a hand-over, the cells with lowest
/// rank below b and highest from b on (`lo_below[b] − hi_below[b]`), and it packs, for the
/// parts below, the cells it evaluates that have a node below a (`lo_below[a] − hi_below[a]`).
#[derive(Debug, Clone)]
pub(crate) struct Sweep {
    lo_below: Vec<u32>,
    hi_below: Vec<u32>,
}

impl Sweep {
    /// From each cell's (lowest, highest) rank, over `nodes` ranks.
    pub(crate) fn new(nodes: usize, spans: impl Iterator<Item = (usize, usize)>) -> Self {
        let mut lo_below = vec![0u32; nodes + 1];
        let mut hi_below = vec![0u32; nodes + 1];
        for (lo, hi) in spans {
            lo_below[lo + 1] += 1;
            hi_below[hi + 1] += 1;
        }
        for s in 0..nodes {
            lo_below[s + 1] += lo_below[s];
            hi_below[s + 1] += hi_below[s];
        }
        Self { lo_below, hi_below }
    }

    /// Cells across rank s: lowest rank below s, highest from s on.
    fn across(&self, s: usize) -> u64 {
        u64::from(self.lo_below[s] - self.hi_below[s])
    }

    /// Cost of the part [a, b) (a < b): its evaluations, hand-overs read and packed.
    pub(crate) fn cost(&self, a: usize, b: usize) -> u64 {
        let owned = u64::from(self.hi_below[b] - self.hi_below[a]);
        COST_EVAL * owned + COST_READ * self.across(b) + COST_SEND * self.across(a)
    }

    /// Greedy parts of cost at most `w` each from rank 0 on; None if more than `parts` are
    /// needed.
    fn greedy(&self, parts: usize, w: u64) -> Option<Vec<usize>> {
        let nodes = self.lo_below.len() - 1;
        let mut out = vec![0];
        let mut a = 0;
        while a < nodes {
            if out.len() > parts {
                return None;
            }
            // The furthest b whose part stays within w: cost(a, b) is non-decreasing in b
            // (COST_EVAL·hi_below[b] + COST_READ·(lo_below[b] − hi_below[b]), COST_READ ≤
            // COST_EVAL), so bisect on b in (a, nodes].
            let (mut lo, mut hi) = (a, nodes);
            while lo < hi {
                let mid = lo + (hi - lo).div_ceil(2);
                if self.cost(a, mid) <= w {
                    lo = mid;
                } else {
                    hi = mid - 1;
                }
            }
            if lo == a {
                return None;
            }
            out.push(lo);
            a = lo;
        }
        (out.len() <= parts + 1).then_some(out)
    }

    /// Rank boundaries 0 = s_0 < s_1 < … = nodes, at most `parts` parts, with the largest
    /// part's [`cost`](Self::cost) minimised by bisection on it (each bound tried greedily:
    /// exact for the evaluations and reads, blind to the packing a split adds to the next
    /// part, which is a few cells' worth at most).
    pub(crate) fn splits(&self, parts: usize) -> Vec<usize> {
        const { assert!(COST_READ <= COST_EVAL) };
        let nodes = self.lo_below.len() - 1;
        if parts <= 1 || nodes < 2 {
            return vec![0, nodes];
        }
        let whole = self.cost(0, nodes).max(1);
        let (mut lo, mut hi) = (whole.div_ceil(parts as u64), whole);
        let mut best = self.greedy(parts, hi).unwrap_or_else(|| vec![0, nodes]);
        while lo < hi {
            let mid = lo + (hi - lo) / 2;
            match self.greedy(parts, mid) {
                Some(s) => {
                    best = s;
                    hi = mid;
                }
                None => lo = mid + 1,
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Splits are increasing, cover the range, and minimise the largest part's cost (cells it
    /// evaluates, hand-overs it reads and packs, counted straight from the spans): within the
    /// packing of the cells across each split of the optimum of a search over every split,
    /// for 2 and 3 parts.
    #[test]
    fn splits_balance_the_parts() {
        // A chain of 100 cells over ranks 2k … 2k + 3 (an even rank is straddled by one cell,
        // an odd one by two), and a second chain whose cells are twice as dense at the start.
        let chain: Vec<(usize, usize)> = (0..100).map(|k| (2 * k, 2 * k + 3)).collect();
        let dense: Vec<(usize, usize)> = (0..150)
            .map(|k| {
                if k < 100 {
                    (k, k + 3)
                } else {
                    (2 * k - 100, 2 * k - 97)
                }
            })
            .collect();
        for spans in [&chain, &dense] {
            let nodes = spans.iter().map(|s| s.1).max().unwrap() + 1;
            let sweep = Sweep::new(nodes, spans.iter().copied());
            let cost = |a: usize, b: usize| -> u64 {
                let count = |f: &dyn Fn(&(usize, usize)) -> bool| {
                    spans.iter().filter(|s| f(s)).count() as u64
                };
                COST_EVAL * count(&|&(_, h)| h >= a && h < b)
                    + COST_READ * count(&|&(l, h)| l < b && h >= b)
                    + COST_SEND * count(&|&(l, h)| l < a && h >= a)
            };
            let worst = |s: &[usize]| s.windows(2).map(|w| cost(w[0], w[1])).max().unwrap();
            for parts in 1..6 {
                let s = sweep.splits(parts);
                assert_eq!(s.first(), Some(&0));
                assert_eq!(s.last(), Some(&nodes));
                assert_eq!(s.len(), parts + 1, "{parts} parts: {s:?}");
                assert!(s.windows(2).all(|w| w[0] < w[1]), "{s:?}");
                for w in s.windows(2) {
                    assert_eq!(sweep.cost(w[0], w[1]), cost(w[0], w[1]), "{w:?}");
                }
                let best = match parts {
                    1 => cost(0, nodes),
                    2 => (1..nodes).map(|a| worst(&[0, a, nodes])).min().unwrap(),
                    3 => (1..nodes)
                        .flat_map(|a| (a + 1..nodes).map(move |b| [0, a, b, nodes]))
                        .map(|s| worst(&s))
                        .min()
                        .unwrap(),
                    // Within one cell's evaluation and the straddlers of each split.
                    _ => spans.len() as u64 * COST_EVAL / parts as u64,
                };
                // The greedy takes each part as far as it goes, blind to the packing the next
                // part then does: off by at most that, the most cells across one rank.
                let max_across = (0..nodes).map(|r| sweep.across(r)).max().unwrap();
                let slack = (parts as u64 - 1) * COST_SEND * max_across
                    + if parts <= 3 {
                        0
                    } else {
                        COST_EVAL + 3 * (COST_READ + COST_SEND)
                    };
                assert!(
                    worst(&s) <= best + slack,
                    "{parts} parts: {s:?} costs {} best {best}",
                    worst(&s)
                );
            }
        }
        assert_eq!(Sweep::new(3, [(0, 2)].into_iter()).splits(4), vec![0, 3]);
    }
}
