//! The named sets of the embedded delamination model (thesis §3.1–3.2, Fig. 3.2.1): the
//! symmetry and loaded planes, the perturbation node, the paired crack faces, the front, and
//! the base and sublaminate cells — named by [`crate::names`].

use super::EmbeddedParams;
use super::extrusion::Solid;
use super::planform::Section;
use crate::model::Mesh;
use crate::names;
use nonlin3d_element::ElementKind;
use std::collections::HashMap;

/// The node sets of §3.2 on the extruded mesh of the §3.1 planform (eq. 3.1.1–3.1.2):
/// planes x0 y0 z0 x1 y1, `center_top`, `crack_upper`/`crack_lower` (paired), `front`.
pub(super) fn add_node_sets(p: &EmbeddedParams, s: &Section, solid: &mut Solid) {
    let tol = 1e-9 * p.w;
    solid.mesh.add_plane_sets(
        &[
            (names::X0, 0, 0.0),
            (names::Y0, 1, 0.0),
            (names::Z0, 2, 0.0),
            (names::X1, 0, p.w),
            (names::Y1, 1, p.w),
        ],
        tol,
    );
    // The O-grid has a node on the axis; the thesis's centre the arc node on y = 0.
    let top = solid.corner.len() - 1;
    let centre_top = solid.corner[top][s.centre].into_iter().collect();
    let (up, lo) = crack_faces(p.kind, solid);
    let front = front_nodes(p, s, solid);
    let sets = &mut solid.mesh.node_sets;
    sets.insert(names::CENTER_TOP.into(), centre_top);
    sets.insert(names::CRACK_UPPER.into(), up);
    sets.insert(names::CRACK_LOWER.into(), lo);
    sets.insert(names::FRONT.into(), front);
}

/// The crack faces on z = H inside the front (§3.2): corner pairs (upper, lower) in vertex
/// order, then for Hex20 the mid-edge pairs sorted by the upper node.
fn crack_faces(kind: ElementKind, solid: &Solid) -> (Vec<usize>, Vec<usize>) {
    let (mut up, mut lo) = (Vec::new(), Vec::new());
    for (v, lower) in solid.lower.iter().enumerate() {
        if let (Some(l), Some(u)) = (*lower, solid.upper(v)) {
            up.push(u);
            lo.push(l);
        }
    }
    if kind == ElementKind::Hex20 {
        for (u, l) in mid_edge_crack_pairs(solid) {
            up.push(u);
            lo.push(l);
        }
    }
    (up, lo)
}

/// The Hex20 mid-edge node pairs (upper, lower) of the crack faces (§3.2), sorted: a mid-edge
/// node on the lower face has both corners on z = H, at least one a lower copy and the other a
/// lower copy or a front node; its partner is keyed by the corresponding upper corners.
fn mid_edge_crack_pairs(solid: &Solid) -> Vec<(usize, usize)> {
    let upper_of: HashMap<usize, usize> = (0..solid.lower.len())
        .filter_map(|v| Some((solid.lower[v]?, solid.upper(v)?)))
        .collect();
    let mut pairs: Vec<(usize, usize)> = Vec::new();
    for (&(na, nb), &id) in &solid.mid {
        let (la, lb) = (upper_of.get(&na), upper_of.get(&nb));
        if la.is_some() || lb.is_some() {
            let ua = la.copied().unwrap_or(na);
            let ub = lb.copied().unwrap_or(nb);
            if let Some(uid) = solid.midside(ua, ub) {
                pairs.push((uid, id));
            }
        }
    }
    pairs.sort_unstable();
    pairs
}

/// The front nodes on z = H (the front ring, the ellipse of eq. 3.1.1–3.1.2): its corner
/// nodes from the x axis to the y axis, then for Hex20 the mid-edge nodes between them.
fn front_nodes(p: &EmbeddedParams, s: &Section, solid: &Solid) -> Vec<usize> {
    let ring = &s.rings[s.front_ring];
    let mut nodes: Vec<usize> = ring.iter().filter_map(|&v| solid.upper(v)).collect();
    if p.kind == ElementKind::Hex20 {
        for q in 0..ring.len() - 1 {
            if let (Some(na), Some(nb)) = (solid.upper(ring[q]), solid.upper(ring[q + 1]))
                && let Some(id) = solid.midside(na, nb)
            {
                nodes.push(id);
            }
        }
    }
    nodes
}

/// The cell sets of §3.2 (`base`, `sublaminate`, `all`); hands back the finished mesh.
pub(super) fn add_cell_sets(solid: Solid) -> Mesh {
    let Solid {
        mut mesh,
        base_cells,
        sub_cells,
        ..
    } = solid;
    mesh.cell_sets.insert(names::BASE.into(), base_cells);
    mesh.cell_sets.insert(names::SUBLAMINATE.into(), sub_cells);
    mesh.cell_sets
        .insert(names::ALL.into(), (0..mesh.cells.len()).collect());
    mesh
}
