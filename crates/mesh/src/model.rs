//! The mesh model: nodes, cells with material and ply angle, named sets.

use crate::MeshError;
use nonlin3d_element::ElementKind;
use std::collections::BTreeMap;

/// Initial imperfection shapes (unit maximum at the origin, zero on and outside the front).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Imperfection {
    /// Eq. 5.3.1: ¼(1 + cos πx/a)(1 + cos πy/b) for |x| ≤ a, |y| ≤ b (rectangular fronts).
    Cosine {
        /// Half-length along x, m.
        a: f64,
        /// Half-width along y, m.
        b: f64,
    },
    /// (1 − (x/a)² − (y/b)²)² inside the ellipse (elliptic fronts; zero slope at the front).
    Bubble {
        /// Semi-axis along x, m.
        a: f64,
        /// Semi-axis along y, m.
        b: f64,
    },
    /// A through-width strip: ½(1 + cos πx/a) for |x| ≤ a, any y.
    Strip {
        /// Half-length along x, m.
        a: f64,
    },
}

impl Imperfection {
    /// w₀ at (x, y).
    pub fn value(&self, x: f64, y: f64) -> f64 {
        use std::f64::consts::PI;
        match *self {
            Self::Cosine { a, b } if x.abs() <= a && y.abs() <= b => {
                0.25 * (1.0 + (PI * x / a).cos()) * (1.0 + (PI * y / b).cos())
            }
            Self::Bubble { a, b } => {
                let s = 1.0 - (x / a).powi(2) - (y / b).powi(2);
                if s > 0.0 { s * s } else { 0.0 }
            }
            Self::Strip { a } if x.abs() <= a => 0.5 * (1.0 + (PI * x / a).cos()),
            _ => 0.0,
        }
    }
}

/// One hexahedral cell.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Hex8 or Hex20.
    pub kind: ElementKind,
    /// Node indices in Abaqus C3D8/C3D20 (= VTK) order.
    pub nodes: Vec<usize>,
    /// Material index (into the analysis's material table).
    pub material: usize,
    /// Ply angle in degrees about z (0 for homogenised material).
    pub ply_angle_deg: f64,
}

/// A hexahedral mesh: node coordinates (m), cells, and named node, cell and face sets.
///
/// Face numbers follow Abaqus C3D8/C3D20: S1 = ζ = −1 (nodes 1-2-3-4), S2 = ζ = +1, S3 = η = −1,
/// S4 = ξ = +1, S5 = η = +1, S6 = ξ = −1, stored zero-based (0 = S1).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Node coordinates.
    pub nodes: Vec<[f64; 3]>,
    /// Cells.
    pub cells: Vec<Cell>,
    /// Named node sets (sorted, unique node indices).
    pub node_sets: BTreeMap<String, Vec<usize>>,
    /// Named cell sets.
    pub cell_sets: BTreeMap<String, Vec<usize>>,
    /// Named face sets: (cell, face 0..6).
    pub face_sets: BTreeMap<String, Vec<(usize, u8)>>,
}

impl Mesh {
    /// Checks node counts, indices (cells and sets), finiteness; not geometry (see
    /// [`crate::quality`] for inverted cells).
    pub fn validate(&self) -> Result<(), MeshError> {
        let count = self.nodes.len();
        if let Some(index) = self
            .nodes
            .iter()
            .position(|p| !p.iter().all(|v| v.is_finite()))
        {
            return Err(MeshError::NonFinite {
                what: "node",
                index,
            });
        }
        for (c, cell) in self.cells.iter().enumerate() {
            let expected = cell.kind.nodes();
            if cell.nodes.len() != expected {
                return Err(MeshError::NodeCount {
                    cell: c,
                    kind: kind_name(cell.kind),
                    expected,
                    got: cell.nodes.len(),
                });
            }
            if let Some(&node) = cell.nodes.iter().find(|&&n| n >= count) {
                return Err(MeshError::NodeIndex {
                    owner: format!("cell {c}"),
                    node,
                    count,
                });
            }
            if !cell.ply_angle_deg.is_finite() {
                return Err(MeshError::NonFinite {
                    what: "ply angle of cell",
                    index: c,
                });
            }
        }
        for (name, set) in &self.node_sets {
            if let Some(&node) = set.iter().find(|&&n| n >= count) {
                return Err(MeshError::NodeIndex {
                    owner: format!("node set {name}"),
                    node,
                    count,
                });
            }
        }
        let cells = self.cells.len();
        for (name, set) in &self.cell_sets {
            if let Some(&cell) = set.iter().find(|&&c| c >= cells) {
                return Err(MeshError::CellIndex {
                    owner: format!("cell set {name}"),
                    cell,
                    face: None,
                    count: cells,
                });
            }
        }
        for (name, set) in &self.face_sets {
            if let Some(&(cell, face)) = set.iter().find(|&&(c, f)| c >= cells || f >= 6) {
                return Err(MeshError::CellIndex {
                    owner: format!("face set {name}"),
                    cell,
                    face: Some(face),
                    count: cells,
                });
            }
        }
        Ok(())
    }

