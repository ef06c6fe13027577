//! The partition of a delamination model into a nonlinear and a linear substructure (thesis
//! §2.6, §3.2 and Fig. 3.2.2, §4.5).
//!
//! NONLIN3D solved only the postbuckled sublaminate iteratively: the nonlinear substructure is
//! the sublaminate inside a contour at a distance ℓ inside the delamination front (ℓ ≈ h "in
//! all cases", §3.2); everything else — the base, the far field and the sublaminate's strip
//! next to the front, so the front itself — is linear and condensed onto the interface nodes.
//!
//! The cells are chosen by geometry, not by the generators' ring indices: a sublaminate cell is
//! nonlinear when every one of its nodes lies at least ℓ inside the front
//! ([`FrontShape::inside_distance`]: the distance to the foot point on the ellipse, to the
//! rectangle's nearest side, or to the line x = a), measured in the plane of the delamination.
//! The region inside the front offset by ℓ is convex (the inner parallel set of a convex
//! planform), and a cell with straight edges lies in the convex hull of its corners, so such a
//! cell lies entirely inside. The contour follows element edges, so the ℓ realised on the mesh
//! is at least the ℓ asked for; [`NonlinearRegion::realised_offset_m`] reports it.

mod shape;

pub use shape::{FrontShape, ellipse_distance};

use crate::MeshError;
use crate::model::Mesh;
use crate::names;

/// Which cells the nonlinear substructure holds (thesis §2.6, §3.2).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Partition {
    /// The thesis's (Fig. 3.2.2): the sublaminate cells lying entirely inside the front offset
    /// inward by ℓ = `offset_m` (m, ≥ 0; the thesis used ℓ ≈ h). The front and the strip of
    /// width ≥ ℓ behind it stay linear for ℓ > 0; ℓ = 0 takes every sublaminate cell inside
    /// the front, so the front is then on the interface.
    Thesis {
        /// ℓ, m.
        offset_m: f64,
    },
    /// The conservative choice: the whole sublaminate (set `sublaminate`) nonlinear, the base
    /// laminate linear.
    Sublaminate,
    /// [`Partition::Sublaminate`] and the base cells with a node on the lower crack face (set
    /// `crack_lower`: the base's top under the delamination): both faces of every crack pair
    /// in the nonlinear region, where crack-face contact (thesis §2.7) acts on them.
    SublaminateAndCrackBase,
}

/// The nonlinear substructure of a [`Partition`] on a mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct NonlinearRegion {
    /// The nonlinear cells, sorted.
    pub cells: Vec<usize>,
    /// The interface: nodes used both by a nonlinear and by a linear cell, sorted.
    pub interface: Vec<usize>,
    /// The smallest and largest inside distance (m) of the interface nodes from the front: for
    /// [`Partition::Thesis`] the ℓ realised on the mesh (≥ the ℓ asked for); for
    /// [`Partition::Sublaminate`] ≤ 0 (the interface is the bonded plane and the front). `None`
    /// when the interface is empty.
    pub realised_offset_m: Option<(f64, f64)>,
}

impl NonlinearRegion {
    /// The linear cells: every cell of `mesh` not in [`Self::cells`], sorted.
    pub fn linear_cells(&self, mesh: &Mesh) -> Vec<usize> {
        let mut nonlinear = vec![false; mesh.cells.len()];
        for &c in &self.cells {
            if let Some(flag) = nonlinear.get_mut(c) {
                *flag = true;
            }
        }
        (0..mesh.cells.len()).filter(|&c| !nonlinear[c]).collect()
    }
}

/// The nonlinear cells of `partition` on a generated delamination mesh whose front is `front`
/// (from [`EmbeddedParams::front_shape`](crate::EmbeddedParams::front_shape) or
/// [`ThroughWidthParams::front_shape`](crate::ThroughWidthParams::front_shape)), with the
/// interface nodes and the realised ℓ (thesis §2.6, §3.2, Fig. 3.2.2).
///
/// Errors: the mesh fails [`Mesh::validate`]; it has no `sublaminate` cell set, or (for
/// [`Partition::Thesis`]) no `front` node set; a front corner node lies off `front` (the shape
/// does not describe this mesh); ℓ negative, not finite, or so large that no sublaminate cell
/// lies ℓ inside the front (the error gives the largest ℓ that leaves cells).
///
/// ```
/// use nonlin3d_mesh::{EmbeddedParams, Partition, embedded_delamination, nonlinear_region};
/// let p = EmbeddedParams::thesis_reference();
/// let mesh = embedded_delamination(&p).unwrap();
/// let thesis = Partition::Thesis { offset_m: p.h };
/// let region = nonlinear_region(&mesh, &p.front_shape(), thesis).unwrap();
/// let (shortest, _) = region.realised_offset_m.unwrap();
/// assert!(shortest >= p.h);
/// assert_eq!(region.cells.len() + region.linear_cells(&mesh).len(), mesh.cells.len());
/// ```
pub fn nonlinear_region(
    mesh: &Mesh,
    front: &FrontShape,
    partition: Partition,
) -> Result<NonlinearRegion, MeshError> {
    mesh.validate()?;
    let sub = mesh
        .cell_sets
        .get(names::SUBLAMINATE)
        .ok_or(MeshError::MissingSet {
            kind: "cell",
            name: names::SUBLAMINATE,
            purpose: "the nonlinear substructure is chosen among the sublaminate's cells",
        })?;
    let distance: Vec<f64> = mesh
        .nodes
        .iter()
        .map(|p| front.inside_distance(p[0], p[1]))
        .collect();
    let cells = match partition {
        Partition::Sublaminate => sorted(sub.clone()),
        Partition::SublaminateAndCrackBase => {
            let lower = node_set(
                mesh,
                names::CRACK_LOWER,
                "the base cells under the delamination join the nonlinear region",
            )?;
            let mut on = vec![false; mesh.nodes.len()];
            for &n in lower {
                if let Some(x) = on.get_mut(n) {
                    *x = true;
                }
            }
            let mut cells = sub.clone();
            cells.extend(
                (0..mesh.cells.len()).filter(|&c| mesh.cells[c].nodes.iter().any(|&n| on[n])),
            );
            sorted(cells)
        }
        Partition::Thesis { offset_m } => {
            check_front(mesh, front, &distance)?;
            thesis_cells(mesh, sub, front, &distance, offset_m)?
        }
    };
    let interface = interface_nodes(mesh, &cells);
    let realised_offset_m = interface.iter().map(|&n| distance[n]).fold(None, |acc, d| {
        Some(acc.map_or((d, d), |(lo, hi): (f64, f64)| (lo.min(d), hi.max(d))))
    });
    Ok(NonlinearRegion {
        cells,
        interface,
        realised_offset_m,
    })
}

