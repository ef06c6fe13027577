//! The planform maps of thesis §3.1: the front circle of the circular mesh onto the ellipse
//! (eq. 3.1.1, 3.1.2) or onto a rectangle (Fig. 3.1.3), and the radial stations of that mesh.
//!
//! Every map stretches along the long axis only, so the front circle has the SHORT semi-axis
//! min(a, b) as its radius: eq. 3.1.1 is written for b > a (circle of radius a, y stretched);
//! for a > b "x and y are interchanged" (§3.1), the circle has radius b and x is stretched. The
//! maps below are written once for a ≤ b and mirrored about x = y for a > b, so the mesh of
//! (a, b) is the mirror image of the mesh of (b, a).

use super::EmbeddedParams;
use crate::MeshError;
use crate::generators::grading::graded_to_last;
use crate::generators::{graded_coordinates, graded_from_first};

/// Which elliptic map turns the front circle into the ellipse.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum EllipticMap {
    /// Eq. 3.1.1: y′ = y·√(1 + (b² − a²)/(x² + y²)) maps the circle of radius a onto the
    /// ellipse for b ≥ a; x and y swapped when a > b (circle of radius b, x stretched).
    /// Conformal.
    Conformal,
    /// Eq. 3.1.2: the stretch of eq. 3.1.1 scaled by F = ρ/r for ρ ≤ r, F = 1 beyond; `r` a
    /// little below the front circle's radius min(a, b) keeps the front region conformal and
    /// spreads the refinement more evenly.
    Modified {
        /// The radius r of eq. 3.1.2 (m), 0 < r ≤ min(a, b).
        r: f64,
    },
    /// Not elliptic: a square or rectangular delamination of half-sides a × b (§5.3,
    /// Fig. 3.1.3): the circular arcs are stretched radially onto the sides of a square of
    /// half-side min(a, b), then the long direction is magnified by max(a, b)/min(a, b). Not
    /// conformal (the thesis notes the loss of orthogonality at the front).
    Rectangle,
}

impl EllipticMap {
    /// r/min(a, b) of [`EllipticMap::modified_for`]: below the ring just behind the front
    /// (0.923·min(a, b) on the reference mesh), so the cells on both sides of the front keep
    /// eq. 3.1.1's orthogonality, which the single-solution VCCT relies on.
    pub const MODIFIED_R_FRACTION: f64 = 0.9;

    /// Eq. 3.1.2 with r = 0.9·min(a, b): the map for ellipses. Eq. 3.1.1's stretch
    /// √(1 + (b² − a²)/ρ²) diverges at the centre, mapping the inner rings onto slivers along
    /// the long axis (min scaled Jacobian 0.074 at a/b = 1/2, 0.045 at 1/3); its onset
    /// strains of elliptic sublaminates come out 5.8 % (a/b = 1/2) and 10 % (1/3) stiff, eq.
    /// 3.1.2's within the circle's 0.5 % (docs/VALIDATION.md).
    pub fn modified_for(a: f64, b: f64) -> Self {
        Self::Modified {
            r: Self::MODIFIED_R_FRACTION * a.min(b),
        }
    }
}

/// The radius of the front circle in the circular mesh: the short semi-axis min(a, b), the
/// circle that eq. 3.1.1 (or the rectangle's stretch) maps onto the front.
pub(super) fn front_radius(p: &EmbeddedParams) -> f64 {
    p.a.min(p.b)
}

/// Radial stations: core radius … r₀ = min(a, b) (graded finer towards r₀), r₀ … W (finer at
/// r₀), as radii of the circular mesh (the outer ones become blend parameters towards the
/// square); and the index of the front circle.
pub(super) fn radial_stations(p: &EmbeddedParams) -> Result<(Vec<f64>, usize), MeshError> {
    let r0 = front_radius(p);
    let rc = p.core_fraction * r0;
    let inside = match p.front_element {
        Some(e) => graded_to_last(p.radial_inside, r0 - rc, e)?,
        None => graded_coordinates(p.radial_inside, r0 - rc, p.front_grading)?,
    };
    // The ring ahead of the front as wide as the one behind it (VCCT pairs them, §2.8).
    let behind = inside[inside.len() - 1] - inside[inside.len() - 2];
    let outside = graded_from_first(p.radial_outside, p.w - r0, behind)?;
    let mut rho: Vec<f64> = inside.iter().map(|d| rc + d).collect();
    let front = rho.len() - 1;
    rho.extend(outside.iter().skip(1).map(|d| r0 + d));
    Ok((rho, front))
}

