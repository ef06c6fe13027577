//! The scene's structural problem (thesis §3.2): the load factors of its levels, the
//! constraints and load of its model, the assembler over it, and the Newton and stepping
//! settings. Used by the analysis pipeline ([`crate::analysis`], which re-exports these), the
//! contact and substructuring stages and the deck export.

use crate::Error;
use crate::model::{Model, Value};
use crate::scene::{Geometry, NewtonName, Scene, SolverName};
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_element::Kinematics;
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_newton::{NewtonSettings, Stepping, StructuralProblem};
use nonlin3d_solver::SolverKind;

/// The load factors of the levels: strains (or loads) divided by the largest in magnitude,
/// and that reference value.
pub fn load_factors(scene: &Scene) -> (Vec<f64>, f64) {
    let values = if matches!(scene.geometry, Geometry::Plate { .. }) {
        &scene.loads.transverse_n
    } else {
        &scene.loads.strains
    };
    let reference = values
        .iter()
        .copied()
        .max_by(|a, b| a.abs().total_cmp(&b.abs()))
        .unwrap_or(1.0);
    (values.iter().map(|v| v / reference).collect(), reference)
}

/// The constraints and load of a model (§3.2) from its [`Model::supports`] and
/// [`Model::central_load`], at load factor λ = 1: held components 0, the end displacement
/// u = x_end·ε_ref (ε_ref the scene's largest strain), the plate's load P_ref/4 split over the
/// `center_top` nodes; `reference` is ε_ref (or P_ref, N), as [`load_factors`] gives it.
pub fn constraints(model: &Model, reference: f64) -> Result<Constraints, Error> {
    let mut c = Constraints::new(3 * model.mesh.nodes.len());
    for s in model.supports()? {
        let nodes = model.nodes_of(&s.nodes)?;
        match s.value {
            Value::Zero => c.fix_nodes(nodes, s.axis.offset())?,
            v => {
                for &n in nodes {
                    let x = model.mesh.nodes[n];
                    c.prescribe(3 * n + s.axis.offset(), v.at(s.axis, x, reference))?;
                }
            }
        }
    }
    if let Some(load) = model.central_load() {
        let nodes = model.node_set(load.set)?;
        let share = 1.0 / nodes.len() as f64;
        for &n in nodes {
            c.add_load(3 * n + 2, load.fraction * reference * share)?;
        }
    }
    Ok(c)
}

/// The assembler and constraints of a model (§3.2): supports, the prescribed end
/// displacement u = x_end·ε_ref·λ (or the plate's load P_ref·λ/4 on the quarter model), as
/// [`constraints`] gives them.
pub fn build_problem(scene: &Scene, model: &Model) -> Result<StructuralProblem, Error> {
    let rule = scene.analysis.integration.rule();
    let assembler = Assembler::new(
        &model.mesh,
        &model.materials,
        ShearCoupling::Exact,
        rule,
        rule,
        Kinematics::Nonlinear,
    )?;
    let (_, reference) = load_factors(scene);
    let c = constraints(model, reference)?;
    Ok(StructuralProblem::new(assembler, c)?)
}

/// Newton and stepping settings of a scene. Convergence: the relative residual criterion of
/// [`NewtonSettings::default`] (‖r‖∞ ≤ 1e-8·F), or with `analysis.tolerance_n` that absolute
/// tolerance in N alone (relative tolerance 0), as given.
pub fn settings(scene: &Scene) -> (NewtonSettings, Stepping) {
    let a = &scene.analysis;
    let base = NewtonSettings::default();
    let newton = NewtonSettings {
        force_tolerance: a.tolerance_n.unwrap_or(0.0),
        relative_tolerance: match a.tolerance_n {
            Some(_) => 0.0,
            None => base.relative_tolerance,
        },
        refactor_every: match a.newton {
            NewtonName::Full => 1,
            NewtonName::Modified => a.refactor_every,
            NewtonName::Bfgs => usize::MAX,
        },
        max_iterations: match a.newton {
            NewtonName::Full => 25,
            NewtonName::Modified | NewtonName::Bfgs => 60,
        },
        // BFGS on a tangent kept across increments (the fastest strategy on the plate,
        // docs/PERFORMANCE.md): refactor when an iteration leaves ‖r‖∞ above twice the
        // previous; no line search (it rejects BFGS's first overshooting directions).
        keep_tangent: a.newton == NewtonName::Bfgs,
        quasi_newton: if a.newton == NewtonName::Bfgs { 20 } else { 0 },
        line_search: a.newton != NewtonName::Bfgs,
        refactor_ratio: if a.newton == NewtonName::Bfgs {
            nonlin3d_newton::BFGS_REFACTOR_RATIO
        } else {
            0.5
        },
        solver: match (a.solver, a.threads) {
            (SolverName::Profile, _) => SolverKind::Profile,
            (SolverName::Auto, n) if a.newton == NewtonName::Full => SolverKind::FaerLdltAuto(n),
            // A factorisation serves many directions, each solved to 1 % of ‖r‖
            // (`nonlin3d_newton::KEPT_FORCING`): f32 from a smaller size.
            (SolverName::Auto, n) => SolverKind::FaerLdltKept(n),
            // 0: the rayon pool's threads (`--threads N`); the bits do not depend on it.
            (SolverName::Faer, 0) => SolverKind::FaerLdlt,
            (SolverName::Faer, n) => SolverKind::FaerLdltThreads(n),
            (SolverName::FaerMixed, n) => SolverKind::FaerLdltMixed(n),
        },
        ..NewtonSettings::default()
    };
    let stepping = Stepping {
        initial: a.max_increment,
        max: a.max_increment,
        max_attempts: a.max_attempts,
        ..Stepping::default()
    };
    (newton, stepping)
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    fn solver_of(analysis: &str) -> SolverKind {
        let text = std::fs::read_to_string(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/scenes/fig_5_1_3_circle_30mm.toml"
        ))
        .unwrap();
        let text = text.replace("[analysis]", &format!("[analysis]\n{analysis}"));
        settings(&Scene::from_toml(&text).unwrap()).0.solver
    }

    /// `solver = "auto"` (the default): the size rule of mixed precision with full Newton, the
    /// kept tangent's (from a smaller size, directions to 1 % of ‖r‖) with BFGS and modified
    /// Newton; named solvers as named.
    #[test]
    fn the_default_solver_follows_the_newton_strategy() {
        assert_eq!(solver_of(""), SolverKind::FaerLdltAuto(0));
        assert_eq!(solver_of("threads = 1"), SolverKind::FaerLdltAuto(1));
        assert_eq!(solver_of("newton = \"bfgs\""), SolverKind::FaerLdltKept(0));
        assert_eq!(
            solver_of("newton = \"modified\"\nthreads = 2"),
            SolverKind::FaerLdltKept(2)
        );
        assert_eq!(solver_of("solver = \"faer\""), SolverKind::FaerLdlt);
        assert_eq!(
            solver_of("solver = \"faer-mixed\""),
            SolverKind::FaerLdltMixed(0)
        );
    }
}
