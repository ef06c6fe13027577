//! Closed-form node and tangent-nonzero counts of the generated meshes, from the mesh counts
//! alone (nothing is meshed).
//!
//! Both generators (`embedded_delamination_with_front`, `through_width_delamination`) sweep a
//! 2-D quad section through L layers of cells. A 3-D node is a pair (2-D entity, z entity):
//! a 2-D vertex or mid-edge, and a z station or (Hex20 only, for vertices only) a mid-layer
//! point. Two nodes share a cell exactly when their 2-D entities share a quad and their z
//! entities share a layer, so the node graph is counted as a product of a 2-D and a 1-D count.
//! The crack splits z station H of the "inside" entities (vertices strictly inside the front,
//! mid-edges with at least one such end) into a lower copy, in the layer below only, and an
//! upper copy, in the layer above only.
//!
//! 2-D ordered pairs sharing a quad (the quads of a conforming mesh meet in one edge or one
//! vertex): Σ_quads (pairs in the quad) − Σ_interior edges (pairs on the edge, counted twice)
//! + the entities themselves. With P the node pairs that share a cell, the lower triangle of
//!   the 3N × 3N tangent holds 6N + 9P entries (a 3 × 3 block per pair, the lower half of the
//!   diagonal blocks).

/// Entity classes of the 2-D section: vertex or mid-edge, whole or split by the crack.
const V: usize = 0;
const VI: usize = 1;
const E: usize = 2;
const EI: usize = 3;

/// A 2-D section: entity counts per class, quads and interior edges with the classes of
/// their entities (a quad: 4 vertices and, for Hex20, 4 mid-edges; an edge: 2 vertices and 1
/// mid-edge).
struct Section {
    entities: [u128; 4],
    quads: Vec<(u128, [u128; 4])>,
    interior_edges: Vec<(u128, [u128; 4])>,
}

/// The node and tangent counts of a swept mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Counts {
    /// Nodes.
    pub nodes: u128,
    /// Cells.
    pub cells: u128,
    /// Stored entries of the tangent's lower triangle (diagonal included).
    pub tangent_nonzeros: u128,
    /// Entities of the swept 2-D section (vertices, and mid-edges for Hex20); 0 for a mesh
    /// that is not a sweep.
    pub section_entities: u128,
}

/// The z entities of one 2-D entity's column: for each, the first and last layer it lies in.
fn column(layers: usize, split: Option<usize>, mids: bool) -> Vec<(usize, usize)> {
    let mut z = Vec::with_capacity(2 * layers + 2);
    for j in 0..=layers {
        match split {
            Some(h) if j == h => {
                z.push((h - 1, h - 1));
                z.push((h, h));
            }
            _ => z.push((j.saturating_sub(1), j.min(layers - 1))),
        }
    }
    if mids {
        z.extend((0..layers).map(|l| (l, l)));
    }
    z
}

/// Ordered pairs (x, y) of z entities of two columns that share a layer.
fn column_pairs(a: &[(usize, usize)], b: &[(usize, usize)]) -> u128 {
    // Entities of b by first layer; each lies in at most two consecutive layers.
    let last = b.iter().map(|e| e.1).max().unwrap_or(0);
    let mut starting = vec![0u128; last + 2];
    let mut spanning = vec![0u128; last + 2]; // in layers l and l + 1
    for &(lo, hi) in b {
        starting[lo] += 1;
        if hi > lo {
            spanning[lo] += 1;
        }
    }
    // In layer l: those starting at l, plus those starting at l − 1 that span into l.
    let in_layer = |l: usize| starting[l] + if l > 0 { spanning[l - 1] } else { 0 };
    a.iter()
        .map(|&(lo, hi)| {
            if hi == lo {
                in_layer(lo)
            } else {
                // In lo or lo + 1: count each once (the spanning ones of lo are in both).
                in_layer(lo) + in_layer(hi) - spanning[lo]
            }
        })
        .sum()
}

impl Section {
    /// Nodes and tangent nonzeros of this section swept through `layers` layers (Hex20 with
    /// mid-edge and mid-layer nodes, or Hex8), the crack at station `split`.
    fn sweep(&self, layers: usize, split: usize, hex20: bool) -> Counts {
        let columns = [
            column(layers, None, hex20),
            column(layers, Some(split), hex20),
            column(layers, None, false),
            column(layers, Some(split), false),
        ];
        let nodes: u128 = (0..4)
            .map(|c| self.entities[c] * columns[c].len() as u128)
            .sum();
        let mut ordered = 0u128;
        for a in 0..4 {
            for b in 0..4 {
                let same = u128::from(a == b);
                let quads: u128 = self
                    .quads
                    .iter()
                    .map(|(n, q)| n * (q[a] * q[b] - same * q[a]))
                    .sum();
                let edges: u128 = self
                    .interior_edges
                    .iter()
                    .map(|(n, e)| n * (e[a] * e[b] - same * e[a]))
                    .sum();
                let pairs_2d = quads - edges + same * self.entities[a];
                if pairs_2d > 0 {
                    ordered += pairs_2d * column_pairs(&columns[a], &columns[b]);
                }
            }
        }
        let cells: u128 = self.quads.iter().map(|(n, _)| n).sum::<u128>() * layers as u128;
        Counts {
            nodes,
            cells,
            tangent_nonzeros: 6 * nodes + 9 * (ordered - nodes) / 2,
            section_entities: self.entities.iter().sum(),
        }
    }
}

