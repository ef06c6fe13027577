//! The layer band's through-thickness transition (issue 25, `EmbeddedParams::layer_band`): the
//! rings near the front keep every thickness station of §3.2 (`sub_layers`, `base_layers`), the
//! rest of the model every other one, and one ring on each side joins them conformally.
//!
//! In the radial–thickness plane the transition ring is a column of N coarse layers (N =
//! (`sub_layers` + `base_layers`)/2) on its coarse side against 2N fine layers on its fine
//! side. A quadrilateral region has an even number of edges, and one coarse layer against two
//! fine ones has five (1 + 2 + top + bottom), so a layer cannot be closed alone: each coarse
//! layer j (fine stations 2j, 2j + 1, 2j + 2) gets one extra vertex M on its top or bottom
//! edge, alternately, so that each M is shared by the two layers around it (with N odd the
//! first M lies on z = 0). The hexagon C₀ M F₀ F₁ F₂ C₂ (M on the bottom; C coarse side, F fine
//! side) is closed by one interior vertex I at the middle fine station and three quadrilaterals
//! C₀ M I C₂, M F₀ F₁ I, I F₁ F₂ C₂ (mirrored in z when M is on the top). M and I sit on the
//! radial line of their slice, a fraction [`MID_FRACTION`] of the ring's width from its coarse
//! side. Swept along the slices (the same template on every slice line), every face is shared
//! by exactly two cells or lies on the boundary, so the Hex20 mid-edge nodes, keyed by their
//! corners, stay conformal and linear fields are reproduced exactly (no tie).

/// Which thickness stations a section vertex carries nodes on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Column {
    /// Every station (the layer band, or the whole model without one).
    Full,
    /// Every other station (away from the front).
    Half,
    /// The transition ring's vertices M and I: the middle station of every coarse layer (I)
    /// and the coarse stations that carry an M.
    Mid,
}

/// Where M and I sit across the transition ring, as a fraction of its width from the coarse
/// side (the template's corner angles at the coarse side are about atan(t_f / (f·w)) for a
/// fine layer t_f thick in a ring w wide).
pub(super) const MID_FRACTION: f64 = 0.5;

/// One arc of a transition ring (slice lines q and q + 1, index 0 and 1): its vertices on the
/// coarse side, on the middle line (M and I) and on the fine side.
#[derive(Debug, Clone, Copy)]
pub(super) struct LayerTransition {
    /// The coarse side's ring vertices (every other station).
    pub(super) coarse: [usize; 2],
    /// The middle vertices (the `Mid` column).
    pub(super) mid: [usize; 2],
    /// The fine side's ring vertices (every station).
    pub(super) fine: [usize; 2],
}

impl Column {
    /// Whether a vertex of this column has a node on station l; `parity` is that of the
    /// coarse stations carrying an M ([`mid_parity`]).
    pub(super) fn has_station(self, l: usize, parity: usize) -> bool {
        match self {
            Self::Full => true,
            Self::Half => l.is_multiple_of(2),
            Self::Mid => l % 2 == 1 || mid_on(l, parity),
        }
    }
}

/// Whether M lies on station l: the even stations l = 2j with j of the given parity. Every
/// coarse layer j has stations j and j + 1, exactly one of either parity, so each has one M
/// on its bottom or top edge, shared with the layer beyond it (or on z = 0 or the top face).
fn mid_on(l: usize, parity: usize) -> bool {
    l.is_multiple_of(2) && (l / 2) % 2 == parity
}

/// A corner of the template: side (0 coarse, 1 middle, 2 fine) and station.
pub(super) type Corner = (usize, usize);

/// The three quadrilaterals of coarse layer j in the radial–thickness plane, each
/// counter-clockwise with the coarse-to-fine direction first and z second.
pub(super) fn template(j: usize, parity: usize) -> [[Corner; 4]; 3] {
    let (f0, f1, f2) = (2 * j, 2 * j + 1, 2 * j + 2);
    if mid_on(f0, parity) {
        // M on the bottom: C₀ M I C₂, M F₀ F₁ I, I F₁ F₂ C₂.
        [
            [(0, f0), (1, f0), (1, f1), (0, f2)],
            [(1, f0), (2, f0), (2, f1), (1, f1)],
            [(1, f1), (2, f1), (2, f2), (0, f2)],
        ]
    } else {
        // M on the top: C₀ I M C₂, I F₁ F₂ M, C₀ F₀ F₁ I.
        [
            [(0, f0), (1, f1), (1, f2), (0, f2)],
            [(1, f1), (2, f1), (2, f2), (1, f2)],
            [(0, f0), (2, f0), (2, f1), (1, f1)],
        ]
    }
}

