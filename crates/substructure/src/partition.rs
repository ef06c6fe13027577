//! The partition of a mesh into a linear and a nonlinear region (thesis §2.6, Fig. 3.2.2): the
//! interface nodes Γ (in a linear and a nonlinear cell), the linear region's interior nodes (in
//! linear cells only), the nonlinear region's nodes (Γ included), the two sub-meshes with
//! their nodes renumbered compactly, and the maps between the numberings.

use crate::SubstructureError;
use nonlin3d_assembly::Constraints;
use nonlin3d_mesh::Mesh;

/// Name of the node set of the interface nodes in both sub-meshes.
pub const INTERFACE: &str = "interface";

/// Which side of a partition a list of cells (or a named cell set) gives.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Region {
    /// The cells to condense (kept small-strain).
    Linear,
    /// The cells solved by Newton on top of the superelement.
    Nonlinear,
}

/// One sub-mesh of a partition and its node maps.
#[derive(Debug, Clone)]
struct Side {
    cells: Vec<usize>,
    mesh: Mesh,
    /// Full node → sub-mesh node.
    to_sub: Vec<Option<usize>>,
    /// Sub-mesh node → full node.
    to_full: Vec<usize>,
}

impl Side {
    fn new(mesh: &Mesh, cells: Vec<usize>, interface: &[usize]) -> Result<Self, SubstructureError> {
        let (mut sub, to_sub) = mesh.extract(&cells)?;
        let mut to_full = vec![0; sub.nodes.len()];
        for (full, s) in to_sub.iter().enumerate() {
            if let Some(s) = *s {
                to_full[s] = full;
            }
        }
        let set: Vec<usize> = interface.iter().filter_map(|&v| to_sub[v]).collect();
        sub.node_sets.insert(INTERFACE.into(), set);
        Ok(Self {
            cells,
            mesh: sub,
            to_sub,
            to_full,
        })
    }
}

/// A mesh cut into a linear region (condensed onto the interface) and a nonlinear region (solved
/// by Newton with the superelement as one more contribution): thesis §2.6 and Fig. 3.2.2, where
/// the linear region is everything but the sublaminate inside a contour ℓ inside the front.
///
/// Nodes of the full mesh in no cell belong to neither region.
#[derive(Debug, Clone)]
pub struct Partition {
    full_nodes: usize,
    linear: Side,
    nonlinear: Side,
    /// Full nodes in both a linear and a nonlinear cell, ascending.
    interface: Vec<usize>,
    /// Full nodes in linear cells only, ascending.
    interior: Vec<usize>,
}

impl Partition {
    /// The partition whose linear region is `cells` (duplicates ignored) and whose nonlinear
    /// region is every other cell.
    pub fn from_linear_cells(mesh: &Mesh, cells: &[usize]) -> Result<Self, SubstructureError> {
        Self::new(mesh, cells, Region::Linear)
    }

    /// The partition whose nonlinear region is `cells` and whose linear region is every other
    /// cell.
    pub fn from_nonlinear_cells(mesh: &Mesh, cells: &[usize]) -> Result<Self, SubstructureError> {
        Self::new(mesh, cells, Region::Nonlinear)
    }

    /// The partition with the mesh's cell set `name` as the `region` side.
    pub fn from_cell_set(
        mesh: &Mesh,
        name: &str,
        region: Region,
    ) -> Result<Self, SubstructureError> {
        let set = mesh
            .cell_sets
            .get(name)
            .ok_or_else(|| SubstructureError::UnknownSet { name: name.into() })?;
        Self::new(mesh, set, region)
    }

