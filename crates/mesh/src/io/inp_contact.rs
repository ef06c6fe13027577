//! Crack-face contact in a deck (writer side): the element faces of the two crack faces as
//! `*SURFACE, TYPE=ELEMENT` sets, and the `*SURFACE`, `*SURFACE INTERACTION`,
//! `*SURFACE BEHAVIOR` and `*CONTACT PAIR` cards that make CalculiX hold them apart (thesis
//! §2.7: frictionless contact of the node pairs of the two faces).
//!
//! The pair is node-to-surface: the slave is the upper face's element faces, the master the
//! lower face's (their nodes coincide, so every slave node sits on a master node: the
//! node-to-node pairs `nonlin3d solve` reads back; the front's nodes, on both, are bonded).
//! A slave given as a node surface (`TYPE=NODE` over `crack_upper`) was tried and dropped:
//! CalculiX then let two pairs on the symmetry plane y = 0 of the 30 mm circle sink by 2.5 µm
//! and closed three more pairs than the exact solution (docs/VALIDATION.md); with the face
//! surface its closed set is nonlin3d's.
//! `PRESSURE-OVERCLOSURE=HARD`: CalculiX 2.20 reduces it to its linear penalty
//! (`surfacebehaviors.f`), whose stiffness K (Pa/m), tension at large clearance σ∞ (Pa) and
//! c₀ it reads from the data line when one follows; without one it takes K = 50 × the first
//! elastic constant of the first material, per unit of length, which depends on the units
//! (in metres, 100× softer than in millimetres). The writer gives K explicitly.

use crate::names::{CRACK_LOWER, CRACK_UPPER};
use crate::{Mesh, MeshError};
use std::collections::HashSet;
use std::fmt::Write as _;

/// Name of the element-face surface of the upper crack face (the sublaminate's underside).
pub const UPPER_FACES: &str = "crack_upper_faces";
/// Name of the element-face surface of the lower crack face (the base's top): the master.
pub const LOWER_FACES: &str = "crack_lower_faces";
/// Name of the surface interaction.
pub const INTERACTION: &str = "crack_faces";

/// CalculiX's penalty of the hard contact, the data line of `*SURFACE BEHAVIOR,
/// PRESSURE-OVERCLOSURE=HARD` (CalculiX 2.20 reads it as its linear law).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Penalty {
    /// Stiffness K, Pa/m: pressure per overclosure.
    pub stiffness: f64,
    /// Tension at large clearances σ∞, Pa (node-to-surface only; small and positive).
    pub tension: f64,
}

/// The faces (cell, Abaqus face 0..6) of the cells that hold a node of `set` and none of
/// `other`, whose nodes all lie on `set` or on the rim (nodes shared by the cells touching
/// `set` and those touching `other`, on neither: the front), at least one on `set`.
pub fn face_surface(mesh: &Mesh, set: &[usize], other: &[usize]) -> Vec<(usize, u8)> {
    let on: HashSet<usize> = set.iter().copied().collect();
    let off: HashSet<usize> = other.iter().copied().collect();
    let touching = |s: &HashSet<usize>| -> HashSet<usize> {
        mesh.cells
            .iter()
            .filter(|c| c.nodes.iter().any(|v| s.contains(v)))
            .flat_map(|c| c.nodes.iter().copied())
            .collect()
    };
    let near_other = touching(&off);
    let rim: HashSet<usize> = touching(&on)
        .into_iter()
        .filter(|v| near_other.contains(v) && !on.contains(v) && !off.contains(v))
        .collect();
    // (axis, side) → Abaqus face (zero-based): ξ−: S6, ξ+: S4, η−: S3, η+: S5, ζ−: S1, ζ+: S2.
    let face_of = [[5u8, 3], [2, 4], [0, 1]];
    let mut out = Vec::new();
    for (c, cell) in mesh.cells.iter().enumerate() {
        if !cell.nodes.iter().any(|v| on.contains(v)) || cell.nodes.iter().any(|v| off.contains(v))
        {
            continue;
        }
        let reference = cell.kind.reference_nodes();
        for axis in 0..3 {
            for (k, side) in [-1.0, 1.0].into_iter().enumerate() {
                let nodes: Vec<usize> = (0..reference.len().min(cell.nodes.len()))
                    .filter(|&i| reference[i][axis] == side)
                    .map(|i| cell.nodes[i])
                    .collect();
                if nodes.iter().all(|v| on.contains(v) || rim.contains(v))
                    && nodes.iter().any(|v| on.contains(v))
                {
                    out.push((c, face_of[axis][k]));
                }
            }
        }
    }
    out
}

/// Adds the face sets [`UPPER_FACES`] and [`LOWER_FACES`] of the mesh's paired crack faces
/// (`crack_upper`, `crack_lower`) to `mesh`; false (and nothing added) when it has no crack
/// faces. An upper or lower node on no face is an error naming it (1-based, as in the deck).
pub fn add_crack_surfaces(mesh: &mut Mesh) -> Result<bool, MeshError> {
    let (Some(up), Some(lo)) = (
        mesh.node_sets.get(CRACK_UPPER),
        mesh.node_sets.get(CRACK_LOWER),
    ) else {
        return Ok(false);
    };
    if up.is_empty() {
        return Ok(false);
    }
    let upper = face_surface(mesh, up, lo);
    let lower = face_surface(mesh, lo, up);
    for (faces, set, name) in [(&upper, up, CRACK_UPPER), (&lower, lo, CRACK_LOWER)] {
        let covered: HashSet<usize> = faces
            .iter()
            .flat_map(|&(c, f)| face_nodes(mesh, c, f))
            .collect();
        if let Some(v) = set.iter().find(|v| !covered.contains(v)) {
            return Err(MeshError::Parameter {
                name: "crack-face contact",
                reason: format!("node {} of {name} lies on no element face of it", v + 1),
            });
        }
    }
    mesh.face_sets.insert(UPPER_FACES.into(), upper);
    mesh.face_sets.insert(LOWER_FACES.into(), lower);
    Ok(true)
}

