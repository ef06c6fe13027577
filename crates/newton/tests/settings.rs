//! `NewtonSettings::full_newton`: the settings of a level where a kept tangent does not apply.

use nonlin3d_newton::NewtonSettings;
use nonlin3d_solver::SolverKind;

/// Full Newton keeps the solver and the force tolerances and drops what keeps a tangent.
#[test]
fn full_newton_keeps_the_tolerances_and_drops_the_kept_tangent() {
    let bfgs = NewtonSettings {
        solver: SolverKind::Profile,
        force_tolerance: 1e-4,
        relative_tolerance: 1e-10,
        keep_tangent: true,
        quasi_newton: 20,
        refactor_every: 4,
        max_iterations: 7,
        ..NewtonSettings::default()
    };
    let full = bfgs.full_newton();
    assert_eq!(
        (full.solver, full.force_tolerance, full.relative_tolerance),
        (SolverKind::Profile, 1e-4, 1e-10)
    );
    assert!(!full.keep_tangent);
    assert_eq!((full.quasi_newton, full.refactor_every), (0, 1));
    assert_eq!(
        full.max_iterations,
        NewtonSettings::default().max_iterations
    );
}
