//! The delamination-front descriptor the virtual crack closure technique needs (thesis §2.8,
//! Fig. 2.8.1, eq. 2.8.1–2.8.2).

/// One node c_i on the delamination front with the nodes VCCT pairs with it.
///
/// Hex20 (Fig. 2.8.1): forces at c_i pair with the opening between a_i (upper face) and a′_i
/// (lower face) one element behind the front (distance Δa); on corner lines also the force at
/// d_i (the mid-edge node Δa/2 ahead) pairs with the opening between b_i and b′_i (Δa/2
/// behind). Hex8 fronts have only c and a.
#[derive(Debug, Clone, PartialEq)]
pub struct FrontPoint {
    /// The front node (shared by both faces).
    pub c: usize,
    /// Whether c is an element corner (false: a mid-edge node).
    pub corner: bool,
    /// Upper-face node one element behind the front.
    pub a_upper: usize,
    /// Lower-face node one element behind the front.
    pub a_lower: usize,
    /// Upper-face node Δa/2 behind (Hex20 corner lines).
    pub b_upper: Option<usize>,
    /// Lower-face node Δa/2 behind (Hex20 corner lines).
    pub b_lower: Option<usize>,
    /// Node Δa/2 ahead of the front (Hex20 corner lines).
    pub d: Option<usize>,
    /// Cells above the delamination plane that contain c (or d): their internal forces give the
    /// forces transmitted across the plane at c and d.
    pub cells_above: Vec<usize>,
    /// Δa: distance from c to a.
    pub delta_a: f64,
    /// Position (x, y) of c.
    pub x: f64,
    /// y coordinate of c.
    pub y: f64,
    /// Unit tangent x′ (direction of increasing S).
    pub tangent: [f64; 2],
    /// Unit outward normal y′ in the delamination plane: (−sin θ, cos θ).
    pub normal: [f64; 2],
    /// θ: angle of x′ from x in degrees (0° where the front meets the y axis, −90° on the x axis).
    pub theta_deg: f64,
    /// Perimeter coordinate S (m), 0 on the y axis, growing towards the x axis.
    pub s: f64,
}

impl FrontPoint {
    /// A point with its node pairing; Δa, position, frame, θ and S are filled in by the front
    /// once all points are known.
    pub(crate) fn new(
        c: usize,
        corner: bool,
        a: (usize, usize),
        b: Option<(usize, usize)>,
        d: Option<usize>,
        cells_above: Vec<usize>,
    ) -> Self {
        Self {
            c,
            corner,
            a_upper: a.0,
            a_lower: a.1,
            b_upper: b.map(|p| p.0),
            b_lower: b.map(|p| p.1),
            d,
            cells_above,
            delta_a: 0.0,
            x: 0.0,
            y: 0.0,
            tangent: [0.0; 2],
            normal: [0.0; 2],
            theta_deg: 0.0,
            s: 0.0,
        }
    }
}

/// A generator's internal inconsistency: a node the sets or the VCCT pairs (§2.8) need is not
/// in its mesh.
pub(crate) fn missing_node(what: &str) -> crate::MeshError {
    crate::MeshError::Parameter {
        name: "front",
        reason: format!("internal: {what} node not found"),
    }
}

/// Which of a set of cells contain each node: for the cells above the delamination plane that
/// touch c and d.
pub(crate) struct CellsTouching(std::collections::HashMap<usize, Vec<usize>>);

impl CellsTouching {
    /// Index of `cells` of `mesh` by node.
    pub(crate) fn new(mesh: &crate::Mesh, cells: &[usize]) -> Self {
        let mut map: std::collections::HashMap<usize, Vec<usize>> =
            std::collections::HashMap::new();
        for &c in cells {
            for &n in &mesh.cells[c].nodes {
                map.entry(n).or_default().push(c);
            }
        }
        Self(map)
    }

    /// The indexed cells containing node `a` or node `b`, sorted, without repeats.
    pub(crate) fn touching(&self, a: usize, b: Option<usize>) -> Vec<usize> {
        let mut v: Vec<usize> = self.0.get(&a).cloned().unwrap_or_default();
        if let Some(b) = b {
            v.extend(self.0.get(&b).cloned().unwrap_or_default());
        }
        v.sort_unstable();
        v.dedup();
        v
    }
}

/// The front, ordered by increasing S.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Front {
    /// Front nodes from the y axis (S = 0) to the x axis.
    pub points: Vec<FrontPoint>,
    /// How VCCT measures the length of front a corner point closes (eq. 2.8.1).
    pub widths: FrontWidths,
}

/// How the virtual crack closure measures the width of front a Hex20 corner point closes
/// (thesis eq. 2.8.1: G = Ē / (Δa · width)).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FrontWidths {
    /// The chord between the midside nodes on either side (§2.8: "Δa times the distance
    /// between the midside nodes"), for fronts of straight edges.
    #[default]
    Chords,
    /// The length along the quadratic edges from the midside node on one side through the
    /// corner to the midside node on the other, for fronts whose midside nodes lie on the curve
    /// ([`MidEdges::Mapped`](crate::MidEdges::Mapped)).
    AlongEdges,
}

impl Front {
    /// Fills the fields for a straight front with unit tangent `tangent` (all points share it).
    pub(crate) fn finish_straight(mut self, nodes: &[[f64; 3]], tangent: [f64; 2]) -> Self {
        let mut s = 0.0;
        for i in 0..self.points.len() {
            let c = nodes[self.points[i].c];
            if i > 0 {
                let prev = nodes[self.points[i - 1].c];
                s += (c[0] - prev[0]).hypot(c[1] - prev[1]);
            }
            let p = &mut self.points[i];
            let a = nodes[p.a_upper];
            p.delta_a = (a[0] - c[0]).hypot(a[1] - c[1]);
            p.x = c[0];
            p.y = c[1];
            p.tangent = tangent;
            p.normal = [-tangent[1], tangent[0]];
            p.theta_deg = tangent[1].atan2(tangent[0]).to_degrees();
            p.s = s;
        }
        self
    }

    /// Fills tangent, normal, θ, S and Δa from node positions, for points already in order
    /// of increasing S. Interior tangents are central differences over the neighbouring front
    /// nodes (second order); the end points lie on the symmetry planes of the quarter model,
    /// which the front crosses at right angles, so their tangents are exact: θ = 0° on the
    /// y axis, −90° on the x axis.
    pub(crate) fn finish(mut self, nodes: &[[f64; 3]]) -> Self {
        let n = self.points.len();
        let pos: Vec<[f64; 3]> = self.points.iter().map(|p| nodes[p.c]).collect();
        let mut s = 0.0;
        for i in 0..n {
            if i > 0 {
                s += (pos[i][0] - pos[i - 1][0]).hypot(pos[i][1] - pos[i - 1][1]);
            }
            let t = if i == 0 {
                [1.0, 0.0]
            } else if i + 1 == n {
                [0.0, -1.0]
            } else {
                let t = [pos[i + 1][0] - pos[i - 1][0], pos[i + 1][1] - pos[i - 1][1]];
                let len = t[0].hypot(t[1]).max(f64::MIN_POSITIVE);
                [t[0] / len, t[1] / len]
            };
            let p = &mut self.points[i];
            let a = nodes[p.a_upper];
            p.delta_a = (a[0] - pos[i][0]).hypot(a[1] - pos[i][1]);
            p.x = pos[i][0];
            p.y = pos[i][1];
            p.tangent = t;
            p.normal = [-t[1], t[0]];
            p.theta_deg = t[1].atan2(t[0]).to_degrees();
            p.s = s;
        }
        self
    }
}
