//! A part's share of a cell's tangent: the node pairs (I, J) whose higher-ranked node the part
//! owns, max(rank I, rank J) ∈ [lo, hi). Every entry of K has one owner (the part of its
//! higher-ranked node), and every cell that adds to it holds both nodes, so its highest rank is
//! in the owner's range or beyond: the owner meets all of them, its own cells first, then those
//! handed over from higher parts, each group in sweep order, which is the order a single part
//! adds them in. Hence the bitwise independence of the thread count.
//!
//! One walk ([`walk`]) visits a share in scatter order (column node by column node: the
//! diagonal block, the stored pairs, the added pairs); what is done at each step is a [`Sink`]:
//! scatter from the full tangent, pack for a hand-over, scatter from a pack, list positions.

use super::scatter::{column_bases, segment};

/// What a [`walk`] does at each step.
pub(crate) trait Sink {
    /// Column node j's turn starts (before its diagonal block and pairs).
    fn column(&mut self, j: usize, nj: usize);
    /// The lower triangle of the diagonal block of node j (`first`: stored, not added).
    fn diagonal(&mut self, j: usize, first: bool);
    /// Pair (i, j) at offset o(I, J), stored (the cell is the first to reach it).
    fn store(&mut self, i: usize, o: usize);
    /// Pair (i, j) at offset o(I, J), added.
    fn add(&mut self, i: usize, o: usize);
}

/// Walks the share of ranks [lo, hi) of a cell (`nodes`, its [`pair_lists`] table `pairs`)
/// into `sink`, in scatter order.
///
/// [`pair_lists`]: super::scatter::pair_lists
pub(crate) fn walk(
    nodes: &[usize],
    pairs: &[u32],
    rank: &[usize],
    (lo, hi): (usize, usize),
    sink: &mut impl Sink,
) {
    let nn = nodes.len();
    // `pair_lists` refuses cells of over 91 nodes (4 095 pairs), so the masks hold every node.
    debug_assert!(nn <= 128, "cells of at most 128 nodes");
    // Bit k: node k ranked below hi; ranked in [lo, hi).
    let (mut below, mut inside) = (0u128, 0u128);
    for (k, &v) in nodes.iter().enumerate().take(128) {
        let r = rank[v];
        below |= u128::from(r < hi) << k;
        inside |= u128::from(r >= lo && r < hi) << k;
    }
    let all = if nn >= 128 {
        u128::MAX
    } else {
        (1u128 << nn) - 1
    };
    if inside == all {
        // Every node in the part: the whole cell, no test per pair.
        for (j, &nj) in nodes.iter().enumerate() {
            let (first, stored, added) = segment(pairs, nn, j);
            sink.column(j, nj);
            sink.diagonal(j, first);
            for &e in stored {
                sink.store((e >> 24) as usize, (e & 0xff_ffff) as usize);
            }
            for &e in added {
                sink.add((e >> 24) as usize, (e & 0xff_ffff) as usize);
            }
        }
        return;
    }
    for (j, &nj) in nodes.iter().enumerate() {
        if below >> j & 1 == 0 {
            continue;
        }
        // Pair (i, j) is ours when its higher rank is in [lo, hi): i below hi if j is in the
        // range, i in the range if j is below it.
        let own_column = inside >> j & 1 == 1;
        let mask = if own_column { below } else { inside };
        let ours = |e: &&u32| (mask >> (**e >> 24)) & 1 == 1;
        let (first, stored, added) = segment(pairs, nn, j);
        if !own_column && !stored.iter().chain(added).any(|e| ours(&e)) {
            continue;
        }
        sink.column(j, nj);
        if own_column {
            sink.diagonal(j, first);
        }
        for &e in stored.iter().filter(ours) {
            sink.store((e >> 24) as usize, (e & 0xff_ffff) as usize);
        }
        for &e in added.iter().filter(ours) {
            sink.add((e >> 24) as usize, (e & 0xff_ffff) as usize);
        }
    }
}

/// Rows 3j, 3j + 1, 3j + 2 of a row-major nd × nd tangent.
#[inline(always)]
fn rows(ke: &[f64], nd: usize, j: usize) -> [&[f64]; 3] {
    let block = &ke[3 * j * nd..(3 * j + 3) * nd];
    let (r0, rest) = block.split_at(nd);
    let (r1, r2) = rest.split_at(nd);
    [r0, r1, r2]
}

/// Scatters from a cell's full symmetric tangent `ke` (row-major, nd × nd; row 3j + c read as
/// column 3j + c) into the global values: K(3I + a, 3J + c) (+)= Ke(3i + a, 3j + c).
pub(crate) struct Scatter<'a, 'v> {
    ke: &'a [f64],
    nd: usize,
    col_ptr: &'a [usize],
    values: &'a super::scatter::Shared<'v>,
    base: [usize; 3],
    rows: [&'a [f64]; 3],
}

impl<'a, 'v> Scatter<'a, 'v> {
    pub(crate) fn new(
        ke: &'a [f64],
        nd: usize,
        col_ptr: &'a [usize],
        values: &'a super::scatter::Shared<'v>,
    ) -> Self {
        Self {
            ke,
            nd,
            col_ptr,
            values,
            base: [0; 3],
            rows: [&[]; 3],
        }
    }
}

impl Sink for Scatter<'_, '_> {
    #[inline(always)]
    fn column(&mut self, j: usize, nj: usize) {
        self.base = column_bases(self.col_ptr, nj);
        self.rows = rows(self.ke, self.nd, j);
    }

    #[inline(always)]
    fn diagonal(&mut self, j: usize, first: bool) {
        for c in 0..3 {
            for a in c..3 {
                let x = self.rows[c][3 * j + a];
                if first {
                    self.values.set(self.base[c] + a, x);
                } else {
                    self.values.add(self.base[c] + a, x);
                }
            }
        }
    }

