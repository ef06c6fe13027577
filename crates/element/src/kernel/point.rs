//! The material at each integration station (the door for materials whose axes vary in
//! space: `*ORIENTATION, SYSTEM=CYLINDRICAL`): the uniform path returns one stiffness, the
//! turning path rotates the local one to the axes at the station's position.

use crate::ElementError;
use crate::material::CylindricalAxes;
use crate::simd::dot;
use nonlin3d_laminate::Stiffness;

/// The stiffness at each station: the same one everywhere ([`Fixed`], the uniform path), or
/// the local one turned to the axes at the station's position ([`Turning`]).
pub(super) trait PointMaterial {
    /// The stiffness at station `g`, whose shape values are `n`; `xs` are the element's
    /// coordinates as three runs over the nodes.
    fn at<const NS: usize, const FMA: bool>(
        &mut self,
        g: usize,
        n: &[f64],
        xs: &[[f64; NS]; 3],
    ) -> Result<&Stiffness, ElementError>;
}

/// A uniform material: the stiffness, untouched, at every station.
pub(super) struct Fixed<'a>(pub(super) &'a Stiffness);

impl PointMaterial for Fixed<'_> {
    #[inline(always)]
    fn at<const NS: usize, const FMA: bool>(
        &mut self,
        _: usize,
        _: &[f64],
        _: &[[f64; NS]; 3],
    ) -> Result<&Stiffness, ElementError> {
        Ok(self.0)
    }
}

/// A material in varying axes: at each station x = Σ_m N^m x^m, R = the axes at x, then
/// C = R·C_local (tensor rotation) and its Cholesky factor, as the kernel needs Q (eq. 2.3.4).
pub(super) struct Turning<'a> {
    pub(super) local: &'a Stiffness,
    pub(super) axes: &'a CylindricalAxes,
    pub(super) index: usize,
    /// The selective-reduced rule: each station's C must not couple the transverse shears.
    pub(super) selective: bool,
    pub(super) here: Stiffness,
}

impl PointMaterial for Turning<'_> {
    #[inline(always)]
    fn at<const NS: usize, const FMA: bool>(
        &mut self,
        g: usize,
        n: &[f64],
        xs: &[[f64; NS]; 3],
    ) -> Result<&Stiffness, ElementError> {
        let Some(n) = n.first_chunk::<NS>() else {
            return Err(ElementError::LengthMismatch {
                what: "shape values",
                expected: NS,
                got: n.len(),
            });
        };
        let x = [
            dot::<NS, FMA>(n, &xs[0]),
            dot::<NS, FMA>(n, &xs[1]),
            dot::<NS, FMA>(n, &xs[2]),
        ];
        self.here = Stiffness::new(crate::material::turn(self.local.c(), &self.axes.axes_at(x)))
            .map_err(|e| ElementError::MaterialAtPoint {
                element: None,
                material: self.index,
                point: g,
                x,
                reason: e.to_string(),
            })?;
        if self.selective {
            let coupling = self.here.transverse_shear_coupling();
            if coupling > 1e-12 {
                return Err(ElementError::CoupledTransverseShear {
                    element: None,
                    material: self.index,
                    coupling,
                });
            }
        }
        Ok(&self.here)
    }
}
