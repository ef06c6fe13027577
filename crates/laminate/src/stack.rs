//! Ply stacks and their homogenised stiffness (thesis §2.9, eq. 2.9.1; chapter 7).

use crate::{LaminateError, Orthotropic, ShearCoupling, Stiffness};
use nalgebra::Matrix3;

/// One ply: its material in material axes, its angle about z and its thickness.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ply {
    /// Engineering constants in the ply's material axes.
    pub material: Orthotropic,
    /// Ply angle in degrees, counter-clockwise from x to the fibre direction.
    pub angle_deg: f64,
    /// Thickness in m.
    pub thickness: f64,
}

impl Ply {
    /// The ply's stiffness in the global axes.
    pub fn stiffness(&self, coupling: ShearCoupling) -> Result<Stiffness, LaminateError> {
        self.material
            .stiffness()?
            .rotated_about_z(self.angle_deg.to_radians(), coupling)
    }
}

/// A stack of plies from the bottom (z smallest) to the top.
#[derive(Debug, Clone, PartialEq)]
pub struct PlyStack {
    plies: Vec<Ply>,
}

/// In-plane strain components (xx, yy, γxy): continuous through a stack.
const IN_PLANE: [usize; 3] = [0, 1, 3];
/// Out-of-plane components (zz, γyz, γxz): their stresses are continuous through a stack.
const OUT_OF_PLANE: [usize; 3] = [2, 4, 5];

impl PlyStack {
    /// A validated stack: at least one ply, thicknesses positive and finite, angles finite,
    /// materials valid.
    pub fn new(plies: Vec<Ply>) -> Result<Self, LaminateError> {
        if plies.is_empty() {
            return Err(LaminateError::EmptyStack);
        }
        for (index, p) in plies.iter().enumerate() {
            if !(p.thickness.is_finite() && p.thickness > 0.0) {
                return Err(LaminateError::InvalidPly {
                    index,
                    reason: format!("thickness {} must be positive and finite", p.thickness),
                });
            }
            if !p.angle_deg.is_finite() {
                return Err(LaminateError::InvalidPly {
                    index,
                    reason: format!("angle {} is not finite", p.angle_deg),
                });
            }
            p.material.validate()?;
        }
        Ok(Self { plies })
    }

    /// Plies of one material at the given angles (degrees, bottom first), each of thickness
    /// `ply_thickness`; `symmetric` appends the mirror image, as the subscript s does.
    pub fn from_angles(
        material: Orthotropic,
        angles_deg: &[f64],
        ply_thickness: f64,
        symmetric: bool,
    ) -> Result<Self, LaminateError> {
        let mut angles = angles_deg.to_vec();
        if symmetric {
            angles.extend(angles_deg.iter().rev());
        }
        Self::new(
            angles
                .into_iter()
                .map(|angle_deg| Ply {
                    material,
                    angle_deg,
                    thickness: ply_thickness,
                })
                .collect(),
        )
    }

    /// The 8-ply quasi-isotropic laminate (±45/0/90)s of eq. 2.9.1.
    pub fn quasi_isotropic(
        material: Orthotropic,
        ply_thickness: f64,
    ) -> Result<Self, LaminateError> {
        Self::from_angles(material, &[45.0, -45.0, 0.0, 90.0], ply_thickness, true)
    }

    /// The plies, bottom first.
    pub fn plies(&self) -> &[Ply] {
        &self.plies
    }

    /// Total thickness in m.
    pub fn thickness(&self) -> f64 {
        self.plies.iter().map(|p| p.thickness).sum()
    }

    /// Thickness-weighted average of the ply stiffnesses, C̄_ij = Σ t_ℓ (C_ij)^ℓ / Σ t_ℓ:
    /// for equal plies this is eq. 2.9.1, the "homogeneous quasi-isotropic laminate" the
    /// thesis used in chapters 4 and 5 (with its C5j = C6j = 0 assumption, which the ±45°
    /// pairs of (±45/0/90)s satisfy anyway).
    ///
    /// This is the iso-strain (Voigt) bound: exact for the in-plane membrane response, but it
    /// assumes all six strains equal in every ply, so it overestimates the through-thickness
    /// and transverse shear stiffness where the stresses, not the strains, are continuous.
    pub fn average_stiffness(&self, coupling: ShearCoupling) -> Result<Stiffness, LaminateError> {
        let total = self.thickness();
        let mut c = [[0.0; 6]; 6];
        for p in &self.plies {
            let k = p.stiffness(coupling)?;
            let w = p.thickness / total;
            for i in 0..6 {
                for j in 0..6 {
                    c[i][j] += w * k.c()[i][j];
                }
            }
        }
        Stiffness::new(c)
    }

