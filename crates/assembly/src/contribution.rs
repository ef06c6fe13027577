//! What adds to the unconstrained global system (thesis eq. 2.1.3 before the boundary
//! conditions): the solid's cells, and anything else that has internal forces and a tangent
//! over some DOFs — a spring, a superelement's condensed stiffness, a contact pair.

use crate::AssemblyError;
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::any::Any;
use std::sync::Arc;

/// One term c of the unconstrained system a [`System`](crate::System) sums:
///
/// r(u, λ) = Σ_c f_int,c(u) − f_ext(λ),  f_ext(λ) = λ f + f_dead + Σ_c f_ext,c(λ),
/// K(u) = Σ_c ∂f_int,c/∂u,  E(u) = Σ_c E_c(u),
///
/// before any constraint is applied (the system applies them once, after the sum). The tangent
/// entries a contribution adds must lie in the couplings it declares
/// ([`couplings`](Self::couplings)); the system's pattern holds their union.
pub trait Contribution: Any + Send + Sync {
    /// The DOF couplings it needs: each list is a dense block (every pair of its DOFs coupled,
    /// K_ij ≠ 0 allowed for i, j in the list). Lists of any length (a superelement's hundreds
    /// of DOFs are one list); the system widens them to whole nodes (3 DOFs each).
    fn couplings(&self) -> Vec<Vec<usize>>;

    /// Takes the system's pattern (a superset of [`couplings`](Self::couplings)) once it is
    /// built, e.g. to precompute positions into it. Default: nothing.
    fn adopt(&mut self, _pattern: &Arc<SymmetricPattern>) -> Result<(), AssemblyError> {
        Ok(())
    }

    /// f += f_int,c(u); K += ∂f_int,c/∂u(u) when `tangent` is given (on the system's pattern);
    /// returns the energy E_c(u) (f_int,c = ∂E_c/∂u).
    fn add(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError>;

    /// f = f_int,c(u); K = ∂f_int,c/∂u(u) (every stored value written) when given; returns
    /// E_c(u). The system calls it for its first contribution, [`add`](Self::add) for the
    /// others. Default: zeros, then [`add`](Self::add).
    fn set(
        &self,
        u: &[f64],
        internal: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, AssemblyError> {
        internal.fill(0.0);
        let mut tangent = tangent;
        if let Some(k) = tangent.as_deref_mut() {
            k.set_zero();
        }
        self.add(u, internal, tangent)
    }

    /// y += ∂f_int,c/∂u(u)·v (the unconstrained tangent times v, e.g. for the coupling force
    /// K_fc·Δu_c of a change of prescribed values).
    fn add_product(&self, u: &[f64], v: &[f64], y: &mut [f64]) -> Result<(), AssemblyError>;

    /// f_ext += f_ext,c(λ), a load the contribution carries (a superelement's condensed load,
    /// scaled by λ or not as it decides). Default: none (f_ext is left untouched).
    fn add_external(&self, _lambda: f64, _f_ext: &mut [f64]) {}
}

/// Checks that a vector has the system's length.
pub(crate) fn check_len(what: &'static str, x: &[f64], n: usize) -> Result<(), AssemblyError> {
    if x.len() == n {
        Ok(())
    } else {
        Err(AssemblyError::Length {
            what,
            expected: n,
            got: x.len(),
        })
    }
}
