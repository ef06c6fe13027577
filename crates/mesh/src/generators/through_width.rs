//! The through-width delamination model of thesis Fig. 3.2.3: a slab 0 ≤ x ≤ L, 0 ≤ y ≤ W,
//! base 0 ≤ z ≤ H, sublaminate H ≤ z ≤ H + h, delaminated on z = H for 0 ≤ x < a (x = 0 a
//! symmetry plane), so the front is the straight line x = a across the width. With v = 0 on
//! y = 0 and y = W it responds in plane strain (§3.2).

use crate::MeshError;
use crate::front::{CellsTouching, Front, FrontPoint, FrontWidths, missing_node as missing};
use crate::generators::{graded_coordinates, graded_from_first, grid_index, grid_position};
use crate::model::{Cell, Mesh};
use crate::names;
use nonlin3d_element::ElementKind;
use std::collections::HashMap;

/// Doubled grid indices across the width (y = W·g/(2·across)) of the `center_top` nodes: the
/// sublaminate top at x = 0 (the symmetry plane, the thesis's perturbation point, §3.2) at
/// mid-width, g = across. Hex20 always has a node there (a corner for even `across`, a mid-edge
/// node for odd); Hex8 has one for even `across` only, otherwise the two nodes either side of
/// the centre line (g = across ± 1; for across = 1 the edge nodes y = 0 and y = W), over which
/// a perturbation force is split equally.
fn centre_top_nodes(p: &ThroughWidthParams) -> Vec<usize> {
    if p.kind == ElementKind::Hex20 || p.across.is_multiple_of(2) {
        vec![p.across]
    } else {
        vec![p.across - 1, p.across + 1]
    }
}

/// Parameters of [`through_width_delamination`] (SI units).
#[derive(Debug, Clone, PartialEq)]
pub struct ThroughWidthParams {
    /// Hex20 or Hex8.
    pub kind: ElementKind,
    /// Delamination half-length: delaminated for 0 ≤ x < a, m.
    pub a: f64,
    /// Model length along x (load direction), L > a, m.
    pub length: f64,
    /// Width along y, m.
    pub width: f64,
    /// Sublaminate thickness h, m.
    pub h: f64,
    /// Base laminate thickness H, m.
    pub base: f64,
    /// Elements along x over the delamination.
    pub inside: usize,
    /// Elements along x beyond the front.
    pub outside: usize,
    /// Inside the delamination: the element next to the front over the one farthest from it
    /// (< 1 refines towards the front). Outside, the first element is as long as the last one
    /// inside (the single-solution VCCT pairs them, §2.8) and the sizes grow geometrically.
    pub front_grading: f64,
    /// Elements across the width.
    pub across: usize,
    /// Elements through the sublaminate.
    pub sub_layers: usize,
    /// Elements through the base (graded towards z = H by `base_grading`).
    pub base_layers: usize,
    /// Base element at z = H over the one at z = 0.
    pub base_grading: f64,
}

impl ThroughWidthParams {
    /// A 20 mm delamination (a = 10 mm) in the thesis's h = 0.4 mm, H = 4 mm laminate, L = 30 mm,
    /// one Hex20 across a 1 mm width.
    pub fn example() -> Self {
        Self {
            kind: ElementKind::Hex20,
            a: 10e-3,
            length: 30e-3,
            width: 1e-3,
            h: 0.4e-3,
            base: 4e-3,
            inside: 10,
            outside: 6,
            front_grading: 0.3,
            across: 1,
            sub_layers: 2,
            base_layers: 3,
            base_grading: 0.25,
        }
    }
}

/// The default strip mesh's grading along x inside the delamination (the element at the
/// front over the one at x = 0).
pub const DEFAULT_STRIP_GRADING: f64 = 0.1;