/// Class counts of a quad or edge: vertices (whole, split), mid-edges (whole, split); Hex8
/// drops the mid-edges.
fn classes(v: u128, vi: u128, e: u128, ei: u128, hex20: bool) -> [u128; 4] {
    let mut c = [0; 4];
    c[V] = v;
    c[VI] = vi;
    if hex20 {
        c[E] = e;
        c[EI] = ei;
    }
    c
}

/// The quad classes of both sections: inside the front, astride it (two split vertices, two
/// whole ones on the front; the mid-edge along the front whole, the other three split), and
/// outside; the interior edges likewise.
#[allow(clippy::too_many_arguments)]
fn section(
    vertices: [u128; 2],
    edges: [u128; 2],
    quads: [u128; 3],
    interior_edges: [u128; 3],
    hex20: bool,
) -> Section {
    let h = u128::from(hex20);
    Section {
        entities: [vertices[0], vertices[1], h * edges[0], h * edges[1]],
        quads: vec![
            (quads[0], classes(0, 4, 0, 4, hex20)),
            (quads[1], classes(2, 2, 1, 3, hex20)),
            (quads[2], classes(4, 0, 4, 0, hex20)),
        ],
        interior_edges: vec![
            (interior_edges[0], classes(0, 2, 0, 1, hex20)),
            (interior_edges[1], classes(1, 1, 0, 1, hex20)),
            (interior_edges[2], classes(2, 0, 1, 0, hex20)),
        ],
    }
}

/// The embedded (and edge, and plate) mesh: `slices` arcs (even), an O-grid core of
/// (slices/2)² quads, `inside` rings up to the front and `outside` beyond, `layers` layers with
/// the crack at station `split`.
pub fn embedded(
    slices: usize,
    inside: usize,
    outside: usize,
    layers: usize,
    split: usize,
    hex20: bool,
) -> Counts {
    let (s, k) = (slices as u128, (slices / 2) as u128);
    let (ri, ro) = (inside as u128, outside as u128);
    let rings = ri + ro + 1; // circles beyond the core boundary
    let v_in = (k + 1) * (k + 1) + ri * (s + 1);
    let v_all = (k + 1) * (k + 1) + rings * (s + 1);
    let core_edges = 2 * k * (k + 1);
    let e_in = core_edges + (ri + 1) * (s + 1) + ri * s;
    let e_all = core_edges + rings * (2 * s + 1);
    section(
        [v_all - v_in, v_in],
        [e_all - e_in, e_in],
        [k * k + ri * s, s, ro * s],
        // Boundary edges: 2k of the core on the axes, 2 radial ones per ring band, the outer ring.
        [
            2 * k * k + ri * (s - 1) + ri * s,
            s - 1,
            ro * (s - 1) + ro * s,
        ],
        hex20,
    )
    .sweep(layers, split, hex20)
}

/// The through-width mesh: `inside` + `outside` cells along x, `across` along y, `layers`
/// layers with the crack at station `split` for x < a.
pub fn through_width(
    inside: usize,
    outside: usize,
    across: usize,
    layers: usize,
    split: usize,
    hex20: bool,
) -> Counts {
    let (ri, ro, ny) = (inside as u128, outside as u128, across as u128);
    let v_in = ri * (ny + 1);
    let v_all = (ri + ro + 1) * (ny + 1);
    let e_in = ri * (ny + 1) + ri * ny;
    let e_all = (ri + ro) * (ny + 1) + (ri + ro + 1) * ny;
    section(
        [v_all - v_in, v_in],
        [e_all - e_in, e_in],
        [(ri - 1) * ny, ny, ro * ny],
        [
            (ri - 1) * (ny - 1) + (ri - 1) * ny,
            ny - 1,
            ro * (ny - 1) + ro * ny,
        ],
        hex20,
    )
    .sweep(layers, split, hex20)
}