/// The nodes of face `f` (0-based Abaqus number) of cell `c`.
pub fn face_nodes(mesh: &Mesh, c: usize, f: u8) -> Vec<usize> {
    let (axis, side) = match f {
        0 => (2, -1.0),
        1 => (2, 1.0),
        2 => (1, -1.0),
        3 => (0, 1.0),
        4 => (1, 1.0),
        _ => (0, -1.0),
    };
    let cell = &mesh.cells[c];
    let reference = cell.kind.reference_nodes();
    (0..reference.len().min(cell.nodes.len()))
        .filter(|&i| reference[i][axis] == side)
        .map(|i| cell.nodes[i])
        .collect()
}

/// The contact cards (model data, before the first `*STEP`): the interaction with its hard
/// behaviour (and CalculiX's penalty as its data line), and the node-to-surface pair
/// [`UPPER_FACES`] (slave) → [`LOWER_FACES`] (master). The mesh must hold both face sets
/// ([`add_crack_surfaces`]).
pub fn contact_cards(mesh: &Mesh, penalty: Penalty) -> Result<String, MeshError> {
    if !mesh.face_sets.contains_key(UPPER_FACES) || !mesh.face_sets.contains_key(LOWER_FACES) {
        return Err(MeshError::Parameter {
            name: "crack-face contact",
            reason: format!("the mesh needs the face sets {UPPER_FACES} and {LOWER_FACES}"),
        });
    }
    let positive = |v: f64| v > 0.0 && v.is_finite();
    if !(positive(penalty.stiffness) && positive(penalty.tension)) {
        return Err(MeshError::Parameter {
            name: "crack-face contact",
            reason: format!(
                "penalty K = {} Pa/m and σ∞ = {} Pa must be finite and > 0",
                penalty.stiffness, penalty.tension
            ),
        });
    }
    let mut s = String::new();
    let _ = writeln!(
        s,
        "** Crack-face contact (frictionless): the upper face against the lower face.\n\
         ** HARD: CalculiX 2.20 reads it as its linear penalty K (Pa/m), sigma_inf (Pa) from the\n\
         ** data line; nonlin3d solve holds the node pairs exactly and lists the line as not used.\n\
         *SURFACE INTERACTION, NAME={INTERACTION}\n\
         *SURFACE BEHAVIOR, PRESSURE-OVERCLOSURE=HARD\n{:.6e}, {:.6e}\n\
         *CONTACT PAIR, INTERACTION={INTERACTION}, TYPE=NODE TO SURFACE\n\
         {UPPER_FACES}, {LOWER_FACES}",
        penalty.stiffness, penalty.tension
    );
    Ok(s)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use crate::Cell;
    use nonlin3d_element::ElementKind;

    /// Two unit Hex8 cubes stacked, with separate nodes on z = 1 except one shared corner
    /// (a "front" node): the lower cube's top (S2) and the upper cube's bottom (S1) are the
    /// crack faces.
    fn stacked() -> Mesh {
        let mut nodes = Vec::new();
        for z in [0.0, 1.0, 1.0, 2.0] {
            for (x, y) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
                nodes.push([x, y, z]);
            }
        }
        // Node 8 (upper copy of node 4) is replaced by node 4: shared, on the front.
        let upper: Vec<usize> = vec![4, 9, 10, 11, 12, 13, 14, 15];
        let cell = |nodes: Vec<usize>| Cell {
            kind: ElementKind::Hex8,
            nodes,
            material: 0,
            ply_angle_deg: 0.0,
        };
        let mut m = Mesh {
            nodes,
            cells: vec![cell((0..8).collect()), cell(upper)],
            ..Mesh::default()
        };
        m.node_sets.insert(CRACK_UPPER.into(), vec![9, 10, 11]);
        m.node_sets.insert(CRACK_LOWER.into(), vec![5, 6, 7]);
        m
    }

    /// The faces are the lower cube's S2 and the upper cube's S1; the cards name them.
    #[test]
    fn crack_faces_are_the_facing_element_faces() {
        let mut m = stacked();
        assert!(add_crack_surfaces(&mut m).unwrap());
        assert_eq!(m.face_sets[LOWER_FACES], vec![(0, 1)]);
        assert_eq!(m.face_sets[UPPER_FACES], vec![(1, 0)]);
        let text = contact_cards(
            &m,
            Penalty {
                stiffness: 1e15,
                tension: 1.0,
            },
        )
        .unwrap();
        assert!(text.contains("*CONTACT PAIR, INTERACTION=crack_faces, TYPE=NODE TO SURFACE\ncrack_upper_faces, crack_lower_faces"));
        assert!(text.contains("PRESSURE-OVERCLOSURE=HARD\n1.000000e15, 1.000000e0"));
        // No crack sets: nothing to add.
        let mut plain = stacked();
        plain.node_sets.clear();
        assert!(!add_crack_surfaces(&mut plain).unwrap());
    }
}