/// The planform map of a point (x, y) of the circular mesh (eq. 3.1.1 / 3.1.2, or the
/// rectangle): for a ≤ b y is stretched; for a > b the point is mirrored about x = y, mapped
/// with the semi-axes swapped, and mirrored back (§3.1: "x and y are interchanged").
pub(super) fn planform(map: EllipticMap, a: f64, b: f64, x: f64, y: f64) -> (f64, f64) {
    if a > b {
        let (v, u) = stretch_y(map, b, a, y, x);
        (u, v)
    } else {
        stretch_y(map, a, b, x, y)
    }
}

/// The maps for `short` ≤ `long` along x and y: the circle ρ = short goes onto the ellipse
/// (x/short)² + (y/long)² = 1 (eq. 3.1.1: x′ = x, y′ = y·√(1 + (long² − short²)/ρ²)), or onto
/// the rectangle |x| ≤ short, |y| ≤ long.
fn stretch_y(map: EllipticMap, short: f64, long: f64, x: f64, y: f64) -> (f64, f64) {
    if map == EllipticMap::Rectangle {
        // Radially onto the square of half-side ρ (max(|x|, |y|) = ρ), then y by long/short.
        let rho = x.hypot(y);
        let s = if rho > 0.0 {
            rho / x.abs().max(y.abs())
        } else {
            1.0
        };
        return (x * (1.0 + (s - 1.0)), y * (1.0 + (s * long / short - 1.0)));
    }
    if short == long {
        return (x, y);
    }
    let rho2 = x * x + y * y;
    let factor = if rho2 > 0.0 {
        let root = (1.0 + (long * long - short * short) / rho2).sqrt();
        match map {
            EllipticMap::Modified { r } => {
                // Eq. 3.1.2: root·F − F + 1.
                let f = (rho2.sqrt() / r).min(1.0);
                root * f - f + 1.0
            }
            EllipticMap::Conformal | EllipticMap::Rectangle => root,
        }
    } else {
        long / short
    };
    (x, y * (1.0 + (factor - 1.0)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_short_axis_circle_lands_on_the_ellipse_for_either_long_axis() {
        // Points of the circle ρ = min(a, b) satisfy (x′/a)² + (y′/b)² = 1 (eq. 3.1.1 with x and
        // y interchanged when a > b); the circle ρ = a, used before for a > b, does not.
        for (a, b) in [(10.0f64, 30.0f64), (30.0, 10.0), (15.0, 7.5), (7.5, 15.0)] {
            for map in [
                EllipticMap::Conformal,
                EllipticMap::Modified { r: 0.9 * a.min(b) },
            ] {
                for k in 0..=8 {
                    let phi = std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
                    let r0 = a.min(b);
                    let (x, y) = planform(map, a, b, r0 * phi.cos(), r0 * phi.sin());
                    let e = (x / a).powi(2) + (y / b).powi(2) - 1.0;
                    assert!(e.abs() < 1e-14, "{map:?} a={a} b={b} φ={phi}: {e}");
                }
            }
            if a > b {
                let (x, _) = planform(EllipticMap::Conformal, a, b, a, 0.0);
                assert!(x > a * 1.1, "the circle ρ = a overshoots the ellipse: {x}");
            }
        }
    }

    #[test]
    fn the_rectangle_starts_from_the_short_side() {
        // The circle ρ = min(a, b) goes onto the rectangle's sides; the short direction is not
        // scaled, the long one by max/min.
        for (a, b) in [(10.0, 30.0), (30.0, 10.0)] {
            let r0 = f64::min(a, b);
            for k in 0..=8 {
                let phi = std::f64::consts::FRAC_PI_2 * k as f64 / 8.0;
                let (x, y) = planform(EllipticMap::Rectangle, a, b, r0 * phi.cos(), r0 * phi.sin());
                let on_side = (x - a).abs() < 1e-12 || (y - b).abs() < 1e-12;
                assert!(
                    on_side && x <= a + 1e-12 && y <= b + 1e-12,
                    "{a} {b}: ({x}, {y})"
                );
            }
        }
    }
}
