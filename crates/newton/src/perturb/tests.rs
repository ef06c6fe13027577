//! The perturbation protocol on a problem that wraps [`StructuralProblem`].

use crate::{
    DeadLoads, NewtonError, NewtonSettings, NonlinearProblem, PathSolver, Stepping,
    StructuralProblem, follow_path_with, perturbed_step, perturbed_step_with, solve_level,
};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_element::{IntegrationRule, Kinematics};
use nonlin3d_laminate::{ShearCoupling, materials};
use nonlin3d_mesh::{ThroughWidthParams, through_width_delamination};
use nonlin3d_solver::{SymmetricMatrix, SymmetricPattern};
use std::cell::Cell;
use std::sync::Arc;

/// A problem of a crate above newton: the finite element model plus a log of the dead loads
/// set on it, every call forwarded.
struct Wrapped {
    inner: StructuralProblem,
    dead: Vec<(usize, f64)>,
    /// Calls of `pattern()`: a symbolic analysis needs one (and a new tangent's storage
    /// another); a session asks once per path call to check that its analysis still fits.
    patterns: Cell<usize>,
}

impl Wrapped {
    fn new(inner: StructuralProblem) -> Self {
        Self {
            inner,
            dead: Vec::new(),
            patterns: Cell::new(0),
        }
    }
}

impl NonlinearProblem for Wrapped {
    fn n(&self) -> usize {
        self.inner.n()
    }
    fn pattern(&self) -> Arc<SymmetricPattern> {
        self.patterns.set(self.patterns.get() + 1);
        self.inner.pattern()
    }
    fn prescribe(&self, u: &mut [f64], lambda: f64) {
        self.inner.prescribe(u, lambda);
    }
    fn expand(&self, du: &mut [f64]) {
        self.inner.expand(du);
    }
    fn coupling_force(
        &mut self,
        u: &[f64],
        from: f64,
        to: f64,
        out: &mut [f64],
    ) -> Result<bool, NewtonError> {
        self.inner.coupling_force(u, from, to, out)
    }
    fn evaluate(
        &mut self,
        u: &[f64],
        lambda: f64,
        r: &mut [f64],
        tangent: Option<&mut SymmetricMatrix>,
    ) -> Result<f64, NewtonError> {
        self.inner.evaluate(u, lambda, r, tangent)
    }
}

impl DeadLoads for Wrapped {
    fn set_dead_load(&mut self, dof: usize, value: f64) -> Result<(), NewtonError> {
        self.dead.push((dof, value));
        self.inner.set_dead_load(dof, value)
    }
}

/// Thesis §3.2's through-width model (the mesh crate's example: ℓ = 2a = 20 mm, h = 0.4 mm,
/// steel) compressed to u = −ε_max·L on x = L at λ = 1, ε_max = 1.3·ε_c, ε_c = π²h²/(3ℓ²)
/// the clamped column's buckling strain; the sublaminate's top node at x = 0.
pub(crate) fn compressed() -> (StructuralProblem, usize, f64) {
    let p = ThroughWidthParams::example();
    let (mesh, _) = through_width_delamination(&p).unwrap();
    let steel = materials::steel().stiffness().unwrap();
    let rule = IntegrationRule::Gauss2;
    let assembler = Assembler::new(
        &mesh,
        &[steel],
        ShearCoupling::Exact,
        rule,
        rule,
        Kinematics::Nonlinear,
    )
    .unwrap();
    let mut c = Constraints::new(assembler.n());
    for (set, r) in [("x0", 0), ("y0", 1), ("y1", 1), ("z0", 2)] {
        c.fix_nodes(&mesh.node_sets[set], r).unwrap();
    }
    let ell = 2.0 * p.a;
    let eps_max = 1.3 * std::f64::consts::PI.powi(2) * p.h * p.h / (3.0 * ell * ell);
    let mut problem = StructuralProblem::new(assembler, c).unwrap();
    for &n in &mesh.node_sets["x1"] {
        problem.prescribe_value(3 * n, -eps_max * p.length).unwrap();
    }
    (problem, mesh.node_sets["center_top"][0], p.h)
}

