//! The cache lines of the tangent each cell's scatter writes, per part of a split: the hints
//! the kernel prefetches during that cell's tangent product (`nonlin3d_element::Prefetch`).
//!
//! At 100 k DOF the tangent (56 MB) is far larger than the caches and a Hex20 cell's adds
//! touch ≈ 380 distinct lines of it, ≈ 130 of them for the first time in the assembly
//! (from DRAM). Waiting on them was a quarter of the assembly's time; spread as prefetches
//! over the cell's Σ TᵀT product (≈ 6 per register block), their latency overlaps the
//! arithmetic (docs/PERFORMANCE.md, docs/DESIGN.md).

/// A line that one of the previous `RECENT` cells of the list touched is not hinted again: it
/// is still in L2 (16 Hex20 cells touch ≈ 6 000 lines, 390 kB of the 1 MB). At 89 k DOF this
/// leaves 204 hints per Hex20 cell of 377 (docs/PERFORMANCE.md: 16 to 64 measured alike,
/// each ≈ 1 ms faster per assembly than hinting every line).
const RECENT: u32 = 16;

/// Per cell of a part's list, the tangent positions (one per distinct 64-byte line, the first
/// the scatter writes there) that its scatter touches and the previous [`RECENT`] cells did
/// not.
#[derive(Debug, Default)]
pub(crate) struct CellLines {
    start: Vec<u32>,
    positions: Vec<u32>,
}

impl CellLines {
    /// Builds the lists of `cells` (each given by a function that visits the tangent positions
    /// its scatter writes), for a values array whose element 0 sits `align` f64s past a
    /// 64-byte boundary; `marks` is scratch of at least (positions + 8) / 8 + 1 entries.
    pub(crate) fn new<C>(cells: impl Iterator<Item = C>, align: usize, marks: &mut [u32]) -> Self
    where
        C: FnOnce(&mut dyn FnMut(usize)),
    {
        marks.fill(0);
        let mut out = Self {
            start: vec![0],
            positions: Vec::new(),
        };
        for (stamp, visit_cell) in (1u32..).zip(cells) {
            let positions = &mut out.positions;
            visit_cell(&mut |p: usize| {
                let line = (align + p) / 8;
                if let Some(m) = marks.get_mut(line)
                    && *m != stamp
                {
                    let recent = *m != 0 && *m + RECENT >= stamp;
                    *m = stamp;
                    if recent {
                        return;
                    }
                    // Positions fit: the plan is only made for tangents below 2³² entries.
                    positions.push(p as u32);
                }
            });
            out.start.push(out.positions.len() as u32);
        }
        out
    }

    /// The positions of the k-th listed cell (empty past the end).
    pub(crate) fn of(&self, k: usize) -> &[u32] {
        match (self.start.get(k), self.start.get(k + 1)) {
            (Some(&a), Some(&b)) => &self.positions[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Number of positions over all cells.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.positions.len()
    }
}

/// The hints of every part of one split, for one alignment of the values array.
#[derive(Debug, Default)]
pub(crate) struct PrefetchPlan {
    /// The split (part boundaries in rank) and alignment the plan was made for.
    pub(crate) key: (Vec<usize>, usize),
    /// `[part][group]`.
    pub(crate) parts: Vec<Vec<CellLines>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_position_per_line_per_cell_in_visit_order() {
        // Two cells: the first writes 0..10 and 30, the second 5..7 and 16; aligned by 3.
        let cells: Vec<Vec<usize>> = vec![(0..10).chain([30]).collect(), vec![5, 6, 16]];
        let mut marks = vec![0; 8];
        let lines = CellLines::new(
            cells
                .iter()
                .map(|c| move |visit: &mut dyn FnMut(usize)| c.iter().for_each(|&p| visit(p))),
            3,
            &mut marks,
        );
        // Lines (3 + p) / 8: 0..5 → 0, 5..10 → 1, 30 → 4; then 5, 6 → 1 (just hinted), 16 → 2.
        assert_eq!(lines.of(0), &[0, 5, 30]);
        assert_eq!(lines.of(1), &[16]);
        assert!(lines.of(2).is_empty());
        assert_eq!(lines.len(), 4);
    }

    #[test]
    fn a_line_is_hinted_again_once_recent_cells_have_passed() {
        // Cell k writes position 8k (line k) and position 0 (line 0) every RECENT + 1 cells.
        let n = 3 * (RECENT as usize + 1);
        let cells: Vec<Vec<usize>> = (0..n)
            .map(|k| {
                let mut c = vec![8 * k + 1];
                if k % (RECENT as usize + 1) == 0 {
                    c.push(0);
                }
                c
            })
            .collect();
        let mut marks = vec![0; n + 2];
        let lines = CellLines::new(
            cells
                .iter()
                .map(|c| move |visit: &mut dyn FnMut(usize)| c.iter().for_each(|&p| visit(p))),
            0,
            &mut marks,
        );
        // Line 0 belongs to cell 0 (position 1) and every RECENT + 1 cells (position 0): too
        // far apart to count as recent, so it is hinted each time.
        assert_eq!(lines.of(0), &[1]);
        for k in (1..n).filter(|k| k % (RECENT as usize + 1) == 0) {
            assert_eq!(lines.of(k), &[8 * k as u32 + 1, 0], "cell {k}");
        }
        assert_eq!(lines.of(1), &[9]);
    }
}
