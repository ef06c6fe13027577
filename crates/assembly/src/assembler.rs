//! Parallel, deterministic assembly of internal forces and tangents over the cells of a mesh
//! (thesis §2.2–2.3: f_int = Σ_cells ∫ Bᵀ S dV, K = Σ_cells (K_L + K_NL)), owner-computes: see
//! `scatter.rs` for the layout and the split among threads.

use crate::handover::{HandOverPlan, Mailbox, Slot};
use crate::prefetch::{CellLines, PrefetchPlan};
use crate::scatter::{
    Shared, Sweep, block_offsets, check_node_blocked, mark_first, pair_lists, pair_stride,
};
use crate::share::{Count, Pack, Positions, Scatter, Unpack, walk};
use crate::{AssemblyError, Constraints};
use nonlin3d_element::{
    BatchInput, ElementError, ElementKind, ElementOutput, IntegrationRule, Kinematics, Material,
    Prefetch, ShapeTable, Workspace, evaluate, evaluate_listed_prefetching, prefetch_line,
};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::Mesh;
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern, reverse_cuthill_mckee};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Mutex, TryLockError};

mod product;

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

/// Positions of the tangent entries in the rows and columns of the constrained DOFs (with
/// whether each is on the diagonal), for the set of constrained DOFs they were found for.
#[derive(Default)]
struct FixedMask {
    dofs: Vec<usize>,
    positions: Vec<(usize, bool)>,
}

/// Positions of the tangent entries in each tie slave's row and column, with the index on the
/// other side ((position, j) for entry (s, j) or (j, s)), for the slaves they were found for.
#[derive(Default)]
struct TieMask {
    slaves: Vec<usize>,
    entries: Vec<Vec<(usize, usize)>>,
}

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
    mask: Mutex<FixedMask>,
    /// The slave rows and columns of the last tie set folded into a tangent.
    tie_mask: Mutex<TieMask>,
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

/// Re-attributes a batch error (group-local element index) to the mesh cell.
/// `lists` and the DOF triple of every node none of them holds: a node in no cell keeps a
/// whole (zero) diagonal block, so the pattern stays node-blocked and a solve names its DOF.
fn with_lone_nodes(mut lists: Vec<Vec<usize>>, n: usize) -> Vec<Vec<usize>> {
    let mut held = vec![false; n / 3];
    for &d in lists.iter().flatten() {
        held[d / 3] = true;
    }
    for (v, _) in held.iter().enumerate().filter(|(_, h)| !**h) {
        lists.push(vec![3 * v, 3 * v + 1, 3 * v + 2]);
    }
    lists
}

fn relocate(err: ElementError, cells: &[usize]) -> ElementError {
    relabel(err, |e| e.and_then(|e| cells.get(e).copied()))
}

