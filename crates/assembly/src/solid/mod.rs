//! The solid: parallel, deterministic assembly of internal forces and tangents over the cells
//! of a mesh (thesis §2.2–2.3: f_int = Σ_cells ∫ Bᵀ S dV, K = Σ_cells (K_L + K_NL)),
//! owner-computes: see `scatter.rs` for the layout, `sweep.rs` for the split among threads,
//! `share.rs` and `handover.rs` for what each thread adds and hands over. By stage:
//!
//! | file | stage |
//! |---|---|
//! | `mod.rs` | set-up: per-cell stiffness, node ranks, cell groups in sweep order |
//! | `pattern.rs` | the node-blocked pattern and each cell's node-pair offsets into it |
//! | `plans.rs` | per split: the prefetch hints and the hand-over plan |
//! | `assemble.rs` | the assembly proper (evaluate, scatter, hand over) |
//! | `partial.rs`, `product.rs` | forces of some cells; K·v over the cells that v touches |
//!
//! The solid is a [`Contribution`](crate::Contribution) to a [`System`](crate::System); on its
//! own, [`Assembler::residual`] applies the constraints to it as the system does.

use crate::constrain::Masks;
use crate::{AssemblyError, Constraints};
use handover::HandOverPlan;
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics, Material, ShapeTable};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::Mesh;
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern, reverse_cuthill_mckee};
use prefetch::PrefetchPlan;
use scatter::pair_stride;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use sweep::Sweep;

mod assemble;
mod contribution;
mod handover;
mod partial;
pub(crate) mod pattern;
mod plans;
mod prefetch;
mod product;
mod scatter;
mod share;
mod sweep;
#[cfg(test)]
mod tests;

pub(crate) use partial::relabel;

/// The cells of one element kind, in sweep order (by highest node rank, then lowest), with what the
/// kernel and the scatter need of each.
struct Group {
    table: ShapeTable,
    /// Mesh cell of each member.
    cells: Vec<usize>,
    /// Node coordinates, `table.nodes()` per member.
    coords: Vec<[f64; 3]>,
    /// Stiffness index of each member.
    material_of: Vec<usize>,
    /// Nodes, `table.nodes()` per member.
    nodes: Vec<usize>,
    /// (lowest, highest) node rank of each member.
    span: Vec<(usize, usize)>,
    /// Node pairs and their offsets into the pattern, grouped for the scatter
    /// (`scatter::pair_lists`), `pair_stride(table.nodes())` words per member.
    pairs: Vec<u32>,
}

impl Group {
    fn nodes_of(&self, i: usize) -> &[usize] {
        let nn = self.table.nodes();
        &self.nodes[i * nn..(i + 1) * nn]
    }

    fn pairs_of(&self, i: usize) -> &[u32] {
        let stride = pair_stride(self.table.nodes());
        &self.pairs[i * stride..(i + 1) * stride]
    }

    /// The members with a node ranked in [lo, hi), in sweep order: what that part evaluates.
    fn listed(&self, lo: usize, hi: usize) -> Vec<usize> {
        (0..self.cells.len())
            .filter(|&i| self.span[i].0 < hi && self.span[i].1 >= lo)
            .collect()
    }
}

/// How many cells ahead of its scatter a hand-over's pack and tangent lines are prefetched.
const AHEAD: usize = 3;

/// (group, position in the group, strain energy) of a cell, from the part that owns it.
type OwnedEnergy = (usize, usize, f64);

/// Everything needed to assemble a mesh again and again: shape tables, per-cell stiffness
/// (rotated to each cell's ply angle once), DOF lists, the node-blocked sparsity pattern and
/// each cell's node-pair offsets into it.
pub struct Assembler {
    n: usize,
    groups: Vec<Group>,
    stiffness: Vec<Material>,
    dofs: Vec<Vec<usize>>,
    pattern: Arc<SymmetricPattern>,
    kinematics: Kinematics,
    /// (group, position in the group) of each cell.
    place: Vec<(usize, usize)>,
    /// Sweep rank of each node (reverse Cuthill–McKee on the node graph).
    rank: Vec<usize>,
    sweep: Sweep,
    /// Tangent positions no cell reaches (tie couplings, nodes in no cell): zeroed apart.
    unreached: Vec<usize>,
    /// The constrained rows and columns of the last constraints applied to a tangent.
    masks: Masks,
    /// Prefetch hints of the last split and values alignment assembled with a tangent.
    plan: Mutex<Arc<PrefetchPlan>>,
    /// Whether tangent assemblies issue prefetch hints (see [`Assembler::set_prefetch`]).
    prefetch: bool,
    /// Cells across the last split, and the buffer they are handed over through.
    hand_over: Mutex<Arc<HandOverPlan>>,
    mailbox: Mutex<Vec<f64>>,
}

