//! Hex8 and Hex20 shape functions and reference gradients (thesis §2.2, appendix).
//!
//! Node order is Abaqus C3D8 / C3D20, identical to `VTK_HEXAHEDRON` /
//! `VTK_QUADRATIC_HEXAHEDRON`. Reference coordinates (ξ, η, ζ) are the thesis's
//! (δ1, δ2, δ3); only the node numbering differs (see [`THESIS_NODE_HEX8`],
//! [`THESIS_NODE_HEX20`]).
//!
//! ```text
//!  Hex20 (Hex8: corners 1–8 only)            ζ
//!                                              |
//!          8 ------15------- 7                 +--- η
//!         /|                /|                /
//!       16 |              14 |               ξ
//!       /  20             /  19
//!      5 ------13------- 6   |        corners: 1 (−,−,−) 2 (+,−,−) 3 (+,+,−) 4 (−,+,−)
//!      |   |             |   |                 5 (−,−,+) 6 (+,−,+) 7 (+,+,+) 8 (−,+,+)
//!      |   4 ------11----|-- 3        edges:   9 1–2   10 2–3   11 3–4   12 4–1
//!     17  /             18  /                 13 5–6   14 6–7   15 7–8   16 8–5
//!      | 12              | 10                 17 1–5   18 2–6   19 3–7   20 4–8
//!      |/                |/
//!      1 ------ 9 ------ 2        (ξ runs 1→2, η runs 1→4, ζ runs 1→5)
//! ```

/// The element families nonlin3d supports.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElementKind {
    /// 8-node trilinear hexahedron (C3D8).
    Hex8,
    /// 20-node serendipity hexahedron (C3D20).
    Hex20,
}

impl ElementKind {
    /// Number of nodes (NS in the thesis).
    pub const fn nodes(self) -> usize {
        match self {
            Self::Hex8 => 8,
            Self::Hex20 => 20,
        }
    }

    /// Number of degrees of freedom, 3 per node.
    pub const fn dofs(self) -> usize {
        3 * self.nodes()
    }

    /// Reference coordinates of the nodes.
    pub fn reference_nodes(self) -> &'static [[f64; 3]] {
        match self {
            Self::Hex8 => &HEX20_NODES[..8],
            Self::Hex20 => &HEX20_NODES,
        }
    }

    /// Shape function values N^m(ξ) written into `n` (length [`nodes`](Self::nodes)).
    pub fn shape_values(self, xi: [f64; 3], n: &mut [f64]) {
        let nodes = self.reference_nodes();
        for (m, (out, p)) in n.iter_mut().zip(nodes).enumerate() {
            *out = match self {
                Self::Hex8 => hex8_value(p, xi),
                Self::Hex20 => hex20_value(m, p, xi),
            };
        }
    }

    /// det J at reference point `xi` of the element with node coordinates `coords`, where
    /// J_rc = Σ_m ∂N^m/∂ξ_r x^m_c (eq. 2.4.1.1, 2.4.1.9): positive for a valid element; mesh
    /// quality metrics and validity checks build on it.
    pub fn jacobian_determinant(
        self,
        xi: [f64; 3],
        coords: &[[f64; 3]],
    ) -> Result<f64, crate::ElementError> {
        if coords.len() != self.nodes() {
            return Err(crate::ElementError::LengthMismatch {
                what: "coordinates",
                expected: self.nodes(),
                got: coords.len(),
            });
        }
        let mut dn = [[0.0; 3]; 20];
        let dn = &mut dn[..self.nodes()];
        self.shape_gradients(xi, dn);
        let mut j = [[0.0; 3]; 3];
        for (d, xm) in dn.iter().zip(coords) {
            for r in 0..3 {
                for c in 0..3 {
                    j[r][c] += d[r] * xm[c];
                }
            }
        }
        Ok(j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
            - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
            + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0]))
    }

    /// Reference gradients ∂N^m/∂ξ_r written into `dn` (length [`nodes`](Self::nodes)).
    pub fn shape_gradients(self, xi: [f64; 3], dn: &mut [[f64; 3]]) {
        let nodes = self.reference_nodes();
        for (m, (out, p)) in dn.iter_mut().zip(nodes).enumerate() {
            *out = match self {
                Self::Hex8 => hex8_gradient(p, xi),
                Self::Hex20 => hex20_gradient(m, p, xi),
            };
        }
    }
}

/// Reference coordinates of the Hex20 nodes in Abaqus/VTK order; the first 8 are the Hex8.
pub const HEX20_NODES: [[f64; 3]; 20] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// Corner pairs (zero-based) of the Hex20 mid-edge nodes 9–20 in Abaqus/VTK order: node
/// 8 + e sits on the edge between corners `HEX20_EDGES[e]`.
pub const HEX20_EDGES: [(usize, usize); 12] = [
    (0, 1),
    (1, 2),
    (2, 3),
    (3, 0),
    (4, 5),
    (5, 6),
    (6, 7),
    (7, 4),
    (0, 4),
    (1, 5),
    (2, 6),
    (3, 7),
];