    #[inline(always)]
    fn store(&mut self, i: usize, o: usize) {
        for c in 0..3 {
            self.values
                .set3(self.base[c] + o, &self.rows[c][3 * i..3 * i + 3]);
        }
    }

    #[inline(always)]
    fn add(&mut self, i: usize, o: usize) {
        for c in 0..3 {
            self.values
                .add3(self.base[c] + o, &self.rows[c][3 * i..3 * i + 3]);
        }
    }
}

/// Copies a share's values, in walk order, into `out` (6 per diagonal block, 9 per pair): a
/// hand-over pack that [`Unpack`] scatters. Panics if `out` is shorter than [`Count`] says.
pub(crate) struct Pack<'a, 'o> {
    ke: &'a [f64],
    nd: usize,
    out: &'o mut [f64],
    at: usize,
    rows: [&'a [f64]; 3],
}

impl<'a, 'o> Pack<'a, 'o> {
    pub(crate) fn new(ke: &'a [f64], nd: usize, out: &'o mut [f64]) -> Self {
        Self {
            ke,
            nd,
            out,
            at: 0,
            rows: [&[]; 3],
        }
    }

    fn triple(&mut self, i: usize) {
        for c in 0..3 {
            self.out[self.at..self.at + 3].copy_from_slice(&self.rows[c][3 * i..3 * i + 3]);
            self.at += 3;
        }
    }
}

impl Sink for Pack<'_, '_> {
    fn column(&mut self, j: usize, _nj: usize) {
        self.rows = rows(self.ke, self.nd, j);
    }

    fn diagonal(&mut self, j: usize, _first: bool) {
        for c in 0..3 {
            for a in c..3 {
                self.out[self.at] = self.rows[c][3 * j + a];
                self.at += 1;
            }
        }
    }

    fn store(&mut self, i: usize, _o: usize) {
        self.triple(i);
    }

    fn add(&mut self, i: usize, _o: usize) {
        self.triple(i);
    }
}

/// Scatters a [`Pack`] (read in the same walk order) into the global values.
pub(crate) struct Unpack<'a, 'v> {
    pack: &'a [f64],
    col_ptr: &'a [usize],
    values: &'a super::scatter::Shared<'v>,
    at: usize,
    base: [usize; 3],
}

impl<'a, 'v> Unpack<'a, 'v> {
    pub(crate) fn new(
        pack: &'a [f64],
        col_ptr: &'a [usize],
        values: &'a super::scatter::Shared<'v>,
    ) -> Self {
        Self {
            pack,
            col_ptr,
            values,
            at: 0,
            base: [0; 3],
        }
    }
}

impl Sink for Unpack<'_, '_> {
    #[inline(always)]
    fn column(&mut self, _j: usize, nj: usize) {
        self.base = column_bases(self.col_ptr, nj);
    }

    #[inline(always)]
    fn diagonal(&mut self, _j: usize, first: bool) {
        let x = &self.pack[self.at..self.at + 6];
        let mut k = 0;
        for c in 0..3 {
            for a in c..3 {
                if first {
                    self.values.set(self.base[c] + a, x[k]);
                } else {
                    self.values.add(self.base[c] + a, x[k]);
                }
                k += 1;
            }
        }
        self.at += 6;
    }

    #[inline(always)]
    fn store(&mut self, _i: usize, o: usize) {
        let x = &self.pack[self.at..self.at + 9];
        for c in 0..3 {
            self.values.set3(self.base[c] + o, &x[3 * c..3 * c + 3]);
        }
        self.at += 9;
    }

    #[inline(always)]
    fn add(&mut self, _i: usize, o: usize) {
        let x = &self.pack[self.at..self.at + 9];
        for c in 0..3 {
            self.values.add3(self.base[c] + o, &x[3 * c..3 * c + 3]);
        }
        self.at += 9;
    }
}

/// Counts the values of a share (the length of its [`Pack`]).
#[derive(Default)]
pub(crate) struct Count(pub(crate) usize);

impl Sink for Count {
    fn column(&mut self, _j: usize, _nj: usize) {}
    fn diagonal(&mut self, _j: usize, _first: bool) {
        self.0 += 6;
    }
    fn store(&mut self, _i: usize, _o: usize) {
        self.0 += 9;
    }
    fn add(&mut self, _i: usize, _o: usize) {
        self.0 += 9;
    }
}

/// Calls `visit(p)` for every tangent position a share writes, in the scatter's order: what
/// the prefetch hints of a cell are made from.
pub(crate) struct Positions<'a, F> {
    col_ptr: &'a [usize],
    visit: F,
    base: [usize; 3],
}

impl<'a, F: FnMut(usize)> Positions<'a, F> {
    pub(crate) fn new(col_ptr: &'a [usize], visit: F) -> Self {
        Self {
            col_ptr,
            visit,
            base: [0; 3],
        }
    }

    fn triple(&mut self, o: usize) {
        for c in 0..3 {
            for a in 0..3 {
                (self.visit)(self.base[c] + o + a);
            }
        }
    }
}

impl<F: FnMut(usize)> Sink for Positions<'_, F> {
    fn column(&mut self, _j: usize, nj: usize) {
        self.base = column_bases(self.col_ptr, nj);
    }
    fn diagonal(&mut self, _j: usize, _first: bool) {
        for c in 0..3 {
            for a in c..3 {
                (self.visit)(self.base[c] + a);
            }
        }
    }
    fn store(&mut self, _i: usize, o: usize) {
        self.triple(o);
    }
    fn add(&mut self, _i: usize, o: usize) {
        self.triple(o);
    }
}
