//! The planform mesh of thesis §3.1 (Fig. 3.1.1): the 2-D quarter section 0 ≤ x, y ≤ W of
//! quadrilaterals — a centre, rings graded towards the front circle, the rings beyond the
//! transition blended into the square — with every point taken through the planform map
//! (eq. 3.1.1–3.1.2 or the rectangle, module `maps`).

use super::layers::{Column, LayerTransition, MID_FRACTION};
use super::maps::{EllipticMap, front_radius, planform, radial_stations};
use super::{Centre, EmbeddedParams, FrontBand, MidEdges};
use crate::MeshError;
use std::f64::consts::{FRAC_PI_2, FRAC_PI_4};

/// The 2-D quarter section of §3.1, already mapped onto the planform.
pub(super) struct Section {
    /// Vertex positions (x, y), m.
    pub(super) points: Vec<[f64; 2]>,
    /// Whether each vertex lies strictly inside the front (its node on z = H is duplicated).
    pub(super) inside: Vec<bool>,
    /// Which thickness stations each vertex carries (the layer band, issue 25).
    pub(super) column: Vec<Column>,
    /// Where each vertex lies in the circular mesh before the map (for mapped mid-edges).
    source: Vec<Source>,
    /// The map and blend every point goes through; `Some` when the mid-edge nodes are mapped
    /// too ([`MidEdges::Mapped`]), `None` when they sit on the chords.
    curve: Option<Curve>,
    /// The arcs of the layer band's 1 → 2 transition rings (module `layers`); their
    /// quadrilaterals are not in `quads`.
    pub(super) layer_transitions: Vec<LayerTransition>,
    /// Quadrilaterals, counter-clockwise seen from +z: the centre's, then ring by ring.
    pub(super) quads: Vec<[usize; 4]>,
    /// `rings[m][q]`: the vertex of ring m at slice q (q = 0 on the x axis, q = slices on the
    /// y axis); ring 0 is the boundary of the centre, ring m ≥ 1 radial station m − 1.
    pub(super) rings: Vec<Vec<usize>>,
    /// The vertex at the centre (x = y = 0, or the thesis's arc node on y = 0).
    pub(super) centre: usize,
    /// The index in `rings` of the front ring (the front circle ρ = min(a, b) before the map).
    pub(super) front_ring: usize,
}

/// Where a section vertex lies in the circular mesh of §3.1, before the planform map.
#[derive(Debug, Clone, Copy)]
enum Source {
    /// A ring vertex: radius r and angle φ from the x axis, and whether its ring's arcs are
    /// curved (with mapped mid-edges: every ring, or with a front band the band's rings only).
    Polar(f64, f64, bool),
    /// A vertex of the layer band's transition: a fraction t of the way from vertex c to vertex
    /// f of its slice line; its arcs blend theirs alike.
    Between(usize, usize, f64),
    /// Any other vertex (the core, the front band's transition): its edges stay straight.
    Joint,
}

/// The planform's point map (§3.1): eq. 3.1.1–3.1.2 (or the rectangle) up to the transition
/// radius, the blend into the square beyond.
#[derive(Debug, Clone, Copy)]
struct Curve {
    map: EllipticMap,
    a: f64,
    b: f64,
    /// Half-width W of the square.
    w: f64,
    /// The transition radius of the circular mesh (`transition`·min(a, b)).
    wt: f64,
}

impl Curve {
    fn new(p: &EmbeddedParams) -> Self {
        Self {
            map: p.map,
            a: p.a,
            b: p.b,
            w: p.w,
            wt: p.transition * front_radius(p),
        }
    }

    /// A point (x, y) of the circular mesh taken through the planform map (eq. 3.1.1–3.1.2 or
    /// the rectangle of Fig. 3.1.3).
    fn plane(&self, x: f64, y: f64) -> [f64; 2] {
        let (u, v) = planform(self.map, self.a, self.b, x, y);
        [u, v]
    }

    /// The point at radius r on the slice line at angle φ (§3.1, Fig. 3.1.1c): the planform
    /// map of the circle point for r ≤ `wt`; beyond, the straight blend from the mapped
    /// transition ring (β = 0) to the square boundary (β = 1 at W).
    fn polar(&self, r: f64, phi: f64) -> [f64; 2] {
        if r <= self.wt {
            return self.plane(r * phi.cos(), r * phi.sin());
        }
        let on_ring = self.plane(self.wt * phi.cos(), self.wt * phi.sin());
        let beta = (r - self.wt) / (self.w - self.wt);
        // The y axis (φ = (π/2)·n/n, within round-off of π/2): the corner (0, W) exactly.
        let sq = if same(phi, FRAC_PI_2) {
            [0.0, self.w]
        } else if phi <= FRAC_PI_4 {
            [self.w, self.w * phi.tan()]
        } else {
            [self.w / phi.tan(), self.w]
        };
        [
            (1.0 - beta) * on_ring[0] + beta * sq[0],
            (1.0 - beta) * on_ring[1] + beta * sq[1],
        ]
    }
}