/// Thesis appendix number (1-based) of each Hex8 node in Abaqus order:
/// `N_abaqus[i] = S_thesis(THESIS_NODE_HEX8[i])`. The thesis numbers the δ1 = +1 face first.
pub const THESIS_NODE_HEX8: [usize; 8] = [5, 1, 2, 6, 8, 4, 3, 7];

/// Thesis appendix number (1-based) of each Hex20 node in Abaqus order:
/// `N_abaqus[i] = S_thesis(THESIS_NODE_HEX20[i])`. The thesis walks the δ1 = −1 face
/// (1–8, corners odd), then the δ1 = 0 mid-plane (9–12), then the δ1 = +1 face (13–20).
pub const THESIS_NODE_HEX20: [usize; 20] = [
    1, 13, 15, 3, 7, 19, 17, 5, 9, 14, 10, 2, 12, 18, 11, 6, 8, 20, 16, 4,
];

/// N = (1 + ξξi)(1 + ηηi)(1 + ζζi)/8.
fn hex8_value(p: &[f64; 3], x: [f64; 3]) -> f64 {
    0.125 * (1.0 + p[0] * x[0]) * (1.0 + p[1] * x[1]) * (1.0 + p[2] * x[2])
}

fn hex8_gradient(p: &[f64; 3], x: [f64; 3]) -> [f64; 3] {
    let a = [1.0 + p[0] * x[0], 1.0 + p[1] * x[1], 1.0 + p[2] * x[2]];
    [
        0.125 * p[0] * a[1] * a[2],
        0.125 * a[0] * p[1] * a[2],
        0.125 * a[0] * a[1] * p[2],
    ]
}

/// Corners: N = (1 + ξξi)(1 + ηηi)(1 + ζζi)(ξξi + ηηi + ζζi − 2)/8;
/// mid-edge nodes with ξi = 0: N = (1 − ξ²)(1 + ηηi)(1 + ζζi)/4 (and cyclically).
fn hex20_value(m: usize, p: &[f64; 3], x: [f64; 3]) -> f64 {
    if m < 8 {
        let a = [1.0 + p[0] * x[0], 1.0 + p[1] * x[1], 1.0 + p[2] * x[2]];
        0.125 * a[0] * a[1] * a[2] * (p[0] * x[0] + p[1] * x[1] + p[2] * x[2] - 2.0)
    } else {
        let mut v = 0.25;
        for r in 0..3 {
            v *= if p[r] == 0.0 {
                1.0 - x[r] * x[r]
            } else {
                1.0 + p[r] * x[r]
            };
        }
        v
    }
}

