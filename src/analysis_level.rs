//! The stages of one level of the sweep ([`super::run`]): the Newton strategy of each level,
//! the solve without contact (whole, by arc length, or in the contact loop's steps, with the
//! BFGS redo), the contact stage, and the level's record (G by [`front_table`],
//! [`deflections`], convergence).

use crate::Error;
use crate::contact::ContactStage;
use crate::model::{Model, ModelKind};
use crate::problem::settings;
use crate::results::{ContactSummary, Crossing, LevelResult};
use crate::scene::ForceKinematics;
use crate::scene::{NewtonName, Scene};
use crate::substructure::Substructured;
use nonlin3d_element::Kinematics;
use nonlin3d_mesh::names::{CENTER_TOP, CRACK_LOWER, CRACK_UPPER};
use nonlin3d_newton::{
    ArcLength, IncrementReport, LevelReport, NewtonSettings, PathSolver, Stepping,
    StructuralProblem, solve_level, solve_level_arc,
};
use nonlin3d_solver::SolverKind;
use nonlin3d_vcct::respect_contact;
use nonlin3d_vcct::{FrontRelease, cells_above, release_rates};
use std::time::Instant;

/// G along the front at state `u`.
pub fn front_table(
    scene: &Scene,
    model: &Model,
    problem: &StructuralProblem,
    u: &[f64],
) -> Result<Vec<FrontRelease>, Error> {
    let kin = match scene.analysis.vcct_forces {
        ForceKinematics::Nonlinear => Kinematics::Nonlinear,
        ForceKinematics::Linear => Kinematics::Linear,
    };
    let f = problem
        .assembler()
        .partial_internal(&cells_above(&model.front), u, kin)?;
    Ok(release_rates(&model.front, &model.mesh.nodes, u, &f)?)
}

/// Deflections at a state: w at the sublaminate centre top (the mean over the `center_top`
/// nodes; 0 without the set), and the largest opening w(upper) − w(lower) over the crack faces
/// (the sublaminate's deflection off the base).
pub fn deflections(model: &Model, u: &[f64]) -> (f64, f64) {
    let mesh = &model.mesh;
    let centre = mesh
        .node_sets
        .get(CENTER_TOP)
        .filter(|s| !s.is_empty())
        .map_or(0.0, |s| {
            s.iter().map(|&n| u[3 * n + 2]).sum::<f64>() / s.len() as f64
        });
    let (up, low) = (
        mesh.node_sets.get(CRACK_UPPER),
        mesh.node_sets.get(CRACK_LOWER),
    );
    let peak = match (up, low) {
        (Some(up), Some(low)) => up
            .iter()
            .zip(low)
            .map(|(&a, &b)| u[3 * a + 2] - u[3 * b + 2])
            .fold(0.0_f64, |m, d| if d.abs() > m.abs() { d } else { m }),
        _ => 0.0,
    };
    (centre, peak)
}

/// The Newton settings of a sweep's levels: the scene's (`newton`), and full Newton for the
/// levels up to the one that takes the §3.2 perturbation when the scene's is modified Newton.
/// Modified Newton reaches the same equilibrium as full Newton along a path, but where the path
/// bifurcates its iterates (an older tangent, other line-search steps) may settle on another
/// branch: on the Hex8 selective-reduced circle full Newton's perturbed level lands on the
/// flat state held by contact, modified Newton's on the state buckled outward. Full Newton
/// there picks the branch as before; past it the levels follow that branch.
pub(super) struct Strategy {
    scene: NewtonSettings,
    full: Option<NewtonSettings>,
}

impl Strategy {
    /// The scene's strategy and its stepping ([`settings`]).
    pub(super) fn of(scene: &Scene) -> (Self, Stepping) {
        let (newton, stepping) = settings(scene);
        let full = (scene.analysis.newton == NewtonName::Modified).then(|| newton.full_newton());
        (
            Self {
                scene: newton,
                full,
            },
            stepping,
        )
    }

    /// The linear solver.
    pub(super) fn solver(&self) -> SolverKind {
        self.scene.solver
    }

    /// The settings of a level (`perturbing`: the perturbation is still offered on it).
    pub(super) fn level(&self, perturbing: bool) -> &NewtonSettings {
        match &self.full {
            Some(full) if perturbing => full,
            _ => &self.scene,
        }
    }
}

