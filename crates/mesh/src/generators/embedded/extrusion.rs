//! The through-thickness extrusion of thesis §3.1–3.2 (Fig. 3.2.1): the planform section swept
//! through the thickness stations (base graded towards z = H, sublaminate or ply layers above),
//! corner nodes on z = H inside the front duplicated, Hex20 mid-edge nodes at the midpoints of
//! their corners (the thesis's re-centring after the map of eq. 3.1.1–3.1.2).

use super::EmbeddedParams;
use super::planform::Section;
use crate::MeshError;
use crate::model::{Cell, Mesh};
use nonlin3d_element::ElementKind;
use std::collections::HashMap;

/// The extruded solid of §3.2 before its sets: mesh, and the indices the sets and the front
/// are found by.
pub(super) struct Solid {
    /// Nodes and cells (no sets yet).
    pub(super) mesh: Mesh,
    /// `corner[l][v]`: the corner node of section vertex v at thickness station l (on z = H
    /// the upper copy, which the sublaminate's cells use).
    pub(super) corner: Vec<Vec<usize>>,
    /// The lower copy on z = H of each vertex strictly inside the front (the base's cells use
    /// it), `None` elsewhere.
    pub(super) lower: Vec<Option<usize>>,
    /// The thickness station of the delamination plane z = H.
    pub(super) zh: usize,
    /// Hex20 mid-edge nodes keyed by their two corner nodes (smaller index first).
    pub(super) mid: HashMap<(usize, usize), usize>,
    /// Cells below z = H (the base laminate).
    pub(super) base_cells: Vec<usize>,
    /// Cells above z = H (the sublaminate).
    pub(super) sub_cells: Vec<usize>,
}

/// Sweeps the §3.1 planform section through the thickness stations of §3.2 (ply layers of
/// chapter 7 when given): corner nodes first, then the cells layer by layer.
pub(super) fn extrude(p: &EmbeddedParams, s: &Section) -> Result<Solid, MeshError> {
    let (z, layer_props, zh) = p.layers()?;
    let mut solid = corner_nodes(s, &z, zh);
    for (l, &props) in layer_props.iter().enumerate() {
        solid.layer(p.kind, s, l, props);
    }
    Ok(solid)
}

/// The corner nodes (vertex, station) of §3.2, station by station; a vertex strictly inside
/// the front gets a second (lower) node on z = H right after its upper one.
fn corner_nodes(s: &Section, z: &[f64], zh: usize) -> Solid {
    let nv = s.points.len();
    let mut mesh = Mesh::default();
    let mut corner = vec![vec![0usize; nv]; z.len()];
    let mut lower = vec![None; nv];
    for (l, &zl) in z.iter().enumerate() {
        for (v, pt) in s.points.iter().enumerate() {
            corner[l][v] = mesh.nodes.len();
            mesh.nodes.push([pt[0], pt[1], zl]);
            if l == zh && s.inside[v] {
                lower[v] = Some(mesh.nodes.len());
                mesh.nodes.push([pt[0], pt[1], zl]);
            }
        }
    }
    Solid {
        mesh,
        corner,
        lower,
        zh,
        mid: HashMap::new(),
        base_cells: Vec::new(),
        sub_cells: Vec::new(),
    }
}

impl Solid {
    /// The upper (sublaminate-side) node of vertex v on the delamination plane z = H (§3.2).
    pub(super) fn upper(&self, v: usize) -> usize {
        self.corner[self.zh][v]
    }

    /// The base-side node of vertex v on z = H (§3.2): its lower copy inside the front, the
    /// shared node elsewhere.
    pub(super) fn lower_or_shared(&self, v: usize) -> usize {
        self.lower[v].unwrap_or(self.corner[self.zh][v])
    }

    /// The Hex20 mid-edge node between corner nodes a and b, if there is one (at their
    /// midpoint, §3.1's re-centring after eq. 3.1.1–3.1.2).
    pub(super) fn midside(&self, a: usize, b: usize) -> Option<usize> {
        self.mid.get(&(a.min(b), a.max(b))).copied()
    }

    /// The node of vertex v at station l for a cell below (`below`) or above z = H: below the
    /// plane, the lower copy where there is one (the delamination of §3.2).
    fn node(&self, l: usize, v: usize, below: bool) -> usize {
        match self.lower[v] {
            Some(lower) if l == self.zh && below => lower,
            _ => self.corner[l][v],
        }
    }

    /// The cells of layer l (between stations l and l + 1), one per section quad, with their
    /// material and ply angle (chapter 7); base cells below z = H, sublaminate cells above.
    fn layer(&mut self, kind: ElementKind, s: &Section, l: usize, props: (usize, f64)) {
        let below_plane = l < self.zh; // cells under z = H use the lower copies on it
        for qd in &s.quads {
            let bottom = qd.iter().map(|&v| self.node(l, v, below_plane));
            let top = qd.iter().map(|&v| self.node(l + 1, v, below_plane));
            let mut nodes: Vec<usize> = bottom.chain(top).collect();
            if kind == ElementKind::Hex20 {
                for &(a, b) in nonlin3d_element::HEX20_EDGES.iter() {
                    let id = self.mid_edge_node(nodes[a], nodes[b]);
                    nodes.push(id);
                }
            }
            let c = self.mesh.cells.len();
            let (material, ply_angle_deg) = props;
            self.mesh.cells.push(Cell {
                kind,
                nodes,
                material,
                ply_angle_deg,
            });
            if below_plane {
                self.base_cells.push(c)
            } else {
                self.sub_cells.push(c)
            }
        }
    }

    /// The mid-edge node between corner nodes na and nb, at their midpoint, made on first use:
    /// keyed by the corner pair, so exactly the edges between duplicated corners (or a
    /// duplicated corner and the front) get duplicated mid-edge nodes.
    fn mid_edge_node(&mut self, na: usize, nb: usize) -> usize {
        let nodes = &mut self.mesh.nodes;
        *self.mid.entry((na.min(nb), na.max(nb))).or_insert_with(|| {
            let (pa, pb) = (nodes[na], nodes[nb]);
            nodes.push([
                0.5 * (pa[0] + pb[0]),
                0.5 * (pa[1] + pb[1]),
                0.5 * (pa[2] + pb[2]),
            ]);
            nodes.len() - 1
        })
    }
}
