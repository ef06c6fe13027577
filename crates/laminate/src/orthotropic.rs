//! Orthotropic engineering constants → 6×6 stiffness (thesis §2.1, Table 1).

use crate::{LaminateError, Stiffness};
use nalgebra::Matrix3;

/// The nine engineering constants of an orthotropic ply in its material axes
/// (1 = fibre, 2 = in-plane transverse, 3 = through the thickness), in Pa.
///
/// ν_ij is the contraction in j under stress in i, so ν_ji = ν_ij·E_j/E_i.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Orthotropic {
    /// Young's modulus along 1.
    pub e11: f64,
    /// Young's modulus along 2.
    pub e22: f64,
    /// Young's modulus along 3.
    pub e33: f64,
    /// Major in-plane Poisson ratio ν12.
    pub nu12: f64,
    /// Poisson ratio ν23.
    pub nu23: f64,
    /// Poisson ratio ν13.
    pub nu13: f64,
    /// In-plane shear modulus G12 (pairs with γxy, component 4).
    pub g12: f64,
    /// Transverse shear modulus G23 (pairs with γyz, component 5).
    pub g23: f64,
    /// Transverse shear modulus G13 (pairs with γxz, component 6).
    pub g13: f64,
}

impl Orthotropic {
    /// An isotropic material from Young's modulus and Poisson ratio (G = E/(2(1+ν))).
    pub fn isotropic(e: f64, nu: f64) -> Self {
        let g = e / (2.0 * (1.0 + nu));
        Self {
            e11: e,
            e22: e,
            e33: e,
            nu12: nu,
            nu23: nu,
            nu13: nu,
            g12: g,
            g23: g,
            g13: g,
        }
    }