/// Whether two circular-mesh coordinates are the same station (radii of one ring, angles of
/// one slice line computed as q/n and 3q/3n): equal to 1e-12 relative.
fn same(u: f64, v: f64) -> bool {
    (u - v).abs() <= 1e-12 * u.abs().max(v.abs()).max(1e-300)
}

/// Whether a ring of n arcs is curved by mapped mid-edges: every ring without a front band,
/// only the band's rings (n = [`FrontBand::FACTOR`]·slices) with one (module doc of
/// [`Section::mid_point`]).
fn curved_ring(p: &EmbeddedParams, n: usize) -> bool {
    p.front_band.is_none() || n == FrontBand::FACTOR * p.slices
}

/// The angle φ = (π/2)·q/n of slice line q of n in the circular mesh (§3.1).
fn angle(q: usize, n: usize) -> f64 {
    FRAC_PI_2 * q as f64 / n as f64
}

/// Arcs of the ring at radial station m0 (index into the radial stations, `front` the front
/// circle's): `slices`, or [`FrontBand::FACTOR`]·`slices` inside the front band (issue 25).
fn arcs(p: &EmbeddedParams, m0: usize, front: usize) -> usize {
    match p.front_band {
        Some(b) if m0 + b.inside >= front && m0 <= front + b.outside => {
            FrontBand::FACTOR * p.slices
        }
        _ => p.slices,
    }
}

/// The §3.1 planform mesh: centre, rings at the radial stations (the front ring mapped onto
/// the ellipse by eq. 3.1.1–3.1.2), and their quadrilaterals.
pub(super) fn section(p: &EmbeddedParams) -> Result<Section, MeshError> {
    let (rho, front) = radial_stations(p)?;
    let curve = Curve::new(p);
    let mut s = Section {
        points: Vec::new(),
        inside: Vec::new(),
        column: Vec::new(),
        source: Vec::new(),
        curve: (p.mid_edges == MidEdges::Mapped).then_some(curve),
        layer_transitions: Vec::new(),
        quads: Vec::new(),
        rings: Vec::new(),
        centre: 0,
        front_ring: front + 1,
    };
    // The core and its joining ring lie outside every layer band (inside < radial_inside).
    let core = if p.layer_band.is_some() {
        Column::Half
    } else {
        Column::Full
    };
    let ring0 = match p.centre {
        Centre::OGrid => s.o_grid_core(&curve, p.slices, 0.5 * rho[0], core),
        Centre::ThesisArc => s.thesis_arc(p, &curve, core),
    };
    s.rings.push(ring0);
    // Ring nodes: the planform map (ellipse or rectangle) of the circle point up to the
    // transition ring; beyond it, points on the straight line from the mapped transition ring to
    // the square boundary, reached on the last ring. Monotone whenever the mapped transition
    // ring lies inside the square, which `check` ensures: it needs transition·max(a, b) < W, and
    // every map sends the ring ρ = t·r₀ (t ≥ 1) inside |x| ≤ t·a, |y| ≤ t·b (eq. 3.1.1 for
    // a ≤ b: semi-axes t·a and √(t²a² + b² − a²) ≤ t·b; mirrored for a > b).
    for (m0, &r) in rho.iter().enumerate() {
        let n = arcs(p, m0, front);
        let col = column(p, m0, front);
        let ring = (0..=n)
            .map(|q| {
                let phi = angle(q, n);
                let source = Source::Polar(r, phi, curved_ring(p, n));
                s.push(curve.polar(r, phi), source, m0 < front, col)
            })
            .collect();
        s.rings.push(ring);
    }
    s.ring_quads(p, front);
    Ok(s)
}

/// The column of the vertices on radial station m0 (`front` the front circle's): every
/// thickness station in the layer band (or without one), every other one elsewhere.
fn column(p: &EmbeddedParams, m0: usize, front: usize) -> Column {
    if p.full_layers_at(m0, front) {
        Column::Full
    } else {
        Column::Half
    }
}

impl Section {
    /// Adds a vertex of the §3.1 section (`inside`: strictly inside the front); its index.
    fn push(&mut self, point: [f64; 2], source: Source, inside: bool, column: Column) -> usize {
        self.points.push(point);
        self.source.push(source);
        self.inside.push(inside);
        self.column.push(column);
        self.points.len() - 1
    }

