//! Per split of the rank range, what an assembly reuses from one call to the next: the
//! prefetch hints of each cell's scatter (`prefetch.rs`) and which cells cross the split and
//! are handed over where (`handover.rs`).

use super::Assembler;
use super::handover::{HandOverPlan, Slot};
use super::prefetch::{CellLines, PrefetchPlan};
use super::share::{Count, Positions, walk};
use rayon::prelude::*;
use std::sync::Arc;

impl Assembler {
    /// The prefetch hints for this split of the rank range and a values array starting `align`
    /// f64s past a 64-byte boundary: the cached plan if it was made for them, else a new one
    /// (one pass over every cell's scatter positions, parts in parallel). Tangents of 2³² or
    /// more entries get no hints.
    pub(super) fn prefetch_plan(&self, splits: &[usize], align: usize) -> Arc<PrefetchPlan> {
        let mut cached = self.plan.lock().unwrap_or_else(|e| e.into_inner());
        if cached.key.0 == splits && cached.key.1 == align {
            return cached.clone();
        }
        let nnz = self.pattern.nnz_lower();
        let col_ptr = self.pattern.col_ptr();
        let rank = &self.rank;
        let parts = if u32::try_from(nnz).is_err() {
            Vec::new()
        } else {
            splits
                .par_windows(2)
                .map(|w| {
                    let (lo, hi) = (w[0], w[1]);
                    let mut marks = vec![0u32; (nnz + 8) / 8 + 1];
                    self.groups
                        .iter()
                        .map(|g| {
                            let cells = g.listed(lo, hi).into_iter().map(|i| {
                                move |visit: &mut dyn FnMut(usize)| {
                                    let (nodes, pairs) = (g.nodes_of(i), g.pairs_of(i));
                                    walk(
                                        nodes,
                                        pairs,
                                        rank,
                                        (lo, hi),
                                        &mut Positions::new(col_ptr, visit),
                                    )
                                }
                            });
                            CellLines::new(cells, align, &mut marks)
                        })
                        .collect()
                })
                .collect()
        };
        *cached = Arc::new(PrefetchPlan {
            key: (splits.to_vec(), align),
            parts,
        });
        cached.clone()
    }

    /// Which cells cross the parts of this split and where each is handed over: the cached
    /// plan if it was made for the split, else a new one.
    pub(super) fn hand_over_plan(&self, splits: &[usize]) -> Arc<HandOverPlan> {
        let mut cached = self.hand_over.lock().unwrap_or_else(|e| e.into_inner());
        if cached.key == splits {
            return cached.clone();
        }
        let parts = splits.len().saturating_sub(1);
        let part_of = |r: usize| splits.partition_point(|&s| s <= r).saturating_sub(1);
        let rank = &self.rank;
        let mut plan = HandOverPlan {
            key: splits.to_vec(),
            incoming: vec![vec![Vec::new(); self.groups.len()]; parts],
            outgoing: vec![vec![Vec::new(); self.groups.len()]; parts],
            ..HandOverPlan::default()
        };
        let (mut end_k, mut end_f) = (0, 0);
        for (q, w) in splits.windows(2).enumerate() {
            let (lo, hi) = (w[0], w[1]);
            for (gi, g) in self.groups.iter().enumerate() {
                for (at, i) in g.listed(lo, hi).into_iter().enumerate() {
                    let nodes = g.nodes_of(i);
                    let inside = nodes
                        .iter()
                        .filter(|&&v| rank[v] >= lo && rank[v] < hi)
                        .count();
                    if g.span[i].1 < hi || inside == 0 {
                        continue;
                    }
                    let mut share = Count::default();
                    walk(nodes, g.pairs_of(i), rank, (lo, hi), &mut share);
                    let k = plan.with_tangent.len();
                    for (slots, end, len) in [
                        (&mut plan.with_tangent, &mut end_k, 3 * inside + share.0),
                        (&mut plan.forces_only, &mut end_f, 3 * inside),
                    ] {
                        slots.push(Slot { start: *end, len });
                        *end += len;
                    }
                    plan.incoming[q][gi].push((i, k, at));
                    plan.outgoing[part_of(g.span[i].1)][gi].push((i, k, q));
                }
            }
        }
        for lists in &mut plan.outgoing {
            for l in lists {
                l.sort_unstable_by_key(|&(i, _, q)| (i, q));
            }
        }
        *cached = Arc::new(plan);
        cached.clone()
    }
}
