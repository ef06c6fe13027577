//! The assembly proper: each part of the rank range evaluates its own cells and scatters its
//! share of them, hands over the shares of lower parts, then scatters what higher parts hand
//! over (or evaluates those cells itself when nobody has started on them). See `scatter.rs`.

use super::handover::{HandOverPlan, Mailbox};
use super::partial::relocate;
use super::prefetch::PrefetchPlan;
use super::scatter::Shared;
use super::share::{Pack, Scatter, Unpack, walk};
use super::{AHEAD, Assembler, Assembly, Group, OwnedEnergy};
use crate::AssemblyError;
use nonlin3d_element::{
    BatchInput, ElementOutput, Material, Prefetch, evaluate_listed_prefetching, prefetch_line,
};
use nonlin3d_solver::SymmetricMatrix;
use rayon::prelude::*;
use std::sync::{Arc, TryLockError};

/// What every part of one assembly shares: the split, the kernel's input, the plans of this
/// split, the hand-over slots and the arrays written (each entry by its owner only).
struct Run<'a> {
    asm: &'a Assembler,
    splits: &'a [usize],
    /// Each group's nodal displacements, cell after cell (the kernel's input layout).
    disp: &'a [Vec<[f64; 3]>],
    plan: Option<&'a PrefetchPlan>,
    hand_over: &'a HandOverPlan,
    mail: &'a Mailbox<'a>,
    forces: &'a Shared<'a>,
    values: &'a Shared<'a>,
    want_k: bool,
}

impl Assembler {
    /// Internal forces (and energy) at displacements `u`; the tangent into `tangent` (made by
    /// [`new_tangent`](Self::new_tangent); every value is overwritten) when given.
    ///
    /// Owner-computes on the current rayon pool: thread t adds the forces of the nodes in its
    /// part of the node range and the tangent entries whose higher-ranked node is there. It
    /// evaluates the cells whose highest node is its own, and takes the other cells with a node
    /// there over from the thread that evaluated them (no cell is evaluated twice). Each adds
    /// in the sweep order, so every entry receives its contributions in the same order and the
    /// results are bitwise the same on any number of threads. The first cell to reach a node
    /// pair stores its block, later ones add, so the tangent is never zeroed as a whole.
    pub fn assemble(
        &self,
        u: &[f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<Assembly, AssemblyError> {
        self.assemble_in_parts(u, tangent, rayon::current_num_threads())
    }

    /// [`assemble`](Self::assemble) with the node range cut into `parts` (one per thread in
    /// `assemble`; tests run more parts than threads, so that a part meets hand-overs nobody
    /// has started and evaluates them itself).
    pub(super) fn assemble_in_parts(
        &self,
        u: &[f64],
        tangent: Option<&mut SymmetricMatrix>,
        parts: usize,
    ) -> Result<Assembly, AssemblyError> {
        let mut internal = vec![0.0; self.n];
        let energy = self.assemble_into(u, &mut internal, tangent, parts)?;
        Ok(Assembly { internal, energy })
    }

    /// The tangent's values, checked to be on this assembler's pattern.
    fn tangent_values<'k>(
        &self,
        tangent: Option<&'k mut SymmetricMatrix>,
    ) -> Result<&'k mut [f64], AssemblyError> {
        Ok(match tangent {
            Some(k) => {
                if !Arc::ptr_eq(k.pattern(), &self.pattern) && **k.pattern() != *self.pattern {
                    return Err(AssemblyError::Length {
                        what: "tangent entries (make it with Assembler::new_tangent)",
                        expected: self.pattern.nnz_lower(),
                        got: k.pattern().nnz_lower(),
                    });
                }
                k.values_mut()
            }
            None => &mut [],
        })
    }