    /// The exact 3-D effective stiffness of the block for uniform in-plane strains
    /// (εxx, εyy, γxy continuous) and uniform out-of-plane stresses (σzz, τyz, τxz
    /// continuous), the homogenisation of Pagano (1974) and Sun & Li (1988).
    ///
    /// Per ply, with I = in-plane and O = out-of-plane components, the mixed form
    /// [σ_I; ε_O] = [C_II − C_IO C_OO⁻¹ C_OI, C_IO C_OO⁻¹; −C_OO⁻¹ C_OI, C_OO⁻¹]·[ε_I; σ_O]
    /// is averaged over the thickness (its right-hand side is the same in every ply) and
    /// converted back to a stiffness.
    ///
    /// Use it for blocks of plies meshed as one material (chapter 7 base laminate far from the
    /// delamination); it agrees with [`average_stiffness`](Self::average_stiffness) in the
    /// in-plane block and is softer through the thickness. The thesis used the average.
    pub fn smeared_stiffness(&self, coupling: ShearCoupling) -> Result<Stiffness, LaminateError> {
        let total = self.thickness();
        let mut a_ii = Matrix3::zeros();
        let mut a_io = Matrix3::zeros();
        let mut a_oi = Matrix3::zeros();
        let mut a_oo = Matrix3::zeros();
        for (index, p) in self.plies.iter().enumerate() {
            let k = p.stiffness(coupling)?;
            let block = |rows: [usize; 3], cols: [usize; 3]| {
                Matrix3::from_fn(|i, j| k.c()[rows[i]][cols[j]])
            };
            let c_ii = block(IN_PLANE, IN_PLANE);
            let c_io = block(IN_PLANE, OUT_OF_PLANE);
            let c_oi = block(OUT_OF_PLANE, IN_PLANE);
            let c_oo_inv = block(OUT_OF_PLANE, OUT_OF_PLANE)
                .try_inverse()
                .ok_or_else(|| LaminateError::InvalidPly {
                    index,
                    reason: "singular out-of-plane stiffness block".into(),
                })?;
            let w = p.thickness / total;
            a_ii += w * (c_ii - c_io * c_oo_inv * c_oi);
            a_io += w * (c_io * c_oo_inv);
            a_oi += w * (-c_oo_inv * c_oi);
            a_oo += w * c_oo_inv;
        }
        // σ_O = A_OO⁻¹ (ε_O − A_OI ε_I);  σ_I = A_II ε_I + A_IO σ_O.
        let a_oo_inv = a_oo.try_inverse().ok_or(LaminateError::InvalidPly {
            index: 0,
            reason: "singular averaged out-of-plane compliance".into(),
        })?;
        let c_oo = a_oo_inv;
        let c_oi = -a_oo_inv * a_oi;
        let c_ii = a_ii + a_io * c_oi;
        let c_io = a_io * a_oo_inv;
        let mut c = [[0.0; 6]; 6];
        for i in 0..3 {
            for j in 0..3 {
                c[IN_PLANE[i]][IN_PLANE[j]] = c_ii[(i, j)];
                c[IN_PLANE[i]][OUT_OF_PLANE[j]] = c_io[(i, j)];
                c[OUT_OF_PLANE[i]][IN_PLANE[j]] = c_oi[(i, j)];
                c[OUT_OF_PLANE[i]][OUT_OF_PLANE[j]] = c_oo[(i, j)];
            }
        }
        // Round-off leaves C_IO and C_OIᵀ equal to ~1e-15 relative; symmetrise before checking.
        for i in 0..6 {
            for j in i + 1..6 {
                let m = 0.5 * (c[i][j] + c[j][i]);
                c[i][j] = m;
                c[j][i] = m;
            }
        }
        Stiffness::new(c)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::materials::generic_graphite_epoxy;
    use approx::assert_relative_eq;

    fn qi() -> PlyStack {
        PlyStack::quasi_isotropic(generic_graphite_epoxy(), 0.125e-3).unwrap()
    }

    #[test]
    fn quasi_isotropic_average_is_transversely_isotropic() {
        let c = qi().average_stiffness(ShearCoupling::Exact).unwrap();
        let k = c.c();
        let tol = 1e-9 * k[0][0];
        assert_relative_eq!(k[0][0], k[1][1], epsilon = tol);
        assert_relative_eq!(k[0][2], k[1][2], epsilon = tol);
        assert_relative_eq!(k[4][4], k[5][5], epsilon = tol);
        // In-plane isotropy: C44 = (C11 − C12)/2.
        assert_relative_eq!(k[3][3], 0.5 * (k[0][0] - k[0][1]), epsilon = tol);
        for (i, j) in [(0, 3), (1, 3), (2, 3), (4, 5), (0, 4), (0, 5)] {
            assert!(k[i][j].abs() < tol, "C[{i}][{j}] = {}", k[i][j]);
        }
        let thesis = qi().average_stiffness(ShearCoupling::Thesis).unwrap();
        for i in 0..6 {
            for j in 0..6 {
                assert_relative_eq!(thesis.c()[i][j], k[i][j], epsilon = tol);
            }
        }
    }

    #[test]
    fn smeared_equals_ply_for_a_single_material_orientation() {
        let m = generic_graphite_epoxy();
        let s = PlyStack::from_angles(m, &[30.0, 30.0, 30.0], 1e-4, false).unwrap();
        let a = s.smeared_stiffness(ShearCoupling::Exact).unwrap();
        let b = s.plies()[0].stiffness(ShearCoupling::Exact).unwrap();
        for i in 0..6 {
            for j in 0..6 {
                assert_relative_eq!(a.c()[i][j], b.c()[i][j], epsilon = 1e-9 * b.c()[0][0]);
            }
        }
    }

    #[test]
    fn smeared_is_softer_through_the_thickness_and_matches_series_shear() {
        let s = qi();
        let avg = s.average_stiffness(ShearCoupling::Exact).unwrap();
        let sm = s.smeared_stiffness(ShearCoupling::Exact).unwrap();
        // Transverse shear: stresses continuous → softer (series instead of parallel).
        assert!(sm.c()[4][4] < avg.c()[4][4]);
        // C33 is invariant under rotation about z, the same in every ply, so the series and
        // parallel means agree; the Poisson couplings C13 differ by ply and make the smeared
        // C33 only as soft as ⟨C13⟩ allows: never stiffer than the average.
        assert!(sm.c()[2][2] <= avg.c()[2][2] * (1.0 + 1e-12));
        let m = generic_graphite_epoxy();
        // Transverse shear of the smeared block is the series (harmonic) mean over plies of
        // the ply's 2×2 shear block; for the ±45/0/90 stack it is isotropic with
        // G = 1 / mean over θ of the compliance, which for a 2×2 block averages to
        // the inverse of ⟨S⟩; compute it directly.
        let mut comp = Matrix3::<f64>::zeros();
        for p in s.plies() {
            let k = p.stiffness(ShearCoupling::Exact).unwrap();
            let b = nalgebra::Matrix2::new(k.c()[4][4], k.c()[4][5], k.c()[5][4], k.c()[5][5]);
            let inv = b.try_inverse().unwrap();
            comp[(0, 0)] += inv[(0, 0)] / 8.0;
            comp[(0, 1)] += inv[(0, 1)] / 8.0;
            comp[(1, 1)] += inv[(1, 1)] / 8.0;
        }
        assert_relative_eq!(sm.c()[4][4], 1.0 / comp[(0, 0)], max_relative = 1e-10);
        assert!(comp[(0, 1)].abs() < 1e-12 * comp[(0, 0)]);
        assert!(sm.c()[4][4] > m.g23 && sm.c()[4][4] < m.g13);
    }

    #[test]
    fn invalid_plies_are_named() {
        let m = generic_graphite_epoxy();
        assert!(matches!(
            PlyStack::new(vec![]),
            Err(LaminateError::EmptyStack)
        ));
        let bad = vec![
            Ply {
                material: m,
                angle_deg: 0.0,
                thickness: 1e-4,
            },
            Ply {
                material: m,
                angle_deg: 0.0,
                thickness: 0.0,
            },
        ];
        assert!(matches!(
            PlyStack::new(bad),
            Err(LaminateError::InvalidPly { index: 1, .. })
        ));
    }
}
