//! Nodal fields carried from one mesh onto the nodes of another mesh of the same body: the
//! step of nested iteration (mesh sequencing) that starts a fine mesh's Newton solve from a
//! coarse mesh's converged state, as deal.II's `interpolate_to_different_mesh` does.
//!
//! Isoparametric interpolation: a target node at x lies in a source cell at the reference
//! point ξ with x = Σ_a N_a(ξ) X_a (thesis eq. 2.4.1.1, inverted by Newton's method with
//! J_rc = Σ_a ∂N_a/∂ξ_r X_a_c); the field there is v(x) = Σ_a N_a(ξ) v_a. A field linear in x
//! is carried exactly by any isoparametric cell (x itself is interpolated), a quadratic one by
//! Hex20 cells whose map is affine.
//!
//! Crack faces: a delamination's two faces are coincident nodes with different values. A
//! target node is located from a point moved a little into one of its own cells (the upper
//! crack node's cells lie above the crack, the lower one's below), so it takes the values of
//! the source cell on its own side; its ξ is then found for the node's own position in that
//! cell.

use crate::{Mesh, MeshError};

/// How far (relative to the distance to the cell's centroid) a target node is moved into one
/// of its cells to pick the source cell on its side of a crack.
const NUDGE: f64 = 1e-3;

/// A target node may lie this far outside its source cell in reference coordinates (|ξ|∞ ≤
/// 1 + this) and still take the cell's interpolation (curved boundaries: a coarse cell's
/// quadratic edge and the fine cells' edges on the same ellipse differ slightly); beyond it
/// the node is outside the source mesh.
const OUTSIDE: f64 = 0.05;

/// The interpolation of nodal fields from a source mesh onto the nodes of a target mesh:
/// per target node, the source nodes and weights N_a(ξ) (rows of a sparse matrix, Σ_a N_a = 1).
#[derive(Debug, Clone, PartialEq)]
pub struct Transfer {
    /// Row j's entries are `offsets[j]..offsets[j + 1]`.
    offsets: Vec<usize>,
    sources: Vec<usize>,
    weights: Vec<f64>,
    /// The source cell of each target node.
    cells: Vec<usize>,
    /// Source nodes (the length of a field per component).
    source_nodes: usize,
    /// The largest max(|ξ|∞ − 1, 0) over the target nodes.
    outside: f64,
}

impl Transfer {
    /// The interpolation from `source` onto the nodes of `target` (both in the same
    /// coordinates). Errors: a mesh without cells, a target node outside the source mesh
    /// (named, with its position in mm), a source cell whose map cannot be inverted there.
    pub fn between(source: &Mesh, target: &Mesh) -> Result<Self, MeshError> {
        if source.cells.is_empty() {
            return Err(MeshError::Parameter {
                name: "source mesh",
                reason: "has no cells to interpolate in".into(),
            });
        }
        let bins = Bins::new(source);
        // One cell of each target node (the first that holds it), to move it into.
        let mut cell_of_node = vec![usize::MAX; target.nodes.len()];
        for (c, cell) in target.cells.iter().enumerate() {
            for &n in &cell.nodes {
                if cell_of_node[n] == usize::MAX {
                    cell_of_node[n] = c;
                }
            }
        }
        let mut out = Self {
            offsets: Vec::with_capacity(target.nodes.len() + 1),
            sources: Vec::new(),
            weights: Vec::new(),
            cells: Vec::with_capacity(target.nodes.len()),
            source_nodes: source.nodes.len(),
            outside: 0.0,
        };
        out.offsets.push(0);
        let mut n = [0.0; 20];
        for (j, &x) in target.nodes.iter().enumerate() {
            let probe = match cell_of_node[j] {
                usize::MAX => x,
                c => {
                    let centroid = centroid(target, c);
                    std::array::from_fn(|k| x[k] + NUDGE * (centroid[k] - x[k]))
                }
            };
            let Some((cell, _)) = bins.locate(source, probe) else {
                return Err(outside_error(j, x));
            };
            let coords = coordinates(source, cell);
            let kind = source.cells[cell].kind;
            let xi = inverse_map(kind, &coords, x).ok_or_else(|| outside_error(j, x))?;
            let over = xi.iter().fold(0.0_f64, |m, v| m.max(v.abs() - 1.0));
            if over > OUTSIDE {
                return Err(outside_error(j, x));
            }
            out.outside = out.outside.max(over);
            let n = &mut n[..kind.nodes()];
            kind.shape_values(xi, n);
            for (&node, &w) in source.cells[cell].nodes.iter().zip(n.iter()) {
                out.sources.push(node);
                out.weights.push(w);
            }
            out.offsets.push(out.sources.len());
            out.cells.push(cell);
        }
        Ok(out)
    }

    /// Target nodes.
    pub fn len(&self) -> usize {
        self.cells.len()
    }