/// Round-off allowance on distances: 1e-9 of the planform's inradius (the meshes' coordinates
/// are exact to ~1e-16 relative, so this only absorbs round-off, never a ring of cells).
fn tolerance(front: &FrontShape) -> f64 {
    1e-9 * front.max_inside_distance()
}

/// The sublaminate cells whose nodes all lie at least ℓ inside the front (Fig. 3.2.2), or the
/// error for an ℓ that is negative, not finite, or leaves no cell.
fn thesis_cells(
    mesh: &Mesh,
    sub: &[usize],
    front: &FrontShape,
    distance: &[f64],
    offset_m: f64,
) -> Result<Vec<usize>, MeshError> {
    let offset_mm = 1e3 * offset_m;
    if !(offset_m.is_finite() && offset_m >= 0.0) {
        return Err(MeshError::Offset {
            offset_mm,
            reason: "it must be zero or positive (the thesis used ℓ ≈ h)".into(),
        });
    }
    // Each cell's depth: the smallest inside distance of its nodes.
    let depth = |c: usize| {
        mesh.cells[c]
            .nodes
            .iter()
            .map(|&n| distance[n])
            .fold(f64::INFINITY, f64::min)
    };
    let tol = tolerance(front);
    let cells: Vec<usize> = sub
        .iter()
        .copied()
        .filter(|&c| depth(c) >= offset_m - tol)
        .collect();
    if cells.is_empty() {
        let largest = sub
            .iter()
            .map(|&c| depth(c))
            .fold(f64::NEG_INFINITY, f64::max);
        return Err(MeshError::Offset {
            offset_mm,
            reason: format!(
                "no sublaminate cell lies that far inside the front; the largest ℓ that leaves \
                 cells on this mesh is {:.4} mm (the planform's inradius is {:.4} mm)",
                1e3 * largest.max(0.0),
                1e3 * front.max_inside_distance()
            ),
        });
    }
    Ok(sorted(cells))
}

/// Every corner node of the `front` set must lie on `front` (within [`tolerance`]): otherwise
/// the shape was made from other parameters than the mesh. Hex20 mid-edge nodes on a curved
/// front sit on chords, inside the curve by their sagitta, and are not checked.
fn check_front(mesh: &Mesh, front: &FrontShape, distance: &[f64]) -> Result<(), MeshError> {
    let nodes = node_set(
        mesh,
        names::FRONT,
        "the offset ℓ is checked against the front the mesh was generated with",
    )?;
    let mut corner = vec![false; mesh.nodes.len()];
    for cell in &mesh.cells {
        for &n in cell.nodes.iter().take(8) {
            corner[n] = true;
        }
    }
    let tol = 1e3 * tolerance(front);
    match nodes
        .iter()
        .find(|&&n| corner[n] && distance[n].abs() > tol)
    {
        Some(&node) => Err(MeshError::FrontMismatch {
            node,
            distance_mm: 1e3 * distance[node],
        }),
        None => Ok(()),
    }
}

/// The nodes used both by a cell of `nonlinear` (sorted) and by a cell outside it, sorted.
fn interface_nodes(mesh: &Mesh, nonlinear: &[usize]) -> Vec<usize> {
    let mut in_nonlinear = vec![false; mesh.cells.len()];
    for &c in nonlinear {
        in_nonlinear[c] = true;
    }
    // Bit 0: used by a nonlinear cell; bit 1: by a linear one.
    let mut used = vec![0u8; mesh.nodes.len()];
    for (c, cell) in mesh.cells.iter().enumerate() {
        let bit = if in_nonlinear[c] { 1 } else { 2 };
        for &n in &cell.nodes {
            used[n] |= bit;
        }
    }
    (0..mesh.nodes.len()).filter(|&n| used[n] == 3).collect()
}

/// `v` sorted, without repeats.
/// The mesh's node set `name`, or the error saying what it was needed for.
fn node_set<'a>(
    mesh: &'a Mesh,
    name: &'static str,
    purpose: &'static str,
) -> Result<&'a Vec<usize>, MeshError> {
    mesh.node_sets.get(name).ok_or(MeshError::MissingSet {
        kind: "node",
        name,
        purpose,
    })
}

fn sorted(mut v: Vec<usize>) -> Vec<usize> {
    v.sort_unstable();
    v.dedup();
    v
}

#[cfg(test)]
mod tests;
