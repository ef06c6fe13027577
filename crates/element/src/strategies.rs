//! Proptest strategies for element invariants (feature `proptest`): random valid distorted
//! Hex8/Hex20 elements, SPD orthotropic materials and displacement fields of realistic size.
//!
//! ```
//! use nonlin3d_element::strategies::{distorted_element, material, displacements};
//! use nonlin3d_element::{ElementKind, IntegrationRule, ShapeTable, b0bl3d};
//! use proptest::prelude::*;
//! use proptest::test_runner::TestRunner;
//!
//! let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss2).unwrap();
//! let mut runner = TestRunner::default();
//! let strategy = distorted_element(ElementKind::Hex20)
//!     .prop_flat_map(|x| (Just(x.clone()), displacements(x, 0.02, 0.3), material()));
//! runner
//!     .run(&strategy, |(x, u, c)| {
//!         // Your invariant here: strain energy is never negative.
//!         let out = b0bl3d(&table, &x, &u, &c).unwrap();
//!         prop_assert!(out.energy >= 0.0);
//!         Ok(())
//!     })
//!     .unwrap();
//! ```

use crate::{ElementKind, HEX20_EDGES, IntegrationRule, ShapeTable};
use nonlin3d_laminate::{Orthotropic, ShearCoupling, Stiffness};
use proptest::prelude::*;

/// Rotation matrix from three angles (z–y–x), row-major.
pub fn rotation(a: f64, b: f64, c: f64) -> [[f64; 3]; 3] {
    let (sa, ca) = a.sin_cos();
    let (sb, cb) = b.sin_cos();
    let (sc, cc) = c.sin_cos();
    let rz = [[ca, -sa, 0.0], [sa, ca, 0.0], [0.0, 0.0, 1.0]];
    let ry = [[cb, 0.0, sb], [0.0, 1.0, 0.0], [-sb, 0.0, cb]];
    let rx = [[1.0, 0.0, 0.0], [0.0, cc, -sc], [0.0, sc, cc]];
    mul(&mul(&rz, &ry), &rx)
}