/// A level by arc length ([`solve_level_arc`]) from `from` to `lambda`.
pub(super) fn solve_arc(
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    (from, lambda): (f64, f64),
    pert: &[(usize, f64)],
    (newton, arc, stepping): (&NewtonSettings, &ArcLength, &Stepping),
    session: &mut PathSolver,
) -> Result<Solved, Error> {
    let l = solve_level_arc(
        problem, u, from, lambda, pert, newton, arc, stepping, session,
    )?;
    Ok(Solved {
        attempts: l.attempts,
        perturbed: l.perturbed,
        pivots: l.negative_pivots,
        fallback: false,
    })
}

/// One level as [`solve_level`] left it.
#[derive(Default)]
pub(super) struct Solved {
    /// Every increment tried.
    pub(super) attempts: Vec<IncrementReport>,
    /// Whether the perturbation was applied.
    pub(super) perturbed: bool,
    /// Negative pivots of the tangent at the converged state.
    pub(super) pivots: Option<usize>,
    /// Whether full Newton redid the level after BFGS.
    pub(super) fallback: bool,
}

/// Whether `newton` iterates on an older tangent (BFGS, or modified Newton's
/// `refactor_every` > 1): its iteration map may carry a long step to another equilibrium than
/// full Newton's.
pub(super) fn kept_tangent(newton: &NewtonSettings) -> bool {
    newton.keep_tangent || newton.refactor_every > 1
}

/// One level from `from` to `to` by [`solve_level`]; with a kept tangent ([`kept_tangent`]:
/// BFGS, modified Newton) redone by full Newton from the same start if it fails, lands on the
/// branch buckled into the base (`inward` of the converged state; always false with contact
/// `auto`/`on`), or ends with more negative pivots than `before`, the count at the start
/// state (thesis §2.5: an unstable state the path did not cross into by a bifurcation the
/// §3.2 protocol handled; the levels that offer the perturbation are full Newton's already).
#[allow(clippy::too_many_arguments)]
pub(super) fn solve_or_redo(
    inward: &mut dyn FnMut(&[f64]) -> bool,
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    (from, lambda): (f64, f64),
    pert: &[(usize, f64)],
    (newton, stepping): (&NewtonSettings, &Stepping),
    session: &mut PathSolver,
    before: usize,
) -> Result<Solved, Error> {
    let start = u.clone();
    let first = solve_level(problem, u, from, lambda, pert, newton, stepping, session)
        .map(|l| (l.attempts, l.perturbed, l.negative_pivots));
    // BFGS's early directions come from an older tangent and can carry the sublaminate
    // across to the branch buckled into the base (seen on the reference scene at −0.003);
    // a kept tangent's long steps may end on an unstable state full Newton would not reach
    // (the contact loop's passes do so far past buckling: docs/PERFORMANCE.md, "The scene's
    // time"); full Newton follows the stable branch, so the level is redone with it — also
    // when the kept tangent does not converge at all.
    let redo = kept_tangent(newton)
        && first.as_ref().map_or(true, |(_, _, pivots)| {
            inward(u) || pivots.is_some_and(|p| p > before)
        });
    let (mut attempts, mut perturbed, mut pivots) = match first {
        Err(_) if redo => (Vec::new(), false, None),
        r => r?,
    };
    if redo {
        *u = start;
        let full = NewtonSettings {
            solver: newton.solver,
            force_tolerance: newton.force_tolerance,
            ..NewtonSettings::default()
        };
        let level = solve_level(problem, u, from, lambda, pert, &full, stepping, session)?;
        attempts.extend(level.attempts);
        (perturbed, pivots) = (level.perturbed, level.negative_pivots);
    }
    Ok(Solved {
        attempts,
        perturbed,
        pivots,
        fallback: redo,
    })
}

/// What [`solve_in_steps`] solved, the state at the start of its last step, and that step.
pub(super) type Stepped = (Solved, Vec<f64>, (f64, f64));

