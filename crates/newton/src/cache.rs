//! The factorised tangent and the BFGS pairs an iteration may reuse from earlier ones
//! (modified and quasi-Newton, thesis §2.1's option of keeping K_T; Matthies & Strang 1979).

use crate::NewtonSettings;
use crate::vector::dot;
use nonlin3d_solver::LinearSolver;
use std::collections::VecDeque;

/// What an iteration may reuse from earlier ones: whether the solver holds a valid
/// factorisation, how many iterations it has served, and the BFGS pairs gathered since.
#[derive(Debug, Clone, Default)]
pub struct TangentCache {
    pub(crate) factored: bool,
    pub(crate) age: usize,
    pub(crate) slow: bool,
    pub(crate) pairs: VecDeque<(Vec<f64>, Vec<f64>, f64)>,
}

impl TangentCache {
    /// An empty cache: the first iteration factors.
    pub fn new() -> Self {
        Self::default()
    }

    /// Forgets the factorisation and the pairs (after a failed attempt, or when the problem
    /// changed in a way the old tangent does not describe).
    pub fn invalidate(&mut self) {
        *self = Self::default();
    }

    /// A cache vouching for a factorisation just made (age 0, no BFGS pairs).
    pub(crate) fn factored_now() -> Self {
        Self {
            factored: true,
            ..Self::default()
        }
    }

    /// Whether the solver holds a factorisation this cache vouches for.
    pub fn is_factored(&self) -> bool {
        self.factored
    }

    /// Whether the next increment's first iteration will use the kept factorisation rather
    /// than factor a tangent at its start.
    pub(crate) fn serves(&self, settings: &NewtonSettings) -> bool {
        settings.keep_tangent && self.factored && self.age < settings.refactor_every && !self.slow
    }

    /// Records a pair s = Δu, y = Δr unless its curvature yᵀs is not clearly positive.
    pub(crate) fn push_pair(&mut self, s: Vec<f64>, y: Vec<f64>, limit: usize) {
        let ys = dot(&y, &s);
        let curved = ys > 1e-10 * (dot(&y, &y) * dot(&s, &s)).sqrt();
        if !curved {
            return;
        }
        if self.pairs.len() == limit {
            self.pairs.pop_front();
        }
        self.pairs.push_back((s, y, 1.0 / ys));
    }

    /// d = −H r by the two-loop recursion with H₀ = K₀⁻¹ (the factorised tangent); with
    /// `residual`, H₀ is applied to a residual ‖q − K₀ x‖∞ ≤ `residual` N
    /// ([`LinearSolver::solve_to_residual`]), else exactly.
    pub(crate) fn direction(
        &self,
        r: &[f64],
        solver: &mut dyn LinearSolver,
        residual: Option<f64>,
    ) -> Result<Vec<f64>, nonlin3d_solver::SolverError> {
        let mut q: Vec<f64> = r.iter().map(|x| -x).collect();
        let mut alphas = Vec::with_capacity(self.pairs.len());
        for (s, y, rho) in self.pairs.iter().rev() {
            let a = rho * dot(s, &q);
            axpy(-a, y, &mut q);
            alphas.push(a);
        }
        match residual {
            Some(t) => solver.solve_to_residual(&mut q, t)?,
            None => solver.solve_in_place(&mut q, 1)?,
        }
        for ((s, y, rho), a) in self.pairs.iter().zip(alphas.iter().rev()) {
            let b = rho * dot(y, &q);
            axpy(a - b, s, &mut q);
        }
        Ok(q)
    }
}

fn axpy(a: f64, x: &[f64], y: &mut [f64]) {
    for (y, x) in y.iter_mut().zip(x) {
        *y += a * x;
    }
}