fn hex20_gradient(m: usize, p: &[f64; 3], x: [f64; 3]) -> [f64; 3] {
    let a = [1.0 + p[0] * x[0], 1.0 + p[1] * x[1], 1.0 + p[2] * x[2]];
    if m < 8 {
        let s = p[0] * x[0] + p[1] * x[1] + p[2] * x[2] - 2.0;
        let mut g = [0.0; 3];
        for r in 0..3 {
            let (b, c) = (a[(r + 1) % 3], a[(r + 2) % 3]);
            // d/dξr [a_r·b·c·s] = p_r·b·c·s + a_r·b·c·p_r
            g[r] = 0.125 * p[r] * b * c * (s + a[r]);
        }
        g
    } else {
        let f = |r: usize| if p[r] == 0.0 { 1.0 - x[r] * x[r] } else { a[r] };
        let df = |r: usize| if p[r] == 0.0 { -2.0 * x[r] } else { p[r] };
        [
            0.25 * df(0) * f(1) * f(2),
            0.25 * f(0) * df(1) * f(2),
            0.25 * f(0) * f(1) * df(2),
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The appendix formulas exactly as printed, δ = (δ1, δ2, δ3), thesis numbering 1…8.
    fn thesis_hex8(k: usize, d: [f64; 3]) -> f64 {
        let (a, b, c) = (d[0], d[1], d[2]);
        match k {
            1 => (1.0 + a) * (1.0 - b) * (1.0 - c) / 8.0,
            2 => (1.0 + a) * (1.0 + b) * (1.0 - c) / 8.0,
            3 => (1.0 + a) * (1.0 + b) * (1.0 + c) / 8.0,
            4 => (1.0 + a) * (1.0 - b) * (1.0 + c) / 8.0,
            5 => (1.0 - a) * (1.0 - b) * (1.0 - c) / 8.0,
            6 => (1.0 - a) * (1.0 + b) * (1.0 - c) / 8.0,
            7 => (1.0 - a) * (1.0 + b) * (1.0 + c) / 8.0,
            _ => (1.0 - a) * (1.0 - b) * (1.0 + c) / 8.0,
        }
    }

    /// The appendix formulas for the 20-node element, thesis numbering 1…20.
    fn thesis_hex20(k: usize, d: [f64; 3]) -> f64 {
        let (a, b, c) = (d[0], d[1], d[2]);
        match k {
            1 => 0.125 * (1.0 - a) * (1.0 - b) * (1.0 - c) * (-a - b - c - 2.0),
            3 => 0.125 * (1.0 - a) * (1.0 + b) * (1.0 - c) * (-a + b - c - 2.0),
            5 => 0.125 * (1.0 - a) * (1.0 + b) * (1.0 + c) * (-a + b + c - 2.0),
            7 => 0.125 * (1.0 - a) * (1.0 - b) * (1.0 + c) * (-a - b + c - 2.0),
            13 => 0.125 * (1.0 + a) * (1.0 - b) * (1.0 - c) * (a - b - c - 2.0),
            15 => 0.125 * (1.0 + a) * (1.0 + b) * (1.0 - c) * (a + b - c - 2.0),
            17 => 0.125 * (1.0 + a) * (1.0 + b) * (1.0 + c) * (a + b + c - 2.0),
            19 => 0.125 * (1.0 + a) * (1.0 - b) * (1.0 + c) * (a - b + c - 2.0),
            9 => 0.25 * (1.0 - a * a) * (1.0 - b) * (1.0 - c),
            10 => 0.25 * (1.0 - a * a) * (1.0 + b) * (1.0 - c),
            11 => 0.25 * (1.0 - a * a) * (1.0 + b) * (1.0 + c),
            12 => 0.25 * (1.0 - a * a) * (1.0 - b) * (1.0 + c),
            2 => 0.25 * (1.0 - b * b) * (1.0 - a) * (1.0 - c),
            6 => 0.25 * (1.0 - b * b) * (1.0 - a) * (1.0 + c),
            14 => 0.25 * (1.0 - b * b) * (1.0 + a) * (1.0 - c),
            18 => 0.25 * (1.0 - b * b) * (1.0 + a) * (1.0 + c),
            4 => 0.25 * (1.0 - c * c) * (1.0 - a) * (1.0 + b),
            8 => 0.25 * (1.0 - c * c) * (1.0 - a) * (1.0 - b),
            16 => 0.25 * (1.0 - c * c) * (1.0 + a) * (1.0 + b),
            _ => 0.25 * (1.0 - c * c) * (1.0 + a) * (1.0 - b),
        }
    }

    fn sample_points() -> Vec<[f64; 3]> {
        let v = [-1.0, -0.77, -0.3, 0.0, 0.41, 0.9, 1.0];
        let mut pts = Vec::new();
        for &a in &v {
            for &b in &v {
                for &c in &v {
                    pts.push([a, b, c]);
                }
            }
        }
        pts
    }

    #[test]
    fn shape_functions_equal_thesis_appendix_under_permutation() {
        let mut n8 = [0.0; 8];
        let mut n20 = [0.0; 20];
        for x in sample_points() {
            ElementKind::Hex8.shape_values(x, &mut n8);
            ElementKind::Hex20.shape_values(x, &mut n20);
            for i in 0..8 {
                assert!((n8[i] - thesis_hex8(THESIS_NODE_HEX8[i], x)).abs() < 1e-15);
            }
            for i in 0..20 {
                assert!((n20[i] - thesis_hex20(THESIS_NODE_HEX20[i], x)).abs() < 1e-15);
            }
        }
    }

    #[test]
    fn edge_table_matches_reference_nodes() {
        for (e, &(a, b)) in HEX20_EDGES.iter().enumerate() {
            for r in 0..3 {
                let mid = 0.5 * (HEX20_NODES[a][r] + HEX20_NODES[b][r]);
                assert_eq!(HEX20_NODES[8 + e][r], mid);
            }
        }
    }

    #[test]
    fn shape_functions_are_kronecker_at_nodes() {
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let mut n = vec![0.0; kind.nodes()];
            for (j, &p) in kind.reference_nodes().iter().enumerate() {
                kind.shape_values(p, &mut n);
                for (i, v) in n.iter().enumerate() {
                    let e = if i == j { 1.0 } else { 0.0 };
                    assert!((v - e).abs() < 1e-15, "{kind:?} N{i} at node {j} = {v}");
                }
            }
        }
    }

    #[test]
    fn gradients_match_central_differences() {
        // Shape functions are cubic at most: the central-difference error is h²/6·N''' ≲ 1e-9
        // for h = 1e-4, plus round-off 1e-16/h.
        let h = 1e-4;
        for kind in [ElementKind::Hex8, ElementKind::Hex20] {
            let nn = kind.nodes();
            let (mut dn, mut np, mut nm) = (vec![[0.0; 3]; nn], vec![0.0; nn], vec![0.0; nn]);
            for x in sample_points() {
                kind.shape_gradients(x, &mut dn);
                for r in 0..3 {
                    let (mut xp, mut xm) = (x, x);
                    xp[r] += h;
                    xm[r] -= h;
                    kind.shape_values(xp, &mut np);
                    kind.shape_values(xm, &mut nm);
                    for m in 0..nn {
                        let fd = (np[m] - nm[m]) / (2.0 * h);
                        assert!((fd - dn[m][r]).abs() < 1e-8, "{kind:?} dN{m}/dξ{r}");
                    }
                }
            }
        }
    }
}
