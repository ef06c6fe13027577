//! The solid's sparsity pattern: node-blocked (three DOFs per node, whole node blocks), from the
//! cells' DOF lists (plus the couplings of ties or of a [`System`](crate::System)'s union), and
//! each cell's node-pair offsets into it (`scatter.rs`).

use super::Assembler;
use super::scatter::{block_offsets, check_node_blocked, mark_first, pair_lists, pair_stride};
use crate::constrain::Masks;
use crate::{AssemblyError, Constraints};
use nonlin3d_solver::SymmetricPattern;
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Arc;

/// `lists` and the DOF triple of every node none of them holds: a node in no cell keeps a
/// whole (zero) diagonal block, so the pattern stays node-blocked and a solve names its DOF.
pub(crate) fn with_lone_nodes(mut lists: Vec<Vec<usize>>, n: usize) -> Vec<Vec<usize>> {
    let mut held = vec![false; n / 3];
    for &d in lists.iter().flatten() {
        held[d / 3] = true;
    }
    for (v, _) in held.iter().enumerate().filter(|(_, h)| !**h) {
        lists.push(vec![3 * v, 3 * v + 1, 3 * v + 2]);
    }
    lists
}

/// `l` widened to whole nodes: the three DOFs of every node it touches, sorted.
pub(crate) fn whole_nodes(mut l: Vec<usize>) -> Vec<usize> {
    let mut nodes: Vec<usize> = l.iter().map(|d| d / 3).collect();
    nodes.sort_unstable();
    nodes.dedup();
    l.clear();
    l.extend(nodes.iter().flat_map(|&v| [3 * v, 3 * v + 1, 3 * v + 2]));
    l
}

impl Assembler {
    /// Adopts `pattern` (node-blocked, checked) and recomputes every cell's offsets into it.
    pub(crate) fn set_pattern(
        &mut self,
        pattern: Arc<SymmetricPattern>,
    ) -> Result<(), AssemblyError> {
        check_node_blocked(&pattern, self.n / 3)?;
        let mut offsets = Vec::with_capacity(self.groups.len());
        for g in &self.groups {
            let nn = g.table.nodes();
            let of_group: Result<Vec<Vec<u32>>, AssemblyError> = g
                .nodes
                .par_chunks(nn)
                .map(|nodes| block_offsets(&pattern, nodes))
                .collect();
            offsets.push(of_group?.concat());
        }
        // Flags in sweep order: group after group (as `assemble` visits them), cell after cell.
        self.unreached = mark_first(
            &pattern,
            self.groups
                .iter()
                .zip(offsets.iter_mut())
                .flat_map(|(g, o)| {
                    let nn = g.table.nodes();
                    g.nodes.chunks(nn).zip(o.chunks_mut(nn * nn))
                }),
        );
        for (g, o) in self.groups.iter_mut().zip(&offsets) {
            let nn = g.table.nodes();
            let stride = pair_stride(nn);
            let mut pairs = vec![0u32; stride * g.cells.len()];
            for ((nodes, o), out) in g
                .nodes
                .chunks(nn)
                .zip(o.chunks(nn * nn))
                .zip(pairs.chunks_mut(stride))
            {
                pair_lists(nodes, o, out)?;
            }
            g.pairs = pairs;
        }
        self.share_pattern(pattern);
        Ok(())
    }

    /// Holds `pattern`, whose entries the cells' offsets are computed for, and drops what was
    /// derived from the one before (the constraint masks, the prefetch plan, the hand-over
    /// lists; each is made again when next needed).
    pub(crate) fn share_pattern(&mut self, pattern: Arc<SymmetricPattern>) {
        self.pattern = pattern;
        self.masks = Masks::default();
        *self.plan.lock().unwrap_or_else(|e| e.into_inner()) = Arc::default();
        *self.hand_over.lock().unwrap_or_else(|e| e.into_inner()) = Arc::default();
    }

    /// Rebuilds the sparsity pattern for the ties of `constraints`: a cell that holds a slave
    /// DOF couples its nodes with the slave's master nodes too (all three DOFs of each, so the
    /// pattern stays node-blocked), the entries K′ = TᵀKT needs when
    /// [`residual`](Self::residual) folds the slave onto them. Tangents made before this call
    /// no longer fit ([`new_tangent`](Self::new_tangent) again).
    pub fn tie(&mut self, constraints: &Constraints) -> Result<(), AssemblyError> {
        let masters: HashMap<usize, Vec<usize>> = constraints
            .ties()
            .iter()
            .map(|t| (t.slave, t.masters.iter().map(|m| m.0).collect()))
            .collect();
        let mut all: Vec<Vec<usize>> = self
            .dofs
            .iter()
            .map(|d| {
                let mut l = d.clone();
                for x in d {
                    if let Some(m) = masters.get(x) {
                        l.extend(m);
                    }
                }
                whole_nodes(l)
            })
            .collect();
        // Ties whose slave no cell holds still need their masters coupled to each other.
        all.extend(constraints.ties().iter().map(|t| {
            let mut l: Vec<usize> = t.masters.iter().map(|m| m.0).collect();
            l.push(t.slave);
            whole_nodes(l)
        }));
        let pattern = Arc::new(SymmetricPattern::from_dof_lists(
            self.n,
            &with_lone_nodes(all, self.n),
        )?);
        self.set_pattern(pattern)
    }
}