/// The protocol drives a wrapped problem through its `DeadLoads` door exactly as it drives the
/// bare one: the same attempts and a bitwise-equal state, the load set on and finally off, and
/// the state on the buckled branch.
#[test]
fn a_wrapped_problem_follows_the_protocol_bitwise_like_the_bare_one() {
    let (bare, top, h) = compressed();
    let (inner, _, _) = compressed();
    let mut wrapped = Wrapped::new(inner);
    // 0.5 N at the top node of this 1 mm wide half model lifts the sublaminate by ~0.1·h on
    // the way (tests/newton_bifurcation.rs's postbuckling test).
    let dof = 3 * top + 2;
    let perturbation = [(dof, 0.5)];
    let settings = NewtonSettings::default();
    let stepping = Stepping {
        initial: 0.25,
        max: 0.25,
        ..Stepping::default()
    };
    let mut bare = bare;
    let n = bare.n();
    let (mut u_bare, mut u_wrapped) = (vec![0.0; n], vec![0.0; n]);
    let a = perturbed_step(
        &mut bare,
        &mut u_bare,
        0.0,
        1.0,
        &perturbation,
        &settings,
        &stepping,
    )
    .unwrap();
    let b = perturbed_step(
        &mut wrapped,
        &mut u_wrapped,
        0.0,
        1.0,
        &perturbation,
        &settings,
        &stepping,
    )
    .unwrap();
    assert_eq!(a, b);
    assert!(
        u_bare
            .iter()
            .zip(&u_wrapped)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    assert_eq!(wrapped.dead.first(), Some(&(dof, 0.5)));
    assert_eq!(wrapped.dead.last(), Some(&(dof, 0.0)));
    assert!(b.last().is_some_and(|r| r.converged()));
    // On the buckled branch after the removal: the clamped column's amplitude
    // (2ℓ/π)·√(ε − ε_b) = 12.7 mm·√(0.3·1.32e-3) = 0.25 mm = 0.63·h at 1.3·ε_c (ε_b ≈ ε_c;
    // measured 0.70·h, the base's compliance lowering ε_b to 0.975·ε_c); the same step with
    // the load never applied stays near the trivial path (measured 0.008·h). Above 0.3·h
    // separates the two.
    let w = u_wrapped[dof];
    assert!(w > 0.3 * h, "w = {w:e} m, h = {h:e} m");
}

/// A dead load on a DOF out of range is refused by the protocol before any solve, with the
/// DOF named, and nothing changes.
#[test]
fn a_perturbation_out_of_range_is_refused_by_dof() {
    let (inner, _, _) = compressed();
    let n = inner.n();
    let mut wrapped = Wrapped::new(inner);
    let mut u = vec![0.0; n];
    let e = perturbed_step(
        &mut wrapped,
        &mut u,
        0.0,
        0.1,
        &[(n, 1.0)],
        &NewtonSettings::default(),
        &Stepping::default(),
    )
    .unwrap_err();
    assert!(matches!(e, NewtonError::Assembly(_)), "{e}");
    assert!(e.to_string().contains(&n.to_string()), "{e}");
    assert!(u.iter().all(|&x| x == 0.0));
}

/// The protocol on a session that already served a path (the level's, holding a
/// factorisation and a last state of the unperturbed problem) takes the steps a new solver
/// takes, bitwise: what the session held is forgotten, only its analysis is kept.
#[test]
fn a_perturbed_step_on_a_used_session_is_bitwise_that_of_a_new_solver() {
    let (mut problem, top, _) = compressed();
    let perturbation = [(3 * top + 2, 0.5)];
    let settings = NewtonSettings::default();
    let stepping = Stepping {
        initial: 0.25,
        max: 0.25,
        ..Stepping::default()
    };
    let n = problem.n();
    let mut fresh = vec![0.0; n];
    let a = perturbed_step(
        &mut problem,
        &mut fresh,
        0.0,
        1.0,
        &perturbation,
        &settings,
        &stepping,
    )
    .unwrap();
    let mut session = PathSolver::new(&problem, settings.solver).unwrap();
    let mut used = vec![0.0; n];
    follow_path_with(
        &mut problem,
        &mut used,
        0.0,
        &[0.5],
        &settings,
        &stepping,
        &mut session,
    )
    .unwrap();
    assert!(session.is_factored());
    let mut u = vec![0.0; n];
    let b = perturbed_step_with(
        &mut problem,
        &mut u,
        (0.0, 1.0),
        &perturbation,
        &settings,
        &stepping,
        &mut session,
    )
    .unwrap();
    assert_eq!(a, b);
    assert!(
        fresh
            .iter()
            .zip(&u)
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    assert!(!session.is_factored());
    assert_eq!(session.analyses(), 1);
}

/// A level redone by the protocol (trivial path past the bifurcation, §3.2) runs on the
/// level's session: one analysis over the level, and the pattern asked for once per stage
/// (first pass, perturbed path, removal: 3), not again for new analyses (a new session for the
/// redo: 4 calls; a new solver for the path and another for the removal, as before: 5).
#[test]
fn a_perturbed_level_makes_no_new_analysis() {
    let (inner, top, h) = compressed();
    let mut wrapped = Wrapped::new(inner);
    let newton = NewtonSettings::default();
    let stepping = Stepping {
        initial: 0.25,
        max: 0.25,
        ..Stepping::default()
    };
    let mut session = PathSolver::new(&wrapped, newton.solver).unwrap();
    wrapped.patterns.set(0);
    let mut u = vec![0.0; wrapped.n()];
    let dof = 3 * top + 2;
    let level = solve_level(
        &mut wrapped,
        &mut u,
        0.0,
        1.0,
        &[(dof, 0.5)],
        &newton,
        &stepping,
        &mut session,
    )
    .unwrap();
    assert!(level.perturbed);
    assert!(u[dof] > 0.3 * h, "w/h = {}", u[dof] / h);
    assert_eq!(session.analyses(), 1);
    assert!(
        wrapped.patterns.get() <= 3,
        "{} calls",
        wrapped.patterns.get()
    );
}

/// The removal of the perturbation past the bifurcation (the column at 1.3·ε_c, 0.5 N lifting
/// it to ~h) is where Newton's full step may raise ‖r‖∞ on its way to the buckled branch: the
/// energy line search (line_search.rs) takes such a step when the potential energy
/// still falls along it. Every iteration of the removal is a full step, and it converges (4
/// iterations). With the residual's backtracking alone it took 10, 7 of them at α ≤ ½ (0.25,
/// 0.25, 0.125, 0.125, 0.25, 0.25, 0.5, then 1).
#[test]
fn the_removal_past_the_bifurcation_takes_full_newton_steps() {
    let (mut problem, top, h) = compressed();
    let dof = 3 * top + 2;
    let stepping = Stepping {
        initial: 0.25,
        max: 0.25,
        ..Stepping::default()
    };
    let mut u = vec![0.0; problem.n()];
    let attempts = perturbed_step(
        &mut problem,
        &mut u,
        0.0,
        1.0,
        &[(dof, 0.5)],
        &NewtonSettings::default(),
        &stepping,
    )
    .unwrap();
    let removal = attempts.last().unwrap();
    assert!(removal.converged(), "{removal:?}");
    let steps: Vec<f64> = removal.iterations.iter().map(|i| i.step).collect();
    eprintln!("the removal's steps: {steps:?}");
    assert!(steps.iter().all(|&a| a == 1.0), "{steps:?}");
    assert!(u[dof] > 0.3 * h, "w/h = {}", u[dof] / h);
}