    /// The partition with `cells` on side `region`, every other cell on the other side.
    pub fn new(mesh: &Mesh, cells: &[usize], region: Region) -> Result<Self, SubstructureError> {
        let count = mesh.cells.len();
        let mut chosen = vec![false; count];
        for &c in cells {
            *chosen
                .get_mut(c)
                .ok_or(SubstructureError::CellOutOfRange { cell: c, count })? = true;
        }
        let (mut linear, mut nonlinear) = (Vec::new(), Vec::new());
        for (c, &x) in chosen.iter().enumerate() {
            if x == (region == Region::Linear) {
                linear.push(c);
            } else {
                nonlinear.push(c);
            }
        }
        for (region, list) in [("linear", &linear), ("nonlinear", &nonlinear)] {
            if list.is_empty() {
                return Err(SubstructureError::EmptyRegion { region });
            }
        }
        mesh.validate()?;
        // 1: in a linear cell, 2: in a nonlinear cell, 3: both (the interface).
        let mut owner = vec![0u8; mesh.nodes.len()];
        for (list, bit) in [(&linear, 1u8), (&nonlinear, 2u8)] {
            for &c in list {
                for &v in &mesh.cells[c].nodes {
                    owner[v] |= bit;
                }
            }
        }
        let interface: Vec<usize> = (0..owner.len()).filter(|&v| owner[v] == 3).collect();
        let interior: Vec<usize> = (0..owner.len()).filter(|&v| owner[v] == 1).collect();
        if interface.is_empty() {
            return Err(SubstructureError::NoInterface {
                linear: linear.len(),
                nonlinear: nonlinear.len(),
            });
        }
        Ok(Self {
            full_nodes: mesh.nodes.len(),
            linear: Side::new(mesh, linear, &interface)?,
            nonlinear: Side::new(mesh, nonlinear, &interface)?,
            interface,
            interior,
        })
    }

    /// Nodes of the full mesh.
    pub fn full_nodes(&self) -> usize {
        self.full_nodes
    }

    /// The linear region's cells (full-mesh indices, ascending).
    pub fn linear_cells(&self) -> &[usize] {
        &self.linear.cells
    }

    /// The nonlinear region's cells (full-mesh indices, ascending).
    pub fn nonlinear_cells(&self) -> &[usize] {
        &self.nonlinear.cells
    }

    /// The interface nodes Γ (full mesh, ascending): in both a linear and a nonlinear cell.
    pub fn interface(&self) -> &[usize] {
        &self.interface
    }

    /// The linear region's interior nodes (full mesh, ascending): in linear cells only.
    pub fn interior(&self) -> &[usize] {
        &self.interior
    }

    /// The nonlinear region's nodes (full mesh, ascending; Γ included).
    pub fn nonlinear_nodes(&self) -> &[usize] {
        &self.nonlinear.to_full
    }

    /// The linear region's nodes (full mesh, ascending; Γ included).
    pub fn linear_nodes(&self) -> &[usize] {
        &self.linear.to_full
    }

    /// The nonlinear sub-mesh: its cells in full-mesh order, its nodes renumbered compactly in
    /// full-mesh order, the node, cell and face sets restricted to it, and the interface as the
    /// node set [`INTERFACE`]. The ordinary [`Assembler`](nonlin3d_assembly::Assembler) runs on it.
    pub fn nonlinear_mesh(&self) -> &Mesh {
        &self.nonlinear.mesh
    }

    /// The linear sub-mesh (as [`nonlinear_mesh`](Self::nonlinear_mesh)), to build the
    /// assembler [`condense`](crate::condense) takes.
    pub fn linear_mesh(&self) -> &Mesh {
        &self.linear.mesh
    }

    /// Full node → nonlinear sub-mesh node (None outside the nonlinear region).
    pub fn to_nonlinear(&self, node: usize) -> Option<usize> {
        self.nonlinear.to_sub.get(node).copied().flatten()
    }

    /// Nonlinear sub-mesh node → full node.
    pub fn from_nonlinear(&self, node: usize) -> Option<usize> {
        self.nonlinear.to_full.get(node).copied()
    }

    /// Full node → linear sub-mesh node (None outside the linear region).
    pub fn to_linear(&self, node: usize) -> Option<usize> {
        self.linear.to_sub.get(node).copied().flatten()
    }

    /// Linear sub-mesh node → full node.
    pub fn from_linear(&self, node: usize) -> Option<usize> {
        self.linear.to_full.get(node).copied()
    }

    /// The interface DOFs in the nonlinear sub-mesh's numbering (3 per interface node, in
    /// interface order): the superelement's DOFs.
    pub fn interface_dofs_nonlinear(&self) -> Vec<usize> {
        self.interface
            .iter()
            .filter_map(|&v| self.to_nonlinear(v))
            .flat_map(|s| [3 * s, 3 * s + 1, 3 * s + 2])
            .collect()
    }

