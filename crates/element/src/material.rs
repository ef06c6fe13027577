//! Materials as the kernels see them: one stiffness for the whole element (thesis §2.1,
//! eq. 2.1.5), or a stiffness given in local axes that turn with the position, so that at each
//! quadrature point C(x) = C′_ijkl = R_ia R_jb R_kc R_ld C_abcd with R = R(x) (CalculiX's
//! cylindrical `*ORIENTATION`, evaluated at each integration point as its `transformatrix`).

use nonlin3d_laminate::{LaminateError, ShearCoupling, Stiffness, VOIGT_PAIRS};

/// A cylindrical system of material axes: an axis through point a towards point b; at a point
/// x, local 1 is radial (x − a without its axial part, normalised), local 3 axial (a → b) and
/// local 2 = 3 × 1 tangential, so 1, 2, 3 is right-handed (CalculiX's definition).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CylindricalAxes {
    a: [f64; 3],
    axis: [f64; 3],
}

/// Radial distance below which a point counts as on the axis: CalculiX's (absolute, in the
/// deck's length unit).
const ON_AXIS: f64 = 1e-10;

fn unit(v: [f64; 3]) -> Option<[f64; 3]> {
    let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (n > 0.0 && n.is_finite()).then(|| [v[0] / n, v[1] / n, v[2] / n])
}

impl CylindricalAxes {
    /// The system whose axis runs from `a` to `b`; None when a = b or a coordinate is not
    /// finite.
    pub fn new(a: [f64; 3], b: [f64; 3]) -> Option<Self> {
        if !a.iter().all(|v| v.is_finite()) {
            return None;
        }
        let axis = unit([b[0] - a[0], b[1] - a[1], b[2] - a[2]])?;
        Some(Self { a, axis })
    }

    /// Point a (on the axis).
    pub fn origin(&self) -> [f64; 3] {
        self.a
    }

    /// The unit axial direction a → b (local 3 everywhere).
    pub fn direction(&self) -> [f64; 3] {
        self.axis
    }

    /// The local axes at `x` as columns (local 1 radial, 2 tangential, 3 axial in global
    /// coordinates): e3 = (b − a)/|b − a|, e1 = (x − a) − ((x − a)·e3) e3 normalised,
    /// e2 = e3 × e1. On the axis (radial distance < 1e-10) e1 is the normal CalculiX takes
    /// there: (−e3y/e3x, 1, 0), else (0, −e3z/e3y, 1), else (1, 0, −e3x/e3z), normalised.
    pub fn axes_at(&self, x: [f64; 3]) -> [[f64; 3]; 3] {
        let e3 = self.axis;
        let mut e1 = [x[0] - self.a[0], x[1] - self.a[1], x[2] - self.a[2]];
        let d = e1[0] * e3[0] + e1[1] * e3[1] + e1[2] * e3[2];
        for r in 0..3 {
            e1[r] -= d * e3[r];
        }
        let mut n = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
        if n.is_nan() || n < ON_AXIS {
            e1 = if e3[0].abs() > ON_AXIS {
                [-e3[1] / e3[0], 1.0, 0.0]
            } else if e3[1].abs() > ON_AXIS {
                [0.0, -e3[2] / e3[1], 1.0]
            } else {
                [1.0, 0.0, -e3[0] / e3[2]]
            };
            n = (e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]).sqrt();
        }
        for v in &mut e1 {
            *v /= n;
        }
        let e2 = [
            e3[1] * e1[2] - e1[1] * e3[2],
            e3[2] * e1[0] - e1[2] * e3[0],
            e3[0] * e1[1] - e1[0] * e3[1],
        ];
        [
            [e1[0], e2[0], e3[0]],
            [e1[1], e2[1], e3[1]],
            [e1[2], e2[2], e3[2]],
        ]
    }
}