/// Replaces the element index of an error by `cell(index)`.
fn relabel(err: ElementError, cell: impl Fn(Option<usize>) -> Option<usize>) -> ElementError {
    match err {
        ElementError::NonPositiveJacobian {
            element,
            point,
            xi,
            det,
        } => ElementError::NonPositiveJacobian {
            element: cell(element),
            point,
            xi,
            det,
        },
        ElementError::NonFiniteInput {
            element,
            what,
            node,
            value,
        } => ElementError::NonFiniteInput {
            element: cell(element),
            what,
            node,
            value,
        },
        ElementError::CoupledTransverseShear {
            element,
            material,
            coupling,
        } => ElementError::CoupledTransverseShear {
            element: cell(element),
            material,
            coupling,
        },
        other => other,
    }
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
        // One stiffness per distinct (material, angle).
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
        // Ranks for the sweep: a banded order of the node graph, whatever the mesh numbering.
        let node_lists: Vec<&[usize]> = mesh.cells.iter().map(|c| &c.nodes[..]).collect();
        let graph = SymmetricPattern::from_dof_lists(mesh.nodes.len(), &node_lists)?;
        let rcm = reverse_cuthill_mckee(&graph);
        let rank = rcm.inverse().to_vec();
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
            &with_lone_nodes(dofs.clone(), n),
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
            mask: Mutex::new(FixedMask::default()),
            tie_mask: Mutex::default(),
            plan: Mutex::default(),
            prefetch: true,
            hand_over: Mutex::default(),
            mailbox: Mutex::default(),
        };
        assembler.set_pattern(pattern)?;
        Ok(assembler)
    }

    /// Adopts `pattern` (node-blocked, checked) and recomputes every cell's offsets into it.
    fn set_pattern(&mut self, pattern: Arc<SymmetricPattern>) -> Result<(), AssemblyError> {
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
        self.pattern = pattern;
        *self.mask.lock().unwrap_or_else(|e| e.into_inner()) = FixedMask::default();
        *self.tie_mask.lock().unwrap_or_else(|e| e.into_inner()) = TieMask::default();
        *self.plan.lock().unwrap_or_else(|e| e.into_inner()) = Arc::default();
        *self.hand_over.lock().unwrap_or_else(|e| e.into_inner()) = Arc::default();
        Ok(())
    }

    /// The prefetch hints for this split of the rank range and a values array starting `align`
    /// f64s past a 64-byte boundary: the cached plan if it was made for them, else a new one
    /// (one pass over every cell's scatter positions, parts in parallel). Tangents of 2³² or
    /// more entries get no hints.
    fn prefetch_plan(&self, splits: &[usize], align: usize) -> Arc<PrefetchPlan> {
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
    fn hand_over_plan(&self, splits: &[usize]) -> Arc<HandOverPlan> {
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

    /// Internal forces of the listed cells alone, f = Σ_cells ∫ Bᵀ S dV, node-major over the
    /// whole model, with `kinematics` (which may differ from the assembler's own): the forces a
    /// part of the model exerts at its nodes, as VCCT needs for the cells above the
    /// delamination plane (thesis §2.8: linear or nonlinear strain–displacement relations).
    pub fn partial_internal(
        &self,
        cells: &[usize],
        u: &[f64],
        kinematics: Kinematics,
    ) -> Result<Vec<f64>, AssemblyError> {
        if u.len() != self.n {
            return Err(AssemblyError::Length {
                what: "displacements",
                expected: self.n,
                got: u.len(),
            });
        }
        let mut f = vec![0.0; self.n];
        for &c in cells {
            let &(gi, i) = self.place.get(c).ok_or(AssemblyError::Length {
                what: "cell index",
                expected: self.place.len(),
                got: c,
            })?;
            let g = &self.groups[gi];
            let nn = g.table.nodes();
            let coords = &g.coords[i * nn..(i + 1) * nn];
            let disp: Vec<[f64; 3]> = self.dofs[c]
                .chunks_exact(3)
                .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
                .collect();
            let mut out = ElementOutput::new(&g.table);
            let mut ws = Workspace::new(&g.table);
            evaluate(
                &g.table,
                coords,
                &disp,
                &self.stiffness[g.material_of[i]],
                kinematics,
                false,
                &mut ws,
                &mut out,
            )
            .map_err(|e| relabel(e, |_| Some(c)))?;
            for (a, &d) in self.dofs[c].iter().enumerate() {
                f[d] += out.forces[a];
            }
        }
        Ok(f)
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
        let whole_nodes = |mut l: Vec<usize>| {
            let mut nodes: Vec<usize> = l.iter().map(|d| d / 3).collect();
            nodes.sort_unstable();
            nodes.dedup();
            l.clear();
            l.extend(nodes.iter().flat_map(|&v| [3 * v, 3 * v + 1, 3 * v + 2]));
            l
        };
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
    fn assemble_in_parts(
        &self,
        u: &[f64],
        tangent: Option<&mut SymmetricMatrix>,
        parts: usize,
    ) -> Result<Assembly, AssemblyError> {
        if u.len() != self.n {
            return Err(AssemblyError::Length {
                what: "displacements",
                expected: self.n,
                got: u.len(),
            });
        }
        let want_k = tangent.is_some();
        let col_ptr = self.pattern.col_ptr();
        let values: &mut [f64] = match tangent {
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
        };
        // Each group's nodal displacements, cell after cell (the kernel's input layout).
        let disp: Vec<Vec<[f64; 3]>> = self
            .groups
            .iter()
            .map(|g| {
                let mut d = vec![[0.0; 3]; g.nodes.len()];
                d.par_chunks_mut(1024)
                    .zip(g.nodes.par_chunks(1024))
                    .for_each(|(d, nodes)| {
                        for (d, &v) in d.iter_mut().zip(nodes) {
                            *d = [u[3 * v], u[3 * v + 1], u[3 * v + 2]];
                        }
                    });
                d
            })
            .collect();
        if want_k {
            for &p in &self.unreached {
                values[p] = 0.0;
            }
        }
        let mut internal = vec![0.0; self.n];
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
        let (forces, values) = (Shared::new(&mut internal), Shared::new(values));
        let rank = &self.rank;
        let owned: Vec<Result<Vec<OwnedEnergy>, AssemblyError>> = splits
            .par_windows(2)
            .enumerate()
            .map(|(part, w)| {
                let (lo, hi) = (w[0], w[1]);
                let inside = |v: usize| rank[v] >= lo && rank[v] < hi;
                let base = values.as_ptr();
                let mut energies = Vec::new();
                for (gi, g) in self.groups.iter().enumerate() {
                    let list = g.listed(lo, hi);
                    // The part's own cells (highest rank in it) come first in the sweep.
                    let own = list.partition_point(|&i| g.span[i].1 < hi);
                    let hints = plan.as_ref().and_then(|p| p.parts.get(part)?.get(gi));
                    let input = BatchInput {
                        coords: &g.coords,
                        disp: &disp[gi],
                        materials: &self.stiffness,
                        material_of: &g.material_of,
                    };
                    let nd = g.table.dofs();
                    // An evaluated cell's forces at the part's nodes and its share of K.
                    let scatter = |i: usize, out: &ElementOutput| {
                        let nodes = g.nodes_of(i);
                        for (a, &v) in nodes.iter().enumerate() {
                            if inside(v) {
                                forces.add3(3 * v, &out.forces[3 * a..]);
                            }
                        }
                        if want_k {
                            let mut to = Scatter::new(&out.tangent, nd, col_ptr, &values);
                            walk(nodes, g.pairs_of(i), rank, (lo, hi), &mut to);
                        }
                    };
                    let mut outgoing = hand_over.outgoing[part][gi].iter().peekable();
                    evaluate_listed_prefetching(
                        &g.table,
                        &input,
                        self.kinematics,
                        want_k,
                        &list[..own],
                        |k| {
                            // The scatter's lookups per node, a cell's evaluation ahead.
                            for &v in g.nodes_of(list[k]) {
                                prefetch_line(rank.as_ptr().wrapping_add(v));
                                prefetch_line(col_ptr.as_ptr().wrapping_add(3 * v));
                                prefetch_line(col_ptr.as_ptr().wrapping_add(3 * v + 2));
                                prefetch_line(forces.as_ptr().wrapping_add(3 * v));
                                prefetch_line(forces.as_ptr().wrapping_add(3 * v + 2));
                            }
                            hints.map_or(Prefetch::NONE, |h| Prefetch::new(base, h.of(k)))
                        },
                        |i, out| {
                            scatter(i, out);
                            energies.push((gi, i, out.energy));
                            let nodes = g.nodes_of(i);
                            while let Some(&(_, k, reader)) = outgoing.next_if(|o| o.0 == i) {
                                let range = (splits[reader], splits[reader + 1]);
                                let theirs = |v: usize| rank[v] >= range.0 && rank[v] < range.1;
                                mail.publish(k, |r| {
                                    let mut at = 0;
                                    for (a, &v) in nodes.iter().enumerate() {
                                        if theirs(v) {
                                            r[at..at + 3]
                                                .copy_from_slice(&out.forces[3 * a..][..3]);
                                            at += 3;
                                        }
                                    }
                                    if want_k {
                                        let mut pack = Pack::new(&out.tangent, nd, &mut r[at..]);
                                        walk(nodes, g.pairs_of(i), rank, range, &mut pack);
                                    }
                                });
                            }
                        },
                    )
                    .map_err(|e| relocate(e, &g.cells))?;
                    // Cells owned by higher parts, in sweep order: scattered from their
                    // hand-over, or evaluated here if nobody had started on them.
                    let incoming = &hand_over.incoming[part][gi];
                    for (t, &(i, k, _)) in incoming.iter().enumerate() {
                        // The pack and the tangent lines of the cell AHEAD on (at the start, of
                        // the first ones too).
                        let from = if t == 0 { 0 } else { t + AHEAD };
                        let soon = from..(t + AHEAD + 1).min(incoming.len());
                        for &(_, k, at) in incoming.get(soon).unwrap_or(&[]) {
                            mail.prefetch(k);
                            if let Some(h) = hints {
                                Prefetch::new(base, h.of(at)).issue(0, usize::MAX);
                            }
                        }
                        let nodes = g.nodes_of(i);
                        match mail.take(k) {
                            Some(pack) => {
                                let mut f = pack.chunks_exact(3);
                                for &v in nodes.iter().filter(|&&v| inside(v)) {
                                    if let Some(f) = f.next() {
                                        forces.add3(3 * v, f);
                                    }
                                }
                                if want_k {
                                    let at = 3 * nodes.iter().filter(|&&v| inside(v)).count();
                                    let mut from = Unpack::new(&pack[at..], col_ptr, &values);
                                    walk(nodes, g.pairs_of(i), rank, (lo, hi), &mut from);
                                }
                            }
                            None => evaluate_listed_prefetching(
                                &g.table,
                                &input,
                                self.kinematics,
                                want_k,
                                &[i],
                                |_| Prefetch::NONE,
                                |i, out| scatter(i, out),
                            )
                            .map_err(|e| relocate(e, &g.cells))?,
                        }
                    }
                }
                Ok(energies)
            })
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
        let energy = per_cell.iter().flatten().sum();
        Ok(Assembly { internal, energy })
    }

    /// The tangent positions in the rows and columns of the (sorted) DOFs `fixed`: one pass
    /// over the pattern, done again only when the set of constrained DOFs changes.
    fn fixed_mask(&self, fixed: Vec<usize>) -> FixedMask {
        let mut is_fixed = vec![false; self.n];
        for &d in &fixed {
            is_fixed[d] = true;
        }
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let mut positions = Vec::new();
        for j in 0..self.n {
            for (p, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
                if is_fixed[i] || is_fixed[j] {
                    positions.push((p, i == j));
                }
            }
        }
        FixedMask {
            dofs: fixed,
            positions,
        }
    }

    /// The tangent positions in the rows and columns of the tie slaves `slaves` (in tie order):
    /// one pass over the pattern, done again only when the slaves change.
    fn tie_mask(&self, slaves: Vec<usize>) -> TieMask {
        let mut tie_of = vec![usize::MAX; self.n];
        for (t, &s) in slaves.iter().enumerate() {
            tie_of[s] = t;
        }
        let (cp, ri) = (self.pattern.col_ptr(), self.pattern.row_idx());
        let mut entries = vec![Vec::new(); slaves.len()];
        for j in 0..self.n {
            for (p, &i) in ri.iter().enumerate().take(cp[j + 1]).skip(cp[j]) {
                if let Some(e) = entries.get_mut(tie_of[i]) {
                    e.push((p, j));
                }
                if i != j
                    && let Some(e) = entries.get_mut(tie_of[j])
                {
                    e.push((p, i));
                }
            }
        }
        TieMask { slaves, entries }
    }

    /// The residual r = f_int − f_ext(λ) with zeros at constrained DOFs, the reactions
    /// (f_int − f_ext at constrained DOFs, zero elsewhere), and the tangent with identity rows
    /// and columns at constrained DOFs when given.
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
        if !constraints.ties().is_empty() {
            let mut mask = self.tie_mask.lock().unwrap_or_else(|e| e.into_inner());
            let slaves: Vec<usize> = constraints.ties().iter().map(|t| t.slave).collect();
            if k.is_some() && mask.slaves != slaves {
                *mask = self.tie_mask(slaves);
            }
            let k = k.as_deref_mut().map(|k| (k, &*mask));
            fold_ties(constraints, &mut r, &mut reactions, k)?;
        }
        let mut fixed: Vec<usize> = constraints.prescribed().map(|(d, _)| d).collect();
        fixed.sort_unstable();
        fixed.dedup();
        for &d in &fixed {
            reactions[d] = r[d];
            r[d] = 0.0;
        }
        if let Some(k) = k {
            let mut mask = self.mask.lock().unwrap_or_else(|e| e.into_inner());
            if mask.dofs != fixed {
                *mask = self.fixed_mask(fixed);
            }
            let vals = k.values_mut();
            for &(p, diagonal) in &mask.positions {
                vals[p] = if diagonal { 1.0 } else { 0.0 };
            }
        }
        Ok((r, reactions, a.energy))
    }
}

/// Folds each tie's slave onto its masters (K′ = TᵀKT, r′ = Tᵀr for u_s = Σ c_k u_{m_k}),
/// slave by slave: r_m += c·r_s; K_{m j} += c·K_{s j} (twice on the diagonal m = j, which stands
/// for both triangles); K_{m m′} += c c′ K_ss; then the slave's row and column become the
/// identity and its residual (the force the tie carries) its reaction. `k` comes with the
/// stored positions of each slave's row and column (a `TieMask` made for these ties).
fn fold_ties(
    constraints: &Constraints,
    r: &mut [f64],
    reactions: &mut [f64],
    k: Option<(&mut SymmetricMatrix, &TieMask)>,
) -> Result<(), AssemblyError> {
    for t in constraints.ties() {
        let rs = r[t.slave];
        for &(m, c) in &t.masters {
            r[m] += c * rs;
        }
        reactions[t.slave] = rs;
        r[t.slave] = 0.0;
    }
    let Some((k, mask)) = k else {
        return Ok(());
    };
    let entries = &mask.entries;
    for (t, tie) in constraints.ties().iter().enumerate() {
        let s = tie.slave;
        let missing = |i: usize, j: usize| AssemblyError::Tie {
            slave: s,
            reason: format!(
                "the tangent has no entry ({i}, {j}): build the problem after adding ties \
                 (Assembler::tie; StructuralProblem::new calls it)"
            ),
        };
        // Current values of row s (other slaves' folds may have added to it).
        let row: Vec<(usize, f64)> = entries[t]
            .iter()
            .map(|&(p, j)| (j, k.values()[p]))
            .collect();
        let kss = k.get(s, s);
        for &(m, c) in &tie.masters {
            for &(j, v) in row.iter().filter(|e| e.0 != s) {
                let w = if j == m { 2.0 * c * v } else { c * v };
                k.add(m, j, w).map_err(|_| missing(m, j))?;
            }
        }
        for (a, &(m, c)) in tie.masters.iter().enumerate() {
            for &(m2, c2) in &tie.masters[..=a] {
                k.add(m, m2, c * c2 * kss).map_err(|_| missing(m, m2))?;
            }
        }
        let values = k.values_mut();
        for &(p, j) in &entries[t] {
            values[p] = if j == s { 1.0 } else { 0.0 };
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_laminate::Stiffness;
    use nonlin3d_mesh::{BoxParams, EmbeddedParams, embedded_delamination, structured_box};

    /// A 2×2×2, nonlinear-kinematics assembler for `mesh` and a deterministic displacement
    /// field of size `scale` (m) over its DOFs.
    fn nonlinear_gauss2(mesh: &Mesh, mats: &[Stiffness], scale: f64) -> (Assembler, Vec<f64>) {
        let asm = Assembler::new(
            mesh,
            mats,
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap();
        let u = (0..asm.n())
            .map(|d| scale * ((d * 7919) % 23) as f64 / 23.0)
            .collect();
        (asm, u)
    }

    /// A Hex20 box of 2 × 1 × 1 (m) in `cells` cells.
    fn hex20_box(cells: [usize; 3]) -> Mesh {
        structured_box(&BoxParams::new(ElementKind::Hex20, cells, [2.0, 1.0, 1.0])).unwrap()
    }

    /// Steel's stiffness.
    fn steel() -> Stiffness {
        nonlin3d_laminate::materials::steel().stiffness().unwrap()
    }

    /// A rayon pool of `threads` threads.
    fn pool_of(threads: usize) -> rayon::ThreadPool {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
    }

    /// The owner-computes assembly equals the plain element-by-element sum (each cell's
    /// `evaluate` added through `SymmetricMatrix::scatter_add`, an independent path) to
    /// summation-order rounding (1e-12 of the largest entry), and is bitwise the same on 1 to 4
    /// threads, with prefetch hints on and off, and with more parts than threads (cells across
    /// a split handed over, or evaluated by the lower part when it gets there first), on a
    /// swept model with two materials and ply angles.
    #[test]
    fn assembly_equals_the_plain_sum_on_any_thread_count() {
        use nonlin3d_laminate::materials;
        let mut mesh = embedded_delamination(&EmbeddedParams {
            slices: 4,
            ..EmbeddedParams::thesis_reference()
        })
        .unwrap();
        for (c, cell) in mesh.cells.iter_mut().enumerate() {
            cell.material = c % 2;
            cell.ply_angle_deg = [0.0, 45.0, -45.0, 90.0][c % 4];
        }
        let mats = [
            materials::generic_graphite_epoxy().stiffness().unwrap(),
            materials::steel().stiffness().unwrap(),
        ];
        let (mut asm, u) = nonlinear_gauss2(&mesh, &mats, 1e-5);
        let mut runs = Vec::new();
        // With and without prefetch hints (hints only move cache lines), a fresh tangent (new
        // alignment, so a new hint plan) each time.
        for hints in [true, false] {
            asm.set_prefetch(hints);
            for threads in 1..=4 {
                let pool = pool_of(threads);
                let mut k = asm.new_tangent();
                // Stale values must not survive.
                k.values_mut().fill(7.0);
                let a = pool.install(|| asm.assemble(&u, Some(&mut k))).unwrap();
                runs.push((a, k));
            }
        }
        // More parts than threads: on one thread the lower part runs first and evaluates the
        // cells it would have been handed; on two, either may happen cell by cell.
        for (threads, parts) in [(1, 2), (1, 5), (2, 3), (2, 7)] {
            let pool = pool_of(threads);
            let mut k = asm.new_tangent();
            let a = pool.install(|| asm.assemble_in_parts(&u, Some(&mut k), parts));
            runs.push((a.unwrap(), k));
            // Forces alone hand over forces alone.
            let f = pool
                .install(|| asm.assemble_in_parts(&u, None, parts))
                .unwrap();
            assert!(
                f == runs[0].0,
                "{parts} parts: forces without the tangent differ"
            );
        }
        for r in &runs[1..] {
            assert!(r.0 == runs[0].0, "forces or energy depend on the threads");
            assert!(r.1 == runs[0].1, "the tangent depends on the threads");
        }
        let mut reference = asm.new_tangent();
        let mut f = vec![0.0; asm.n()];
        let mut energy = 0.0;
        for (c, dofs) in asm.dofs.iter().enumerate() {
            let (gi, i) = asm.place[c];
            let g = &asm.groups[gi];
            let nn = g.table.nodes();
            let disp: Vec<[f64; 3]> = dofs
                .chunks(3)
                .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
                .collect();
            let mut out = ElementOutput::new(&g.table);
            let mut ws = Workspace::new(&g.table);
            evaluate(
                &g.table,
                &g.coords[i * nn..(i + 1) * nn],
                &disp,
                &asm.stiffness[g.material_of[i]],
                Kinematics::Nonlinear,
                true,
                &mut ws,
                &mut out,
            )
            .unwrap();
            reference.scatter_add(dofs, &out.tangent).unwrap();
            for (a, &d) in dofs.iter().enumerate() {
                f[d] += out.forces[a];
            }
            energy += out.energy;
        }
        let (a, k) = &runs[0];
        let kmax = reference
            .values()
            .iter()
            .fold(0.0_f64, |m, v| m.max(v.abs()));
        for (x, y) in k.values().iter().zip(reference.values()) {
            assert!((x - y).abs() <= 1e-12 * kmax, "{x} vs {y}");
        }
        let fmax = f.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for (x, y) in a.internal.iter().zip(&f) {
            assert!((x - y).abs() <= 1e-12 * fmax, "{x} vs {y}");
        }
        assert!((a.energy - energy).abs() <= 1e-12 * energy.abs());
    }

    /// A non-finite displacement fails the assembly with a cell holding that node named (mesh
    /// numbering), on one thread and on several, where the cell may straddle a split and be
    /// evaluated by either part.
    #[test]
    fn a_bad_cell_is_named_on_any_thread_count() {
        let mesh = embedded_delamination(&EmbeddedParams {
            slices: 4,
            ..EmbeddedParams::thesis_reference()
        })
        .unwrap();
        let steel = steel();
        let (asm, mut u) = nonlinear_gauss2(&mesh, &[steel], 1e-6);
        for bad in [0, mesh.cells.len() / 2, mesh.cells.len() - 1] {
            let v = mesh.cells[bad].nodes[5];
            let keep = u[3 * v + 1];
            u[3 * v + 1] = f64::NAN;
            for threads in 1..=3 {
                let pool = pool_of(threads);
                let mut k = asm.new_tangent();
                let err = match pool.install(|| asm.assemble(&u, Some(&mut k))) {
                    Ok(_) => panic!("node {v} has a NaN displacement, yet the assembly succeeded"),
                    Err(e) => e,
                };
                let AssemblyError::Element(ElementError::NonFiniteInput {
                    element: Some(c),
                    what: "displacements",
                    ..
                }) = err
                else {
                    panic!("{err}");
                };
                assert!(
                    mesh.cells[c].nodes.contains(&v),
                    "cell {c} does not hold node {v}"
                );
            }
            u[3 * v + 1] = keep;
        }
    }

    /// A node in no cell (a stray node of a deck) keeps a zero diagonal block in a node-blocked
    /// pattern; every tangent value is written (the matrix starts as NaN), and the other nodes'
    /// entries are those of the mesh without it (1e-12 of the largest: summation order).
    #[test]
    fn a_node_in_no_cell_gets_a_zero_block() {
        let mesh = hex20_box([2, 1, 1]);
        let mut stray = mesh.clone();
        stray.nodes.push([5.0, 5.0, 5.0]);
        let v = mesh.nodes.len();
        let steel = steel();
        let (plain, u) = nonlinear_gauss2(&mesh, std::slice::from_ref(&steel), 1e-3);
        let (asm, mut us) = nonlinear_gauss2(&stray, &[steel], 1e-3);
        us[..u.len()].copy_from_slice(&u);
        let mut k = asm.new_tangent();
        k.values_mut().fill(f64::NAN);
        let a = asm.assemble(&us, Some(&mut k)).unwrap();
        assert!(k.values().iter().all(|x| x.is_finite()));
        assert_eq!(&a.internal[3 * v..], &[0.0; 3]);
        for c in 3 * v..3 * v + 3 {
            assert_eq!(asm.pattern().column(c).len(), 3 * v + 3 - c);
            assert_eq!(k.get(c, c), 0.0);
        }
        let mut kp = plain.new_tangent();
        plain.assemble(&u, Some(&mut kp)).unwrap();
        let kmax = kp.values().iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        for col in 0..plain.n() {
            for &row in plain.pattern().column(col) {
                let (x, y) = (k.get(row, col), kp.get(row, col));
                assert!((x - y).abs() <= 1e-12 * kmax, "({row}, {col})");
            }
        }
    }

    /// The forces of all cells through `partial_internal` are the assembled internal forces,
    /// and the two halves of a split cell list add up to them (to rounding: 1e-12 relative).
    #[test]
    fn partial_internal_adds_up_to_the_assembly() {
        let mesh = hex20_box([3, 2, 2]);
        let steel = steel();
        let (asm, u) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
        let full = asm.assemble(&u, None).unwrap().internal;
        let all: Vec<usize> = (0..mesh.cells.len()).collect();
        let (a, b) = all.split_at(5);
        let fa = asm.partial_internal(a, &u, Kinematics::Nonlinear).unwrap();
        let fb = asm.partial_internal(b, &u, Kinematics::Nonlinear).unwrap();
        let scale = full.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for d in 0..asm.n() {
            assert!((fa[d] + fb[d] - full[d]).abs() <= 1e-12 * scale, "dof {d}");
        }
        let lin = asm.partial_internal(&all, &u, Kinematics::Linear).unwrap();
        assert!(
            lin.iter()
                .zip(&full)
                .any(|(l, f)| (l - f).abs() > 1e-9 * scale)
        );
        assert!(asm.partial_internal(&[99], &u, Kinematics::Linear).is_err());
    }

    /// The slave rows and columns found for one tie set are not reused for another: folding
    /// set B after set A on one assembler gives bitwise what a fresh assembler gives for B.
    #[test]
    fn a_new_tie_set_gets_its_own_slave_positions() {
        let mesh = hex20_box([2, 1, 1]);
        let steel = steel();
        let (mut asm, u) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
        let n = asm.n();
        // The pattern is extended for both sets at once; each is then folded on its own.
        let nodes = &mesh.cells[0].nodes;
        let (p, q) = (3 * nodes[0], 3 * nodes[5]);
        let mut a = Constraints::new(n);
        a.tie(p, &[(q + 1, 0.5)], 0.0).unwrap();
        let mut b = Constraints::new(n);
        b.tie(q, &[(p + 2, -0.3), (p + 1, 0.2)], 1e-4).unwrap();
        let mut both = a.clone();
        both.tie(q, &[(p + 2, -0.3), (p + 1, 0.2)], 1e-4).unwrap();
        asm.tie(&both).unwrap();
        let (mut fresh, _) = nonlinear_gauss2(&mesh, &[steel], 1e-3);
        fresh.tie(&both).unwrap();
        let mut k = asm.new_tangent();
        asm.residual(&u, 1.0, &a, Some(&mut k)).unwrap();
        let got = asm.residual(&u, 1.0, &b, Some(&mut k)).unwrap();
        let mut k_fresh = fresh.new_tangent();
        let want = fresh.residual(&u, 1.0, &b, Some(&mut k_fresh)).unwrap();
        assert!(got == want, "residual or reactions differ");
        assert!(k == k_fresh, "the tangent kept set A's slave positions");
    }
}
