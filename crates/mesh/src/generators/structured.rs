//! The structured box: a graded hexahedral block with its end sets (the meshes of the
//! element and convergence tests, and the DCB of §5).

use super::grading::{graded_coordinates, grid_index, grid_position};
use crate::MeshError;
use crate::model::{Cell, Mesh};
use crate::names;
use nonlin3d_element::ElementKind;
use std::collections::HashMap;

/// A structured box `[0, size[0]] × [0, size[1]] × [0, size[2]]` (m) of `counts` elements per
/// axis, graded so that along each axis the last element is `grading` times the first
/// (1 = uniform; < 1 refines towards the far end).
#[derive(Debug, Clone, PartialEq)]
pub struct BoxParams {
    /// Hex8 or Hex20.
    pub kind: ElementKind,
    /// Elements along x, y, z.
    pub counts: [usize; 3],
    /// Edge lengths along x, y, z in m.
    pub size: [f64; 3],
    /// Ratio of last to first element size per axis.
    pub grading: [f64; 3],
    /// Material index of every cell.
    pub material: usize,
}

impl BoxParams {
    /// Uniform box, material 0.
    pub fn new(kind: ElementKind, counts: [usize; 3], size: [f64; 3]) -> Self {
        Self {
            kind,
            counts,
            size,
            grading: [1.0; 3],
            material: 0,
        }
    }
}

/// The structured box of `p`, with node sets `x0`, `x1`, `y0`, `y1`, `z0`, `z1` (nodes on each
/// face), face sets of the same names, and the cell set `all`. Hex20 mid-edge nodes sit at the
/// midpoints of their edges.
pub fn structured_box(p: &BoxParams) -> Result<Mesh, MeshError> {
    let axes = [
        graded_coordinates(p.counts[0], p.size[0], p.grading[0])?,
        graded_coordinates(p.counts[1], p.size[1], p.grading[1])?,
        graded_coordinates(p.counts[2], p.size[2], p.grading[2])?,
    ];
    let (mut mesh, grid) = box_cells(p, &axes);
    add_end_node_sets(&mut mesh, &grid, p.counts);
    add_end_face_sets(&mut mesh, p.counts);
    mesh.cell_sets
        .insert(names::ALL.into(), (0..mesh.cells.len()).collect());
    mesh.validate()?;
    Ok(mesh)
}

/// The cells of the box, x fastest then y then z, nodes made on first use at the vertex
/// positions `axes` (mid-edge nodes at the midpoints); returns the mesh and each node's doubled
/// grid index.
fn box_cells(p: &BoxParams, axes: &[Vec<f64>; 3]) -> (Mesh, Vec<[usize; 3]>) {
    let mut ids: HashMap<[usize; 3], usize> = HashMap::new();
    let mut mesh = Mesh::default();
    let mut grid = Vec::new();
    for k in 0..p.counts[2] {
        for j in 0..p.counts[1] {
            for i in 0..p.counts[0] {
                let mut nodes = Vec::with_capacity(p.kind.nodes());
                for r in p.kind.reference_nodes() {
                    let g = grid_index([i, j, k], r);
                    let id = *ids.entry(g).or_insert_with(|| {
                        mesh.nodes.push([
                            grid_position(&axes[0], g[0]),
                            grid_position(&axes[1], g[1]),
                            grid_position(&axes[2], g[2]),
                        ]);
                        grid.push(g);
                        mesh.nodes.len() - 1
                    });
                    nodes.push(id);
                }
                mesh.cells.push(Cell {
                    kind: p.kind,
                    nodes,
                    material: p.material,
                    ply_angle_deg: 0.0,
                });
            }
        }
    }
    (mesh, grid)
}

/// The node sets `x0` … `z1`: the nodes whose grid index is 0 or 2·count along the axis.
fn add_end_node_sets(mesh: &mut Mesh, grid: &[[usize; 3]], counts: [usize; 3]) {
    for axis in 0..3 {
        let (low, high) = names::box_ends(axis);
        for (end, name) in [(0, low), (2 * counts[axis], high)] {
            let set: Vec<usize> = (0..mesh.nodes.len())
                .filter(|&n| grid[n][axis] == end)
                .collect();
            mesh.node_sets.insert(name.into(), set);
        }
    }
}

/// The face sets `x0` … `z1`: (cell, Abaqus face) of the cells on each end of the box.
fn add_end_face_sets(mesh: &mut Mesh, counts: [usize; 3]) {
    // Faces: (axis, side) → Abaqus face number (zero-based): ζ−: 0, ζ+: 1, η−: 2, ξ+: 3, η+: 4, ξ−: 5.
    let face_of = [[5u8, 3], [2, 4], [0, 1]];
    for axis in 0..3 {
        let (low, high) = names::box_ends(axis);
        for (side, name) in [(0usize, low), (1, high)] {
            let mut faces = Vec::new();
            for c in 0..mesh.cells.len() {
                let idx = [
                    c % counts[0],
                    (c / counts[0]) % counts[1],
                    c / (counts[0] * counts[1]),
                ];
                if (side == 0 && idx[axis] == 0) || (side == 1 && idx[axis] + 1 == counts[axis]) {
                    faces.push((c, face_of[axis][side]));
                }
            }
            mesh.face_sets.insert(name.into(), faces);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_counts_sets_and_volume() {
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let mut p = BoxParams::new(kind, [3, 2, 4], [3e-3, 2e-3, 1e-3]);
            p.grading = [0.5, 1.0, 2.0];
            let m = structured_box(&p).unwrap();
            let corners = 4 * 3 * 5;
            let expected = match kind {
                ElementKind::Hex8 => corners,
                ElementKind::Hex20 => corners + 3 * 3 * 5 + 4 * 2 * 5 + 4 * 3 * 4,
            };
            assert_eq!(m.nodes.len(), expected);
            assert_eq!(m.cells.len(), 24);
            // Volume exact to round-off.
            assert!((m.volume().unwrap() - 6e-9).abs() < 1e-21);
            for (name, axis, value) in [("x0", 0, 0.0), ("x1", 0, 3e-3), ("z1", 2, 1e-3)] {
                let set = &m.node_sets[name];
                assert!(!set.is_empty());
                assert!(
                    set.iter()
                        .all(|&n| (m.nodes[n][axis] - value).abs() < 1e-18)
                );
            }
            assert_eq!(m.face_sets["z0"].len(), 6);
            assert_eq!(m.face_sets["x1"].len(), 8);
        }
    }
}
