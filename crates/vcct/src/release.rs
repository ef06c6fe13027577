//! Single-solution virtual crack closure along a delamination front (thesis §2.8, Fig. 2.8.1,
//! eq. 2.8.1–2.8.2).

use crate::VcctError;
use nonlin3d_mesh::{Front, FrontPoint, FrontWidths};

/// G and its modes at one corner node of the front.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FrontRelease {
    /// The front node c.
    pub node: usize,
    /// Perimeter coordinate S (m) from the y axis.
    pub s: f64,
    /// θ, the angle of the front tangent x′ from x (degrees).
    pub theta_deg: f64,
    /// x of the node (m).
    pub x: f64,
    /// y of the node (m).
    pub y: f64,
    /// Δa, the element length behind the front (m).
    pub delta_a: f64,
    /// Closure area Δa × (distance between the neighbouring midside nodes) (m²).
    pub area: f64,
    /// Mode I (opening, z′) release rate, J/m². Physical only where the faces behind the point
    /// are apart ([`FrontRelease::open`]); where they overlap the state penetrates (no contact
    /// is modelled) and G_I — of either sign there — and the mode split mean nothing. With
    /// contact, [`respect_contact`](crate::respect_contact) sets it to 0 where the faces behind
    /// are held together.
    pub g_i: f64,
    /// Mode II (sliding normal to the front, y′), J/m².
    pub g_ii: f64,
    /// Mode III (tearing along the front, x′), J/m².
    pub g_iii: f64,
    /// G_T = G_I + G_II + G_III, J/m².
    pub g_t: f64,
    /// Opening w(a) − w(a′) one element behind the front (m), in z′; negative: overlap.
    pub opening: f64,
}

impl FrontRelease {
    /// Whether the faces behind the front are apart: opening ≥ −1e-8·Δa. The allowance is round-off
    /// (an unbuckled state's openings are ~1e-17 mm), eight orders below the element; `false`
    /// marks the overlapping stretches the thesis draws dashed (§5.1) — there contact would act
    /// and G is not physical.
    pub fn open(&self) -> bool {
        self.opening >= -OPEN_ALLOWANCE * self.delta_a
    }
}

/// Round-off allowance of [`FrontRelease::open`], relative to the element length behind the
/// front.
pub const OPEN_ALLOWANCE: f64 = 1e-8;

/// A vector (F or Δu) in the local front frame of eq. 2.8.2: [x′ (tangent), y′ (normal), z′].
fn local(v: [f64; 3], p: &FrontPoint) -> [f64; 3] {
    [
        v[0] * p.tangent[0] + v[1] * p.tangent[1],
        v[0] * p.normal[0] + v[1] * p.normal[1],
        v[2],
    ]
}

/// Triple of node `n` from a node-major vector.
fn triple(v: &[f64], n: usize) -> [f64; 3] {
    [v[3 * n], v[3 * n + 1], v[3 * n + 2]]
}

/// Closure energy products [mode III, mode II, mode I] of the force at `c` and the opening
/// `upper − lower`, in the frame of `p`: E = −½ F′ ⊙ Δu′ (F is what the cells above carry at c:
/// the pull of the lower part on the upper, opposite to the opening it resists).
fn products(
    p: &FrontPoint,
    u: &[f64],
    f: &[f64],
    c: usize,
    upper: usize,
    lower: usize,
) -> [f64; 3] {
    let (fu, uu, ul) = (triple(f, c), triple(u, upper), triple(u, lower));
    let fl = local(fu, p);
    let dl = local([uu[0] - ul[0], uu[1] - ul[1], uu[2] - ul[2]], p);
    [
        -0.5 * fl[0] * dl[0],
        -0.5 * fl[1] * dl[1],
        -0.5 * fl[2] * dl[2],
    ]
}

