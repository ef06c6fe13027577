//! Newton's door into the linear solver: each correction K Δu = −r is asked of
//! `LinearSolver::solve_to_residual` with a bound of `LINEAR_RESIDUAL` (1 %) of the
//! iteration's force tolerance, which a mixed-precision solver uses to stop refining.

use nonlin3d_newton::{
    LINEAR_RESIDUAL, NewtonError, NewtonSettings, NonlinearProblem, residual_tolerance,
    solve_increment,
};
use nonlin3d_solver::{
    Analysis, Factorization, FaerMode, FaerSolver, LinearSolver, SolverError, SymmetricMatrix,
    SymmetricPattern,
};
use std::sync::Arc;

/// r = (u₁ + u₁³ − λ, 2u₂ + u₁u₂ − λ/2): a hardening spring beside a softer coupled one; the
/// tangent [[1 + 3u₁², 0], [u₂, 2 + u₁]] symmetrised to [[1 + 3u₁², u₂/2], [u₂/2, 2 + u₁]]
/// (a modified Newton on the second DOF: it still converges, linearly).
struct Springs;

impl NonlinearProblem for Springs {
    fn n(&self) -> usize {
        2
    }
    fn pattern(&self) -> Arc<SymmetricPattern> {
        Arc::new(SymmetricPattern::from_dof_lists(2, &[vec![0, 1]]).unwrap())
    }
    fn prescribe(&self, _u: &mut [f64], _lambda: f64) {}
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        r[0] = u[0] + u[0].powi(3) - lambda;
        r[1] = 2.0 * u[1] + u[0] * u[1] - 0.5 * lambda;
        if let Some(t) = tangent {
            t.set_zero();
            t.add(0, 0, 1.0 + 3.0 * u[0] * u[0]).unwrap();
            t.add(0, 1, 0.5 * u[1]).unwrap();
            t.add(1, 1, 2.0 + u[0]).unwrap();
        }
        Ok(lambda.abs().max(1.0))
    }
}

/// The solver of the run, recording the bound of every residual-bounded solve.
struct Recording {
    inner: FaerSolver,
    bounds: Vec<f64>,
    exact: usize,
}

impl LinearSolver for Recording {
    fn name(&self) -> &'static str {
        "recording"
    }
    fn analyze(&mut self, pattern: &Arc<SymmetricPattern>) -> Result<Analysis, SolverError> {
        self.inner.analyze(pattern)
    }
    fn factorize(&mut self, a: &SymmetricMatrix) -> Result<Factorization, SolverError> {
        self.inner.factorize(a)
    }
    fn solve_in_place(&mut self, b: &mut [f64], nrhs: usize) -> Result<(), SolverError> {
        self.exact += 1;
        self.inner.solve_in_place(b, nrhs)
    }
    fn solve_to_residual(&mut self, b: &mut [f64], residual: f64) -> Result<(), SolverError> {
        self.bounds.push(residual);
        self.inner.solve_to_residual(b, residual)
    }
}

/// Every iteration's correction goes through `solve_to_residual` with 1 % of the force
/// tolerance in force at that iteration (max(force_tolerance, 1e-8·F), F = max(|λ|, 1) = 1
/// here), none through the exact solve, and the increment converges.
#[test]
fn each_correction_is_solved_to_a_hundredth_of_the_force_tolerance() {
    let mut problem = Springs;
    let mut solver = Recording {
        inner: FaerSolver::new(FaerMode::Ldlt),
        bounds: Vec::new(),
        exact: 0,
    };
    let pattern = problem.pattern();
    solver.analyze(&pattern).unwrap();
    let mut k = SymmetricMatrix::zeros(pattern);
    let mut u = vec![0.0; 2];
    let settings = NewtonSettings::default();
    let report =
        solve_increment(&mut problem, &mut u, 0.8, &settings, &mut solver, &mut k).unwrap();
    assert!(report.converged(), "{report:?}");
    assert_eq!(solver.bounds.len(), report.iterations.len());
    assert_eq!(solver.exact, 0);
    assert!(!solver.bounds.is_empty());
    for bound in &solver.bounds {
        assert_eq!(*bound, LINEAR_RESIDUAL * report.tolerance);
    }
    assert_eq!(
        report.tolerance,
        residual_tolerance(&settings, 1.0).unwrap()
    );
}
