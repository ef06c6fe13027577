//! The cache lines of the tangent each cell's scatter writes, per part of a split: the hints
//! the kernel prefetches during that cell's tangent product (`nonlin3d_element::Prefetch`).
//!
//! At 100 k DOF the tangent (56 MB) is far larger than the caches and a Hex20 cell's adds
//! touch ≈ 380 distinct lines of it, ≈ 130 of them for the first time in the assembly
//! (from DRAM). Waiting on them was a quarter of the assembly's time; spread as prefetches
//! over the cell's Σ TᵀT product (≈ 6 per register block), their latency overlaps the
//! arithmetic (docs/PERFORMANCE.md, docs/DESIGN.md).

/// Per cell of a part's list, the tangent positions (one per distinct 64-byte line, the first
/// the scatter writes there) that its scatter touches.
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
                    *m = stamp;
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
        // Lines (3 + p) / 8: 0..5 → 0, 5..10 → 1, 30 → 4; then 5, 6 → 1, 16 → 2.
        assert_eq!(lines.of(0), &[0, 5, 30]);
        assert_eq!(lines.of(1), &[5, 16]);
        assert!(lines.of(2).is_empty());
        assert_eq!(lines.len(), 5);
    }
}