    /// The point of the Hex20 mid-edge node between vertices `va` and `vb` (thesis §3.1):
    /// their midpoint ([`MidEdges::Chords`]), or with [`MidEdges::Mapped`] on an arc of a
    /// curved ring the map of the arc's mid-angle point, so the ring is a quadratic curve
    /// through its map (and on the layer band's transition arcs the same blend of the arcs
    /// either side as its vertices are of theirs). Every other edge stays straight: the slice
    /// lines of eq. 3.1.2 bend sharply where its scale factor F = ρ/r reaches 1 (on the 30 × 60
    /// mm ellipse a mid-radius node 0.2 mm off the chord of a 1.4 mm edge), and a coarse arc
    /// bowed by its sagitta (0.8 mm on the same ellipse's four-slice companion) would invert the
    /// front band's transition cells that span three fine arcs.
    pub(super) fn mid_point(&self, va: usize, vb: usize) -> [f64; 2] {
        let (pa, pb) = (self.points[va], self.points[vb]);
        let chord = [0.5 * (pa[0] + pb[0]), 0.5 * (pa[1] + pb[1])];
        let Some(curve) = &self.curve else {
            return chord;
        };
        match (self.source[va], self.source[vb]) {
            (Source::Polar(r, f, true), Source::Polar(r2, f2, true)) if same(r, r2) => {
                curve.polar(r, 0.5 * (f + f2))
            }
            (Source::Between(c, f, t), Source::Between(c2, f2, t2)) if t == t2 => {
                let (mc, mf) = (self.mid_point(c, c2), self.mid_point(f, f2));
                [mc[0] + t * (mf[0] - mc[0]), mc[1] + t * (mf[1] - mc[1])]
            }
            _ => chord,
        }
    }

    /// The O-grid centre (this crate's change to §3.1): a square core [0, c]² with c = ρ₀/2
    /// (its corner at 0.71 ρ₀) of k × k cells, k = slices/2, mapped by eq. 3.1.1–3.1.2; one ring
    /// of cells joins its boundary to the first circle ρ₀, so no cell is degenerate. Returns
    /// the core boundary counter-clockwise from the x axis (q ≤ k on x = c, q ≥ k on y = c).
    fn o_grid_core(&mut self, curve: &Curve, slices: usize, c: f64, col: Column) -> Vec<usize> {
        let k = slices / 2;
        let mut core_id = vec![vec![0usize; k + 1]; k + 1];
        for (j, row) in core_id.iter_mut().enumerate() {
            for (i, id) in row.iter_mut().enumerate() {
                let (x, y) = (c * i as f64 / k as f64, c * j as f64 / k as f64);
                *id = self.push(curve.plane(x, y), Source::Joint, true, col);
            }
        }
        self.centre = core_id[0][0];
        for j in 0..k {
            for i in 0..k {
                self.quads.push([
                    core_id[j][i],
                    core_id[j][i + 1],
                    core_id[j + 1][i + 1],
                    core_id[j + 1][i],
                ]);
            }
        }
        (0..=slices)
            .map(|q| {
                if q <= k {
                    core_id[q][k]
                } else {
                    core_id[k][2 * k - q]
                }
            })
            .collect()
    }

    /// The thesis's centre (§3.1): the axis nodes spread on an arc of radius 1e-9 m (mapped by
    /// eq. 3.1.1–3.1.2), so the first ring of cells is nearly triangular. Returns the arc nodes.
    fn thesis_arc(&mut self, p: &EmbeddedParams, curve: &Curve, col: Column) -> Vec<usize> {
        let slices = p.slices;
        let ring: Vec<usize> = (0..=slices)
            .map(|q| {
                let phi = angle(q, slices);
                let pt = curve.plane(1e-9 * phi.cos(), 1e-9 * phi.sin());
                self.push(
                    pt,
                    Source::Polar(1e-9, phi, curved_ring(p, slices)),
                    true,
                    col,
                )
            })
            .collect();
        self.centre = ring[0];
        ring
    }

    /// The quadrilaterals between consecutive rings (Fig. 3.1.1), counter-clockwise from +z;
    /// between a ring of n arcs and one of 3n (the front band's edges, issue 25) the conformal
    /// transition of [`Section::transition_quads`]; between stations with the full layers and
    /// with half (the layer band's edges) the arcs of [`Section::layer_transition`] instead.
    fn ring_quads(&mut self, p: &EmbeddedParams, front: usize) {
        for m in 0..self.rings.len() - 1 {
            let (ni, no) = (self.rings[m].len() - 1, self.rings[m + 1].len() - 1);
            // Rings m and m + 1 are stations m − 1 and m; inside the front when m ≤ front.
            if m >= 1 && p.full_layers_at(m - 1, front) != p.full_layers_at(m, front) {
                self.layer_transition(m, m <= front);
            } else if ni == no {
                for q in 0..ni {
                    self.quads.push([
                        self.rings[m][q],
                        self.rings[m + 1][q],
                        self.rings[m + 1][q + 1],
                        self.rings[m][q + 1],
                    ]);
                }
            } else {
                let col = self.column[self.rings[m + 1][0]];
                self.transition_quads(m, m <= front, col);
            }
        }
    }