    /// Checks the constants: moduli positive and finite, Poisson ratios finite with
    /// |ν_ij| < √(E_i/E_j), and 1 − ν12ν21 − ν23ν32 − ν13ν31 − 2ν21ν32ν13 > 0, which together
    /// are the conditions for a positive definite compliance.
    pub fn validate(&self) -> Result<(), LaminateError> {
        // Young's moduli, then the Poisson ratios, then the shear moduli: an isotropic ν = −1
        // gives G = E/(2(1 + ν)) = ∞, and the message must name ν, the cause.
        let positive = |name: &'static str, value: f64| {
            if value.is_finite() && value > 0.0 {
                Ok(())
            } else {
                Err(LaminateError::InvalidModulus { name, value })
            }
        };
        for (name, value) in [("E11", self.e11), ("E22", self.e22), ("E33", self.e33)] {
            positive(name, value)?;
        }
        let ratios = [
            ("nu12", self.nu12, self.e11, self.e22),
            ("nu23", self.nu23, self.e22, self.e33),
            ("nu13", self.nu13, self.e11, self.e33),
        ];
        for (name, value, ei, ej) in ratios {
            if !value.is_finite() {
                return Err(LaminateError::NonFinitePoisson { name, value });
            }
            let limit = (ei / ej).sqrt();
            if value.abs() >= limit {
                return Err(LaminateError::PoissonTooLarge { name, value, limit });
            }
        }
        for (name, value) in [("G12", self.g12), ("G23", self.g23), ("G13", self.g13)] {
            positive(name, value)?;
        }
        let nu21 = self.nu12 * self.e22 / self.e11;
        let nu32 = self.nu23 * self.e33 / self.e22;
        let nu31 = self.nu13 * self.e33 / self.e11;
        let determinant = 1.0
            - self.nu12 * nu21
            - self.nu23 * nu32
            - self.nu13 * nu31
            - 2.0 * nu21 * nu32 * self.nu13;
        if determinant.partial_cmp(&0.0) != Some(core::cmp::Ordering::Greater) {
            return Err(LaminateError::PoissonDeterminant { determinant });
        }
        Ok(())
    }

    /// The compliance S (ε = S σ) in the material axes, thesis strain order.
    ///
    /// S11 = 1/E11, S12 = −ν12/E11, S13 = −ν13/E11, S22 = 1/E22, S23 = −ν23/E22, S33 = 1/E33,
    /// S44 = 1/G12, S55 = 1/G23, S66 = 1/G13.
    pub fn compliance(&self) -> Result<[[f64; 6]; 6], LaminateError> {
        self.validate()?;
        let mut s = [[0.0; 6]; 6];
        s[0][0] = 1.0 / self.e11;
        s[1][1] = 1.0 / self.e22;
        s[2][2] = 1.0 / self.e33;
        s[0][1] = -self.nu12 / self.e11;
        s[1][0] = s[0][1];
        s[0][2] = -self.nu13 / self.e11;
        s[2][0] = s[0][2];
        s[1][2] = -self.nu23 / self.e22;
        s[2][1] = s[1][2];
        s[3][3] = 1.0 / self.g12;
        s[4][4] = 1.0 / self.g23;
        s[5][5] = 1.0 / self.g13;
        Ok(s)
    }

    /// The stiffness C = S⁻¹ in the material axes (eq. 2.1.5 with no xy coupling), validated.
    pub fn stiffness(&self) -> Result<Stiffness, LaminateError> {
        let s = self.compliance()?;
        // The normal block is a 3×3 SPD matrix after validation; the shear block is diagonal.
        let normal = Matrix3::from_fn(|i, j| s[i][j]);
        let inv = normal
            .try_inverse()
            .ok_or(LaminateError::PoissonDeterminant { determinant: 0.0 })?;
        let mut c = [[0.0; 6]; 6];
        for i in 0..3 {
            for j in 0..3 {
                c[i][j] = inv[(i, j)];
            }
        }
        c[3][3] = self.g12;
        c[4][4] = self.g23;
        c[5][5] = self.g13;
        Stiffness::new(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use approx::assert_relative_eq;

    /// ν = −1 makes G = E/(2(1 + ν)) infinite; the error names ν, not G.
    #[test]
    fn an_isotropic_poisson_ratio_of_minus_one_is_named() {
        let e = Orthotropic::isotropic(70e9, -1.0).validate().unwrap_err();
        assert!(
            matches!(e, LaminateError::PoissonTooLarge { name: "nu12", .. }),
            "{e}"
        );
    }

    #[test]
    fn isotropic_stiffness_matches_lame_constants() {
        let (e, nu) = (207e9, 0.3);
        let c = Orthotropic::isotropic(e, nu).stiffness().unwrap();
        let lambda = e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu));
        let mu = e / (2.0 * (1.0 + nu));
        // Inverting a 3×3 block loses a few ulps; 1e-12 relative is ample.
        assert_relative_eq!(c.c()[0][0], lambda + 2.0 * mu, max_relative = 1e-12);
        assert_relative_eq!(c.c()[0][1], lambda, max_relative = 1e-12);
        assert_relative_eq!(c.c()[1][2], lambda, max_relative = 1e-12);
        assert_relative_eq!(c.c()[4][4], mu, max_relative = 1e-12);
    }

    #[test]
    fn stiffness_inverts_compliance() {
        let m = crate::materials::generic_graphite_epoxy();
        let s = m.compliance().unwrap();
        let c = m.stiffness().unwrap();
        for i in 0..6 {
            for j in 0..6 {
                let p: f64 = (0..6).map(|k| c.c()[i][k] * s[k][j]).sum();
                let expected = if i == j { 1.0 } else { 0.0 };
                assert!((p - expected).abs() < 1e-12, "C·S[{i}][{j}] = {p}");
            }
        }
    }

    #[test]
    fn invalid_constants_are_named() {
        let mut m = crate::materials::generic_graphite_epoxy();
        m.e22 = -1.0;
        assert!(matches!(
            m.validate(),
            Err(LaminateError::InvalidModulus { name: "E22", .. })
        ));
        let mut m = crate::materials::generic_graphite_epoxy();
        m.g13 = f64::NAN;
        assert!(matches!(
            m.validate(),
            Err(LaminateError::InvalidModulus { name: "G13", .. })
        ));
        let mut m = crate::materials::generic_graphite_epoxy();
        m.nu23 = 1.0; // limit is √(E22/E33) = 1
        assert!(matches!(
            m.validate(),
            Err(LaminateError::PoissonTooLarge { name: "nu23", .. })
        ));
        let mut m = crate::materials::generic_graphite_epoxy();
        m.nu12 = f64::INFINITY;
        assert!(matches!(
            m.validate(),
            Err(LaminateError::NonFinitePoisson { name: "nu12", .. })
        ));
        // Each ratio within its pair bound but jointly indefinite (isotropic ν > 0.5).
        let m = Orthotropic::isotropic(1e9, 0.6);
        assert!(matches!(
            m.validate(),
            Err(LaminateError::PoissonDeterminant { .. })
        ));
        assert!(m.stiffness().is_err());
    }
}