impl ThroughWidthParams {
    /// The default strip mesh (issue 25; docs/MESH.md, "The default mesh"), for a strip scene
    /// without mesh knobs, with the geometry and element kind of `self`: graded
    /// [`DEFAULT_STRIP_GRADING`] towards the front, as many elements inside the delamination
    /// as make the one at the front no longer than 0.6 h (16 at least), 10 beyond it, 2
    /// sublaminate and 3 base layers, one element across. On the 30 mm strip (a = 15 mm,
    /// h = 0.4 mm: 16 inside, a front element of 0.23 mm = 0.58 h; 3 444 DOF) it gives G_T max
    /// −0.87 %, G_II −0.66 % and G_I +0.56 J/m² against the converged 244.57, 243.49 and
    /// 0.7 … 1.2 (docs/ACCURACY.md §2d); the generator's [`Self::example`] counts (10 + 6,
    /// graded 0.3) gave G_I = −4.9 J/m², a mode mix 2 % of G_T off.
    pub fn with_default_mesh(&self) -> Self {
        let inside = (16..512)
            .find(|&n| front_element(n, self.a, DEFAULT_STRIP_GRADING) <= 0.6 * self.h)
            .unwrap_or(512);
        Self {
            inside,
            outside: 10,
            front_grading: DEFAULT_STRIP_GRADING,
            across: 1,
            sub_layers: 2,
            base_layers: 3,
            ..self.clone()
        }
    }
}

/// The length of the element at the front when `n` elements graded `ratio` (front over far
/// end) span `length`: sizes h₀qᵏ, q^(n−1) = ratio, Σ = h₀(1 − qⁿ)/(1 − q) = length, so the
/// front element is h₀·ratio.
fn front_element(n: usize, length: f64, ratio: f64) -> f64 {
    if n <= 1 {
        return length;
    }
    let q = ratio.powf(1.0 / (n - 1) as f64);
    let h0 = if (q - 1.0).abs() < 1e-12 {
        length / n as f64
    } else {
        length * (1.0 - q) / (1.0 - q.powi(n as i32))
    };
    h0 * ratio
}

