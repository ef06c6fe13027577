//! A deliberately plain implementation of the same element: per quadrature point, nalgebra
//! matrices, B formed explicitly (eq. 2.2.3), K = Σ (Bᵀ C B + Σ_i σ_i a_i) |J| W (eq. 2.3.2)
//! with the a_i^{mn} of eq. 2.2.5 written out. It is the oracle the fast kernels are tested
//! against and the baseline the benchmarks measure their speed-up over. Not for production.

use crate::kernel::{check_finite, strains};
use crate::{AsMaterial, ElementError, Kinematics, ShapeTable};
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector6};
use nonlin3d_laminate::Stiffness;

/// Forces, tangent and energy of one element.
#[derive(Debug, Clone, PartialEq)]
pub struct ReferenceOutput {
    /// Internal nodal forces, node-major.
    pub forces: DVector<f64>,
    /// Tangent stiffness.
    pub tangent: DMatrix<f64>,
    /// Strain energy.
    pub energy: f64,
}

/// Evaluates one element the textbook way. Same inputs and conventions as
/// [`evaluate`](crate::evaluate); a material in varying axes is turned to the axes at each
/// station's position x = Σ_m N^m x^m.
pub fn evaluate_reference<M: AsMaterial + ?Sized>(
    table: &ShapeTable,
    coords: &[[f64; 3]],
    disp: &[[f64; 3]],
    material: &M,
    kinematics: Kinematics,
) -> Result<ReferenceOutput, ElementError> {
    let nn = table.nodes();
    let nd = 3 * nn;
    for (what, got) in [("coordinates", coords.len()), ("displacements", disp.len())] {
        if got != nn {
            return Err(ElementError::LengthMismatch {
                what,
                expected: nn,
                got,
            });
        }
    }
    check_finite(coords, "coordinates")?;
    check_finite(disp, "displacements")?;
    let nonlinear = kinematics == Kinematics::Nonlinear;
    let (material, axes) = material.parts();
    let mut forces = DVector::zeros(nd);
    let mut tangent = DMatrix::zeros(nd, nd);
    let mut energy = 0.0;
    for (g, st) in table.stations().iter().enumerate() {
        let dn = table.gradients(g);
        let mut jac = Matrix3::zeros();
        for m in 0..nn {
            for r in 0..3 {
                for c in 0..3 {
                    jac[(r, c)] += dn[m][r] * coords[m][c];
                }
            }
        }
        let det = jac.determinant();
        let inv = match jac.try_inverse() {
            Some(inv) if det > 0.0 => inv,
            _ => {
                return Err(ElementError::NonPositiveJacobian {
                    element: None,
                    point: g,
                    xi: st.xi,
                    det,
                });
            }
        };
        let mut grad = DMatrix::zeros(3, nn);
        for m in 0..nn {
            let d = nalgebra::Vector3::new(dn[m][0], dn[m][1], dn[m][2]);
            grad.set_column(m, &(inv * d));
        }
        let mut h = [[0.0; 3]; 3];
        for m in 0..nn {
            for i in 0..3 {
                for j in 0..3 {
                    h[i][j] += disp[m][i] * grad[(j, m)];
                }
            }
        }
        let f = |r: usize, j: usize| {
            let id = if r == j { 1.0 } else { 0.0 };
            if nonlinear { id + h[r][j] } else { id }
        };
        let mut b = DMatrix::zeros(6, nd);
        for m in 0..nn {
            let (nx, ny, nz) = (grad[(0, m)], grad[(1, m)], grad[(2, m)]);
            for r in 0..3 {
                let col = 3 * m + r;
                b[(0, col)] = f(r, 0) * nx;
                b[(1, col)] = f(r, 1) * ny;
                b[(2, col)] = f(r, 2) * nz;
                b[(3, col)] = f(r, 0) * ny + f(r, 1) * nx;
                b[(4, col)] = f(r, 1) * nz + f(r, 2) * ny;
                b[(5, col)] = f(r, 0) * nz + f(r, 2) * nx;
            }
        }
        let c_full = match axes {
            None => material.matrix(),
            Some(axes) => {
                let mut x = [0.0; 3];
                for (m, n) in table.values(g).iter().enumerate() {
                    for r in 0..3 {
                        x[r] += n * coords[m][r];
                    }
                }
                let here: Stiffness = material.rotated(&axes.axes_at(x)).map_err(|e| {
                    ElementError::MaterialAtPoint {
                        element: None,
                        material: 0,
                        point: g,
                        x,
                        reason: e.to_string(),
                    }
                })?;
                here.matrix()
            }
        };
        // C restricted to the components integrated at this station.
        let mut c = Matrix6::zeros();
        for i in st.first..st.last {
            for k in st.first..st.last {
                c[(i, k)] = c_full[(i, k)];
            }
        }
        let e = Vector6::from_row_slice(&strains(&h, nonlinear));
        let sigma = c * e;
        let w = det * st.weight;
        energy += 0.5 * w * sigma.dot(&e);
        let cd = DMatrix::from_fn(6, 6, |i, k| c[(i, k)]);
        let sd = DVector::from_fn(6, |i, _| sigma[i]);
        forces += b.transpose() * &sd * w;
        tangent += b.transpose() * &cd * &b * w;
        if nonlinear {
            for m in 0..nn {
                for n in 0..nn {
                    let (gm, gn) = (grad.column(m), grad.column(n));
                    let a = [
                        gm[0] * gn[0],
                        gm[1] * gn[1],
                        gm[2] * gn[2],
                        gm[0] * gn[1] + gm[1] * gn[0],
                        gm[1] * gn[2] + gm[2] * gn[1],
                        gm[0] * gn[2] + gm[2] * gn[0],
                    ];
                    let kmn: f64 = (0..6).map(|i| a[i] * sigma[i]).sum::<f64>() * w;
                    for r in 0..3 {
                        tangent[(3 * m + r, 3 * n + r)] += kmn;
                    }
                }
            }
        }
    }
    Ok(ReferenceOutput {
        forces,
        tangent,
        energy,
    })
}