    /// A full-mesh vector (3 per node) restricted to the nonlinear region's DOFs.
    pub fn restrict_to_nonlinear(&self, full: &[f64]) -> Result<Vec<f64>, SubstructureError> {
        self.check_full("full-mesh vector", full.len())?;
        Ok(self
            .nonlinear
            .to_full
            .iter()
            .flat_map(|&v| [full[3 * v], full[3 * v + 1], full[3 * v + 2]])
            .collect())
    }

    /// The constraints of the nonlinear sub-mesh from those of the full mesh: the prescribed
    /// DOFs (with their ramps), nodal and dead loads and ties on the nonlinear region's nodes
    /// (the interface included), renumbered. What falls on the linear region's interior is
    /// left out: the condensation carries it ([`condense`](crate::condense)). Errors: a size
    /// mismatch, a tie touching an interior node.
    pub fn nonlinear_constraints(
        &self,
        full: &Constraints,
    ) -> Result<Constraints, SubstructureError> {
        self.check_full("constraints", full.n())?;
        let dof = |d: usize| self.to_nonlinear(d / 3).map(|s| 3 * s + d % 3);
        let n = 3 * self.nonlinear.to_full.len();
        let mut out = Constraints::new(n);
        let (at0, at1) = values_at_0_and_1(full);
        for (d, _) in full.prescribed() {
            if let Some(s) = dof(d) {
                out.prescribe_ramp(s, at0.values[d], at1.values[d])?;
            }
        }
        for d in 0..full.n() {
            if let Some(s) = dof(d) {
                let (dead, load) = (at0.forces[d], at1.forces[d] - at0.forces[d]);
                if load != 0.0 {
                    out.add_load(s, load)?;
                }
                if dead != 0.0 {
                    out.set_dead_load(s, dead)?;
                }
            }
        }
        for (t, &g) in full.ties().iter().zip(full.tie_groups()) {
            let interior = std::iter::once(t.slave)
                .chain(t.masters.iter().map(|m| m.0))
                .find(|&d| dof(d).is_none());
            if let Some(d) = interior {
                return Err(SubstructureError::TieInLinearRegion {
                    slave: t.slave,
                    node: d / 3,
                });
            }
            let masters: Vec<(usize, f64)> = t
                .masters
                .iter()
                .filter_map(|&(m, c)| dof(m).map(|s| (s, c)))
                .collect();
            if let Some(s) = dof(t.slave) {
                out.tie_in(g, s, &masters, t.offset)?;
            }
        }
        Ok(out)
    }

    /// Checks a length against the full mesh's 3 DOFs per node.
    pub(crate) fn check_full(
        &self,
        what: &'static str,
        got: usize,
    ) -> Result<(), SubstructureError> {
        if got == 3 * self.full_nodes {
            Ok(())
        } else {
            Err(SubstructureError::Length {
                what,
                expected: 3 * self.full_nodes,
                got,
            })
        }
    }
}

/// Prescribed values and external forces of constraints at one load factor.
pub(crate) struct AtLambda {
    /// u with the prescribed entries set (zero elsewhere).
    pub values: Vec<f64>,
    /// f_ext(λ).
    pub forces: Vec<f64>,
}

/// The constraints' prescribed values and external forces at λ = 0 (the base and dead parts)
/// and at λ = 1: the λ-proportional parts are their differences.
pub(crate) fn values_at_0_and_1(c: &Constraints) -> (AtLambda, AtLambda) {
    let at = |lambda: f64| {
        let mut values = vec![0.0; c.n()];
        c.apply(&mut values, lambda);
        let mut forces = vec![0.0; c.n()];
        c.external(lambda, &mut forces);
        AtLambda { values, forces }
    };
    (at(0.0), at(1.0))
}

#[cfg(test)]
mod tests {
    use super::*;
    use nonlin3d_element::ElementKind;
    use nonlin3d_mesh::{BoxParams, structured_box};

    fn box_mesh() -> Mesh {
        structured_box(&BoxParams::new(
            ElementKind::Hex8,
            [4, 2, 1],
            [4.0, 2.0, 1.0],
        ))
        .unwrap()
    }