fn mul(a: &[[f64; 3]; 3], b: &[[f64; 3]; 3]) -> [[f64; 3]; 3] {
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            r[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    r
}

/// Applies `r` to a vector.
pub fn apply(r: &[[f64; 3]; 3], v: [f64; 3]) -> [f64; 3] {
    [
        r[0][0] * v[0] + r[0][1] * v[1] + r[0][2] * v[2],
        r[1][0] * v[0] + r[1][1] * v[1] + r[1][2] * v[2],
        r[2][0] * v[0] + r[2][1] * v[1] + r[2][2] * v[2],
    ]
}

/// Whether det J > 0 at every 3×3×3 Gauss point and every node (a sufficient practical test of
/// a valid, non-inverted element for these shape functions).
pub fn is_valid(kind: ElementKind, x: &[[f64; 3]]) -> bool {
    let Ok(table) = ShapeTable::new(kind, IntegrationRule::Gauss3) else {
        return false;
    };
    let mut pts: Vec<[f64; 3]> = table.stations().iter().map(|s| s.xi).collect();
    pts.extend_from_slice(kind.reference_nodes());
    pts.iter()
        .all(|&p| matches!(kind.jacobian_determinant(p, x), Ok(d) if d > 0.0))
}

/// A random valid element: a box with sides 0.2–5 mm (aspect ratio up to 25, as in thin
/// laminate layers), corners moved by up to 15 % of the shortest side, Hex20 mid-edge nodes
/// moved off the chord midpoint by up to 5 % (curved edges), then rotated and translated.
pub fn distorted_element(kind: ElementKind) -> impl Strategy<Value = Vec<[f64; 3]>> {
    let nn = kind.nodes();
    (
        proptest::array::uniform3(0.2e-3..5e-3f64),
        proptest::collection::vec(proptest::array::uniform3(-1.0..1.0f64), nn),
        proptest::array::uniform3(-3.2..3.2f64),
        proptest::array::uniform3(-0.1..0.1f64),
    )
        .prop_map(move |(sides, noise, angles, shift)| {
            let h = sides.iter().copied().fold(f64::INFINITY, f64::min);
            let mut corners = [[0.0; 3]; 8];
            for (m, c) in corners.iter_mut().enumerate() {
                let p = kind.reference_nodes()[m];
                for r in 0..3 {
                    c[r] = 0.5 * sides[r] * p[r] + 0.15 * h * noise[m][r];
                }
            }
            let mut x: Vec<[f64; 3]> = corners.to_vec();
            if kind == ElementKind::Hex20 {
                for m in 8..20 {
                    let (a, b) = HEX20_EDGES[m - 8];
                    let mut p = [0.0; 3];
                    for r in 0..3 {
                        p[r] = 0.5 * (corners[a][r] + corners[b][r]) + 0.05 * h * noise[m][r];
                    }
                    x.push(p);
                }
            }
            let rot = rotation(angles[0], angles[1], angles[2]);
            x.iter()
                .map(|&p| {
                    let q = apply(&rot, p);
                    [q[0] + shift[0], q[1] + shift[1], q[2] + shift[2]]
                })
                .collect::<Vec<_>>()
        })
        .prop_filter("element must not be inverted", move |x| is_valid(kind, x))
}

/// A random valid orthotropic ply: E11 1–300 GPa, E22 and E33 1/50–1 of it, G's 1/3–1/2.5 of
/// the smaller E they connect, Poisson ratios within 0.1–0.45 of their bounds, rotated about
/// z by any angle (exact C56 kept).
pub fn orthotropic() -> impl Strategy<Value = Orthotropic> {
    (
        1e9..300e9f64,
        proptest::array::uniform2(0.02..1.0f64),
        proptest::array::uniform3(0.05..0.45f64),
        proptest::array::uniform3(0.3..0.4f64),
    )
        .prop_map(|(e11, r, nu, g)| {
            let (e22, e33) = (e11 * r[0], e11 * r[1]);
            // ν_ij scaled by √(E_i/E_j)·(a fraction ≤ 0.45) keeps every pair bound and the
            // joint determinant (≥ 1 − 3·0.45² − 2·0.45³ > 0) positive.
            Orthotropic {
                e11,
                e22,
                e33,
                nu12: nu[0] * (e11 / e22).sqrt().min(1.0),
                nu23: nu[1] * (e22 / e33).sqrt().min(1.0),
                nu13: nu[2] * (e11 / e33).sqrt().min(1.0),
                g12: g[0] * e11.min(e22),
                g23: g[1] * e22.min(e33),
                g13: g[2] * e11.min(e33),
            }
        })
        .prop_filter("valid engineering constants", |m| m.validate().is_ok())
}

/// A random SPD material: an [`orthotropic`] ply rotated about z by −90°…90°.
pub fn material() -> impl Strategy<Value = Stiffness> {
    (orthotropic(), -90.0..90.0f64).prop_filter_map("SPD rotated stiffness", |(m, deg)| {
        m.stiffness()
            .ok()?
            .rotated_about_z(deg.to_radians(), ShearCoupling::Exact)
            .ok()
    })
}

/// A material under the thesis's assumption (eq. 2.1.5): an orthotropic ply rotated about z
/// with C56 dropped ([`ShearCoupling::Thesis`]).
pub fn decoupled_material() -> impl Strategy<Value = Stiffness> {
    (orthotropic(), -90.0..90.0f64).prop_filter_map("SPD rotated stiffness", |(m, deg)| {
        m.stiffness()
            .ok()?
            .rotated_about_z(deg.to_radians(), ShearCoupling::Thesis)
            .ok()
    })
}

/// Displacements of element `x`: a rigid rotation of up to `max_rotation` radians about the
/// centroid plus nodal noise of up to `strain` times the element size (so strains of order
/// `strain`; 0.02 and 0.3 rad cover a postbuckled sublaminate).
pub fn displacements(
    x: Vec<[f64; 3]>,
    strain: f64,
    max_rotation: f64,
) -> impl Strategy<Value = Vec<[f64; 3]>> {
    let nn = x.len();
    (
        proptest::array::uniform3(-max_rotation..=max_rotation),
        proptest::collection::vec(proptest::array::uniform3(-1.0..1.0f64), nn),
    )
        .prop_map(move |(angles, noise)| {
            let rot = rotation(angles[0], angles[1], angles[2]);
            let mut centre = [0.0; 3];
            for p in &x {
                for r in 0..3 {
                    centre[r] += p[r] / nn as f64;
                }
            }
            let size = x.iter().map(|p| {
                ((p[0] - centre[0]).powi(2)
                    + (p[1] - centre[1]).powi(2)
                    + (p[2] - centre[2]).powi(2))
                .sqrt()
            });
            let size = size.fold(0.0, f64::max);
            x.iter()
                .zip(&noise)
                .map(|(p, n)| {
                    let d = [p[0] - centre[0], p[1] - centre[1], p[2] - centre[2]];
                    let q = apply(&rot, d);
                    let mut u = [0.0; 3];
                    for r in 0..3 {
                        u[r] = q[r] - d[r] + strain * size * n[r];
                    }
                    u
                })
                .collect()
        })
}
