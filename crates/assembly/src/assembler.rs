//! Parallel, deterministic assembly of internal forces and tangents over the cells of a mesh.

use crate::{AssemblyError, Constraints};
use nonlin3d_element::{
    BatchInput, ElementError, ElementKind, ElementOutput, IntegrationRule, Kinematics, ShapeTable,
    Workspace, evaluate, evaluate_batch_with,
};
use nonlin3d_laminate::{ShearCoupling, Stiffness};
use nonlin3d_mesh::Mesh;
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::collections::HashMap;
use std::sync::Arc;

/// Cells of one element kind and one colour: no two share a node, so their contributions can
/// be added to the global arrays concurrently.
struct Group {
    table: ShapeTable,
    cells: Vec<usize>,
    coords: Vec<[f64; 3]>,
    material_of: Vec<usize>,
}

/// Greedy colouring of `cells` (in order) so that no two cells of one colour share a node.
fn colour(mesh: &Mesh, cells: &[usize]) -> Vec<Vec<usize>> {
    let mut used: Vec<Vec<usize>> = vec![Vec::new(); mesh.nodes.len()];
    let mut colours: Vec<Vec<usize>> = Vec::new();
    for &c in cells {
        let nodes = &mesh.cells[c].nodes;
        // The smallest colour none of its nodes has; colours.len() is always free, since every
        // colour recorded at a node is an existing one.
        let k = (0..colours.len())
            .find(|k| nodes.iter().all(|&n| !used[n].contains(k)))
            .unwrap_or(colours.len());
        for &n in nodes {
            used[n].push(k);
        }
        if k == colours.len() {
            colours.push(Vec::new());
        }
        colours[k].push(c);
    }
    colours
}

/// Shared write access to the global force vector and tangent values for the cells of one
/// colour: they touch disjoint entries, so concurrent adds never alias.
struct Disjoint {
    forces: *mut f64,
    forces_len: usize,
    values: *mut f64,
    values_len: usize,
}

// SAFETY: `Disjoint` is only used inside `Assembler::assemble` while the cells of a single
// colour are evaluated; the colouring guarantees that no two of them share a node, hence no
// two write the same force entry or (through their scatter maps, which address entries (i, j)
// of their own DOFs only) the same tangent value. Each entry is therefore written by at most
// one thread, and the pointers outlive the parallel section (they borrow `internal` and `k`,
// which stay alive and unaliased until it ends).
unsafe impl Sync for Disjoint {}

impl Disjoint {
    /// Adds `v` to force entry `i`.
    fn add_force(&self, i: usize, v: f64) {
        assert!(i < self.forces_len);
        // SAFETY: in bounds (checked); exclusive per the type's invariant.
        unsafe { *self.forces.add(i) += v };
    }

    /// Adds `v` to tangent value `p`.
    fn add_value(&self, p: usize, v: f64) {
        assert!(p < self.values_len);
        // SAFETY: in bounds (checked); exclusive per the type's invariant.
        unsafe { *self.values.add(p) += v };
    }
}

/// Everything needed to assemble a mesh again and again: shape tables, per-cell stiffness
/// (rotated to each cell's ply angle once), DOF lists, the sparsity pattern and each cell's
/// scatter map into it.
pub struct Assembler {
    n: usize,
    groups: Vec<Group>,
    stiffness: Vec<Stiffness>,
    dofs: Vec<Vec<usize>>,
    maps: Vec<Vec<Option<usize>>>,
    pattern: Arc<SymmetricPattern>,
    kinematics: Kinematics,
    /// (group, position in the group) of each cell.
    place: Vec<(usize, usize)>,
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
        other => other,
    }
}