    /// Adds f_int(u) into `internal` (zeros on entry for f_int itself) and writes K(u) into
    /// `tangent` (every value); returns the strain energy, cell by cell in sweep order.
    pub(super) fn assemble_into(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
        parts: usize,
    ) -> Result<f64, AssemblyError> {
        for (what, x) in [
            ("displacements", u.len()),
            ("internal forces", internal.len()),
        ] {
            if x != self.n {
                return Err(AssemblyError::Length {
                    what,
                    expected: self.n,
                    got: x,
                });
            }
        }
        let want_k = tangent.is_some();
        let values = self.tangent_values(tangent)?;
        let disp: Vec<Vec<[f64; 3]>> = self.groups.iter().map(|g| gather(g, u)).collect();
        if want_k {
            for &p in &self.unreached {
                values[p] = 0.0;
            }
        }
        let splits = self.sweep.splits(parts);
        let plan = (want_k && self.prefetch).then(|| {
            let align = (values.as_ptr() as usize / std::mem::size_of::<f64>()) % 8;
            self.prefetch_plan(&splits, align)
        });
        let hand_over = self.hand_over_plan(&splits);
        let (slots, need) = hand_over.slots(want_k);
        let mut spare = Vec::new();
        let mut held = match self.mailbox.try_lock() {
            Ok(g) => Some(g),
            Err(TryLockError::Poisoned(e)) => Some(e.into_inner()),
            Err(TryLockError::WouldBlock) => None,
        };
        let buffer = held.as_deref_mut().unwrap_or(&mut spare);
        if buffer.len() < need {
            buffer.resize(need, 0.0);
        }
        let mail = Mailbox::new(slots, &mut buffer[..need]);
        let (forces, values) = (Shared::new(internal), Shared::new(values));
        let run = Run {
            asm: self,
            splits: &splits,
            disp: &disp,
            plan: plan.as_deref(),
            hand_over: &hand_over,
            mail: &mail,
            forces: &forces,
            values: &values,
            want_k,
        };
        let owned: Vec<Result<Vec<OwnedEnergy>, AssemblyError>> = splits
            .par_windows(2)
            .enumerate()
            .map(|(part, w)| run.part(part, (w[0], w[1])))
            .collect();
        drop(mail);
        // Energies cell by cell in sweep order: independent of the split.
        let mut per_cell: Vec<Vec<f64>> = self
            .groups
            .iter()
            .map(|g| vec![0.0; g.cells.len()])
            .collect();
        for part in owned {
            for (gi, i, e) in part? {
                per_cell[gi][i] = e;
            }
        }
        Ok(per_cell.iter().flatten().sum())
    }
}

/// A group's nodal displacements from `u`, cell after cell (the kernel's input layout).
fn gather(g: &Group, u: &[f64]) -> Vec<[f64; 3]> {
    let mut d = vec![[0.0; 3]; g.nodes.len()];
    d.par_chunks_mut(1024)
        .zip(g.nodes.par_chunks(1024))
        .for_each(|(d, nodes)| {
            for (d, &v) in d.iter_mut().zip(nodes) {
                *d = [u[3 * v], u[3 * v + 1], u[3 * v + 2]];
            }
        });
    d
}

