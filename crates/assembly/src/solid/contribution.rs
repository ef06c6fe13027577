//! The solid as a [`Contribution`]: f_int = Σ_cells ∫ Bᵀ S dV, K = Σ_cells (K_L + K_NL) over the
//! cells of the mesh, by the owner-computes engine.

use super::Assembler;
use crate::contribution::check_len;
use crate::{AssemblyError, Contribution};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

impl Contribution for Assembler {
    /// Each cell's DOF list, and the DOF triple of every node in no cell.
    fn couplings(&self) -> Vec<Vec<usize>> {
        super::pattern::with_lone_nodes(self.dofs.clone(), self.n)
    }

    /// Takes the system's pattern as its own: the cells' node-pair offsets are recomputed,
    /// unless it holds the same entries as the solid's own (a system of the solid alone, no
    /// ties), for which they already stand.
    fn adopt(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<(), AssemblyError> {
        if **pattern == *self.pattern {
            self.share_pattern(pattern.clone());
            return Ok(());
        }
        self.set_pattern(pattern.clone())
    }

    /// Assembles into scratch, then adds (the engine writes every value of its tangent).
    fn add(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        check_len("internal forces", internal, self.n)?;
        let mut own = vec![0.0; self.n];
        let energy = match tangent {
            Some(k) => {
                let mut scratch = self.new_tangent();
                let e = self.assemble_into(
                    u,
                    &mut own,
                    Some(&mut scratch),
                    rayon::current_num_threads(),
                )?;
                if !(Arc::ptr_eq(k.pattern(), &self.pattern) || **k.pattern() == *self.pattern) {
                    return Err(AssemblyError::Length {
                        what: "tangent entries (make it on the system's pattern)",
                        expected: self.pattern.nnz_lower(),
                        got: k.pattern().nnz_lower(),
                    });
                }
                for (a, b) in k.values_mut().iter_mut().zip(scratch.values()) {
                    *a += b;
                }
                e
            }
            None => self.assemble_into(u, &mut own, None, rayon::current_num_threads())?,
        };
        for (a, b) in internal.iter_mut().zip(&own) {
            *a += b;
        }
        Ok(energy)
    }

    /// The engine itself (forces added into zeros, every tangent value written, bitwise the
    /// same on any number of threads).
    fn set(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        check_len("internal forces", internal, self.n)?;
        internal.fill(0.0);
        self.assemble_into(u, internal, tangent, rayon::current_num_threads())
    }

    fn add_product(&self, u: &[f64], v: &[f64], y: &mut [f64]) -> Result<(), AssemblyError> {
        check_len("product", y, self.n)?;
        let kv = self.tangent_product(u, v)?;
        for (a, b) in y.iter_mut().zip(&kv) {
            *a += b;
        }
        Ok(())
    }
}
