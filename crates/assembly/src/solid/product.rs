//! The tangent applied to a vector that is non-zero on a few DOFs: the door through which path
//! following gets the coupling force K_fc·Δu_c of a change of prescribed values without an
//! assembly of the whole tangent.

use super::{Assembler, relabel};
use crate::AssemblyError;
use nonlin3d_element::{ElementOutput, Workspace, evaluate};
use rayon::prelude::*;

impl Assembler {
    /// y = K(u)·v, K = ∂f_int/∂u the tangent of eq. 2.1.3 before any constraint (no identity
    /// rows, no ties), summed over the cells that hold a DOF where v ≠ 0: the others add
    /// nothing, so for v on a loaded face the cost is that face's cells, not the model's.
    /// Cells are evaluated in parallel and added in cell order (the same bits on any number of
    /// threads).
    pub fn tangent_product(&self, u: &[f64], v: &[f64]) -> Result<Vec<f64>, AssemblyError> {
        for (what, x) in [("displacements", u), ("product vector", v)] {
            if x.len() != self.n {
                return Err(AssemblyError::Length {
                    what,
                    expected: self.n,
                    got: x.len(),
                });
            }
        }
        let cells: Vec<usize> = (0..self.dofs.len())
            .filter(|&c| self.dofs[c].iter().any(|&d| v[d] != 0.0))
            .collect();
        let parts: Vec<Vec<f64>> = cells
            .par_iter()
            .map(|&c| self.cell_product(c, u, v))
            .collect::<Result<_, _>>()?;
        let mut y = vec![0.0; self.n];
        for (&c, part) in cells.iter().zip(&parts) {
            for (&d, &x) in self.dofs[c].iter().zip(part) {
                y[d] += x;
            }
        }
        Ok(y)
    }

    /// K_e(u_e)·v_e of cell `c`, by its DOF list.
    fn cell_product(&self, c: usize, u: &[f64], v: &[f64]) -> Result<Vec<f64>, AssemblyError> {
        let (gi, i) = self.place[c];
        let g = &self.groups[gi];
        let nn = g.table.nodes();
        let dofs = &self.dofs[c];
        let disp: Vec<[f64; 3]> = dofs
            .chunks_exact(3)
            .map(|d| [u[d[0]], u[d[1]], u[d[2]]])
            .collect();
        let mut out = ElementOutput::new(&g.table);
        let mut ws = Workspace::new(&g.table);
        evaluate(
            &g.table,
            &g.coords[i * nn..(i + 1) * nn],
            &disp,
            &self.stiffness[g.material_of[i]],
            self.kinematics,
            true,
            &mut ws,
            &mut out,
        )
        .map_err(|e| relabel(e, |_| Some(c)))?;
        let nd = dofs.len();
        let ve: Vec<f64> = dofs.iter().map(|&d| v[d]).collect();
        Ok(out
            .tangent
            .chunks_exact(nd)
            .map(|row| row.iter().zip(&ve).map(|(k, x)| k * x).sum())
            .collect())
    }
}

#[cfg(test)]
mod tests {
    use crate::{Assembler, Constraints};
    use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
    use nonlin3d_laminate::ShearCoupling;
    use nonlin3d_mesh::{BoxParams, structured_box};

    /// The product over the face cells equals the whole assembled tangent times v, at a
    /// deformed state and for v on one face only (so most cells are skipped).
    #[test]
    fn product_on_a_face_equals_the_assembled_tangent_times_v() {
        let mesh = structured_box(&BoxParams::new(
            ElementKind::Hex20,
            [4, 2, 2],
            [4.0, 1.0, 1.0],
        ))
        .unwrap();
        let steel = nonlin3d_laminate::materials::steel().stiffness().unwrap();
        let asm = Assembler::new(
            &mesh,
            &[steel],
            ShearCoupling::Exact,
            IntegrationRule::Gauss3,
            IntegrationRule::Gauss2,
            Kinematics::Nonlinear,
        )
        .unwrap();
        let n = asm.n();
        let u: Vec<f64> = (0..n).map(|d| 1e-3 * ((d * 7919) % 23) as f64).collect();
        let mut v = vec![0.0; n];
        for (k, p) in mesh.nodes.iter().enumerate() {
            if p[0] == 4.0 {
                v[3 * k] = 1e-3 * (1.0 + p[1]);
                v[3 * k + 2] = -2e-3 * p[2];
            }
        }
        let y = asm.tangent_product(&u, &v).unwrap();
        let mut k = asm.new_tangent();
        // No constraints: the residual's tangent is the raw K.
        asm.residual(&u, 0.0, &Constraints::new(n), Some(&mut k))
            .unwrap();
        let mut full = vec![0.0; n];
        k.matvec(&v, &mut full).unwrap();
        let scale = full.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        // Same element tangents summed in another order: round-off of the sums (~1e-15 of
        // the largest entry times the ~60 terms of a row).
        for (a, b) in y.iter().zip(&full) {
            assert!((a - b).abs() <= 1e-12 * scale, "{a} vs {b}");
        }
        assert!(y.iter().filter(|x| **x != 0.0).count() < n / 2);
        assert!(asm.tangent_product(&u, &v[1..]).is_err());
    }
}