/// The stiffness `c` (thesis Voigt order, engineering shears) turned from local axes to global
/// ones, `r` holding the local axes as columns: C′ = T C Tᵀ with the stress transformation
/// T_PQ = R_ia R_jb (+ R_ib R_ja when a ≠ b) for P = (i, j), Q = (a, b); the same tensor rotation
/// C′_ijkl = R_ia R_jb R_kc R_ld C_abcd as `nonlin3d_laminate::rotate_voigt` in 2·6³
/// multiply-adds (a twentieth of its cost: this runs at every quadrature point).
pub(crate) fn turn(c: &[[f64; 6]; 6], r: &[[f64; 3]; 3]) -> [[f64; 6]; 6] {
    let mut t = [[0.0; 6]; 6];
    for (p, &(i, j)) in VOIGT_PAIRS.iter().enumerate() {
        for (q, &(a, b)) in VOIGT_PAIRS.iter().enumerate() {
            t[p][q] = if a == b {
                r[i][a] * r[j][a]
            } else {
                r[i][a] * r[j][b] + r[i][b] * r[j][a]
            };
        }
    }
    let mut tc = [[0.0; 6]; 6];
    for p in 0..6 {
        for q in 0..6 {
            tc[p][q] = (0..6).map(|k| t[p][k] * c[k][q]).sum();
        }
    }
    let mut out = [[0.0; 6]; 6];
    for p in 0..6 {
        for q in 0..6 {
            out[p][q] = (0..6).map(|k| tc[p][k] * t[q][k]).sum();
        }
    }
    out
}

/// A material as the kernels take it: uniform over the element, or given in axes that vary
/// with the position.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Material {
    /// One stiffness in global axes for the whole element: the fast path.
    Uniform(Stiffness),
    /// `local` in the axes of `axes`, turned to global axes at each quadrature point:
    /// C(x) = R(x) · C_local (tensor rotation), factored there.
    Cylindrical {
        /// The stiffness in local axes (1 radial, 2 tangential, 3 axial).
        local: Stiffness,
        /// The axes.
        axes: CylindricalAxes,
    },
}

impl From<Stiffness> for Material {
    fn from(s: Stiffness) -> Self {
        Self::Uniform(s)
    }
}

impl Material {
    /// The material turned about z by `theta` (radians), as [`Stiffness::rotated_about_z`]; for
    /// a cylindrical material the local stiffness is turned about its local 3 axis (the axial
    /// direction) instead. `coupling` applies to the turned (local) stiffness.
    pub fn rotated_about_z(
        &self,
        theta: f64,
        coupling: ShearCoupling,
    ) -> Result<Self, LaminateError> {
        Ok(match self {
            Self::Uniform(s) => Self::Uniform(s.rotated_about_z(theta, coupling)?),
            Self::Cylindrical { local, axes } => Self::Cylindrical {
                local: local.rotated_about_z(theta, coupling)?,
                axes: *axes,
            },
        })
    }

    /// The stiffness in global axes at the point `x`.
    pub fn at(&self, x: [f64; 3]) -> Result<Stiffness, LaminateError> {
        match self {
            Self::Uniform(s) => Ok(*s),
            Self::Cylindrical { local, axes } => Stiffness::new(turn(local.c(), &axes.axes_at(x))),
        }
    }
}

/// What the element kernels accept as a material: a [`Stiffness`] (uniform) or a
/// [`Material`]. `parts` gives the stiffness and, for a material whose axes vary, the axes it
/// is given in.
pub trait AsMaterial: Sync {
    /// (stiffness, None) for a uniform material; (local stiffness, Some(axes)) otherwise.
    fn parts(&self) -> (&Stiffness, Option<&CylindricalAxes>);
}

impl AsMaterial for Stiffness {
    #[inline(always)]
    fn parts(&self) -> (&Stiffness, Option<&CylindricalAxes>) {
        (self, None)
    }
}

