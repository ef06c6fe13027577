//! A linear solver, its tangent and the kept-tangent cache carried over several path calls
//! (the levels of a sweep): the symbolic analysis is done once, and with `keep_tangent` a call
//! starts from the last factorisation instead of a new one.

use crate::{NewtonError, NonlinearProblem, TangentCache};
use nonlin3d_solver::{LinearSolver, SolverKind, SymmetricMatrix};
use std::sync::Arc;

/// A solver analysed for a problem's sparsity pattern, with the tangent it factors and the
/// [`TangentCache`] that says whether (and how old) its factorisation is. Made once per
/// problem and handed to [`follow_path_with`](crate::follow_path_with) level after level; the
/// stability test of a converged state ([`PathSolver::inertia_at`]) leaves its factorisation
/// as the next level's kept tangent.
pub struct PathSolver {
    kind: SolverKind,
    pub(crate) solver: Box<dyn LinearSolver>,
    pub(crate) k: SymmetricMatrix,
    pub(crate) cache: TangentCache,
}

impl PathSolver {
    /// A solver of `kind`, analysed for `problem`'s pattern; nothing factorised yet.
    pub fn new(problem: &dyn NonlinearProblem, kind: SolverKind) -> Result<Self, NewtonError> {
        let pattern = problem.pattern();
        let mut solver = kind.build();
        solver.analyze(&pattern)?;
        Ok(Self {
            kind,
            solver,
            k: SymmetricMatrix::zeros(pattern),
            cache: TangentCache::new(),
        })
    }

    /// The solver kind.
    pub fn kind(&self) -> SolverKind {
        self.kind
    }

    /// Made anew (analysis included) if `problem`'s pattern is not the one this solver was
    /// analysed for, or if `kind` differs.
    pub(crate) fn fit(
        &mut self,
        problem: &dyn NonlinearProblem,
        kind: SolverKind,
    ) -> Result<(), NewtonError> {
        let pattern = problem.pattern();
        if kind != self.kind
            || !(Arc::ptr_eq(self.k.pattern(), &pattern) || **self.k.pattern() == *pattern)
        {
            *self = Self::new(problem, kind)?;
        }
        Ok(())
    }

    /// Negative pivots of the tangent at (u, λ) (`u` taken as it is), from one assembly and one
    /// factorisation: the stability test of a converged state (thesis §3.2: past a
    /// bifurcation the trivial path has K_T with negative eigenvalues). The factorisation is
    /// kept as a fresh tangent (no BFGS pairs) for the next call with `keep_tangent`.
    pub fn inertia_at(
        &mut self,
        problem: &mut dyn NonlinearProblem,
        u: &[f64],
        lambda: f64,
    ) -> Result<usize, NewtonError> {
        self.fit(problem, self.kind)?;
        self.cache.invalidate();
        let mut r = vec![0.0; problem.n()];
        problem.evaluate(u, lambda, &mut r, Some(&mut self.k))?;
        let pivots = self.solver.factorize(&self.k)?.negative_pivots;
        self.cache = TangentCache::factored_now();
        Ok(pivots)
    }

    /// Forgets the factorisation (the next call factors anew).
    pub fn invalidate(&mut self) {
        self.cache.invalidate();
    }

    /// Whether a factorisation is held for the next call.
    pub fn is_factored(&self) -> bool {
        self.cache.is_factored()
    }
}

impl std::fmt::Debug for PathSolver {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PathSolver")
            .field("kind", &self.kind)
            .field("n", &self.k.pattern().n())
            .field("factored", &self.cache.is_factored())
            .finish()
    }
}