    /// Whether the target has no nodes.
    pub fn is_empty(&self) -> bool {
        self.cells.is_empty()
    }

    /// The source cell that holds target node `j`.
    pub fn cell(&self, j: usize) -> usize {
        self.cells[j]
    }

    /// The largest distance outside its source cell of any target node, in reference
    /// coordinates: max(|ξ|∞ − 1, 0) (0: every node inside or on its cell).
    pub fn outside(&self) -> f64 {
        self.outside
    }

    /// A nodal field of the source (`per_node` components a node, node-major: a displacement
    /// is `per_node = 3`) interpolated onto the target's nodes.
    pub fn apply(&self, field: &[f64], per_node: usize) -> Result<Vec<f64>, MeshError> {
        if field.len() != per_node * self.source_nodes {
            return Err(MeshError::Parameter {
                name: "field",
                reason: format!(
                    "has {} values, the source mesh's {} nodes × {per_node} need {}",
                    field.len(),
                    self.source_nodes,
                    per_node * self.source_nodes
                ),
            });
        }
        let mut out = vec![0.0; per_node * self.len()];
        for (j, row) in out.chunks_exact_mut(per_node.max(1)).enumerate() {
            for e in self.offsets[j]..self.offsets[j + 1] {
                let (a, w) = (self.sources[e], self.weights[e]);
                for (k, v) in row.iter_mut().enumerate() {
                    *v += w * field[per_node * a + k];
                }
            }
        }
        Ok(out)
    }
}

fn outside_error(node: usize, x: [f64; 3]) -> MeshError {
    MeshError::Parameter {
        name: "target mesh",
        reason: format!(
            "node {node} at ({:.4}, {:.4}, {:.4}) mm lies outside the source mesh",
            x[0] * 1e3,
            x[1] * 1e3,
            x[2] * 1e3
        ),
    }
}

fn coordinates(mesh: &Mesh, cell: usize) -> Vec<[f64; 3]> {
    mesh.cells[cell]
        .nodes
        .iter()
        .map(|&n| mesh.nodes[n])
        .collect()
}

fn centroid(mesh: &Mesh, cell: usize) -> [f64; 3] {
    let nodes = &mesh.cells[cell].nodes;
    let mut c = [0.0; 3];
    for &n in nodes {
        for k in 0..3 {
            c[k] += mesh.nodes[n][k];
        }
    }
    c.map(|v| v / nodes.len() as f64)
}

/// ξ with x(ξ) = `x` in the cell of nodes `coords` (Newton on the isoparametric map from the
/// cell's centre, steps limited to stay within |ξ|∞ ≤ 3); None if the Jacobian is singular,
/// if Newton pushes ξ against that limit in two successive steps (the point lies far outside
/// the cell: the iteration could only stall there), or if it does not settle to 1e-12 in 30
/// steps (the cell folded).
fn inverse_map(
    kind: nonlin3d_element::ElementKind,
    coords: &[[f64; 3]],
    x: [f64; 3],
) -> Option<[f64; 3]> {
    let mut xi = [0.0; 3];
    let (mut n, mut dn) = ([0.0; 20], [[0.0; 3]; 20]);
    let count = kind.nodes();
    let mut held = false;
    for _ in 0..30 {
        kind.shape_values(xi, &mut n[..count]);
        kind.shape_gradients(xi, &mut dn[..count]);
        let mut r = x;
        let mut j = [[0.0; 3]; 3];
        for m in 0..count {
            for c in 0..3 {
                r[c] -= n[m] * coords[m][c];
                for (row, d) in j.iter_mut().zip(dn[m]) {
                    row[c] += d * coords[m][c];
                }
            }
        }
        // x(ξ + δ) ≈ x(ξ) + Jᵀ δ (J_rc = ∂x_c/∂ξ_r): solve Jᵀ δ = r.
        let jt = [
            [j[0][0], j[1][0], j[2][0]],
            [j[0][1], j[1][1], j[2][1]],
            [j[0][2], j[1][2], j[2][2]],
        ];
        let delta = solve3(jt, r)?;
        let beyond = (0..3).any(|k| (xi[k] + delta[k]).abs() > 3.0);
        if beyond && held {
            return None;
        }
        held = beyond;
        for k in 0..3 {
            xi[k] = (xi[k] + delta[k]).clamp(-3.0, 3.0);
        }
        if delta.iter().all(|d| d.abs() < 1e-12) {
            return Some(xi);
        }
    }
    None
}

/// The solution of the 3 × 3 system a·y = b by Cramer's rule; None if a is singular.
fn solve3(a: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let d = det(a);
    let scale = a.iter().flatten().fold(0.0_f64, |s, v| s.max(v.abs()));
    // (A NaN determinant is refused too.)
    if d.is_nan() || d.abs() <= 1e-14 * scale.powi(3) {
        return None;
    }
    Some(std::array::from_fn(|k| {
        let mut m = a;
        for (row, &v) in m.iter_mut().zip(&b) {
            row[k] = v;
        }
        det(m) / d
    }))
}