impl Run<'_> {
    /// Part `part` (ranks [lo, hi)): its own cells of each group, then those handed over.
    fn part(
        &self,
        part: usize,
        (lo, hi): (usize, usize),
    ) -> Result<Vec<OwnedEnergy>, AssemblyError> {
        let mut energies = Vec::new();
        for (gi, g) in self.asm.groups.iter().enumerate() {
            let list = g.listed(lo, hi);
            self.own(part, (lo, hi), gi, &list, &mut energies)?;
            self.incoming(part, (lo, hi), gi)?;
        }
        Ok(energies)
    }

    /// The kernel's input for group `gi`.
    fn input(&self, gi: usize) -> BatchInput<'_, Material> {
        let g = &self.asm.groups[gi];
        BatchInput {
            coords: &g.coords,
            disp: &self.disp[gi],
            materials: &self.asm.stiffness,
            material_of: &g.material_of,
        }
    }

    /// An evaluated cell's forces at the part's nodes and its share of K.
    #[inline(always)]
    fn scatter(&self, g: &Group, i: usize, out: &ElementOutput, (lo, hi): (usize, usize)) {
        let rank = &self.asm.rank;
        let nodes = g.nodes_of(i);
        for (a, &v) in nodes.iter().enumerate() {
            if rank[v] >= lo && rank[v] < hi {
                self.forces.add3(3 * v, &out.forces[3 * a..]);
            }
        }
        if self.want_k {
            let col_ptr = self.asm.pattern.col_ptr();
            let mut to = Scatter::new(&out.tangent, g.table.dofs(), col_ptr, self.values);
            walk(nodes, g.pairs_of(i), rank, (lo, hi), &mut to);
        }
    }

    /// The part's own cells of group `gi` (`list`: those it lists, its own first): evaluated,
    /// scattered, and the shares of lower parts published for them.
    fn own(
        &self,
        part: usize,
        range: (usize, usize),
        gi: usize,
        list: &[usize],
        energies: &mut Vec<OwnedEnergy>,
    ) -> Result<(), AssemblyError> {
        let (asm, g) = (self.asm, &self.asm.groups[gi]);
        let (rank, col_ptr, splits) = (&asm.rank, asm.pattern.col_ptr(), self.splits);
        // The part's own cells (highest rank in it) come first in the sweep.
        let own = list.partition_point(|&i| g.span[i].1 < range.1);
        let hints = self.plan.and_then(|p| p.parts.get(part)?.get(gi));
        let base = self.values.as_ptr();
        let nd = g.table.dofs();
        let mut outgoing = self.hand_over.outgoing[part][gi].iter().peekable();
        evaluate_listed_prefetching(
            &g.table,
            &self.input(gi),
            asm.kinematics,
            self.want_k,
            &list[..own],
            |k| {
                // The scatter's lookups per node, a cell's evaluation ahead.
                for &v in g.nodes_of(list[k]) {
                    prefetch_line(rank.as_ptr().wrapping_add(v));
                    prefetch_line(col_ptr.as_ptr().wrapping_add(3 * v));
                    prefetch_line(col_ptr.as_ptr().wrapping_add(3 * v + 2));
                    prefetch_line(self.forces.as_ptr().wrapping_add(3 * v));
                    prefetch_line(self.forces.as_ptr().wrapping_add(3 * v + 2));
                }
                hints.map_or(Prefetch::NONE, |h| Prefetch::new(base, h.of(k)))
            },
            |i, out| {
                self.scatter(g, i, out, range);
                energies.push((gi, i, out.energy));
                let nodes = g.nodes_of(i);
                while let Some(&(_, k, reader)) = outgoing.next_if(|o| o.0 == i) {
                    let range = (splits[reader], splits[reader + 1]);
                    let theirs = |v: usize| rank[v] >= range.0 && rank[v] < range.1;
                    self.mail.publish(k, |r| {
                        let mut at = 0;
                        for (a, &v) in nodes.iter().enumerate() {
                            if theirs(v) {
                                r[at..at + 3].copy_from_slice(&out.forces[3 * a..][..3]);
                                at += 3;
                            }
                        }
                        if self.want_k {
                            let mut pack = Pack::new(&out.tangent, nd, &mut r[at..]);
                            walk(nodes, g.pairs_of(i), rank, range, &mut pack);
                        }
                    });
                }
            },
        )
        .map_err(|e| relocate(e, &g.cells).into())
    }

    /// Cells of group `gi` owned by higher parts, in sweep order: scattered from their
    /// hand-over, or evaluated here if nobody had started on them.
    fn incoming(
        &self,
        part: usize,
        (lo, hi): (usize, usize),
        gi: usize,
    ) -> Result<(), AssemblyError> {
        let (asm, g) = (self.asm, &self.asm.groups[gi]);
        let (rank, col_ptr) = (&asm.rank, asm.pattern.col_ptr());
        let inside = |v: usize| rank[v] >= lo && rank[v] < hi;
        let hints = self.plan.and_then(|p| p.parts.get(part)?.get(gi));
        let base = self.values.as_ptr();
        let incoming = &self.hand_over.incoming[part][gi];
        for (t, &(i, k, _)) in incoming.iter().enumerate() {
            // The pack and the tangent lines of the cell AHEAD on (at the start, of the first
            // ones too).
            let from = if t == 0 { 0 } else { t + AHEAD };
            let soon = from..(t + AHEAD + 1).min(incoming.len());
            for &(_, k, at) in incoming.get(soon).unwrap_or(&[]) {
                self.mail.prefetch(k);
                if let Some(h) = hints {
                    Prefetch::new(base, h.of(at)).issue(0, usize::MAX);
                }
            }
            let nodes = g.nodes_of(i);
            match self.mail.take(k) {
                Some(pack) => {
                    let mut f = pack.chunks_exact(3);
                    for &v in nodes.iter().filter(|&&v| inside(v)) {
                        if let Some(f) = f.next() {
                            self.forces.add3(3 * v, f);
                        }
                    }
                    if self.want_k {
                        let at = 3 * nodes.iter().filter(|&&v| inside(v)).count();
                        let mut from = Unpack::new(&pack[at..], col_ptr, self.values);
                        walk(nodes, g.pairs_of(i), rank, (lo, hi), &mut from);
                    }
                }
                None => evaluate_listed_prefetching(
                    &g.table,
                    &self.input(gi),
                    asm.kinematics,
                    self.want_k,
                    &[i],
                    |_| Prefetch::NONE,
                    |i, out| self.scatter(g, i, out, (lo, hi)),
                )
                .map_err(|e| relocate(e, &g.cells))?,
            }
        }
        Ok(())
    }
}