impl AsMaterial for Material {
    #[inline(always)]
    fn parts(&self) -> (&Stiffness, Option<&CylindricalAxes>) {
        match self {
            Self::Uniform(s) => (s, None),
            Self::Cylindrical { local, axes } => (local, Some(axes)),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn col(r: &[[f64; 3]; 3], k: usize) -> [f64; 3] {
        [r[0][k], r[1][k], r[2][k]]
    }

    /// Axis along z through the origin: at θ = 0 (on +x) the local axes are the global ones
    /// (the rectangular system with a = (1, 0, 0), b = (0, 1, 0)); at θ = 90° local 1 is +y,
    /// local 2 is −x; the axial position does not matter.
    #[test]
    fn local_axes_are_radial_tangential_axial() {
        let cyl = CylindricalAxes::new([0.0; 3], [0.0, 0.0, 2.0]).unwrap();
        let r = cyl.axes_at([5.0, 0.0, 3.0]);
        let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
        assert_eq!(r, identity);
        let r = cyl.axes_at([0.0, 2.0, -1.0]);
        for (k, want) in [[0.0, 1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
            .iter()
            .enumerate()
        {
            for i in 0..3 {
                assert!((col(&r, k)[i] - want[i]).abs() < 1e-15, "{k} {r:?}");
            }
        }
        // An oblique axis: orthonormal, right-handed, local 3 along a → b, local 1 normal to it
        // and in the plane of the axis and x.
        let cyl = CylindricalAxes::new([1.0, 2.0, 3.0], [2.0, 4.0, 5.0]).unwrap();
        let x = [0.3, -1.0, 7.0];
        let r = cyl.axes_at(x);
        let dot = |a: [f64; 3], b: [f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        for i in 0..3 {
            for k in 0..3 {
                let want = if i == k { 1.0 } else { 0.0 };
                assert!((dot(col(&r, i), col(&r, k)) - want).abs() < 1e-15);
            }
        }
        let e3 = col(&r, 2);
        assert!((dot(e3, [1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0]) - 1.0).abs() < 1e-15);
        let (e1, e2) = (col(&r, 0), col(&r, 1));
        let det = dot(
            e3,
            [
                e1[1] * e2[2] - e1[2] * e2[1],
                e1[2] * e2[0] - e1[0] * e2[2],
                e1[0] * e2[1] - e1[1] * e2[0],
            ],
        );
        assert!((det - 1.0).abs() < 1e-15);
        let d = [x[0] - 1.0, x[1] - 2.0, x[2] - 3.0];
        assert!(dot(d, e1) > 0.0 && dot(d, e2).abs() < 1e-14);
        // On the axis: CalculiX's normal, still an orthonormal system.
        let r = cyl.axes_at([1.5, 3.0, 4.0]);
        assert!(
            dot(col(&r, 0), e3).abs() < 1e-15 && (dot(col(&r, 0), col(&r, 0)) - 1.0).abs() < 1e-15
        );
        assert!(CylindricalAxes::new([1.0; 3], [1.0; 3]).is_none());
    }

    use crate::evaluate;
    use crate::reference::evaluate_reference;

    /// The quick turn equals laminate's four-pass tensor rotation to round-off (1e-15 of the
    /// largest entry), for axes that are no rotation about a global axis.
    #[test]
    fn quick_turn_is_the_tensor_rotation() {
        let c = *materials::generic_graphite_epoxy().stiffness().unwrap().c();
        let r = CylindricalAxes::new([1.0, 2.0, 3.0], [2.0, 4.0, 5.0])
            .unwrap()
            .axes_at([0.3, -1.0, 7.0]);
        let (a, b) = (turn(&c, &r), nonlin3d_laminate::rotate_voigt(&c, &r));
        let scale = c[0][0];
        for p in 0..6 {
            for q in 0..6 {
                assert!((a[p][q] - b[p][q]).abs() < 1e-15 * scale, "{p} {q}");
            }
        }
    }
    use crate::{ElementKind, ElementOutput, IntegrationRule, Kinematics, ShapeTable, Workspace};
    use nonlin3d_laminate::{Orthotropic, materials};

    /// A Hex20 ring segment around the z axis: radii 10–12 mm, θ from 10° to 40°, z 0–2 mm
    /// (mid-edge nodes on the arcs), and a displacement field with rotations of ~0.05 rad.
    fn ring_segment() -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
        let x: Vec<[f64; 3]> = ElementKind::Hex20
            .reference_nodes()
            .iter()
            .map(|p| {
                let (r, t, z) = (11.0 + p[0], (25.0 + 15.0 * p[1]).to_radians(), 1.0 + p[2]);
                [r * t.cos(), r * t.sin(), z]
            })
            .collect();
        let u = x
            .iter()
            .map(|p| {
                [
                    0.05 * p[2] - 0.01 * p[1],
                    0.02 * p[0] * p[2] / 10.0,
                    -0.04 * p[0] + 0.3,
                ]
            })
            .collect();
        (x, u)
    }

    fn run(m: &impl AsMaterial, x: &[[f64; 3]], u: &[[f64; 3]]) -> ElementOutput {
        let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss3).unwrap();
        let mut out = ElementOutput::new(&table);
        let mut ws = Workspace::new(&table);
        evaluate(
            &table,
            x,
            u,
            m,
            Kinematics::Nonlinear,
            true,
            &mut ws,
            &mut out,
        )
        .unwrap();
        out
    }

    fn max_diff(a: &[f64], b: &[f64]) -> f64 {
        a.iter()
            .zip(b)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
    }

    fn max_abs(a: &[f64]) -> f64 {
        a.iter().map(|p| p.abs()).fold(0.0, f64::max)
    }

    fn graphite_in_ring() -> Material {
        Material::Cylindrical {
            local: materials::generic_graphite_epoxy().stiffness().unwrap(),
            axes: CylindricalAxes::new([0.0; 3], [0.0, 0.0, 1.0]).unwrap(),
        }
    }

    /// The varying path against the per-point oracle (B explicit, Bᵀ C(x) B at each point): the
    /// same sums in another order, so they agree to round-off (1e-12 of the largest entry; a
    /// Hex20 tangent sums 27 × 60 terms of ~1e11 N/m). And the axes matter: the same local
    /// stiffness used in global axes gives a tangent that differs by a quarter of its size.
    #[test]
    fn varying_axes_match_the_per_point_oracle() {
        let (x, u) = ring_segment();
        let m = graphite_in_ring();
        let table = ShapeTable::new(ElementKind::Hex20, IntegrationRule::Gauss3).unwrap();
        let ours = run(&m, &x, &u);
        let oracle = evaluate_reference(&table, &x, &u, &m, Kinematics::Nonlinear).unwrap();
        let k_scale = max_abs(&ours.tangent);
        assert!(max_diff(&ours.tangent, oracle.tangent.transpose().as_slice()) < 1e-12 * k_scale);
        assert!(max_diff(&ours.forces, oracle.forces.as_slice()) < 1e-12 * max_abs(&ours.forces));
        assert!((ours.energy - oracle.energy).abs() < 1e-12 * ours.energy);
        let Material::Cylindrical { local, .. } = m else {
            unreachable!()
        };
        let fixed = run(&local, &x, &u);
        assert!(max_diff(&ours.tangent, &fixed.tangent) > 0.25 * k_scale);
    }

    /// At θ = 0 the cylindrical axes are the global ones: there C(x) is the local stiffness,
    /// bit for bit. And a material transversely isotropic about the axis (E1 = E2,
    /// G12 = E1/2(1 + ν12)) is the same in every radial–tangential frame, so the element in a
    /// cylindrical system gives what the local stiffness gives in fixed axes, to round-off.
    #[test]
    fn theta_zero_and_an_axisymmetric_material_reproduce_the_rectangular_result() {
        let m = graphite_in_ring();
        let Material::Cylindrical { local, .. } = m else {
            unreachable!()
        };
        assert_eq!(m.at([7.0, 0.0, -3.0]).unwrap(), local);
        let (e, nu) = (10e9, 0.3);
        let axisymmetric = Orthotropic {
            e11: e,
            e22: e,
            e33: 140e9,
            nu12: nu,
            nu13: 0.02,
            nu23: 0.02,
            g12: e / (2.0 * (1.0 + nu)),
            g13: 5e9,
            g23: 5e9,
        }
        .stiffness()
        .unwrap();
        let (x, u) = ring_segment();
        let turning = Material::Cylindrical {
            local: axisymmetric,
            axes: CylindricalAxes::new([0.0; 3], [0.0, 0.0, 1.0]).unwrap(),
        };
        let (a, b) = (run(&turning, &x, &u), run(&axisymmetric, &x, &u));
        assert!(max_diff(&a.tangent, &b.tangent) < 1e-12 * max_abs(&b.tangent));
        assert!(max_diff(&a.forces, &b.forces) < 1e-12 * max_abs(&b.forces));
    }

    /// Turning the element, its displacements and the axis together by a rotation Q turns the
    /// forces (f′ = Q f per node) and the tangent (K′ = Q K Qᵀ per node block) and keeps the
    /// energy: the material axes follow the geometry, not the global frame. Round-off bound
    /// 1e-11 of the largest entry (the rotation adds a few ulps to every input).
    #[test]
    fn turning_everything_turns_the_results() {
        let (x, u) = ring_segment();
        // Q = about z by 0.7, then about the axis (1, 2, 2)/3 by 1.9 (Rodrigues).
        let rz = nonlin3d_laminate::rotation_about_z(0.7);
        let (n, (s, c)) = ([1.0 / 3.0, 2.0 / 3.0, 2.0 / 3.0], 1.9f64.sin_cos());
        let ra: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| {
                let cross = [[0.0, -n[2], n[1]], [n[2], 0.0, -n[0]], [-n[1], n[0], 0.0]];
                let id = if i == j { 1.0 } else { 0.0 };
                c * id + s * cross[i][j] + (1.0 - c) * n[i] * n[j]
            })
        });
        let q: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| ra[i][k] * rz[k][j]).sum())
        });
        let turn = |p: &[f64; 3]| -> [f64; 3] {
            std::array::from_fn(|i| q[i][0] * p[0] + q[i][1] * p[1] + q[i][2] * p[2])
        };
        let (x2, u2): (Vec<_>, Vec<_>) =
            (x.iter().map(turn).collect(), u.iter().map(turn).collect());
        let axes = CylindricalAxes::new(turn(&[0.0; 3]), turn(&[0.0, 0.0, 1.0])).unwrap();
        let local = materials::generic_graphite_epoxy().stiffness().unwrap();
        let a = run(&graphite_in_ring(), &x, &u);
        let b = run(&Material::Cylindrical { local, axes }, &x2, &u2);
        assert!((a.energy - b.energy).abs() < 1e-11 * a.energy);
        let nd = 60;
        let mut f = vec![0.0; nd];
        let mut k = vec![0.0; nd * nd];
        for m in 0..20 {
            let fm = turn(&[a.forces[3 * m], a.forces[3 * m + 1], a.forces[3 * m + 2]]);
            f[3 * m..3 * m + 3].copy_from_slice(&fm);
            for n in 0..20 {
                for i in 0..3 {
                    for j in 0..3 {
                        let mut s = 0.0;
                        for p in 0..3 {
                            for r in 0..3 {
                                s += q[i][p] * a.tangent[(3 * m + p) * nd + 3 * n + r] * q[j][r];
                            }
                        }
                        k[(3 * m + i) * nd + 3 * n + j] = s;
                    }
                }
            }
        }
        assert!(max_diff(&f, &b.forces) < 1e-11 * max_abs(&b.forces));
        assert!(max_diff(&k, &b.tangent) < 1e-11 * max_abs(&b.tangent));
    }

    /// The selective-reduced Hex8 rule needs each station's C free of coupling between the
    /// transverse shears and ε1–ε4; a graphite ring in cylindrical axes about z keeps that
    /// (the axes turn about z), one about x does not: refused at its first station.
    #[test]
    fn the_selective_reduced_rule_checks_each_station() {
        let table = ShapeTable::new(ElementKind::Hex8, IntegrationRule::SelectiveReduced).unwrap();
        let (x, u) = ring_segment();
        let (x, u) = (&x[..8], &u[..8]);
        let mut out = ElementOutput::new(&table);
        let mut ws = Workspace::new(&table);
        let mut go =
            |m: &Material| evaluate(&table, x, u, m, Kinematics::Linear, true, &mut ws, &mut out);
        assert!(go(&graphite_in_ring()).is_ok());
        let Material::Cylindrical { local, .. } = graphite_in_ring() else {
            unreachable!()
        };
        let about_x = Material::Cylindrical {
            local,
            axes: CylindricalAxes::new([0.0; 3], [1.0, 0.0, 0.0]).unwrap(),
        };
        assert!(matches!(
            go(&about_x),
            Err(crate::ElementError::CoupledTransverseShear { coupling, .. }) if coupling > 1e-3
        ));
    }
}
