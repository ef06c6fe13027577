//! The through-thickness extrusion of thesis §3.1–3.2 (Fig. 3.2.1): the planform section swept
//! through the thickness stations (base graded towards z = H, sublaminate or ply layers above),
//! corner nodes on z = H inside the front duplicated, Hex20 mid-edge nodes at the midpoints of
//! their corners (the thesis's re-centring after the map of eq. 3.1.1–3.1.2) or, in the
//! planform, where the section puts them ([`MidEdges::Mapped`](super::MidEdges::Mapped)).

use super::EmbeddedParams;
use super::layers::{LayerTransition, mid_parity, template};
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
    /// the upper copy, which the sublaminate's cells use); `None` where the vertex's column
    /// skips the station (the layer band, issue 25).
    pub(super) corner: Vec<Vec<Option<usize>>>,
    /// The lower copy on z = H of each vertex strictly inside the front (the base's cells use
    /// it), `None` elsewhere.
    pub(super) lower: Vec<Option<usize>>,
    /// The thickness station of the delamination plane z = H.
    pub(super) zh: usize,
    /// The parity of the coarse stations carrying the layer band's M vertices (module
    /// `layers`).
    parity: usize,
    /// Hex20 mid-edge nodes keyed by their two corner nodes (smaller index first).
    pub(super) mid: HashMap<(usize, usize), usize>,
    /// The section vertex of each corner node (mid-edge nodes are not listed).
    vertex: Vec<usize>,
    /// Cells below z = H (the base laminate).
    pub(super) base_cells: Vec<usize>,
    /// Cells above z = H (the sublaminate).
    pub(super) sub_cells: Vec<usize>,
}

/// Sweeps the §3.1 planform section through the thickness stations of §3.2 (ply layers of
/// chapter 7 when given): corner nodes first, then the cells layer by layer.
pub(super) fn extrude(p: &EmbeddedParams, s: &Section) -> Result<Solid, MeshError> {
    let (z, layer_props, zh) = p.layers()?;
    // The transition rings' widths (coarse to fine vertex), for the template's parity.
    let widths: Vec<f64> = s
        .layer_transitions
        .iter()
        .flat_map(|t| {
            (0..2).map(move |q| {
                let (c, f) = (s.points[t.coarse[q]], s.points[t.fine[q]]);
                (f[0] - c[0]).hypot(f[1] - c[1])
            })
        })
        .collect();
    let parity = if widths.is_empty() {
        0
    } else {
        mid_parity(&z, &widths)
    };
    let mut solid = corner_nodes(s, &z, zh, parity);
    for (l, &props) in layer_props.iter().enumerate() {
        solid.layer(p.kind, s, l, props)?;
    }
    Ok(solid)
}

/// The corner nodes (vertex, station) of §3.2, station by station, where the vertex's column
/// has the station; a vertex strictly inside the front gets a second (lower) node on z = H
/// right after its upper one.
fn corner_nodes(s: &Section, z: &[f64], zh: usize, parity: usize) -> Solid {
    let nv = s.points.len();
    let mut mesh = Mesh::default();
    let mut corner = vec![vec![None; nv]; z.len()];
    let mut lower = vec![None; nv];
    let mut vertex = Vec::new();
    for (l, &zl) in z.iter().enumerate() {
        for (v, pt) in s.points.iter().enumerate() {
            if !s.column[v].has_station(l, parity) {
                continue;
            }
            corner[l][v] = Some(mesh.nodes.len());
            mesh.nodes.push([pt[0], pt[1], zl]);
            vertex.push(v);
            if l == zh && s.inside[v] {
                lower[v] = Some(mesh.nodes.len());
                mesh.nodes.push([pt[0], pt[1], zl]);
                vertex.push(v);
            }
        }
    }
    Solid {
        mesh,
        corner,
        lower,
        zh,
        parity,
        mid: HashMap::new(),
        vertex,
        base_cells: Vec::new(),
        sub_cells: Vec::new(),
    }
}

impl Solid {
    /// The upper (sublaminate-side) node of vertex v on the delamination plane z = H (§3.2),
    /// if its column has that station (z = H is a station of every column but the layer
    /// band's middle vertices with N even).
    pub(super) fn upper(&self, v: usize) -> Option<usize> {
        self.corner[self.zh][v]
    }

    /// The base-side node of vertex v on z = H (§3.2): its lower copy inside the front, the
    /// shared node elsewhere.
    pub(super) fn lower_or_shared(&self, v: usize) -> Option<usize> {
        self.lower[v].or(self.corner[self.zh][v])
    }

    /// The Hex20 mid-edge node between corner nodes a and b, if there is one (at their
    /// midpoint, §3.1's re-centring after eq. 3.1.1–3.1.2).
    pub(super) fn midside(&self, a: usize, b: usize) -> Option<usize> {
        self.mid.get(&(a.min(b), a.max(b))).copied()
    }