    /// Cells with centre x < 2 on one side: the interface is the plane x = 2 (3 × 2 nodes),
    /// each side's sub-mesh holds its own nodes, the maps are inverse, the set is kept.
    #[test]
    fn a_box_cut_in_half_has_the_mid_plane_as_interface() {
        let mesh = box_mesh();
        let left: Vec<usize> = (0..mesh.cells.len())
            .filter(|&c| mesh.cell_coordinates(c).iter().map(|p| p[0]).sum::<f64>() < 16.0)
            .collect();
        let p = Partition::from_linear_cells(&mesh, &left).unwrap();
        assert_eq!(p.interface().len(), 3 * 2);
        assert!(p.interface().iter().all(|&v| mesh.nodes[v][0] == 2.0));
        assert_eq!(p.interior().len(), 2 * 3 * 2);
        assert_eq!(p.nonlinear_nodes().len(), 3 * 3 * 2);
        for (s, &v) in p.nonlinear_nodes().iter().enumerate() {
            assert_eq!(p.to_nonlinear(v), Some(s));
            assert_eq!(p.from_nonlinear(s), Some(v));
        }
        let nl = p.nonlinear_mesh();
        assert_eq!(nl.node_sets[INTERFACE].len(), 6);
        assert_eq!(nl.node_sets["x1"].len(), 6);
        assert!(nl.node_sets["x0"].is_empty());
        let q = Partition::from_nonlinear_cells(&mesh, p.nonlinear_cells()).unwrap();
        assert_eq!(q.interface(), p.interface());
        assert_eq!(q.linear_cells(), p.linear_cells());
    }

    /// Empty sides, a cell out of range, an unknown set and disjoint regions are refused.
    #[test]
    fn bad_partitions_are_typed_errors() {
        let mesh = box_mesh();
        let all: Vec<usize> = (0..mesh.cells.len()).collect();
        assert!(matches!(
            Partition::from_linear_cells(&mesh, &[]),
            Err(SubstructureError::EmptyRegion { region: "linear" })
        ));
        assert!(matches!(
            Partition::from_linear_cells(&mesh, &all),
            Err(SubstructureError::EmptyRegion {
                region: "nonlinear"
            })
        ));
        assert!(matches!(
            Partition::from_linear_cells(&mesh, &[99]),
            Err(SubstructureError::CellOutOfRange { cell: 99, count: 8 })
        ));
        assert!(matches!(
            Partition::from_cell_set(&mesh, "nope", Region::Linear),
            Err(SubstructureError::UnknownSet { .. })
        ));
        // Two copies of a one-cell box side by side, not sharing nodes.
        let one = structured_box(&BoxParams::new(ElementKind::Hex8, [1, 1, 1], [1.0; 3])).unwrap();
        let mut two = one.clone();
        let mut cell = one.cells[0].clone();
        cell.nodes.iter_mut().for_each(|v| *v += 8);
        two.nodes
            .extend(one.nodes.iter().map(|p| [p[0] + 5.0, p[1], p[2]]));
        two.cells.push(cell);
        assert!(matches!(
            Partition::from_linear_cells(&two, &[0]),
            Err(SubstructureError::NoInterface { .. })
        ));
    }

    /// Prescribed ramps, loads and dead loads on the nonlinear nodes are carried over and
    /// renumbered; those on interior nodes are dropped.
    #[test]
    fn nonlinear_constraints_keep_what_falls_on_the_region() {
        let mesh = box_mesh();
        let p = Partition::from_nonlinear_cells(&mesh, &[0]).unwrap();
        let mut c = Constraints::new(3 * mesh.nodes.len());
        let inside = p.nonlinear_nodes()[0];
        let outside = p.interior()[0];
        c.prescribe_ramp(3 * inside, 0.5, 2.0).unwrap();
        c.prescribe(3 * outside, 1.0).unwrap();
        c.add_load(3 * inside + 1, 7.0).unwrap();
        c.set_dead_load(3 * inside + 2, 3.0).unwrap();
        c.add_load(3 * outside + 1, 9.0).unwrap();
        let m = p.nonlinear_constraints(&c).unwrap();
        let s = p.to_nonlinear(inside).unwrap();
        assert_eq!(m.prescribed().collect::<Vec<_>>(), vec![(3 * s, 2.0)]);
        let mut u = vec![0.0; m.n()];
        m.apply(&mut u, 0.0);
        assert_eq!(u[3 * s], 0.5);
        let mut f = vec![0.0; m.n()];
        m.external(2.0, &mut f);
        assert_eq!((f[3 * s + 1], f[3 * s + 2]), (14.0, 3.0));
        assert_eq!(f.iter().filter(|&&x| x != 0.0).count(), 2);
    }
}
