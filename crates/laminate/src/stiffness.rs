//! The validated 6×6 stiffness C and its Cholesky factor Q (thesis §2.1 eq. 2.1.5, §2.3).

use crate::LaminateError;
use crate::rotation::{rotate_voigt, rotation_about_z};
use nalgebra::Matrix6;

/// How a ply rotated about z treats the coupling C56 between γyz and γxz.
///
/// For a ply at angle θ with G13 ≠ G23 the exact rotation gives
/// C56 = (G13 − G23)·sin θ·cos θ (with C55 = G23 cos²θ + G13 sin²θ, C66 = G13 cos²θ + G23 sin²θ).
/// The thesis (§2.1, eq. 2.1.5) assumed C5j = 0 and C6j = 0 off the diagonal; that drops C56
/// and so stiffens the transverse shear of off-axis plies slightly. For Table 1 graphite/epoxy
/// at ±45° it is |C56|/√(C55·C66) = 0.23. The homogeneous quasi-isotropic average (eq. 2.9.1)
/// has C56 = 0 either way, since the ±45° plies cancel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ShearCoupling {
    /// Keep every entry of the exact rotation (the default).
    #[default]
    Exact,
    /// Zero C5j and C6j off the diagonal, as NONLIN3D did (eq. 2.1.5).
    Thesis,
}

/// A symmetric positive definite 6×6 stiffness C in the thesis strain order with its lower
/// triangular Cholesky factor Q, C = Q·Qᵀ (so C_ij = Q_is·Q_js with Q_is = 0 for i < s, §2.3).
///
/// Built only through [`Stiffness::new`], which validates, so element kernels can trust both.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Stiffness {
    c: [[f64; 6]; 6],
    q: [[f64; 6]; 6],
}

impl Stiffness {
    /// Validates C (finite, symmetric to 1e-12 of its largest entry, positive definite) and
    /// factors it. The stored C is exactly symmetric (the mean of C and Cᵀ).
    pub fn new(c: [[f64; 6]; 6]) -> Result<Self, LaminateError> {
        let mut scale = 0.0f64;
        for (row, r) in c.iter().enumerate() {
            for (col, &value) in r.iter().enumerate() {
                if !value.is_finite() {
                    return Err(LaminateError::NonFiniteEntry { row, col, value });
                }
                scale = scale.max(value.abs());
            }
        }
        let mut sym = c;
        for row in 0..6 {
            for col in row + 1..6 {
                let (upper, lower) = (c[row][col], c[col][row]);
                if (upper - lower).abs() > 1e-12 * scale {
                    return Err(LaminateError::NotSymmetric {
                        row,
                        col,
                        upper,
                        lower,
                    });
                }
                let mean = 0.5 * (upper + lower);
                sym[row][col] = mean;
                sym[col][row] = mean;
            }
        }
        let q = cholesky(&sym)?;
        Ok(Self { c: sym, q })
    }

    /// The stiffness C.
    pub fn c(&self) -> &[[f64; 6]; 6] {
        &self.c
    }

    /// The lower triangular Cholesky factor Q with C = Q·Qᵀ.
    pub fn q(&self) -> &[[f64; 6]; 6] {
        &self.q
    }

    /// C as a nalgebra matrix.
    pub fn matrix(&self) -> Matrix6<f64> {
        Matrix6::from_fn(|i, j| self.c[i][j])
    }

    /// σ = C ε for one strain vector in the thesis order.
    pub fn stress(&self, strain: &[f64; 6]) -> [f64; 6] {
        let mut s = [0.0; 6];
        for i in 0..6 {
            s[i] = (0..6).map(|j| self.c[i][j] * strain[j]).sum();
        }
        s
    }

    /// The stiffness of this material rotated about z by `theta` (radians, counter-clockwise
    /// from x to the material 1-axis: the ply angle), exact tensor rotation
    /// C′_ijkl = R_ia R_jb R_kc R_ld C_abcd, then `coupling` applied.
    ///
    /// A rotation keeps C symmetric positive definite, so an error here means the rotated
    /// matrix lost definiteness to round-off (a nearly singular C) or `theta` is not finite.
    pub fn rotated_about_z(
        &self,
        theta: f64,
        coupling: ShearCoupling,
    ) -> Result<Self, LaminateError> {
        let rotated = self.rotated(&rotation_about_z(theta))?;
        match coupling {
            ShearCoupling::Exact => Ok(rotated),
            ShearCoupling::Thesis => rotated.with_thesis_shear_decoupling(),
        }
    }

    /// The stiffness rotated by the proper orthogonal matrix `r` (columns: material axes in
    /// global coordinates).
    pub fn rotated(&self, r: &[[f64; 3]; 3]) -> Result<Self, LaminateError> {
        Self::new(rotate_voigt(&self.c, r))
    }

    /// The thesis's assumption (eq. 2.1.5): C5j = C6j = 0 for j ≠ 5, 6 respectively.
    ///
    /// The result is block diagonal with principal sub-blocks of an SPD matrix, hence SPD.
    pub fn with_thesis_shear_decoupling(&self) -> Result<Self, LaminateError> {
        let mut c = self.c;
        for j in 0..6 {
            if j != 4 {
                c[4][j] = 0.0;
                c[j][4] = 0.0;
            }
            if j != 5 {
                c[5][j] = 0.0;
                c[j][5] = 0.0;
            }
        }
        Self::new(c)
    }