    /// The node of vertex v at station l for a cell below (`below`) or above z = H: below the
    /// plane, the lower copy where there is one (the delamination of §3.2).
    fn node(&self, l: usize, v: usize, below: bool) -> Result<usize, MeshError> {
        match self.lower[v] {
            Some(lower) if l == self.zh && below => Ok(lower),
            _ => self.corner[l][v].ok_or_else(|| MeshError::Parameter {
                name: "layer_band",
                reason: format!("section vertex {v} has no node on thickness station {l}"),
            }),
        }
    }

    /// The cells of layer l (between stations l and l + 1), one per section quad, with their
    /// material and ply angle (chapter 7); base cells below z = H, sublaminate cells above.
    /// Quads whose vertices skip every other station (the layer band, issue 25) get one cell
    /// over layers l and l + 1 when l is even, and so do the transition arcs (three cells).
    fn layer(
        &mut self,
        kind: ElementKind,
        s: &Section,
        l: usize,
        props: (usize, f64),
    ) -> Result<(), MeshError> {
        let below = l < self.zh; // cells under z = H use the lower copies on it
        for qd in &s.quads {
            let col = s.column[qd[0]];
            let full = col.has_station(l, self.parity) && col.has_station(l + 1, self.parity);
            if !full && l % 2 == 1 {
                continue;
            }
            let top_station = if full { l + 1 } else { l + 2 };
            let mut nodes = Vec::with_capacity(8);
            for (station, v) in qd
                .iter()
                .map(|&v| (l, v))
                .chain(qd.iter().map(|&v| (top_station, v)))
            {
                nodes.push(self.node(station, v, below)?);
            }
            self.cell(s, kind, nodes, props, below);
        }
        if l.is_multiple_of(2) {
            for t in &s.layer_transitions {
                self.transition_cells(s, kind, t, l / 2, props, below)?;
            }
        }
        Ok(())
    }

    /// The three cells of coarse layer j on one arc of a layer-band transition ring (module
    /// `layers`): the radial–thickness template on slice line q + 1 as the bottom face and on
    /// q as the top (or the reverse, whichever gives det J > 0: the coarse-to-fine direction
    /// points out of or into the centre).
    fn transition_cells(
        &mut self,
        s: &Section,
        kind: ElementKind,
        t: &LayerTransition,
        j: usize,
        props: (usize, f64),
        below: bool,
    ) -> Result<(), MeshError> {
        for quad in template(j, self.parity) {
            let mut nodes = Vec::with_capacity(8);
            for q in [1, 0] {
                for &(side, station) in &quad {
                    let v = [t.coarse, t.mid, t.fine][side][q];
                    nodes.push(self.node(station, v, below)?);
                }
            }
            if !self.right_handed(&nodes) {
                nodes.rotate_left(4);
            }
            self.cell(s, kind, nodes, props, below);
        }
        Ok(())
    }

    /// Whether the hexahedron of corner nodes `n` has a positive triple product at corner 0:
    /// (n₁ − n₀) × (n₃ − n₀) · (n₄ − n₀) > 0.
    fn right_handed(&self, n: &[usize]) -> bool {
        let x = |k: usize| self.mesh.nodes[n[k]];
        let d = |k: usize| {
            let (a, b) = (x(k), x(0));
            [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
        };
        let (u, v, w) = (d(1), d(3), d(4));
        let cross = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        cross[0] * w[0] + cross[1] * w[1] + cross[2] * w[2] > 0.0
    }

    /// Adds a cell on corner nodes `nodes` (and, for Hex20, its mid-edge nodes), in the base
    /// or the sublaminate set.
    fn cell(
        &mut self,
        s: &Section,
        kind: ElementKind,
        mut nodes: Vec<usize>,
        props: (usize, f64),
        below: bool,
    ) {
        if kind == ElementKind::Hex20 {
            for &(a, b) in nonlin3d_element::HEX20_EDGES.iter() {
                let id = self.mid_edge_node(s, nodes[a], nodes[b]);
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
        if below {
            self.base_cells.push(c)
        } else {
            self.sub_cells.push(c)
        }
    }

    /// The mid-edge node between corner nodes na and nb, made on first use: on an edge in a
    /// thickness station where the section puts it ([`Section::mid_point`]), on any other edge
    /// at the corners' midpoint. Keyed by the corner pair, so exactly the edges between
    /// duplicated corners (or a duplicated corner and the front) get duplicated mid-edge nodes.
    fn mid_edge_node(&mut self, s: &Section, na: usize, nb: usize) -> usize {
        let nodes = &mut self.mesh.nodes;
        let (va, vb) = (self.vertex[na], self.vertex[nb]);
        *self.mid.entry((na.min(nb), na.max(nb))).or_insert_with(|| {
            let (pa, pb) = (nodes[na], nodes[nb]);
            let z = 0.5 * (pa[2] + pb[2]);
            let [x, y] = if pa[2] == pb[2] {
                s.mid_point(va, vb)
            } else {
                [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])]
            };
            nodes.push([x, y, z]);
            nodes.len() - 1
        })
    }
}