/// One assembly: internal forces, strain energy, and the tangent if it was asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Assembly {
    /// f_int(u), node-major.
    pub internal: Vec<f64>,
    /// Strain energy Σ over cells.
    pub energy: f64,
}

/// One stiffness per distinct (material, ply angle) of `mesh`'s cells (`materials` in ply axes,
/// rotated about z), and the index of each cell's.
fn cell_stiffness(
    mesh: &Mesh,
    materials: &[Material],
    coupling: ShearCoupling,
) -> Result<(Vec<Material>, Vec<usize>), AssemblyError> {
    let mut index: HashMap<(usize, u64), usize> = HashMap::new();
    let mut stiffness = Vec::new();
    let mut cell_stiffness = Vec::with_capacity(mesh.cells.len());
    for (c, cell) in mesh.cells.iter().enumerate() {
        let base = materials
            .get(cell.material)
            .ok_or(AssemblyError::Material {
                cell: c,
                material: cell.material,
                count: materials.len(),
            })?;
        let key = (cell.material, cell.ply_angle_deg.to_bits());
        let id = match index.get(&key) {
            Some(&id) => id,
            None => {
                let s = if cell.ply_angle_deg == 0.0 {
                    *base
                } else {
                    base.rotated_about_z(cell.ply_angle_deg.to_radians(), coupling)?
                };
                stiffness.push(s);
                index.insert(key, stiffness.len() - 1);
                stiffness.len() - 1
            }
        };
        cell_stiffness.push(id);
    }
    Ok((stiffness, cell_stiffness))
}

/// The cells of each element kind (Hex20 with `hex20_rule`, then Hex8 with `hex8_rule`) in
/// sweep order for the node ranks `rank`, each with the stiffness index `cell_stiffness[c]`.
fn cell_groups(
    mesh: &Mesh,
    rank: &[usize],
    cell_stiffness: &[usize],
    hex20_rule: IntegrationRule,
    hex8_rule: IntegrationRule,
) -> Result<Vec<Group>, AssemblyError> {
    let span_of = |c: usize| {
        let nodes = &mesh.cells[c].nodes;
        let lo = nodes.iter().map(|&v| rank[v]).min().unwrap_or(0);
        let hi = nodes.iter().map(|&v| rank[v]).max().unwrap_or(0);
        (lo, hi)
    };
    let mut groups = Vec::new();
    for (kind, rule) in [
        (ElementKind::Hex20, hex20_rule),
        (ElementKind::Hex8, hex8_rule),
    ] {
        let mut cells: Vec<usize> = (0..mesh.cells.len())
            .filter(|&c| mesh.cells[c].kind == kind)
            .collect();
        if cells.is_empty() {
            continue;
        }
        // Sweep order, by highest rank: consecutive cells share columns, which stay in cache.
        cells.sort_by_key(|&c| {
            let (lo, hi) = span_of(c);
            (hi, lo, c)
        });
        groups.push(Group {
            table: ShapeTable::new(kind, rule)?,
            coords: cells
                .iter()
                .flat_map(|&c| mesh.cell_coordinates(c))
                .collect(),
            material_of: cells.iter().map(|&c| cell_stiffness[c]).collect(),
            nodes: cells
                .iter()
                .flat_map(|&c| mesh.cells[c].nodes.iter().copied())
                .collect(),
            span: cells.iter().map(|&c| span_of(c)).collect(),
            cells,
            pairs: Vec::new(),
        });
    }
    Ok(groups)
}

