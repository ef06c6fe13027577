//! The delamination front's planform as a curve, and the distance of a point of the
//! delamination plane from it, measured inside (thesis §3.2, Fig. 3.2.2: the nonlinear
//! substructure begins a distance ℓ inside the front).

use crate::generators::{EllipticMap, EmbeddedParams, ThroughWidthParams};

/// The front of a generated delamination model as a curve in the plane z = H (m), with the
/// delaminated region on its inside. The models are symmetric about x = 0 and y = 0 (quarter
/// or half models), so only |x| and |y| matter.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrontShape {
    /// The ellipse (x/a)² + (y/b)² = 1 (eq. 3.1.1–3.1.2): embedded, edge (§5.5: the same
    /// quarter mesh, free edge y = 0) and thin-film (§5.3) models.
    Ellipse {
        /// Semi-axis along x, m.
        a: f64,
        /// Semi-axis along y, m.
        b: f64,
    },
    /// The rectangle |x| ≤ a, |y| ≤ b (§5.3, Fig. 3.1.3).
    Rectangle {
        /// Half-side along x, m.
        a: f64,
        /// Half-side along y, m.
        b: f64,
    },
    /// The straight front x = a across the width (through-width model, Fig. 3.2.3),
    /// delaminated for x < a.
    Line {
        /// Delamination half-length, m.
        a: f64,
    },
}

impl FrontShape {
    /// The distance of (x, y) from the front, positive inside the delaminated region, negative
    /// outside, zero on the front: for the ellipse the distance to its foot point
    /// ([`ellipse_distance`]), for the rectangle min(a − |x|, b − |y|) inside (the Euclidean
    /// distance outside), for the line a − x.
    pub fn inside_distance(&self, x: f64, y: f64) -> f64 {
        let (x, y) = (x.abs(), y.abs());
        match *self {
            Self::Ellipse { a, b } => {
                let d = ellipse_distance(a, b, x, y);
                if (x / a).powi(2) + (y / b).powi(2) <= 1.0 {
                    d
                } else {
                    -d
                }
            }
            Self::Rectangle { a, b } => {
                if x <= a && y <= b {
                    (a - x).min(b - y)
                } else {
                    -(x - a).max(0.0).hypot((y - b).max(0.0))
                }
            }
            Self::Line { a } => a - x,
        }
    }

    /// The largest inside distance any point has: the inradius min(a, b) of the ellipse (its
    /// centre's distance, the short semi-axis) and of the rectangle; for the line, a (at x = 0).
    pub fn max_inside_distance(&self) -> f64 {
        match *self {
            Self::Ellipse { a, b } | Self::Rectangle { a, b } => a.min(b),
            Self::Line { a } => a,
        }
    }
}

impl EmbeddedParams {
    /// The front of the embedded, edge and thin-film models built from these parameters: the
    /// ellipse with semi-axes a, b (eq. 3.1.1–3.1.2), or the rectangle (Fig. 3.1.3).
    pub fn front_shape(&self) -> FrontShape {
        match self.map {
            EllipticMap::Rectangle => FrontShape::Rectangle {
                a: self.a,
                b: self.b,
            },
            EllipticMap::Conformal | EllipticMap::Modified { .. } => FrontShape::Ellipse {
                a: self.a,
                b: self.b,
            },
        }
    }
}

impl ThroughWidthParams {
    /// The front of the through-width model (Fig. 3.2.3): the line x = a.
    pub fn front_shape(&self) -> FrontShape {
        FrontShape::Line { a: self.a }
    }
}

/// The Euclidean distance from (x, y), x, y ≥ 0, to the ellipse (x/a)² + (y/b)² = 1, inside or
/// outside (Eberly's foot-point formulation). With the long semi-axis e₀ along u and the short
/// e₁ along v, r = (e₀/e₁)² and z = (u/e₀, v/e₁), the foot point is (r·u/(t + r − 1), v/t)
/// where t > 0 solves F(t) = (r z₀/(t + r − 1))² + (z₁/t)² − 1 = 0 (Eberly's s = t − 1,
/// written in t to avoid the cancellation in s + 1). Points within 1e-12 of a semi-axis of an
/// axis are taken on it (the distance is 1-Lipschitz, so that moves it by less than 1e-12 of
/// the semi-axis) and have closed forms: the foot point on the short axis is its vertex; on the
/// long axis, off the axis when u lies inside the evolute's cusp, u < (e₀² − e₁²)/e₀.
pub fn ellipse_distance(a: f64, b: f64, x: f64, y: f64) -> f64 {
    // Long axis first: (e0, u) along the long semi-axis.
    let (e0, e1, u, v) = if a >= b { (a, b, x, y) } else { (b, a, y, x) };
    if v <= 1e-12 * e1 {
        let (numer, denom) = (e0 * u, e0 * e0 - e1 * e1);
        if numer < denom {
            let xd = numer / denom;
            let (fx, fy) = (e0 * xd, e1 * (1.0 - xd * xd).max(0.0).sqrt());
            return (fx - u).hypot(fy);
        }
        return (u - e0).abs();
    }
    if u <= 1e-12 * e0 {
        return (v - e1).abs();
    }
    let (z0, z1) = (u / e0, v / e1);
    if z0 * z0 + z1 * z1 == 1.0 {
        return 0.0;
    }
    let r = (e0 / e1).powi(2);
    let t = foot_parameter(r, z0, z1);
    let (fx, fy) = (r * u / (t + r - 1.0), v / t);
    (fx - u).hypot(fy - v)
}

