//! The problem interface and the finite element implementation of it.

use crate::NewtonError;
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::sync::Arc;

/// A discrete nonlinear problem r(u, λ) = 0 with symmetric tangent ∂r/∂u.
pub trait NonlinearProblem {
    /// Number of unknowns.
    fn n(&self) -> usize;
    /// Sparsity pattern of the tangent (fixed).
    fn pattern(&self) -> Arc<SymmetricPattern>;
    /// Sets the prescribed entries of `u` for load factor λ (their increments are then zero).
    fn prescribe(&self, u: &mut [f64], lambda: f64);
    /// Completes a Newton increment `du` for DOFs the solve left at zero but that depend on
    /// others (tied slaves: du_s = Σ c·du_m). Default: nothing.
    fn expand(&self, _du: &mut [f64]) {}
    /// Residual at (u, λ) into `r` (zero at prescribed entries) and, when given, the tangent
    /// (identity at prescribed entries). Returns a force scale for relative convergence tests
    /// (the largest external or reaction force).
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError>;
}

/// The finite element model as a [`NonlinearProblem`].
pub struct StructuralProblem {
    /// The assembler (mesh, materials, kernels).
    pub assembler: Assembler,
    /// Supports, prescribed displacements, loads.
    pub constraints: Constraints,
    /// Reactions of the last evaluation (f_int − f_ext at constrained DOFs).
    pub reactions: Vec<f64>,
}

impl StructuralProblem {
    /// A problem from an assembler and constraints of the same size.
    /// With ties in `constraints`, the assembler's pattern is extended for them
    /// ([`Assembler::tie`]); ties added later are refused at the first evaluation.
    pub fn new(mut assembler: Assembler, constraints: Constraints) -> Result<Self, NewtonError> {
        if assembler.n() != constraints.n() {
            return Err(NewtonError::Setting {
                name: "constraints",
                reason: format!("{} DOFs for a model of {}", constraints.n(), assembler.n()),
            });
        }
        if !constraints.ties().is_empty() {
            assembler.tie(&constraints)?;
        }
        let n = assembler.n();
        Ok(Self {
            assembler,
            constraints,
            reactions: vec![0.0; n],
        })
    }
}

impl NonlinearProblem for StructuralProblem {
    fn n(&self) -> usize {
        self.assembler.n()
    }

    fn pattern(&self) -> Arc<SymmetricPattern> {
        self.assembler.pattern().clone()
    }

    fn prescribe(&self, u: &mut [f64], lambda: f64) {
        self.constraints.apply(u, lambda);
    }

    fn expand(&self, du: &mut [f64]) {
        self.constraints.expand_increment(du);
    }

    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        let (res, reactions, _) = self
            .assembler
            .residual(u, lambda, &self.constraints, tangent)?;
        r.copy_from_slice(&res);
        let mut f = vec![0.0; u.len()];
        self.constraints.external(lambda, &mut f);
        let scale = f
            .iter()
            .chain(&reactions)
            .fold(0.0f64, |a, v| a.max(v.abs()));
        self.reactions = reactions;
        Ok(scale)
    }
}