/// The length of a quadratic edge (corner `far`, midside `mid`, corner `near`; ξ = −1, 0, 1)
/// from its midside node to `near`: ∫₀¹ |x′(ξ)| dξ with x′ = x_far (ξ − ½) − 2ξ x_mid +
/// x_near (ξ + ½), by 5-point Gauss–Legendre (a quarter ellipse's arc to 1e-9 relative).
fn half_edge_length(nodes: &[[f64; 3]], far: usize, mid: usize, near: usize) -> f64 {
    // Gauss–Legendre on [−1, 1] (roots ±x₁, ±x₂, 0), moved to [0, 1].
    const X: [f64; 5] = [
        -0.906_179_845_938_664,
        -0.538_469_310_105_683_1,
        0.0,
        0.538_469_310_105_683_1,
        0.906_179_845_938_664,
    ];
    const W: [f64; 5] = [
        0.236_926_885_056_189_1,
        0.478_628_670_499_366_5,
        0.568_888_888_888_888_9,
        0.478_628_670_499_366_5,
        0.236_926_885_056_189_1,
    ];
    let (a, m, b) = (nodes[far], nodes[mid], nodes[near]);
    X.iter()
        .zip(W)
        .map(|(&x, w)| {
            let xi = 0.5 * (x + 1.0);
            let d: [f64; 3] =
                std::array::from_fn(|k| a[k] * (xi - 0.5) - 2.0 * xi * m[k] + b[k] * (xi + 0.5));
            0.5 * w * (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt()
        })
        .sum()
}

fn distance(nodes: &[[f64; 3]], a: usize, b: usize) -> f64 {
    let (p, q) = (nodes[a], nodes[b]);
    (p[0] - q[0]).hypot(p[1] - q[1]).hypot(p[2] - q[2])
}

fn add(a: &mut [f64; 3], b: [f64; 3], w: f64) {
    for k in 0..3 {
        a[k] += w * b[k];
    }
}

/// The union of the cells above the delamination plane touching the front (c and d nodes),
/// sorted: the cells whose internal forces VCCT needs (thesis §2.8).
pub fn cells_above(front: &Front) -> Vec<usize> {
    let mut v: Vec<usize> = front
        .points
        .iter()
        .flat_map(|p| p.cells_above.iter().copied())
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// G_I, G_II, G_III and G_T at every corner node of `front` (thesis §2.8).
///
/// `u` are the nodal displacements and `forces` the internal forces of the cells above the
/// delamination plane (both node-major over the whole model; see [`cells_above`]).
///
/// Hex20 fronts (corner and midside nodes alternate): at corner c_i eq. 2.8.1,
/// Ē = Ē(a_i a′_i c_i) + Ē(b_i b′_i d_i) + ½ [Ē(a_{i−1} a′_{i−1} c_{i−1}) + Ē(a_{i+1} a′_{i+1} c_{i+1})],
/// with Ē = −½ F′·Δu′ per mode in the local frame (eq. 2.8.2), and
/// G = Ē / (Δa · |c_{i−1} c_{i+1}|). At an end of the front only one midside neighbour exists; its
/// half and the half-length to it are used (exact on a symmetry plane, where the cells on one
/// side carry half the force). With [`FrontWidths::AlongEdges`] the width |c_{i−1} c_{i+1}| is
/// the length along the two quadratic edges instead of the chord (a curved front). Hex8 fronts (corners only): G = Ē(a_i a′_i c_i) /
/// (Δa · ½ (|c_{i−1} c_i| + |c_i c_{i+1}|)).
///
/// Errors: lengths that do not match the nodes, node indices out of range, non-finite input, or a
/// degenerate closure area.
pub fn release_rates(
    front: &Front,
    nodes: &[[f64; 3]],
    u: &[f64],
    forces: &[f64],
) -> Result<Vec<FrontRelease>, VcctError> {
    let n = 3 * nodes.len();
    for (what, v) in [("displacements", u), ("forces", forces)] {
        if v.len() != n {
            return Err(VcctError::Length {
                what,
                expected: n,
                got: v.len(),
            });
        }
        if let Some(d) = v.iter().position(|x| !x.is_finite()) {
            return Err(VcctError::NonFinite { what, dof: d });
        }
    }
    let pts = &front.points;
    if pts.is_empty() {
        return Err(VcctError::EmptyFront);
    }
    for p in pts {
        let ids = [
            Some(p.c),
            Some(p.a_upper),
            Some(p.a_lower),
            p.b_upper,
            p.b_lower,
            p.d,
        ];
        if let Some(bad) = ids.into_iter().flatten().find(|&i| i >= nodes.len()) {
            return Err(VcctError::Node {
                node: bad,
                count: nodes.len(),
            });
        }
    }
    let quadratic = pts.iter().any(|p| !p.corner);
    let own = |p: &FrontPoint| -> [f64; 3] {
        let mut e = products(p, u, forces, p.c, p.a_upper, p.a_lower);
        if let (Some(d), Some(bu), Some(bl)) = (p.d, p.b_upper, p.b_lower) {
            add(&mut e, products(p, u, forces, d, bu, bl), 1.0);
        }
        e
    };
    let mut out = Vec::new();
    for (i, p) in pts.iter().enumerate() {
        if !p.corner {
            continue;
        }
        let prev = i.checked_sub(1).map(|j| &pts[j]);
        let next = pts.get(i + 1);
        let mut e = own(p);
        let width = if quadratic {
            for q in [prev, next].into_iter().flatten().filter(|q| !q.corner) {
                add(&mut e, own(q), 0.5);
            }
            match front.widths {
                FrontWidths::Chords => match (prev, next) {
                    (Some(a), Some(b)) => distance(nodes, a.c, b.c),
                    (Some(a), None) | (None, Some(a)) => distance(nodes, a.c, p.c),
                    (None, None) => 0.0,
                },
                FrontWidths::AlongEdges => {
                    let far = |j: Option<usize>| j.and_then(|j| pts.get(j)).map(|q| q.c);
                    let half = |mid: Option<&FrontPoint>, end: Option<usize>| match (mid, end) {
                        (Some(m), Some(e)) => half_edge_length(nodes, e, m.c, p.c),
                        _ => 0.0,
                    };
                    half(prev, far(i.checked_sub(2))) + half(next, far(Some(i + 2)))
                }
            }
        } else {
            0.5 * (prev.map_or(0.0, |a| distance(nodes, a.c, p.c))
                + next.map_or(0.0, |b| distance(nodes, b.c, p.c)))
        };
        let area = p.delta_a * width;
        if !(area > 0.0 && area.is_finite()) {
            return Err(VcctError::Area { node: p.c, area });
        }
        let ua = triple(u, p.a_upper);
        let la = triple(u, p.a_lower);
        let opening = local([ua[0] - la[0], ua[1] - la[1], ua[2] - la[2]], p)[2];
        let (g_iii, g_ii, g_i) = (e[0] / area, e[1] / area, e[2] / area);
        out.push(FrontRelease {
            node: p.c,
            s: p.s,
            theta_deg: p.theta_deg,
            x: p.x,
            y: p.y,
            delta_a: p.delta_a,
            area,
            g_i,
            g_ii,
            g_iii,
            g_t: g_i + g_ii + g_iii,
            opening,
        });
    }
    Ok(out)
}

/// Total closure energy Σ Ē_T over the whole front (J): the VCCT estimate of −ΔU for a front
/// advance by one element ring, to compare with the energy difference of two solutions.
pub fn closure_energy(rates: &[FrontRelease]) -> f64 {
    rates.iter().map(|r| r.g_t * r.area).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn with_opening(opening: f64) -> FrontRelease {
        FrontRelease {
            node: 0,
            s: 0.0,
            theta_deg: 0.0,
            x: 0.0,
            y: 0.0,
            delta_a: 0.5e-3,
            area: 1e-6,
            g_i: 0.0,
            g_ii: 0.0,
            g_iii: 0.0,
            g_t: 0.0,
            opening,
        }
    }

    /// A straight edge's half is half its length; on a 5° arc of radius 15 mm the quadratic
    /// through the arc's ends and middle is within 1e-6 of the arc (the chord, 3.2e-4 short).
    #[test]
    fn a_half_edge_is_measured_along_the_quadratic() {
        let nodes = [[0.0, 0.0, 0.0], [1.5, 0.0, 0.0], [3.0, 0.0, 0.0]];
        assert!((half_edge_length(&nodes, 0, 1, 2) - 1.5).abs() < 1e-15);
        let (r, d) = (15e-3, 5f64.to_radians());
        let on = |t: f64| [r * t.cos(), r * t.sin(), 0.0];
        let arc = [on(-d), on(0.0), on(d)];
        let half = half_edge_length(&arc, 0, 1, 2);
        assert!(
            (half / (r * d) - 1.0).abs() < 2e-6,
            "{}",
            half / (r * d) - 1.0
        );
        assert!(distance(&arc, 1, 2) / (r * d) - 1.0 < -1e-4);
    }

    /// The widths of a whole front add up to its length: Σ area/Δa over the corner points is
    /// the quarter circle's πa/2 to 1e-5 when the front's mid-edge nodes lie on it and VCCT
    /// measures along the edges; the thesis's chords between mid-edge nodes on chords miss it
    /// by the mid-edge chords' shortfall, about (1/8 + 1/24)·δ² (1.3e-3 at the default mesh's 5° arcs).
    #[test]
    fn the_widths_along_a_curved_front_add_up_to_its_length() {
        use nonlin3d_mesh::{
            DEFAULT_MESH, EmbeddedParams, MidEdges, embedded_delamination_with_front,
        };
        let base = EmbeddedParams::thesis_reference().with_accuracy_row(&DEFAULT_MESH);
        let quarter = std::f64::consts::FRAC_PI_2 * base.a;
        let mut relative = Vec::new();
        for mid_edges in [MidEdges::Mapped, MidEdges::Chords] {
            let p = EmbeddedParams {
                mid_edges,
                ..base.clone()
            };
            let (m, front) = embedded_delamination_with_front(&p).unwrap();
            let zero = vec![0.0; 3 * m.nodes.len()];
            let rates = release_rates(&front, &m.nodes, &zero, &zero).unwrap();
            let length: f64 = rates.iter().map(|r| r.area / r.delta_a).sum();
            relative.push(length / quarter - 1.0);
        }
        assert!(relative[0].abs() < 1e-5, "along the edges: {}", relative[0]);
        assert!(relative[1] < -5e-4, "chords: {}", relative[1]);
    }

    /// An unbuckled state's openings are round-off (−1.4e-20 m seen on the reference scene):
    /// open. An overlap of a micrometre behind a 0.5 mm element is an overlap.
    #[test]
    fn round_off_is_open_and_a_real_overlap_is_not() {
        assert!(with_opening(-1.4e-20).open());
        assert!(with_opening(0.0).open());
        assert!(with_opening(2e-5).open());
        assert!(!with_opening(-1e-6).open());
        assert!(!with_opening(-1e-11).open());
    }
}