/// The counts of any mesh, from its connectivity: node pairs sharing a cell counted with a
/// marker sweep over each node's cells (memory: one index per cell node, one marker per node).
pub fn of_mesh(mesh: &nonlin3d_mesh::Mesh) -> Counts {
    let n = mesh.nodes.len();
    let mut start = vec![0usize; n + 1];
    for c in &mesh.cells {
        for &v in &c.nodes {
            if v < n {
                start[v + 1] += 1;
            }
        }
    }
    for i in 0..n {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut cells_of = vec![0usize; start[n]];
    for (k, c) in mesh.cells.iter().enumerate() {
        for &v in &c.nodes {
            if v < n {
                cells_of[fill[v]] = k;
                fill[v] += 1;
            }
        }
    }
    let mut marker = vec![usize::MAX; n];
    let mut pairs = 0u128;
    for v in 0..n {
        for &k in &cells_of[start[v]..start[v + 1]] {
            for &w in &mesh.cells[k].nodes {
                if w > v && w < n && marker[w] != v {
                    marker[w] = v;
                    pairs += 1;
                }
            }
        }
    }
    let nodes = n as u128;
    Counts {
        nodes,
        cells: mesh.cells.len() as u128,
        tangent_nonzeros: 6 * nodes + 9 * pairs,
        section_entities: 0,
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;
    use nonlin3d_element::ElementKind;
    use nonlin3d_mesh::{
        EmbeddedParams, Mesh, PlyLayout, ThroughWidthParams, embedded_delamination,
        through_width_delamination,
    };
    use nonlin3d_solver::SymmetricPattern;

    /// Nodes, cells and the tangent's stored entries of a built mesh (the pattern the
    /// assembler builds), and the same from [`of_mesh`], which must agree.
    fn real(mesh: &Mesh) -> (u128, u128, u128) {
        let n = 3 * mesh.nodes.len();
        let p = SymmetricPattern::from_dof_lists(n, &mesh.cell_dofs()).unwrap();
        let real = (
            mesh.nodes.len() as u128,
            mesh.cells.len() as u128,
            p.nnz_lower() as u128,
        );
        let c = of_mesh(mesh);
        assert_eq!((c.nodes, c.cells, c.tangent_nonzeros), real);
        real
    }

    fn sizes(c: Counts) -> (u128, u128, u128) {
        (c.nodes, c.cells, c.tangent_nonzeros)
    }

    /// Exact, not a bound: every count of the generated mesh, Hex20 and Hex8, with the core's
    /// smallest case (2 slices), several ring and layer counts and ply layers.
    #[test]
    fn embedded_counts_are_exact() {
        let cases = [
            (8, 4, 5, 1, 3, None),
            (2, 1, 1, 1, 1, None),
            (12, 3, 7, 2, 4, None),
            (6, 5, 2, 3, 2, Some((3, 2))),
        ];
        for (slices, inside, outside, sub, base, plies) in cases {
            for kind in [ElementKind::Hex20, ElementKind::Hex8] {
                let mut p = EmbeddedParams::thesis_reference();
                p.kind = kind;
                p.slices = slices;
                p.radial_inside = inside;
                p.radial_outside = outside;
                p.sub_layers = sub;
                p.base_layers = base;
                let (layers, split) = match plies {
                    None => (base + sub, base),
                    Some((ns, nb)) => {
                        let t = p.h / ns as f64;
                        p.plies = Some(PlyLayout {
                            ply_thickness: t,
                            sublaminate: vec![0.0; ns],
                            base_below: vec![90.0; nb],
                        });
                        (base + nb + ns, base + nb)
                    }
                };
                let mesh = embedded_delamination(&p).unwrap();
                let hex20 = kind == ElementKind::Hex20;
                assert_eq!(
                    sizes(embedded(slices, inside, outside, layers, split, hex20)),
                    real(&mesh),
                    "{kind:?} slices {slices} inside {inside} outside {outside} layers {layers}"
                );
            }
        }
    }

    #[test]
    fn through_width_counts_are_exact() {
        for (inside, outside, across, sub, base) in
            [(10, 6, 1, 2, 3), (1, 1, 1, 1, 1), (4, 3, 5, 3, 2)]
        {
            for kind in [ElementKind::Hex20, ElementKind::Hex8] {
                let mut p = ThroughWidthParams::example();
                p.kind = kind;
                p.inside = inside;
                p.outside = outside;
                p.across = across;
                p.sub_layers = sub;
                p.base_layers = base;
                let (mesh, _) = through_width_delamination(&p).unwrap();
                let hex20 = kind == ElementKind::Hex20;
                assert_eq!(
                    sizes(through_width(
                        inside,
                        outside,
                        across,
                        base + sub,
                        base,
                        hex20
                    )),
                    real(&mesh),
                    "{kind:?} inside {inside} outside {outside} across {across}"
                );
            }
        }
    }

    #[test]
    fn the_reference_mesh_has_its_documented_size() {
        // EmbeddedParams::thesis_reference: 2 263 nodes, 384 cells.
        let c = embedded(8, 4, 5, 4, 3, true);
        assert_eq!((c.nodes, c.cells), (2263, 384));
    }
}
