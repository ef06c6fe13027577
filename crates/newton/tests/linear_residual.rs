//! Newton's door into the linear solver: each correction K Δu = −r is asked of
//! `LinearSolver::solve_to_residual` with a bound of `LINEAR_RESIDUAL` (1 %) of the
//! iteration's force tolerance, which a mixed-precision solver uses to stop refining; on a
//! kept tangent with `KEPT_FORCING` (1 %) of the residual if that is larger.

use nonlin3d_newton::{
    IncrementReport, KEPT_FORCING, LINEAR_RESIDUAL, NewtonSettings, NonlinearProblem,
    residual_tolerance, solve_increment,
};
use nonlin3d_solver::{
    Analysis, Factorization, FaerMode, FaerSolver, LinearSolver, SolverError, SymmetricMatrix,
    SymmetricPattern,
};
use std::sync::Arc;

mod common;
use common::{Truss, p_max, soft};

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

/// The truss at half its limit load from rest with `settings`, through a recording solver;
/// the increment must converge.
fn half_the_limit_load(settings: &NewtonSettings) -> (Recording, IncrementReport) {
    let mut problem = Truss { spring: soft() };
    let mut solver = Recording {
        inner: FaerSolver::new(FaerMode::Ldlt),
        bounds: Vec::new(),
        exact: 0,
    };
    let pattern = problem.pattern();
    solver.analyze(&pattern).unwrap();
    let mut k = SymmetricMatrix::zeros(pattern);
    let mut u = vec![0.0; 2];
    let report = solve_increment(&mut problem, &mut u, 0.5, settings, &mut solver, &mut k).unwrap();
    assert!(report.converged(), "{report:?}");
    (solver, report)
}

/// Every iteration's correction goes through `solve_to_residual` with 1 % of the force
/// tolerance in force at that iteration, none through the exact solve, and the increment
/// converges: the two-bar truss of the arc-length tests with its soft spring (two DOFs), at
/// half its limit load, from rest.
#[test]
fn each_correction_is_solved_to_a_hundredth_of_the_force_tolerance() {
    let settings = NewtonSettings::default();
    let (solver, report) = half_the_limit_load(&settings);
    assert_eq!(solver.bounds.len(), report.iterations.len());
    assert_eq!(solver.exact, 0);
    assert!(!solver.bounds.is_empty());
    for bound in &solver.bounds {
        assert_eq!(*bound, LINEAR_RESIDUAL * report.tolerance);
    }
    // The force scale at the converged state is the load, P_max / 2 (the truss's force
    // matches it to the residual test), so the tolerance is 1e-8 of it.
    let expected = residual_tolerance(&settings, 0.5 * p_max()).unwrap();
    assert!(
        (report.tolerance - expected).abs() <= 1e-6 * expected,
        "{} vs {expected}",
        report.tolerance
    );
}

/// On a kept tangent (BFGS) each direction's bound is max(`KEPT_FORCING`·‖r‖∞,
/// `LINEAR_RESIDUAL`·tol) with ‖r‖∞ the residual the direction answers (the start's, then the
/// last iteration's); far from convergence that is the forcing term, at the tail the floor.
/// The increment still converges to the same tolerance.
#[test]
fn a_kept_tangents_directions_are_solved_to_a_hundredth_of_the_residual() {
    let settings = NewtonSettings {
        keep_tangent: true,
        refactor_every: usize::MAX,
        quasi_newton: 20,
        ..NewtonSettings::default()
    };
    let (solver, report) = half_the_limit_load(&settings);
    assert_eq!(solver.bounds.len(), report.iterations.len());
    assert!(report.iterations.len() >= 3, "{report:?}");
    let floor = LINEAR_RESIDUAL * report.tolerance;
    let mut before = report.initial_residual;
    let mut forced = 0;
    for (bound, iteration) in solver.bounds.iter().zip(&report.iterations) {
        assert_eq!(*bound, floor.max(KEPT_FORCING * before));
        forced += usize::from(*bound > floor);
        before = iteration.residual;
    }
    // The first direction answers the whole load's residual: its bound is the forcing term.
    assert!(forced >= 1, "{:?}", solver.bounds);
}