/// `auto` before contact engages: the level `from` → `lambda` in the contact loop's steps
/// ([`ContactStage::plain_steps`]), each by [`solve_or_redo`] (the perturbation offered until
/// one applies it), up to the first step whose state overlaps (src/contact.rs). Returns what
/// was solved, the state at the start of the last step solved and that step. `before`: the
/// negative pivots at the level's start ([`solve_or_redo`]).
#[allow(clippy::too_many_arguments)]
pub(super) fn solve_in_steps(
    stage: &ContactStage,
    model: &Model,
    inward: &mut dyn FnMut(&[f64]) -> bool,
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    (from, lambda): (f64, f64),
    pert: &[(usize, f64)],
    (newton, stepping): (&NewtonSettings, &Stepping),
    session: &mut PathSolver,
    before: usize,
) -> Result<Stepped, Error> {
    let mut all = Solved::default();
    let mut start = u.clone();
    let mut step = (from, lambda);
    let mut at = from;
    let mut before = before;
    for end in stage.plain_steps(from, lambda) {
        start.clone_from(u);
        step = (at, end);
        let offered = if all.perturbed { &[][..] } else { pert };
        let s = solve_or_redo(
            inward,
            problem,
            u,
            step,
            offered,
            (newton, stepping),
            session,
            before,
        )?;
        before = s.pivots.unwrap_or(before);
        all.attempts.extend(s.attempts);
        all.perturbed |= s.perturbed;
        all.pivots = s.pivots;
        all.fallback |= s.fallback;
        at = end;
        if end != lambda && stage.overlaps(model, u) {
            break;
        }
    }
    Ok((all, start, step))
}

/// A level followed on this mesh from the state `u` at `from` to `lambda`: without contact
/// (by arc length with `arc`, else in the contact loop's steps up to the first that overlaps:
/// [`solve_in_steps`]), then the contact stage if it is active or the state overlaps
/// ([`engage_contact`]). `before`: the negative pivots at the level's start; `t`: when the
/// level started.
#[allow(clippy::too_many_arguments)]
pub(super) fn follow_level(
    stage: &mut ContactStage,
    (scene, model): (&Scene, &Model),
    inward: &mut dyn FnMut(&[f64]) -> bool,
    problem: &mut StructuralProblem,
    u: &mut Vec<f64>,
    (from, lambda): (f64, f64),
    pert: &[(usize, f64)],
    (newton, stepping, arc): (&NewtonSettings, &Stepping, Option<&ArcLength>),
    (session, before, t): (&mut PathSolver, usize, Instant),
) -> Result<(Solved, Option<ContactSummary>), Error> {
    let mut start = u.clone();
    // The step of the level solved last without contact (the whole level unless `auto`
    // solves it in the contact loop's steps).
    let mut step = (from, lambda);
    let mut solved = Solved::default();
    if !stage.active() {
        solved = match arc {
            Some(arc) => solve_arc(
                problem,
                u,
                (from, lambda),
                pert,
                (newton, arc, stepping),
                session,
            )?,
            // `auto`: in the contact loop's steps, up to the first that overlaps
            // (src/contact.rs).
            None => {
                let (all, last_start, last) = solve_in_steps(
                    stage,
                    model,
                    inward,
                    problem,
                    u,
                    (from, lambda),
                    pert,
                    (newton, stepping),
                    session,
                    before,
                )?;
                (start, step) = (last_start, last);
                all
            }
        };
    }
    // (With a superelement `u` is the nonlinear region's and the stage works on it.)
    let contact = engage_contact(
        stage,
        scene,
        model,
        u,
        (&start, step, lambda),
        pert,
        (newton, stepping),
        (&mut solved, t),
    )?;
    Ok((solved, contact))
}