    /// Largest |C_ij| over the blocks {i < 4, j ≥ 4}, relative to the largest diagonal entry:
    /// zero when the transverse shears (γyz, γxz) are decoupled from the other strains, the
    /// condition of the selective-reduced Hex8 rule (§2.3).
    pub fn transverse_shear_coupling(&self) -> f64 {
        let diag = (0..6).map(|i| self.c[i][i]).fold(0.0, f64::max);
        let mut m = 0.0f64;
        for i in 0..4 {
            for j in 4..6 {
                m = m.max(self.c[i][j].abs());
            }
        }
        m / diag
    }
}

/// Lower Cholesky factor of a symmetric 6×6 matrix; a non-positive pivot is an error.
fn cholesky(c: &[[f64; 6]; 6]) -> Result<[[f64; 6]; 6], LaminateError> {
    let mut q = [[0.0; 6]; 6];
    for j in 0..6 {
        let mut d = c[j][j];
        for k in 0..j {
            d -= q[j][k] * q[j][k];
        }
        // Pivots below 1e-14 of the diagonal entry are round-off of a singular matrix.
        let tiny = 1e-14 * c[j][j].abs();
        if d.is_nan() || d <= tiny || d <= 0.0 {
            return Err(LaminateError::NotPositiveDefinite { index: j, pivot: d });
        }
        let djj = d.sqrt();
        q[j][j] = djj;
        for i in j + 1..6 {
            let mut s = c[i][j];
            for k in 0..j {
                s -= q[i][k] * q[j][k];
            }
            q[i][j] = s / djj;
        }
    }
    Ok(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::generic_graphite_epoxy;
    use approx::assert_relative_eq;

    #[test]
    fn cholesky_reproduces_c() {
        let s = generic_graphite_epoxy()
            .stiffness()
            .unwrap()
            .rotated_about_z(0.3, ShearCoupling::Exact)
            .unwrap();
        for i in 0..6 {
            for j in 0..6 {
                let qq: f64 = (0..6).map(|k| s.q()[i][k] * s.q()[j][k]).sum();
                assert_relative_eq!(qq, s.c()[i][j], epsilon = 1e-12 * s.c()[0][0]);
                if j > i {
                    assert_eq!(s.q()[i][j], 0.0, "Q must be lower triangular");
                }
            }
        }
    }

    #[test]
    fn indefinite_and_non_finite_are_rejected() {
        let mut c = [[0.0; 6]; 6];
        for i in 0..6 {
            c[i][i] = 1.0;
        }
        c[2][2] = -1.0;
        assert!(matches!(
            Stiffness::new(c),
            Err(LaminateError::NotPositiveDefinite { index: 2, .. })
        ));
        c[2][2] = 1.0;
        c[0][3] = 2.0;
        assert!(matches!(
            Stiffness::new(c),
            Err(LaminateError::NotSymmetric { row: 0, col: 3, .. })
        ));
        c[3][0] = 2.0;
        assert!(matches!(
            Stiffness::new(c),
            Err(LaminateError::NotPositiveDefinite { index: 3, .. })
        ));
        c[3][0] = f64::NAN;
        assert!(matches!(
            Stiffness::new(c),
            Err(LaminateError::NonFiniteEntry { row: 3, col: 0, .. })
        ));
    }

    #[test]
    fn rotated_ply_shear_block_matches_closed_form() {
        let m = generic_graphite_epoxy();
        let c0 = m.stiffness().unwrap();
        for deg in [0.0f64, 15.0, 30.0, 45.0, 60.0, 90.0, -45.0] {
            let t = deg.to_radians();
            let (s, c) = t.sin_cos();
            let r = c0.rotated_about_z(t, ShearCoupling::Exact).unwrap();
            let tol = 1e-9 * m.g13;
            assert_relative_eq!(r.c()[4][4], m.g23 * c * c + m.g13 * s * s, epsilon = tol);
            assert_relative_eq!(r.c()[5][5], m.g13 * c * c + m.g23 * s * s, epsilon = tol);
            assert_relative_eq!(r.c()[4][5], (m.g13 - m.g23) * s * c, epsilon = tol);
            let thesis = c0.rotated_about_z(t, ShearCoupling::Thesis).unwrap();
            assert_eq!(thesis.c()[4][5], 0.0);
            assert_eq!(thesis.c()[4][4], r.c()[4][4]);
            assert!(r.transverse_shear_coupling() < 1e-12);
        }
    }

    #[test]
    fn rotated_ply_in_plane_terms_match_lamination_theory() {
        // C̄11 = C11 c⁴ + 2(C12 + 2 C44) c² s² + C22 s⁴ holds for the 3-D stiffness too
        // (same tensor rotation restricted to the in-plane indices).
        let c0 = generic_graphite_epoxy().stiffness().unwrap();
        let k = c0.c();
        for deg in [10.0f64, 45.0, 75.0] {
            let t = deg.to_radians();
            let (s, c) = t.sin_cos();
            let r = c0.rotated_about_z(t, ShearCoupling::Exact).unwrap();
            let c11 = k[0][0] * c.powi(4)
                + 2.0 * (k[0][1] + 2.0 * k[3][3]) * c * c * s * s
                + k[1][1] * s.powi(4);
            assert_relative_eq!(r.c()[0][0], c11, max_relative = 1e-12);
            let c13 = k[0][2] * c * c + k[1][2] * s * s;
            assert_relative_eq!(r.c()[0][2], c13, max_relative = 1e-12);
        }
    }
}