/// The source cells binned on a uniform grid by their node boxes (grown by a tenth, for
/// curved edges), to find the cells that may hold a point.
struct Bins {
    /// Each cell's node box, grown by a tenth.
    boxes: Vec<([f64; 3], [f64; 3])>,
    lo: [f64; 3],
    size: [f64; 3],
    count: [usize; 3],
    /// Cells of bin b: `cells[start[b]..start[b + 1]]`.
    start: Vec<usize>,
    cells: Vec<usize>,
}

impl Bins {
    fn new(mesh: &Mesh) -> Self {
        let boxes: Vec<([f64; 3], [f64; 3])> = (0..mesh.cells.len())
            .map(|c| {
                let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
                for &n in &mesh.cells[c].nodes {
                    for k in 0..3 {
                        lo[k] = lo[k].min(mesh.nodes[n][k]);
                        hi[k] = hi[k].max(mesh.nodes[n][k]);
                    }
                }
                let grow: [f64; 3] = std::array::from_fn(|k| 0.1 * (hi[k] - lo[k]));
                (
                    std::array::from_fn(|k| lo[k] - grow[k]),
                    std::array::from_fn(|k| hi[k] + grow[k]),
                )
            })
            .collect();
        let (mut lo, mut hi) = ([f64::INFINITY; 3], [f64::NEG_INFINITY; 3]);
        for (a, b) in &boxes {
            for k in 0..3 {
                lo[k] = lo[k].min(a[k]);
                hi[k] = hi[k].max(b[k]);
            }
        }
        // About one cell a bin along each axis.
        let per_axis = (mesh.cells.len() as f64).cbrt().ceil().max(1.0) as usize;
        let count = [per_axis; 3];
        let size: [f64; 3] =
            std::array::from_fn(|k| ((hi[k] - lo[k]) / count[k] as f64).max(f64::MIN_POSITIVE));
        let mut bins = Self {
            boxes: Vec::new(),
            lo,
            size,
            count,
            start: Vec::new(),
            cells: Vec::new(),
        };
        let total = count.iter().product::<usize>();
        let mut lists: Vec<Vec<usize>> = vec![Vec::new(); total];
        for (c, (a, b)) in boxes.iter().enumerate() {
            let (i0, i1) = (bins.index(*a), bins.index(*b));
            for x in i0[0]..=i1[0] {
                for y in i0[1]..=i1[1] {
                    for z in i0[2]..=i1[2] {
                        lists[bins.flat([x, y, z])].push(c);
                    }
                }
            }
        }
        bins.start.push(0);
        for l in lists {
            bins.cells.extend(l);
            bins.start.push(bins.cells.len());
        }
        bins.boxes = boxes;
        bins
    }

    /// The bin coordinates of a point (clamped to the grid).
    fn index(&self, p: [f64; 3]) -> [usize; 3] {
        std::array::from_fn(|k| {
            let i = ((p[k] - self.lo[k]) / self.size[k]).floor();
            (i.max(0.0) as usize).min(self.count[k] - 1)
        })
    }

    fn flat(&self, i: [usize; 3]) -> usize {
        (i[0] * self.count[1] + i[1]) * self.count[2] + i[2]
    }

    /// The source cell that holds point `p` best (the smallest max(|ξ|∞ − 1, 0), the first
    /// such cell on ties), among the cells of its bin whose grown box holds it, then of the
    /// bins around it, then (no box holding it) among all those cells; None if no cell's map
    /// could be inverted at `p`.
    fn locate(&self, mesh: &Mesh, p: [f64; 3]) -> Option<(usize, f64)> {
        self.search(mesh, p, true)
            .or_else(|| self.search(mesh, p, false))
    }