    /// The layer band's 1 → 2 transition between ring m and ring m + 1 (the same arcs; one
    /// carries every thickness station, the other every other one, module `layers`): a middle
    /// vertex on each slice line, [`MID_FRACTION`] of the way from the coarse side, and one
    /// [`LayerTransition`] per arc.
    fn layer_transition(&mut self, m: usize, inside: bool) {
        let coarse_inside = self.column[self.rings[m][0]] == Column::Half;
        let (c, f) = if coarse_inside {
            (m, m + 1)
        } else {
            (m + 1, m)
        };
        let n = self.rings[c].len() - 1;
        let mid: Vec<usize> = (0..=n)
            .map(|q| {
                let (pc, pf) = (self.points[self.rings[c][q]], self.points[self.rings[f][q]]);
                let t = MID_FRACTION;
                let pt = [pc[0] + t * (pf[0] - pc[0]), pc[1] + t * (pf[1] - pc[1])];
                let source = Source::Between(self.rings[c][q], self.rings[f][q], t);
                self.push(pt, source, inside, Column::Mid)
            })
            .collect();
        for q in 0..n {
            self.layer_transitions.push(LayerTransition {
                coarse: [self.rings[c][q], self.rings[c][q + 1]],
                mid: [mid[q], mid[q + 1]],
                fine: [self.rings[f][q], self.rings[f][q + 1]],
            });
        }
    }

    /// An interior vertex of the 1 → 3 transition: halfway from the point a fraction t along the
    /// chord A–B of the coarse arc (coarse arcs stay straight) to the fine vertex F.
    fn interior(
        &mut self,
        a: usize,
        b: usize,
        f: usize,
        t: f64,
        inside: bool,
        col: Column,
    ) -> usize {
        let (pa, pb, pf) = (self.points[a], self.points[b], self.points[f]);
        let chord = [pa[0] + t * (pb[0] - pa[0]), pa[1] + t * (pb[1] - pa[1])];
        let pt = [0.5 * (chord[0] + pf[0]), 0.5 * (chord[1] + pf[1])];
        self.push(pt, Source::Joint, inside, col)
    }

    /// The conformal 1 → 3 transition between ring m and ring m + 1 (one of them has
    /// [`FrontBand::FACTOR`] times the other's arcs): each coarse arc A–B faces fine vertices
    /// F0…F3; two interior vertices I1, I2, halfway from the points 1/3 and 2/3 along the chord
    /// A–B to F1 and F2 (so they stay between the chord and the fine ring however curved),
    /// close four quadrilaterals A F0 F1 I1, I1 F1 F2 I2, I2 F2 F3 B and A I1 I2 B (coarse ring
    /// inside; mirrored when the coarse ring is outside). Every vertex is shared, so the mesh
    /// stays conformal and reproduces linear fields exactly.
    fn transition_quads(&mut self, m: usize, inside: bool, col: Column) {
        let coarse_inside = self.rings[m].len() < self.rings[m + 1].len();
        let (c, f) = if coarse_inside {
            (m, m + 1)
        } else {
            (m + 1, m)
        };
        let n = self.rings[c].len() - 1;
        let k = FrontBand::FACTOR;
        for q in 0..n {
            let (a, b) = (self.rings[c][q], self.rings[c][q + 1]);
            let fv: Vec<usize> = (0..=k).map(|j| self.rings[f][k * q + j]).collect();
            let [i1, i2] =
                [1, 2].map(|j| self.interior(a, b, fv[j], j as f64 / k as f64, inside, col));
            // Each quad as (inner q, outer q, outer q + 1, inner q + 1), as the ring quads.
            let quads = if coarse_inside {
                [
                    [a, fv[0], fv[1], i1],
                    [i1, fv[1], fv[2], i2],
                    [i2, fv[2], fv[3], b],
                    [a, i1, i2, b],
                ]
            } else {
                [
                    [fv[0], a, i1, fv[1]],
                    [fv[1], i1, i2, fv[2]],
                    [fv[2], i2, b, fv[3]],
                    [i1, a, b, i2],
                ]
            };
            self.quads.extend(quads);
        }
    }
}