/// The through-width delamination mesh and its front (from y = W to y = 0: tangent −y,
/// θ = −90°, normal +x, so S = W − y). Node sets `x0 x1 y0 y1 z0`, `crack_upper`/`crack_lower`
/// (paired), `front`, `center_top` (the sublaminate top at x = 0, mid-width: one node, or for
/// Hex8 with an odd `across` the two either side of the centre line); cell sets `base`,
/// `sublaminate`, `all`.
pub fn through_width_delamination(p: &ThroughWidthParams) -> Result<(Mesh, Front), MeshError> {
    if !(p.a > 0.0 && p.length > p.a && p.length.is_finite()) {
        return Err(MeshError::Parameter {
            name: "a",
            reason: format!("need 0 < a < length ({} vs {})", p.a, p.length),
        });
    }
    let stations = Stations::new(p)?;
    let (mut mesh, grid, cells) = hexes(p, &stations);
    let (up, lo) = grid.crack_faces(p);
    mesh.add_plane_sets(
        &[
            (names::X0, 0, 0.0),
            (names::X1, 0, p.length),
            (names::Y0, 1, 0.0),
            (names::Y1, 1, p.width),
            (names::Z0, 2, 0.0),
        ],
        1e-9 * p.length,
    );
    let (points, front_nodes) = grid.front(p, &CellsTouching::new(&mesh, &cells.1))?;
    let top = 2 * (p.base_layers + p.sub_layers);
    let centre = centre_top_nodes(p)
        .iter()
        .map(|&gy| {
            grid.get([0, gy, top], false)
                .ok_or_else(|| missing("centre top"))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let sets = &mut mesh.node_sets;
    sets.insert(names::CENTER_TOP.into(), centre);
    sets.insert(names::CRACK_UPPER.into(), up);
    sets.insert(names::CRACK_LOWER.into(), lo);
    sets.insert(names::FRONT.into(), front_nodes);
    mesh.cell_sets.insert(names::BASE.into(), cells.0);
    mesh.cell_sets.insert(names::SUBLAMINATE.into(), cells.1);
    mesh.cell_sets
        .insert(names::ALL.into(), (0..mesh.cells.len()).collect());
    mesh.validate()?;
    mesh.check_geometry()?;
    let front = Front {
        points,
        widths: FrontWidths::Chords,
    }
    .finish_straight(&mesh.nodes, [0.0, -1.0]);
    Ok((mesh, front))
}

/// The vertex positions of Fig. 3.2.3 along x (graded towards the front x = a, the element
/// ahead as long as the one behind, §2.8), y (uniform) and z (base graded towards z = H,
/// sublaminate uniform).
struct Stations {
    xs: Vec<f64>,
    ys: Vec<f64>,
    zz: Vec<f64>,
}

impl Stations {
    /// The stations of `p`.
    fn new(p: &ThroughWidthParams) -> Result<Self, MeshError> {
        let xin = graded_coordinates(p.inside, p.a, p.front_grading)?;
        // The element ahead of the front as long as the one behind it (VCCT, §2.8).
        let behind = xin[xin.len() - 1] - xin[xin.len() - 2];
        let xout = graded_from_first(p.outside, p.length - p.a, behind)?;
        let mut xs = xin.clone();
        xs.extend(xout.iter().skip(1).map(|d| p.a + d));
        let ys = graded_coordinates(p.across, p.width, 1.0)?;
        let zb = graded_coordinates(p.base_layers, p.base, p.base_grading)?;
        let zs = graded_coordinates(p.sub_layers, p.h, 1.0)?;
        let mut zz = zb.clone();
        zz.extend(zs.iter().skip(1).map(|d| p.base + d));
        Ok(Self { xs, ys, zz })
    }
}

/// The nodes of Fig. 3.2.3 by doubled grid index (even: vertex, odd: Hex20 mid-edge) and copy:
/// on z = H behind the front the base's cells use a lower copy (the delamination, §3.2).
struct Grid {
    ids: HashMap<(usize, usize, usize, bool), usize>,
    /// Doubled grid index of the front x = a.
    gf: usize,
    /// Doubled grid index of the delamination plane z = H.
    gh: usize,
}

/// The hexahedra of Fig. 3.2.3 layer by layer (z, then y, then x), nodes made on first use;
/// returns the mesh, its node grid, and the (base, sublaminate) cells.
fn hexes(p: &ThroughWidthParams, st: &Stations) -> (Mesh, Grid, (Vec<usize>, Vec<usize>)) {
    let mut grid = Grid {
        ids: HashMap::new(),
        gf: 2 * p.inside,
        gh: 2 * p.base_layers,
    };
    let mut mesh = Mesh::default();
    let (mut base_cells, mut sub_cells) = (Vec::new(), Vec::new());
    for k in 0..st.zz.len() - 1 {
        let below = k < p.base_layers;
        for j in 0..st.ys.len() - 1 {
            for i in 0..st.xs.len() - 1 {
                let nodes: Vec<usize> = p
                    .kind
                    .reference_nodes()
                    .iter()
                    .map(|r| grid.node(&mut mesh, st, grid_index([i, j, k], r), below))
                    .collect();
                let c = mesh.cells.len();
                mesh.cells.push(Cell {
                    kind: p.kind,
                    nodes,
                    material: 0,
                    ply_angle_deg: 0.0,
                });
                if below {
                    base_cells.push(c)
                } else {
                    sub_cells.push(c)
                }
            }
        }
    }
    (mesh, grid, (base_cells, sub_cells))
}

impl Grid {
    /// The node at grid index g for a cell below z = H (`below`) or above, made on first use:
    /// the lower copy when g is on z = H behind the front and the cell is below.
    fn node(&mut self, mesh: &mut Mesh, st: &Stations, g: [usize; 3], below: bool) -> usize {
        let lower = below && g[2] == self.gh && g[0] < self.gf;
        *self
            .ids
            .entry((g[0], g[1], g[2], lower))
            .or_insert_with(|| {
                mesh.nodes.push([
                    grid_position(&st.xs, g[0]),
                    grid_position(&st.ys, g[1]),
                    grid_position(&st.zz, g[2]),
                ]);
                mesh.nodes.len() - 1
            })
    }

    /// The node at grid index g (`lower`: the base-side copy), if the mesh has one.
    fn get(&self, g: [usize; 3], lower: bool) -> Option<usize> {
        self.ids.get(&(g[0], g[1], g[2], lower)).copied()
    }

    /// The crack faces (§3.2): (upper, lower) node pairs on z = H behind the front, y outer,
    /// x inner (every grid index for Hex20, vertices only for Hex8).
    fn crack_faces(&self, p: &ThroughWidthParams) -> (Vec<usize>, Vec<usize>) {
        let step = if p.kind == ElementKind::Hex20 { 1 } else { 2 };
        let (mut up, mut lo) = (Vec::new(), Vec::new());
        for gy in (0..=2 * p.across).step_by(step) {
            for gx in (0..self.gf).step_by(step) {
                let g = [gx, gy, self.gh];
                if let (Some(u), Some(l)) = (self.get(g, false), self.get(g, true)) {
                    up.push(u);
                    lo.push(l);
                }
            }
        }
        (up, lo)
    }

    /// The front points of §2.8 along x = a from y = W down to y = 0 (a/a′ one element behind;
    /// for Hex20 corners b/b′ half an element behind and d half an element ahead), and the
    /// front nodes in the same order.
    fn front(
        &self,
        p: &ThroughWidthParams,
        cells: &CellsTouching,
    ) -> Result<(Vec<FrontPoint>, Vec<usize>), MeshError> {
        let (gf, gh) = (self.gf, self.gh);
        let step = if p.kind == ElementKind::Hex20 { 1 } else { 2 };
        let mut points = Vec::new();
        let mut front_nodes = Vec::new();
        for gy in (0..=2 * p.across).rev().step_by(step) {
            let corner = gy.is_multiple_of(2);
            let c = self.get([gf, gy, gh], false).ok_or_else(|| missing("c"))?;
            let a_up = self
                .get([gf - 2, gy, gh], false)
                .ok_or_else(|| missing("a"))?;
            let a_lo = self
                .get([gf - 2, gy, gh], true)
                .ok_or_else(|| missing("a′"))?;
            let (b, d) = if p.kind == ElementKind::Hex20 && corner {
                let pair = self
                    .get([gf - 1, gy, gh], false)
                    .zip(self.get([gf - 1, gy, gh], true));
                (pair, self.get([gf + 1, gy, gh], false))
            } else {
                (None, None)
            };
            front_nodes.push(c);
            let touching = cells.touching(c, d);
            points.push(FrontPoint::new(c, corner, (a_up, a_lo), b, d, touching));
        }
        Ok((points, front_nodes))
    }
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    #[test]
    fn the_default_strip_puts_an_element_of_at_most_0_6_h_at_the_front() {
        let strip = |a: f64, h: f64| ThroughWidthParams {
            a,
            length: a + 35e-3,
            h,
            ..ThroughWidthParams::example()
        };
        // The 30 mm strip: 16 inside, 0.233 mm at the front (the committed scene's mesh).
        let p = strip(15e-3, 0.4e-3).with_default_mesh();
        assert_eq!(
            (p.inside, p.outside, p.sub_layers, p.base_layers),
            (16, 10, 2, 3)
        );
        let (mesh, _) = through_width_delamination(&p).unwrap();
        let xs = graded_coordinates(p.inside, p.a, p.front_grading).unwrap();
        let last = xs[xs.len() - 1] - xs[xs.len() - 2];
        assert!((front_element(16, 15e-3, 0.1) - last).abs() < 1e-12);
        assert!((last - 0.233e-3).abs() < 0.001e-3, "{last}");
        assert_eq!(3 * mesh.nodes.len(), 3_444);
        // Longer or thinner: more elements, the front element still within 0.6 h.
        for (a, h) in [(30e-3, 0.4e-3), (15e-3, 0.2e-3), (5e-3, 0.4e-3)] {
            let p = strip(a, h).with_default_mesh();
            assert!(front_element(p.inside, a, 0.1) <= 0.6 * h);
            assert!(p.inside == 16 || front_element(p.inside - 1, a, 0.1) > 0.6 * h);
        }
    }

    /// `center_top`: on the sublaminate top (z = H + h) at x = 0, at mid-width — one node, or
    /// (Hex8, odd `across`) two placed symmetrically about it.
    #[test]
    fn centre_top_is_on_the_sublaminate_top_at_x0_mid_width() {
        for (kind, across, count) in [
            (ElementKind::Hex20, 1, 1),
            (ElementKind::Hex20, 2, 1),
            (ElementKind::Hex20, 3, 1),
            (ElementKind::Hex8, 1, 2),
            (ElementKind::Hex8, 2, 1),
            (ElementKind::Hex8, 3, 2),
        ] {
            let p = ThroughWidthParams {
                kind,
                across,
                ..ThroughWidthParams::example()
            };
            let (m, _) = through_width_delamination(&p).unwrap();
            let set = &m.node_sets[names::CENTER_TOP];
            assert_eq!(set.len(), count, "{kind:?} across {across}");
            let mean_y = set.iter().map(|&n| m.nodes[n][1]).sum::<f64>() / count as f64;
            assert!(
                (mean_y - 0.5 * p.width).abs() < 1e-15,
                "{kind:?} across {across}"
            );
            for &n in set {
                let [x, _, z] = m.nodes[n];
                assert!(x == 0.0 && (z - (p.base + p.h)).abs() < 1e-15);
            }
            if count == 2 {
                // One element apart: y = W·(across ∓ 1)/(2·across).
                let gap = m.nodes[set[1]][1] - m.nodes[set[0]][1];
                assert!((gap - p.width / across as f64).abs() < 1e-15);
            }
        }
    }
}