    /// [`locate`](Self::locate), the cells' boxes checked first if `boxed` (the inverse map,
    /// Newton on 20 shape functions, is what costs).
    fn search(&self, mesh: &Mesh, p: [f64; 3], boxed: bool) -> Option<(usize, f64)> {
        let holds = |c: usize| {
            let (a, b) = &self.boxes[c];
            (0..3).all(|k| a[k] <= p[k] && p[k] <= b[k])
        };
        let centre = self.index(p);
        let mut best: Option<(usize, f64)> = None;
        for reach in 0..=2usize {
            let range = |k: usize| {
                centre[k].saturating_sub(reach)..=(centre[k] + reach).min(self.count[k] - 1)
            };
            for x in range(0) {
                for y in range(1) {
                    for z in range(2) {
                        let b = self.flat([x, y, z]);
                        for &c in &self.cells[self.start[b]..self.start[b + 1]] {
                            if boxed && !holds(c) {
                                continue;
                            }
                            let coords = coordinates(mesh, c);
                            let Some(xi) = inverse_map(mesh.cells[c].kind, &coords, p) else {
                                continue;
                            };
                            let over = xi.iter().fold(0.0_f64, |m, v| m.max(v.abs() - 1.0));
                            if best.is_none_or(|(_, o)| over < o) {
                                best = Some((c, over));
                            }
                            // No later cell can hold it better than inside.
                            if over == 0.0 {
                                return best;
                            }
                        }
                    }
                }
            }
            if best.is_some_and(|(_, o)| o <= 1e-9) {
                return best;
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::Cell;
    use nonlin3d_element::ElementKind;

    /// One Hex20 cell on [0, 2] × [0, 1] × [0, 1] (mid-edge nodes at the edge midpoints).
    fn brick() -> Mesh {
        let corner = |p: [f64; 3]| [(p[0] + 1.0), (p[1] + 1.0) / 2.0, (p[2] + 1.0) / 2.0];
        Mesh {
            nodes: ElementKind::Hex20
                .reference_nodes()
                .iter()
                .map(|&p| corner(p))
                .collect(),
            cells: vec![Cell {
                kind: ElementKind::Hex20,
                nodes: (0..20).collect(),
                material: 0,
                ply_angle_deg: 0.0,
            }],
            ..Mesh::default()
        }
    }

    #[test]
    fn a_mesh_onto_itself_is_the_identity() {
        let m = brick();
        let t = Transfer::between(&m, &m).unwrap();
        let field: Vec<f64> = (0..60).map(|i| (i as f64).sin()).collect();
        let out = t.apply(&field, 3).unwrap();
        for (a, b) in out.iter().zip(&field) {
            assert!((a - b).abs() < 1e-12, "{a} against {b}");
        }
        assert!(t.outside() < 1e-12);
    }

    /// A quadratic field on an affine Hex20 cell is carried exactly to any point in it.
    #[test]
    fn a_quadratic_field_is_exact_in_an_affine_cell() {
        let source = brick();
        let f = |x: [f64; 3]| 1.0 + x[0] - 2.0 * x[1] + 0.5 * x[0] * x[2] + x[1] * x[1];
        let field: Vec<f64> = source.nodes.iter().map(|&x| f(x)).collect();
        let target = Mesh {
            nodes: vec![[0.3, 0.2, 0.9], [1.7, 0.5, 0.1], [2.0, 1.0, 1.0]],
            ..Mesh::default()
        };
        let t = Transfer::between(&source, &target).unwrap();
        for (v, &x) in t.apply(&field, 1).unwrap().iter().zip(&target.nodes) {
            assert!((v - f(x)).abs() < 1e-12, "{v} against {}", f(x));
        }
    }

    /// The inverse map finds ξ wherever it lies within the ±3 limit (inside the cell, or
    /// outside it as a neighbour's point may be), and gives up on a point beyond it: Newton
    /// pushes ξ against the limit twice running there.
    #[test]
    fn the_inverse_map_finds_points_within_its_limit_and_gives_up_beyond_it() {
        let m = brick();
        let coords = coordinates(&m, 0);
        // The brick maps ξ ∈ [−1, 1]³ onto [0, 2] × [0, 1] × [0, 1]: x = 1 + ξ₁, y = (1 + ξ₂)/2.
        let at = |xi: [f64; 3]| [1.0 + xi[0], 0.5 * (1.0 + xi[1]), 0.5 * (1.0 + xi[2])];
        for xi in [[0.3, -0.7, 0.9], [1.03, 0.0, -1.02], [2.5, 0.2, 0.0]] {
            let found = inverse_map(ElementKind::Hex20, &coords, at(xi)).unwrap();
            for k in 0..3 {
                assert!((found[k] - xi[k]).abs() < 1e-12, "{found:?} against {xi:?}");
            }
        }
        for xi in [[3.5, 0.0, 0.0], [0.0, -40.0, 0.0]] {
            assert_eq!(
                inverse_map(ElementKind::Hex20, &coords, at(xi)),
                None,
                "{xi:?}"
            );
        }
    }

    #[test]
    fn a_node_outside_is_refused_by_name_and_a_short_field_too() {
        let source = brick();
        let target = Mesh {
            nodes: vec![[0.5, 0.5, 0.5], [3.0, 0.5, 0.5]],
            ..Mesh::default()
        };
        let e = Transfer::between(&source, &target).unwrap_err().to_string();
        assert!(e.contains("node 1") && e.contains("outside"), "{e}");
        let t = Transfer::between(&source, &source).unwrap();
        let e = t.apply(&[0.0; 59], 3).unwrap_err().to_string();
        assert!(e.contains("59 values"), "{e}");
    }
}
