//! Single-solution virtual crack closure along a delamination front (thesis §2.8, Fig. 2.8.1,
//! eq. 2.8.1–2.8.2).

use crate::VcctError;
use nonlin3d_mesh::{Front, FrontPoint};

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
/// side carry half the force). Hex8 fronts (corners only): G = Ē(a_i a′_i c_i) /
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
            match (prev, next) {
                (Some(a), Some(b)) => distance(nodes, a.c, b.c),
                (Some(a), None) | (None, Some(a)) => distance(nodes, a.c, p.c),
                (None, None) => 0.0,
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