/// The parity of the M stations (0 or 1) whose templates have the larger smallest corner
/// sine in the radial–thickness plane, over the thickness stations `z` and the transition
/// rings' widths `widths` (the sides at 0, [`MID_FRACTION`]·w and w). Which is better depends
/// on the grading: a base graded towards z = H wants M on the bottom of its layers, the
/// sublaminate graded from z = H on the top; both parities are valid.
pub(super) fn mid_parity(z: &[f64], widths: &[f64]) -> usize {
    let score = |parity: usize| {
        let mut worst = f64::INFINITY;
        for &w in widths {
            for j in 0..(z.len() - 1) / 2 {
                for quad in template(j, parity) {
                    let p: Vec<[f64; 2]> = quad
                        .iter()
                        .map(|&(side, st)| [[0.0, MID_FRACTION, 1.0][side] * w, z[st]])
                        .collect();
                    worst = worst.min(min_corner_sine(&p));
                }
            }
        }
        worst
    };
    if score(1) > score(0) { 1 } else { 0 }
}

/// The smallest sine of a corner angle of a quadrilateral (counter-clockwise; negative where a
/// corner is reflex).
fn min_corner_sine(p: &[[f64; 2]]) -> f64 {
    (0..4)
        .map(|k| {
            let (a, b, c) = (p[(k + 3) % 4], p[k], p[(k + 1) % 4]);
            let (u, v) = ([c[0] - b[0], c[1] - b[1]], [a[0] - b[0], a[1] - b[1]]);
            (u[0] * v[1] - u[1] * v[0]) / (u[0].hypot(u[1]) * v[0].hypot(v[1]))
        })
        .fold(f64::INFINITY, f64::min)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every coarse layer has exactly one M, on its bottom or top station, for either parity
    /// and N = 1…6 coarse layers.
    #[test]
    fn each_coarse_layer_has_one_mid_vertex_on_its_edges() {
        for n in 1..=6 {
            for parity in [0, 1] {
                for j in 0..n {
                    let (bottom, top) = (mid_on(2 * j, parity), mid_on(2 * j + 2, parity));
                    assert!(bottom ^ top, "N = {n}, layer {j}: {bottom} {top}");
                }
            }
        }
    }

    /// A base graded towards z = H (fine layers 3.7 and 0.3 mm) under a uniform sublaminate
    /// (0.2 + 0.2 mm) in a 0.45 mm ring: M on the bottom of the base layer and on the top of
    /// the sublaminate's (parity 0: z = 0 and the top face) keeps every corner above 30°, the
    /// other parity (M on z = H) puts a 175° corner in the base (sine ≈ 0.06).
    #[test]
    fn the_parity_follows_the_grading() {
        let z = [0.0, 3.7, 4.0, 4.2, 4.4];
        assert_eq!(mid_parity(&z, &[0.45]), 0);
        let quads = |parity| {
            (0..2)
                .flat_map(|j| template(j, parity))
                .map(|q| {
                    let p: Vec<[f64; 2]> = q
                        .iter()
                        .map(|&(side, st)| [[0.0, MID_FRACTION, 1.0][side] * 0.45, z[st]])
                        .collect();
                    min_corner_sine(&p)
                })
                .fold(f64::INFINITY, f64::min)
        };
        assert!(quads(0) > 0.5, "{}", quads(0));
        assert!(quads(1) < 0.1, "{}", quads(1));
    }

    /// The template's three quads are counter-clockwise in (coarse → fine, z) for unit
    /// spacing, and use exactly the hexagon's six boundary corners and I: areas add to the
    /// hexagon's (side 0 at 0, middle at ½, fine at 1; z = station).
    #[test]
    fn template_tiles_the_hexagon_counter_clockwise() {
        for parity in [0, 1] {
            for j in 0..3 {
                let area: f64 = template(j, parity)
                    .iter()
                    .map(|q| {
                        let p: Vec<[f64; 2]> = q
                            .iter()
                            .map(|&(side, st)| [0.5 * side as f64, st as f64])
                            .collect();
                        let a = (0..4)
                            .map(|k| {
                                let (u, v) = (p[k], p[(k + 1) % 4]);
                                u[0] * v[1] - v[0] * u[1]
                            })
                            .sum::<f64>()
                            / 2.0;
                        assert!(a > 0.0, "parity {parity}, j {j}: {q:?}");
                        a
                    })
                    .sum();
                // The column from side 0 to 1 over two stations: area 2.
                assert!((area - 2.0).abs() < 1e-12, "{area}");
            }
        }
    }
}