    /// The sub-mesh of `cells`: only the nodes they use (renumbered in their old order), the
    /// sets restricted and renumbered. Returns it with `old node → new node` (None if dropped).
    pub fn extract(&self, cells: &[usize]) -> Result<(Mesh, Vec<Option<usize>>), MeshError> {
        self.validate()?;
        let mut used = vec![false; self.nodes.len()];
        let mut cell_map = vec![None; self.cells.len()];
        for (new, &c) in cells.iter().enumerate() {
            let cell = self.cells.get(c).ok_or_else(|| MeshError::CellIndex {
                owner: "extract".into(),
                cell: c,
                face: None,
                count: self.cells.len(),
            })?;
            cell_map[c] = Some(new);
            for &n in &cell.nodes {
                used[n] = true;
            }
        }
        let mut node_map = vec![None; self.nodes.len()];
        let mut out = Mesh::default();
        for (old, &u) in used.iter().enumerate() {
            if u {
                node_map[old] = Some(out.nodes.len());
                out.nodes.push(self.nodes[old]);
            }
        }
        for &c in cells {
            let mut cell = self.cells[c].clone();
            cell.nodes = cell.nodes.iter().filter_map(|&n| node_map[n]).collect();
            out.cells.push(cell);
        }
        for (name, set) in &self.node_sets {
            out.node_sets.insert(
                name.clone(),
                set.iter().filter_map(|&n| node_map[n]).collect(),
            );
        }
        for (name, set) in &self.cell_sets {
            out.cell_sets.insert(
                name.clone(),
                set.iter().filter_map(|&c| cell_map[c]).collect(),
            );
        }
        for (name, set) in &self.face_sets {
            out.face_sets.insert(
                name.clone(),
                set.iter()
                    .filter_map(|&(c, f)| cell_map[c].map(|n| (n, f)))
                    .collect(),
            );
        }
        out.validate()?;
        Ok((out, node_map))
    }

    /// Adds, for each (name, axis, value), the node set of the nodes with coordinate `axis`
    /// within `tol` of `value`.
    pub fn add_plane_sets(&mut self, planes: &[(&str, usize, f64)], tol: f64) {
        for &(name, axis, value) in planes {
            let set = (0..self.nodes.len())
                .filter(|&n| (self.nodes[n][axis] - value).abs() < tol)
                .collect();
            self.node_sets.insert(name.into(), set);
        }
    }

    /// Lifts the sublaminate by an initial imperfection w₀(x, y)·`amplitude` along z: every
    /// node with z ≥ `plane` (within 1e-12 relative) except those in the node set `keep` (the
    /// lower crack face) moves; `shape` gives w₀ with its maximum 1 and zero on and outside
    /// the front, so bonded nodes stay where they are.
    pub fn apply_imperfection(
        &mut self,
        plane: f64,
        keep: &str,
        shape: Imperfection,
        amplitude: f64,
    ) -> Result<(), MeshError> {
        if !amplitude.is_finite() {
            return Err(MeshError::Parameter {
                name: "amplitude",
                reason: format!("{amplitude} is not finite"),
            });
        }
        let keep: std::collections::HashSet<usize> = self
            .node_sets
            .get(keep)
            .into_iter()
            .flatten()
            .copied()
            .collect();
        let tol = 1e-12 * plane.abs().max(1e-3);
        for (n, x) in self.nodes.iter_mut().enumerate() {
            if x[2] >= plane - tol && !keep.contains(&n) {
                x[2] += amplitude * shape.value(x[0], x[1]);
            }
        }
        Ok(())
    }