/// The contact stage of a level (src/contact.rs) when it is active or the state solved without
/// contact overlaps: `(start, step, lambda)` the state at the start of the last step solved
/// without contact, that step and the level's end; its attempts, perturbation and pivots are
/// added to `solved` (`t`: when the level started, for the first solve's time). None when
/// contact does not act on the level.
#[allow(clippy::too_many_arguments)]
pub(super) fn engage_contact(
    stage: &mut ContactStage,
    scene: &Scene,
    model: &Model,
    u: &mut Vec<f64>,
    (start, step, lambda): (&[f64], (f64, f64), f64),
    pert: &[(usize, f64)],
    (newton, stepping): (&NewtonSettings, &Stepping),
    (solved, t): (&mut Solved, Instant),
) -> Result<Option<ContactSummary>, Error> {
    // (With a superelement `u` is the nonlinear region's and the stage works on it:
    // src/substructure.rs, `ContactHost`.)
    if !(stage.active() || stage.overlaps(model, u)) {
        return Ok(None);
    }
    // `auto` engaging here continues from the overlapping state (src/contact.rs).
    let plain = (!stage.active()).then(|| {
        let first = LevelReport {
            attempts: Vec::new(),
            perturbed: solved.perturbed,
            negative_pivots: solved.pivots,
        };
        (first, t.elapsed().as_secs_f64())
    });
    let (level, summary) = stage.solve(
        scene,
        model,
        u,
        (start, step.0, step.1, lambda),
        pert,
        plain,
        (newton, stepping),
    )?;
    solved.attempts.extend(level.first.attempts);
    solved.perturbed = level.first.perturbed;
    solved.pivots = level.first.negative_pivots;
    // With BFGS the contact loop runs with full Newton (src/contact.rs).
    solved.fallback |= newton.keep_tangent;
    Ok(Some(summary))
}

/// A solved level's record: G along the front at (u, λ) (VCCT on the full field, recovered
/// with a superelement; the closed points of contact respected), the deflections and the
/// convergence of `solved`; level `k` of value `value`, load factors × `reference` = values.
/// Returns it with the seconds VCCT took. Errors: the sublaminate buckled into the base
/// without contact (peak separation below −1 % of h).
#[allow(clippy::too_many_arguments)]
pub(super) fn record_level(
    scene: &Scene,
    model: &Model,
    problem: &StructuralProblem,
    sub: Option<&mut Substructured>,
    stage: &ContactStage,
    (u, lambda): (&[f64], f64),
    (k, value, reference): (usize, f64, f64),
    solved: Solved,
    contact: Option<ContactSummary>,
) -> Result<(LevelResult, f64), Error> {
    let t = Instant::now();
    let (mut front, full) = match sub {
        Some(s) => {
            let full = s.recover(u, lambda)?;
            (s.front_table(scene, model, &full)?, full)
        }
        None => (front_table(scene, model, problem, u)?, u.to_vec()),
    };
    let closed = stage.closed_upper();
    let states = respect_contact(&mut front, &model.front, |a, _| closed.contains(&a));
    let vcct_s = t.elapsed().as_secs_f64();
    let (centre, peak) = deflections(model, &full);
    if model.kind != ModelKind::Plate && !stage.enabled() && peak < -0.01 * model.h {
        return Err(Error::BuckledIntoBase {
            index: k,
            strain: value,
            separation_mm: peak * 1e3,
        });
    }
    let mut level = LevelResult::new(value, centre, peak, &solved.attempts, &front, full);
    level.set_face_states(&states);
    level.contact = contact;
    level.set_negative_pivots(solved.pivots);
    level.convergence.full_newton_fallback = solved.fallback;
    level.convergence.perturbed = solved.perturbed;
    level.convergence.bifurcation = solved.attempts.iter().find_map(|a| {
        a.bifurcation.map(|b| Crossing {
            from: b.from * reference,
            to: a.lambda * reference,
            negative_pivots_before: b.before,
            negative_pivots_after: b.after,
        })
    });
    Ok((level, vcct_s))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// Modified Newton gives way to full Newton on the levels that still offer the
    /// perturbation, and only there; another strategy is the scene's on every level.
    #[test]
    fn the_perturbed_level_is_solved_with_full_newton() {
        let mut scene = Scene::thesis_reference().unwrap();
        scene.analysis.newton = NewtonName::Modified;
        let (s, _) = Strategy::of(&scene);
        assert_eq!(s.level(true).refactor_every, 1);
        assert!(s.level(false).refactor_every > 1);
        assert_eq!(s.level(true).solver, s.solver());
        for other in [NewtonName::Full, NewtonName::Bfgs] {
            scene.analysis.newton = other;
            let (s, _) = Strategy::of(&scene);
            assert_eq!(s.level(true), s.level(false));
        }
    }
}