impl Assembler {
    /// Sets up `mesh` with `materials[cell.material]` in ply axes (stiffnesses, or [`Material`]s
    /// whose axes may vary with the position), rotated about z by each cell's ply angle
    /// (`coupling` as in [`Material::rotated_about_z`]); Hex20 cells integrated with
    /// `hex20_rule`, Hex8 cells with `hex8_rule`.
    pub fn new<M: Copy + Into<Material>>(
        mesh: &Mesh,
        materials: &[M],
        coupling: ShearCoupling,
        hex20_rule: IntegrationRule,
        hex8_rule: IntegrationRule,
        kinematics: Kinematics,
    ) -> Result<Self, AssemblyError> {
        let materials: Vec<Material> = materials.iter().map(|&m| m.into()).collect();
        mesh.validate()?;
        let n = 3 * mesh.nodes.len();
        let (stiffness, of_cell) = cell_stiffness(mesh, &materials, coupling)?;
        // Ranks for the sweep: a banded order of the node graph, whatever the mesh numbering.
        let node_lists: Vec<&[usize]> = mesh.cells.iter().map(|c| &c.nodes[..]).collect();
        let graph = SymmetricPattern::from_dof_lists(mesh.nodes.len(), &node_lists)?;
        let rcm = reverse_cuthill_mckee(&graph);
        let rank = rcm.inverse().to_vec();
        let groups = cell_groups(mesh, &rank, &of_cell, hex20_rule, hex8_rule)?;
        let mut place = vec![(0, 0); mesh.cells.len()];
        for (gi, g) in groups.iter().enumerate() {
            for (i, &c) in g.cells.iter().enumerate() {
                place[c] = (gi, i);
            }
        }
        let sweep = Sweep::new(
            mesh.nodes.len(),
            groups.iter().flat_map(|g| g.span.iter().copied()),
        );
        let dofs = mesh.cell_dofs();
        let pattern = Arc::new(SymmetricPattern::from_dof_lists(
            n,
            &pattern::with_lone_nodes(dofs.clone(), n),
        )?);
        let mut assembler = Self {
            n,
            groups,
            stiffness,
            dofs,
            pattern: pattern.clone(),
            kinematics,
            place,
            rank,
            sweep,
            unreached: Vec::new(),
            masks: Masks::default(),
            plan: Mutex::default(),
            prefetch: true,
            hand_over: Mutex::default(),
            mailbox: Mutex::default(),
        };
        assembler.set_pattern(pattern)?;
        Ok(assembler)
    }

    /// Turns the prefetch hints of tangent assemblies on (the default) or off. With hints, each
    /// cell's evaluation prefetches the tangent lines its scatter will write (listed once per
    /// thread split, ≈ 1.5 kB per Hex20 cell; see docs/DESIGN.md); results are bitwise the
    /// same either way, only the time differs. Off frees the lists.
    pub fn set_prefetch(&mut self, on: bool) {
        self.prefetch = on;
        if !on {
            *self.plan.lock().unwrap_or_else(|e| e.into_inner()) = Arc::default();
        }
    }

    /// Number of DOFs.
    pub fn n(&self) -> usize {
        self.n
    }

    /// The sparsity pattern of the tangent.
    pub fn pattern(&self) -> &Arc<SymmetricPattern> {
        &self.pattern
    }

    /// A zero tangent on the pattern.
    pub fn new_tangent(&self) -> SymmetricMatrix {
        SymmetricMatrix::zeros(self.pattern.clone())
    }

    /// The DOF list of each cell (mesh order, 3 per node).
    pub fn cell_dofs(&self) -> &[Vec<usize>] {
        &self.dofs
    }

    /// The residual r = f_int − f_ext(λ) with zeros at constrained DOFs, the reactions
    /// (f_int − f_ext at constrained DOFs, zero elsewhere), and the tangent with identity rows
    /// and columns at constrained DOFs when given: the assembly, then the constraints applied
    /// as a [`System`](crate::System) applies them (`constrain.rs`).
    pub fn residual(
        &self,
        u: &[f64],
        lambda: f64,
        constraints: &Constraints,
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<(Vec<f64>, Vec<f64>, f64), AssemblyError> {
        if constraints.n() != self.n {
            return Err(AssemblyError::Length {
                what: "constraints",
                expected: self.n,
                got: constraints.n(),
            });
        }
        let mut k = tangent;
        let a = self.assemble(u, k.as_deref_mut())?;
        let mut f = vec![0.0; self.n];
        constraints.external(lambda, &mut f);
        let mut r: Vec<f64> = a.internal.iter().zip(&f).map(|(i, e)| i - e).collect();
        let mut reactions = vec![0.0; self.n];
        self.masks
            .apply(&self.pattern, constraints, &mut r, &mut reactions, k)?;
        Ok((r, reactions, a.energy))
    }
}