/// The root t > 0 of F(t) = (r z₀/(t + r − 1))² + (z₁/t)² − 1 (z₀, z₁ > 0, r ≥ 1): Newton from
/// t₀ = z₁, where F ≥ 0; F is decreasing and convex for t > 0, so the iterates climb
/// monotonically to the root. Stops when a step no longer increases t (at most 200 steps; from
/// z₁ ≥ 1e-12 the slowest case, u beyond the evolute's cusp, gains a factor ≥ 1.5 a step, so
/// about 70 suffice).
fn foot_parameter(r: f64, z0: f64, z1: f64) -> f64 {
    let mut t = z1;
    for _ in 0..200 {
        let (p, q) = (r * z0 / (t + r - 1.0), z1 / t);
        let f = p * p + q * q - 1.0;
        if f <= 0.0 {
            break;
        }
        let df = -2.0 * (p * p / (t + r - 1.0) + q * q / t);
        let next = t - f / df;
        if next <= t {
            break;
        }
        t = next;
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The distance from (x, y) to the ellipse as the nearest of n chords of the quarter
    /// ellipse (the foot point of a point in the first quadrant lies in it).
    fn polyline_distance(a: f64, b: f64, x: f64, y: f64, n: usize) -> f64 {
        let pt = |k: usize| {
            let t = std::f64::consts::FRAC_PI_2 * k as f64 / n as f64;
            [a * t.cos(), b * t.sin()]
        };
        (0..n)
            .map(|k| {
                let (p, q) = (pt(k), pt(k + 1));
                let d = [q[0] - p[0], q[1] - p[1]];
                let t = (((x - p[0]) * d[0] + (y - p[1]) * d[1]) / (d[0] * d[0] + d[1] * d[1]))
                    .clamp(0.0, 1.0);
                (x - p[0] - t * d[0]).hypot(y - p[1] - t * d[1])
            })
            .fold(f64::INFINITY, f64::min)
    }

    #[test]
    fn ellipse_distance_matches_a_fine_polyline() {
        // The polyline's chords lie inside the ellipse by at most their sagitta L²κ/8, L ≤
        // (π/2)·max(a, b)/n, κ ≤ max/min²; with n = 20 000 and a/b ≤ 4 that is below 2e-8 of
        // max(a, b); the tolerance 1e-7·max(a, b) covers it.
        let n = 20_000;
        for (a, b) in [
            (15.0, 15.0),
            (15.0, 7.5),
            (7.5, 15.0),
            (20.0, 5.0),
            (5.0, 20.0),
        ] {
            let tol = 1e-7 * f64::max(a, b);
            for i in 0..=12i32 {
                for j in 0..=12i32 {
                    // Off the grid by 1e-19 m on the axes: the round-off of the generators'
                    // x = 0 nodes, which once made s + 1 cancel to 0.
                    let off = |k: i32| if k == 0 { 1e-19 } else { 0.0 };
                    let (x, y) = (
                        1.3 * a * f64::from(i) / 12.0 + off(i),
                        1.3 * b * f64::from(j) / 12.0 + off(j),
                    );
                    let d = ellipse_distance(a, b, x, y);
                    let brute = polyline_distance(a, b, x, y, n);
                    assert!(
                        (d - brute).abs() < tol,
                        "a={a} b={b} ({x}, {y}): {d} vs polyline {brute}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_inside_distance_has_the_closed_forms_of_the_circle_and_the_axes() {
        // Circle: r₀ − ρ. Ellipse centre: the short semi-axis. Line and rectangle: their forms.
        let circle = FrontShape::Ellipse { a: 15.0, b: 15.0 };
        for (x, y) in [(3.0, 4.0), (0.0, 14.0), (-9.0, 12.0), (12.0, 16.0)] {
            let d = circle.inside_distance(x, y);
            assert!(
                (d - (15.0 - f64::hypot(x, y))).abs() < 1e-12,
                "({x}, {y}): {d}"
            );
        }
        let ellipse = FrontShape::Ellipse { a: 30.0, b: 10.0 };
        assert!((ellipse.inside_distance(0.0, 0.0) - 10.0).abs() < 1e-12);
        assert_eq!(ellipse.max_inside_distance(), 10.0);
        assert!((ellipse.inside_distance(30.0, 0.0)).abs() < 1e-12);
        assert!(ellipse.inside_distance(31.0, 0.0) < 0.0);
        let rect = FrontShape::Rectangle { a: 12.7, b: 25.4 };
        assert!((rect.inside_distance(10.0, 1.0) - 2.7).abs() < 1e-12);
        assert!((rect.inside_distance(15.7, 29.4) + 5.0).abs() < 1e-12);
        assert_eq!(FrontShape::Line { a: 10.0 }.inside_distance(7.5, 3.0), 2.5);
    }

    #[test]
    fn newton_reaches_the_foot_point_equation_to_round_off() {
        // At the returned t, F(t) is zero to round-off for points near the centre, the front
        // and the axes, from the circle (r = 1) to a 100:1 ellipse (r = 1e4).
        for r in [1.0, 1.0 + 1e-7, 4.0, 16.0, 1e4] {
            for (z0, z1) in [
                (0.01, 0.01),
                (0.5, 0.5),
                (0.7, 0.69),
                (1e-6, 0.3),
                (0.9, 1e-12),
            ] {
                let t = foot_parameter(r, z0, z1);
                let f = (r * z0 / (t + r - 1.0)).powi(2) + (z1 / t).powi(2) - 1.0;
                assert!(f.abs() < 1e-12, "r = {r} ({z0}, {z1}): t = {t}, F = {f}");
            }
        }
    }
}