    /// Global DOFs (3 per node, node-major) of each cell.
    pub fn cell_dofs(&self) -> Vec<Vec<usize>> {
        self.cells
            .iter()
            .map(|c| {
                c.nodes
                    .iter()
                    .flat_map(|&n| [3 * n, 3 * n + 1, 3 * n + 2])
                    .collect()
            })
            .collect()
    }

    /// Coordinates of the nodes of cell `c`.
    pub fn cell_coordinates(&self, c: usize) -> Vec<[f64; 3]> {
        self.cells[c].nodes.iter().map(|&n| self.nodes[n]).collect()
    }

    /// Displacements of the nodes of cell `c` from the node-major vector `u` (u, v, w per node;
    /// `u` holds 3 values per node of the mesh).
    pub fn cell_displacements(&self, c: usize, u: &[f64]) -> Vec<[f64; 3]> {
        self.cells[c]
            .nodes
            .iter()
            .map(|&n| [u[3 * n], u[3 * n + 1], u[3 * n + 2]])
            .collect()
    }

    /// Total volume, Σ over cells of ∫ det J (3×3×3 Gauss, exact for these isoparametric maps
    /// up to degree 5 per direction: exact for Hex8 and for Hex20 with straight edges).
    pub fn volume(&self) -> Result<f64, MeshError> {
        let mut v = 0.0;
        let (pts, wts) = nonlin3d_element::gauss_1d(3).ok_or(MeshError::Parameter {
            name: "quadrature",
            reason: "3-point Gauss rule missing".into(),
        })?;
        for (c, cell) in self.cells.iter().enumerate() {
            let x = self.cell_coordinates(c);
            for (i, wi) in pts.iter().zip(wts) {
                for (j, wj) in pts.iter().zip(wts) {
                    for (k, wk) in pts.iter().zip(wts) {
                        let det =
                            cell.kind
                                .jacobian_determinant([*i, *j, *k], &x)
                                .map_err(|_| MeshError::NodeCount {
                                    cell: c,
                                    kind: kind_name(cell.kind),
                                    expected: cell.kind.nodes(),
                                    got: x.len(),
                                })?;
                        v += det * wi * wj * wk;
                    }
                }
            }
        }
        Ok(v)
    }
}

/// Short name of an element kind.
pub(crate) fn kind_name(kind: ElementKind) -> &'static str {
    match kind {
        ElementKind::Hex8 => "Hex8",
        ElementKind::Hex20 => "Hex20",
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn validation_names_the_problem() {
        let mut m = Mesh {
            nodes: vec![[0.0; 3]; 8],
            cells: vec![Cell {
                kind: ElementKind::Hex8,
                nodes: (0..8).collect(),
                material: 0,
                ply_angle_deg: 0.0,
            }],
            ..Default::default()
        };
        assert!(m.validate().is_ok());
        m.cells[0].nodes[3] = 8;
        assert!(matches!(
            m.validate(),
            Err(MeshError::NodeIndex { node: 8, .. })
        ));
        m.cells[0].nodes.pop();
        assert!(matches!(
            m.validate(),
            Err(MeshError::NodeCount {
                cell: 0,
                expected: 8,
                got: 7,
                ..
            })
        ));
        m.cells[0].nodes = (0..8).collect();
        m.face_sets.insert("top".into(), vec![(0, 6)]);
        assert!(matches!(
            m.validate(),
            Err(MeshError::CellIndex { face: Some(6), .. })
        ));
        m.face_sets.clear();
        m.nodes[2][1] = f64::NAN;
        assert!(matches!(
            m.validate(),
            Err(MeshError::NonFinite {
                what: "node",
                index: 2
            })
        ));
    }
}