impl Assembler {
    /// Sets up `mesh` with `materials[cell.material]` in ply axes, rotated about z by each cell's
    /// ply angle (`coupling` as in [`Stiffness::rotated_about_z`]); Hex20 cells integrated with
    /// `hex20_rule`, Hex8 cells with `hex8_rule`.
    pub fn new(
        mesh: &Mesh,
        materials: &[Stiffness],
        coupling: ShearCoupling,
        hex20_rule: IntegrationRule,
        hex8_rule: IntegrationRule,
        kinematics: Kinematics,
    ) -> Result<Self, AssemblyError> {
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
        let mut groups = Vec::new();
        for (kind, rule) in [
            (ElementKind::Hex20, hex20_rule),
            (ElementKind::Hex8, hex8_rule),
        ] {
            let cells: Vec<usize> = (0..mesh.cells.len())
                .filter(|&c| mesh.cells[c].kind == kind)
                .collect();
            if cells.is_empty() {
                continue;
            }
            let table = ShapeTable::new(kind, rule)?;
            // One group per colour: the parallel scatter in `assemble` relies on it.
            for cells in colour(mesh, &cells) {
                let coords = cells
                    .iter()
                    .flat_map(|&c| mesh.cell_coordinates(c))
                    .collect();
                let material_of = cells.iter().map(|&c| cell_stiffness[c]).collect();
                groups.push(Group {
                    table: table.clone(),
                    cells,
                    coords,
                    material_of,
                });
            }
        }
        let mut place = vec![(0, 0); mesh.cells.len()];
        for (gi, g) in groups.iter().enumerate() {
            for (i, &c) in g.cells.iter().enumerate() {
                place[c] = (gi, i);
            }
        }
        let dofs = mesh.cell_dofs();
        let pattern = Arc::new(SymmetricPattern::from_dof_lists(n, &dofs)?);
        let maps = dofs
            .iter()
            .map(|d| pattern.scatter_map(d))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            n,
            groups,
            stiffness,
            dofs,
            maps,
            pattern,
            kinematics,
            place,
        })
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
    /// DOF couples its DOFs with the slave's masters too, the entries K′ = TᵀKT needs when
    /// [`residual`](Self::residual) folds the slave onto them. Tangents made before this call
    /// no longer fit ([`new_tangent`](Self::new_tangent) again).
    pub fn tie(&mut self, constraints: &Constraints) -> Result<(), AssemblyError> {
        let masters: HashMap<usize, Vec<usize>> = constraints
            .ties()
            .iter()
            .map(|t| (t.slave, t.masters.iter().map(|m| m.0).collect()))
            .collect();
        let lists: Vec<Vec<usize>> = self
            .dofs
            .iter()
            .map(|d| {
                let mut l = d.clone();
                for x in d {
                    if let Some(m) = masters.get(x) {
                        l.extend(m);
                    }
                }
                l.sort_unstable();
                l.dedup();
                l
            })
            .collect();
        // Ties whose slave no cell holds still need their masters coupled to each other.
        let mut all = lists;
        all.extend(constraints.ties().iter().map(|t| {
            let mut l: Vec<usize> = t.masters.iter().map(|m| m.0).collect();
            l.push(t.slave);
            l.sort_unstable();
            l.dedup();
            l
        }));
        let pattern = Arc::new(SymmetricPattern::from_dof_lists(self.n, &all)?);
        self.maps = self
            .dofs
            .iter()
            .map(|d| pattern.scatter_map(d))
            .collect::<Result<Vec<_>, _>>()?;
        self.pattern = pattern;
        Ok(())
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

    /// Internal forces (and energy) at displacements `u`; the tangent into `tangent` (zeroed
    /// first) when given. Elements run in parallel on the current rayon pool; the scatter runs
    /// in cell order, so results do not depend on the thread count.
    pub fn assemble(
        &self,
        u: &[f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<Assembly, AssemblyError> {
        if u.len() != self.n {
            return Err(AssemblyError::Length {
                what: "displacements",
                expected: self.n,
                got: u.len(),
            });
        }
        let mut internal = vec![0.0; self.n];
        let mut energy = 0.0;
        let mut k = tangent;
        if let Some(k) = k.as_deref_mut() {
            k.set_zero();
        }
        // Colour after colour; within a colour, cells in parallel writing straight into the
        // global arrays (no two share an entry). Every entry receives its contributions in
        // colour order, one per colour at most: the result does not depend on the threads.
        let (values_ptr, values_len) = match k.as_deref_mut() {
            Some(k) => {
                let v = k.values_mut();
                (v.as_mut_ptr(), v.len())
            }
            None => (std::ptr::null_mut(), 0),
        };
        let want_k = k.is_some();
        let writer = Disjoint {
            forces: internal.as_mut_ptr(),
            forces_len: internal.len(),
            values: values_ptr,
            values_len,
        };
        for g in &self.groups {
            let nd = g.table.dofs();
            let disp: Vec<[f64; 3]> = g
                .cells
                .iter()
                .flat_map(|&c| {
                    self.dofs[c]
                        .chunks_exact(3)
                        .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
                })
                .collect();
            let input = BatchInput {
                coords: &g.coords,
                disp: &disp,
                materials: &self.stiffness,
                material_of: &g.material_of,
            };
            let energies = evaluate_batch_with(
                &g.table,
                &input,
                self.kinematics,
                want_k,
                || 0.0,
                |e_sum, i, out| {
                    let c = g.cells[i];
                    for (a, &d) in self.dofs[c].iter().enumerate() {
                        writer.add_force(d, out.forces[a]);
                    }
                    if want_k {
                        for (p, v) in self.maps[c].iter().zip(&out.tangent[..nd * nd]) {
                            if let Some(p) = *p {
                                writer.add_value(p, *v);
                            }
                        }
                    }
                    *e_sum += out.energy;
                },
            )
            .map_err(|e| relocate(e, &g.cells))?;
            energy += energies.iter().sum::<f64>();
        }
        Ok(Assembly { internal, energy })
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
            fold_ties(constraints, &mut r, &mut reactions, k.as_deref_mut())?;
        }
        let mut fixed = vec![false; self.n];
        for (d, _) in constraints.prescribed() {
            fixed[d] = true;
            reactions[d] = r[d];
            r[d] = 0.0;
        }
        if let Some(k) = k {
            let (cp, ri) = (
                self.pattern.col_ptr().to_vec(),
                self.pattern.row_idx().to_vec(),
            );
            let vals = k.values_mut();
            for j in 0..self.n {
                for p in cp[j]..cp[j + 1] {
                    let i = ri[p];
                    if fixed[i] || fixed[j] {
                        vals[p] = if i == j { 1.0 } else { 0.0 };
                    }
                }
            }
        }
        Ok((r, reactions, a.energy))
    }
}

/// Folds each tie's slave onto its masters (K′ = TᵀKT, r′ = Tᵀr for u_s = Σ c_k u_{m_k}),
/// slave by slave: r_m += c·r_s; K_{m j} += c·K_{s j} (twice on the diagonal m = j, which stands
/// for both triangles); K_{m m′} += c c′ K_ss; then the slave's row and column become the
/// identity and its residual (the force the tie carries) its reaction.
fn fold_ties(
    constraints: &Constraints,
    r: &mut [f64],
    reactions: &mut [f64],
    k: Option<&mut SymmetricMatrix>,
) -> Result<(), AssemblyError> {
    for t in constraints.ties() {
        let rs = r[t.slave];
        for &(m, c) in &t.masters {
            r[m] += c * rs;
        }
        reactions[t.slave] = rs;
        r[t.slave] = 0.0;
    }
    let Some(k) = k else {
        return Ok(());
    };
    let pattern = k.pattern().clone();
    let (cp, ri) = (pattern.col_ptr(), pattern.row_idx());
    let slave_of: HashMap<usize, usize> = constraints
        .ties()
        .iter()
        .enumerate()
        .map(|(i, t)| (t.slave, i))
        .collect();
    // Stored positions of every slave's row/column: (position, the other index).
    let mut entries: Vec<Vec<(usize, usize)>> = vec![Vec::new(); constraints.ties().len()];
    for j in 0..pattern.n() {
        for p in cp[j]..cp[j + 1] {
            let i = ri[p];
            if let Some(&t) = slave_of.get(&i) {
                entries[t].push((p, j));
            }
            if i != j
                && let Some(&t) = slave_of.get(&j)
            {
                entries[t].push((p, i));
            }
        }
    }
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
    use nonlin3d_mesh::{BoxParams, EmbeddedParams, embedded_delamination, structured_box};

    /// The invariant the parallel scatter relies on: within a colour no two cells share a node,
    /// and every cell is in exactly one colour.
    #[test]
    fn colours_never_share_a_node() {
        let meshes = [
            structured_box(&BoxParams::new(
                ElementKind::Hex20,
                [5, 4, 3],
                [1.0, 1.0, 1.0],
            ))
            .unwrap(),
            structured_box(&BoxParams::new(
                ElementKind::Hex8,
                [7, 2, 2],
                [1.0, 1.0, 1.0],
            ))
            .unwrap(),
            embedded_delamination(&EmbeddedParams {
                slices: 4,
                ..EmbeddedParams::thesis_reference()
            })
            .unwrap(),
        ];
        for mesh in &meshes {
            let all: Vec<usize> = (0..mesh.cells.len()).collect();
            let colours = colour(mesh, &all);
            let mut seen = vec![0usize; mesh.cells.len()];
            for cells in &colours {
                let mut owner = std::collections::HashMap::new();
                for &c in cells {
                    seen[c] += 1;
                    for &n in &mesh.cells[c].nodes {
                        assert!(
                            owner.insert(n, c).is_none(),
                            "node {n} in two cells of one colour"
                        );
                    }
                }
            }
            assert!(seen.iter().all(|&k| k == 1));
            // A structured Hex mesh needs 8 colours (2 per direction); the swept model a few more.
            assert!(colours.len() <= 16, "{} colours", colours.len());
        }
    }

    /// The forces of all cells through `partial_internal` are the assembled internal forces,
    /// and the two halves of a split cell list add up to them (to rounding: 1e-12 relative).
    #[test]
    fn partial_internal_adds_up_to_the_assembly() {
        use nonlin3d_laminate::materials;
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [3, 2, 2],
            [2.0, 1.0, 1.0],
        ))
        .unwrap();
        let steel = materials::steel().stiffness().unwrap();
        let asm = Assembler::new(
            &mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss2,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap();
        let u: Vec<f64> = (0..asm.n())
            .map(|d| 1e-3 * ((d * 7919) % 23) as f64 / 23.0)
            .collect();
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
}
