//! The scene's `[contact]` section and the contact stage of the level loop (thesis §2.7,
//! Fig. 2.7.2): crack-face contact by [`nonlin3d_contact::Contact`] around a level's solve.
//!
//! - `off`: the level is solved as without contact (the facade's BFGS inward redo and the
//!   "buckled into the base" error stay);
//! - `on`: every level is solved by the active-set loop from the first level on;
//! - `auto` (default): a level is solved without contact, in the loop's own sub-levels (steps
//!   of at most `ContactSettings::max_step`, 0.25 of the largest level: a sweep's levels are
//!   one step each) with the overlap checked at the end of each; at the first step whose
//!   state overlaps by more than the tolerance (measured as the loop measures it: the
//!   weighted normal gaps g̃ of the deformed faces, [`max_overlap`]), the active-set loop
//!   starts from that overlapping state (the overlapping pairs close and the step is re-solved
//!   at the same load; followed again from its start only if that fails) and follows the rest
//!   of the level in its sub-levels; all later levels are solved by the loop (the set may
//!   open again there). A level without overlap is therefore solved exactly as with `off` in
//!   levels at the step ends, and the level where contact engages follows the loop's path
//!   (sub-levels of at most `max_step`: passes from a state far past the first contact can
//!   settle on another equilibrium than the loading path's — one level ε = −0.004 on a graded
//!   mesh: centre deflection 0.721 mm against the path's 0.674) without solving any step
//!   twice. With arc length the level is solved whole and, if it overlaps and is longer than
//!   `max_step`, followed again from its start in the loop's sub-levels.
//!
//! The contact system (its pattern grown with the set: `nonlin3d_contact::Reserve`) is built on
//! first use, beside the level loop's own system, with its own solver session. In a
//! substructured model (src/substructure.rs) it is the nonlinear region's problem,
//! superelement included, and the pairs are the region's (`ContactHost` in
//! src/substructure.rs).

use crate::model::Model;
use crate::problem::build_problem;
pub use crate::results::{ContactPass, ContactSummary};
pub use crate::scene::{ContactModeName, ContactOptions, CrackFacesName, DEFAULT_TOLERANCE_MM};
use crate::substructure::ContactHost;
use crate::{Error, Scene};
use nonlin3d_contact::{
    Contact, ContactLevel, ContactSettings, ContactState, CrackFaces, Iterate, LevelSettings, Mode,
    Resumed, Tolerances, update,
};
use nonlin3d_mesh::Mesh;
use nonlin3d_mesh::names::{CRACK_LOWER, CRACK_UPPER};
use nonlin3d_newton::{
    IncrementReport, LevelReport, NewtonSettings, PathSolver, Stepping, StructuralProblem,
    Termination,
};

/// The contact system, built on first use.
struct Engaged {
    contact: Contact,
    problem: StructuralProblem,
    session: PathSolver,
}

/// The contact stage of a sweep.
pub(crate) struct ContactStage {
    options: ContactOptions,
    engaged: Option<Engaged>,
    /// A contact system built ahead of its first use ([`prepare`](Self::prepare)), never
    /// used yet, with the solver kind it was analysed for.
    prepared: Option<(Engaged, nonlin3d_solver::SolverKind)>,
    /// The nonlinear region of a substructured model (None: the model itself).
    host: Option<ContactHost>,
}

impl ContactStage {
    /// The stage of a scene (nothing built yet), on the model's DOFs or (`host`) on a
    /// superelement's nonlinear region.
    pub(crate) fn new(scene: &Scene, host: Option<ContactHost>) -> Self {
        Self {
            options: scene.contact,
            engaged: None,
            prepared: None,
            host,
        }
    }

    /// The mesh whose DOFs the level loop's `u` holds.
    fn mesh<'a>(&'a self, model: &'a Model) -> &'a Mesh {
        self.host.as_ref().map_or(&model.mesh, |h| &h.mesh)
    }

    /// Whether contact can act (`auto`/`on`): then the facade's stand-ins for contact (the BFGS
    /// inward redo, the "buckled into the base" error) are off.
    pub(crate) fn enabled(&self) -> bool {
        self.options.enabled()
    }

    /// Whether this level goes straight to the contact loop (`on`, or `auto` once engaged).
    pub(crate) fn active(&self) -> bool {
        self.options.crack_faces == CrackFacesName::On || self.engaged.is_some()
    }

    /// Whether a state overlaps beyond the tolerance (`auto`'s trigger), measured as the loop
    /// measures it ([`max_overlap`]): engaging means the loop's first pass closes a pair. A
    /// lower face without normals (degenerate) engages, and the loop reports it.
    pub(crate) fn overlaps(&self, model: &Model, u: &[f64]) -> bool {
        self.enabled()
            && overlap_on(self.mesh(model), u, self.options.mode)
                .map_or(true, |o| o > self.options.tolerance() * 1e-3)
    }

    /// Solves one level with the contact loop, building the contact system on first use.
    /// `(start, from, to)`: the state at `from` and where the first solve goes; `end` the
    /// level's load factor. `u` is the level's start (`on`, or `auto` once engaged: path
    /// following with the previous level's set; then `to` = `end`) or, on the level where
    /// `auto` engages, the converged state without contact at `to` whose faces overlap (`to`
    /// the end of the first of the [`plain_steps`](Self::plain_steps) that overlaps, `start`
    /// the state at its start): the passes then start from it (the overlapping pairs close,
    /// Newton at the same λ) instead of following the step again, `plain` (what that solve
    /// reported, its time) stands for the first solve, and the loop follows the rest of the
    /// level (`to` → `end`) in its sub-levels.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn solve(
        &mut self,
        scene: &Scene,
        model: &Model,
        u: &mut Vec<f64>,
        (start, from, to, end): (&[f64], f64, f64, f64),
        perturbation: &[(usize, f64)],
        plain: Option<(LevelReport, f64)>,
        (newton, stepping): (&NewtonSettings, &Stepping),
    ) -> Result<(ContactLevel, ContactSummary), Error> {
        // The active-set loop changes the constraints between passes, which a tangent kept
        // across them (BFGS) does not see: it runs with full Newton (measured: BFGS fails to
        // converge on the 30 mm circle at −0.003, slices = 4).
        let full;
        let newton = if newton.keep_tangent {
            full = newton.full_newton();
            &full
        } else {
            newton
        };
        let mut e = match self.engaged.take() {
            Some(e) => e,
            None => self.engage(scene, model, newton)?,
        };
        // A first solve longer than the contact's largest step (arc length) is followed again
        // from its start in sub-levels (the passes from a state far past the first contact can
        // settle on another equilibrium than the loading path's: `ContactSettings::max_step`).
        let engaging = plain.is_some();
        let plain = plain.filter(|_| e.contact.sublevels(from, to) == 1);
        if engaging && plain.is_none() {
            u.clear();
            u.extend_from_slice(start);
        }
        let settings = LevelSettings {
            newton,
            stepping,
            perturbation,
        };
        let level = match plain {
            Some((first, first_seconds)) => {
                let first = Resumed {
                    start,
                    from,
                    to,
                    first,
                    first_seconds,
                };
                e.contact
                    .continue_level(&mut e.problem, &mut e.session, u, first, end, &settings)
            }
            None => {
                e.contact
                    .solve_level(&mut e.problem, &mut e.session, u, (from, end), &settings)
            }
        };
        // Stability counted on the pairs that hold: a closed pair without compressive force
        // would open, so its tie must not hide a mode that lifts the faces apart
        // (`Contact::holding_inertia`).
        let holding = match &level {
            Ok(l) => e
                .contact
                .holding_inertia(&mut e.problem, u, end, &l.state, &mut e.session)
                .map_err(Error::from),
            Err(_) => Ok(None),
        };
        self.engaged = Some(e);
        let mut level = level?;
        if let Some(p) = holding? {
            let tied = level.first.negative_pivots.unwrap_or(0);
            level.first.negative_pivots = Some(tied.max(p));
        }
        let summary = summary(&level);
        Ok((level, summary))
    }

    /// A level started from a given state and set (nested iteration, src/analysis_seed.rs):
    /// the contact system engaged if it was not, `set` (one flag per pair) installed at `u`,
    /// Newton at λ = `lambda` with that set, then the passes of the loop at the same λ
    /// ([`Contact::settle`], at most [`SEEDED_PASSES`]); the stability as in
    /// [`solve`](Self::solve). `u` is the start and becomes the converged state. Errors
    /// ([`Error::Scene`] naming the cause, or the loop's own): the first solve did not
    /// converge, the set read at its state would change at more than [`SEEDED_CHANGE`] of
    /// the pairs, or (`stable`: the companion's state is stable there) a pass converged on a
    /// state with negative pivots (`Contact::set_stable_only`: another equilibrium than the
    /// companion's, which the passes did not leave on the 0.2 mm sublaminate); the caller then
    /// puts the stage back with [`reset`](Self::reset) and follows the level instead.
    pub(crate) fn seed(
        &mut self,
        scene: &Scene,
        model: &Model,
        u: &mut Vec<f64>,
        (set, stable): (&[bool], bool),
        lambda: f64,
        newton: &NewtonSettings,
    ) -> Result<(ContactLevel, ContactSummary), Error> {
        let mut e = match self.engaged.take() {
            Some(e) => e,
            None => self.engage(scene, model, newton)?,
        };
        let before = e.contact.set_stable_only(stable);
        let result = seeded_level(&mut e, u, set, lambda, newton);
        e.contact.set_stable_only(before);
        self.engaged = Some(e);
        let level = result?;
        let summary = summary(&level);
        Ok((level, summary))
    }

    /// What [`reset`](Self::reset) needs to put the stage back: None when the contact system
    /// is not engaged, else its active set.
    pub(crate) fn mark(&self) -> Option<Vec<bool>> {
        self.engaged.as_ref().map(|e| e.contact.active())
    }

    /// Puts the stage back as `mark` found it: not engaged, or engaged with that set installed
    /// at the state `u`.
    pub(crate) fn reset(&mut self, mark: Option<Vec<bool>>, u: &[f64]) -> Result<(), Error> {
        match (mark, self.engaged.as_mut()) {
            (None, _) => self.engaged = None,
            (Some(set), Some(e)) => e.contact.install(&mut e.problem, u, &set)?,
            (Some(_), None) => {}
        }
        Ok(())
    }

    /// Builds the contact system ahead of its first use, where the sweep would otherwise wait
    /// (src/analysis_seed.rs: a seeded level waiting for the companion's): a stage that can
    /// act (`auto`/`on`) and is not engaged builds it now, and its first engagement takes it
    /// instead of building one — the same system, so the same bits (with a reserve grown from
    /// none, the symbolic analysis waits for the first set: `build`). Nothing changes for a
    /// stage that never engages but the CPU spent. A build that fails is dropped: the
    /// engagement builds again and reports the error where it always did.
    pub(crate) fn prepare(&mut self, scene: &Scene, model: &Model, newton: &NewtonSettings) {
        if !self.enabled() || self.engaged.is_some() || self.prepared.is_some() {
            return;
        }
        match self.build(scene, model, newton) {
            Ok(e) => self.prepared = Some((e, newton.solver)),
            Err(why) => tracing::debug!(%why, "the contact system built ahead failed"),
        }
    }

    /// The contact system for its first engagement: the one [`prepare`](Self::prepare) built
    /// (if for the same solver), else built now.
    fn engage(
        &mut self,
        scene: &Scene,
        model: &Model,
        newton: &NewtonSettings,
    ) -> Result<Engaged, Error> {
        match self.prepared.take() {
            Some((e, kind)) if kind == newton.solver => Ok(e),
            _ => self.build(scene, model, newton),
        }
    }

    /// The contact system: the contact's reserve (none yet by default) in the pattern, its own
    /// solver session.
    fn build(
        &self,
        scene: &Scene,
        model: &Model,
        newton: &NewtonSettings,
    ) -> Result<Engaged, Error> {
        let contact = Contact::new(self.mesh(model), self.settings())?;
        let problem = match &self.host {
            Some(host) => host.problem(scene, model, |b| contact.reserve(b))?,
            None => {
                let (assembler, constraints) = build_problem(scene, model)?.into_parts()?;
                StructuralProblem::with_contributions(assembler, Vec::new(), constraints, |b| {
                    contact.reserve(b)
                })?
            }
        };
        // A reserve that grows from none is analysed at its first factorisation, after the
        // first set has widened the pattern (an analysis now would be thrown away).
        let session = if contact.reserved().iter().any(|&r| r) {
            PathSolver::new(&problem, newton.solver)?
        } else {
            PathSolver::deferred(&problem, newton.solver)
        };
        Ok(Engaged {
            contact,
            problem,
            session,
        })
    }

    /// The contact loop's settings of the scene.
    fn settings(&self) -> ContactSettings {
        ContactSettings {
            gap_tolerance: self.options.tolerance() * 1e-3,
            mode: match self.options.mode {
                ContactModeName::TwoBody => Mode::TwoBody,
                ContactModeName::Thesis => Mode::External,
            },
            inexact_passes: self
                .options
                .inexact_passes
                .unwrap_or(ContactSettings::default().inexact_passes),
            ..ContactSettings::default()
        }
    }

    /// The steps in which a level `from` → `to` not yet in the contact loop is solved without
    /// contact, as their end load factors: with `auto` (enabled, not engaged) the loop's own
    /// sub-levels ([`ContactSettings::sublevels`], steps of at most `max_step`), so that the
    /// overlap is checked where the loop would check it and the step that first overlaps is
    /// the loop's first solve (nothing is followed twice); otherwise the whole level.
    pub(crate) fn plain_steps(&self, from: f64, to: f64) -> Vec<f64> {
        if !self.enabled() || self.active() {
            return vec![to];
        }
        let count = self.settings().sublevels(from, to);
        (1..=count)
            .map(|j| ContactSettings::sublevel_end(from, to, j, count))
            .collect()
    }

    /// What the contact system's analysis found (None: contact never engaged).
    pub(crate) fn factor(&self) -> Option<crate::results::FactorSummary> {
        let e = self.engaged.as_ref()?;
        let analysis = e.session.analysis()?;
        Some(crate::results::FactorSummary::of(
            "contact",
            e.problem.assembler().n(),
            &analysis,
        ))
    }

    /// What mixed precision did in the contact system's solver (None: not engaged, or f64).
    pub(crate) fn mixed_stats(&self) -> Option<nonlin3d_solver::MixedStats> {
        self.engaged.as_ref().and_then(|e| e.session.mixed_stats())
    }

    /// The closed pairs' upper nodes, numbered in the model's mesh (empty when contact never
    /// engaged).
    pub(crate) fn closed_upper(&self) -> std::collections::HashSet<usize> {
        let Some(e) = &self.engaged else {
            return Default::default();
        };
        let full = |n: usize| self.host.as_ref().map_or(n, |h| h.to_full[n]);
        e.contact
            .faces()
            .pairs()
            .iter()
            .zip(e.contact.active())
            .filter(|(_, a)| *a)
            .map(|(p, _)| full(p.upper))
            .collect()
    }
}

/// Most passes of a level started from the companion's set ([`ContactStage::seed`]): the
/// seeded levels of nine committed scenes took at most 7; on model 6's companion mesh seeded
/// from its own 1 365-DOF companion a wrong set ground through 17 passes at up to 21 negative
/// pivots before failing (3.7 s of a 1.2 s run). Beyond it the level is followed instead.
const SEEDED_PASSES: usize = 10;

/// A set carried from the companion that the first read at its converged state would change
/// at more than this share of the pairs is dropped before any pass: on nine committed scenes
/// the first read changed at most 9 % of them (16 of 178), on model 6's companion mesh seeded
/// from its own 1 365-DOF companion 99 % (2 closed, 94 overlapping of 96).
const SEEDED_CHANGE: f64 = 0.25;

/// Newton iterations of a seeded level's first solve before its set is read (at the iterate,
/// as an inexact pass reads it): from a carried start the first iteration corrects the
/// transfer (‖r‖∞ 1–30 N on thesis model 6), and the set read there is the one a second
/// iteration would read (near equilibrium, ‖r‖∞ 1e-4–6e-2 N against a force tolerance of
/// about 1e-5 N) on every scene measured: one iteration fewer a seeded contact level where the
/// set changes (model 6: 32 → 26 of the run's iterations; the 15 mm edge 6 → 4; the 30 mm
/// circle 8 → 6), the same states (docs/PERFORMANCE.md, "Setup only where it is used").
const SEEDED_STEPS: usize = 1;

/// [`ContactStage::seed`] on the engaged system: the carried set installed, [`SEEDED_STEPS`]
/// Newton iterations, the set read at the iterate; if it changes there (and the loop reads
/// iterates, `inexact_passes` > 0) the passes go on from the iterate
/// ([`Contact::settle_iterate`]), else Newton converges the carried set first and the
/// passes start from the converged state.
fn seeded_level(
    e: &mut Engaged,
    u: &mut Vec<f64>,
    set: &[bool],
    lambda: f64,
    newton: &NewtonSettings,
) -> Result<ContactLevel, Error> {
    e.contact.install(&mut e.problem, u, set)?;
    let inexact = e.contact.settings().inexact_passes > 0;
    let few = NewtonSettings {
        max_iterations: if inexact {
            SEEDED_STEPS
        } else {
            newton.max_iterations
        },
        ..newton.clone()
    };
    let mut first = e.session.solve_at(&mut e.problem, u, lambda, &few)?;
    let stopped = matches!(first.termination, Termination::MaxIterations) && inexact;
    if !first.converged() && !stopped {
        return Err(not_converged(lambda, set));
    }
    // The set the first read would make (at the iterate: its forces are off by about ‖r‖∞):
    // a prediction it changes at many pairs is not the companion's state (module docs of
    // src/analysis_seed.rs).
    let residual = match (stopped, first.iterations.last()) {
        (true, Some(last)) => last.residual,
        _ => 0.0,
    };
    let state = e.contact.state(&mut e.problem, u, lambda, newton)?;
    let tolerances = Tolerances {
        gap: e.contact.settings().gap_tolerance,
        force: state.force_tolerance + residual,
    };
    let change = update(
        &state.weighted_gaps,
        &state.recovered,
        &state.active,
        tolerances,
    );
    let changed = change.added.len() + change.released.len();
    if changed as f64 > SEEDED_CHANGE * set.len() as f64 {
        return Err(Error::Scene(format!(
            "the companion's contact set would change at {changed} of {} pairs at λ = {lambda}",
            set.len()
        )));
    }
    let iterate = stopped && changed > 0;
    if stopped && !iterate {
        // The carried set stays at the iterate: converge it, then the passes as before.
        let rest = e.session.solve_at(&mut e.problem, u, lambda, newton)?;
        if !rest.converged() {
            return Err(not_converged(lambda, set));
        }
        first.iterations.extend(rest.iterations);
        first.termination = rest.termination;
    }
    let pivots = first.negative_pivots();
    let limit = e.contact.set_max_passes(SEEDED_PASSES);
    let level = if iterate {
        let from = Iterate {
            steps: first.iterations.len(),
            residual,
            tolerance: state.force_tolerance,
        };
        e.contact
            .settle_iterate(&mut e.problem, u, lambda, newton, &mut e.session, from)
    } else {
        e.contact
            .settle(&mut e.problem, u, lambda, newton, &mut e.session)
    };
    e.contact.set_max_passes(limit);
    let mut level = level?;
    let mut attempts = vec![first];
    if iterate {
        // The first solve stopped at its iterate; the level converged in the passes. Its
        // record ends with that converged state's check (no iteration): ‖r‖∞ there, so that
        // results.json's residual is the level's, not the iterate's.
        attempts.push(converged_here(&level.state, lambda, &attempts[0]));
    }
    level.first = LevelReport {
        attempts,
        perturbed: false,
        negative_pivots: pivots,
    };
    if let Some(p) =
        e.contact
            .holding_inertia(&mut e.problem, u, lambda, &level.state, &mut e.session)?
    {
        level.first.negative_pivots = Some(pivots.unwrap_or(0).max(p));
    }
    Ok(level)
}

/// The record of a converged state reached outside Newton's own iterations (the contact
/// passes after a first solve stopped at its iterate): no iteration, ‖r‖∞ as the passes read
/// it at that state, converged.
fn converged_here(state: &ContactState, lambda: f64, first: &IncrementReport) -> IncrementReport {
    IncrementReport {
        lambda,
        initial_residual: state.residual,
        tolerance: first.tolerance,
        iterations: Vec::new(),
        termination: Termination::Converged,
        bifurcation: None,
    }
}

/// A carried start whose first solve did not converge (the level is then followed).
fn not_converged(lambda: f64, set: &[bool]) -> Error {
    Error::Scene(format!(
        "the start carried from the companion mesh did not converge at λ = {lambda} with its {} \
         closed pairs",
        set.iter().filter(|&&a| a).count()
    ))
}

/// The results.json record of a level: counts, the largest force, pressure and overlap (the
/// gaps along the contact normals, as the loop tests them), iterations and times per pass.
fn summary(level: &ContactLevel) -> ContactSummary {
    let s = &level.state;
    let max = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    ContactSummary {
        passes: level.passes.len(),
        pairs_closed: s.active.iter().filter(|&&a| a).count(),
        max_force_n: max(&s.forces),
        max_pressure_mpa: max(&s.pressures) * 1e-6,
        max_penetration_mm: s.penetration() * 1e3,
        iterations: level.newton_iterations(),
        first_s: level.first_seconds,
        pass_log: level
            .passes
            .iter()
            .map(|p| ContactPass {
                closed: p.closed.len(),
                opened: p.opened.len(),
                refresh: p.refresh,
                inexact: p.inexact,
                iterations: p.iterations,
                seconds: p.seconds,
            })
            .collect(),
    }
}

/// The largest overlap over the crack-face pairs, m (0: none), as the contact loop's closing
/// test reads it (`nonlin3d_contact::update`): −g̃ with g̃ = T⁻ᵀ g the weighted normal gaps
/// (two-body), −g the normal gaps g = n·(x_up − x_low) (thesis mode), n the deformed lower
/// face's normal. Errors: a mesh whose crack faces the contact crate refuses, a degenerate
/// deformed lower face.
pub fn max_overlap(model: &Model, u: &[f64], mode: ContactModeName) -> Result<f64, Error> {
    overlap_on(&model.mesh, u, mode)
}

/// [`max_overlap`] on `mesh` (the model's, or a superelement's nonlinear region) whose DOFs
/// `u` holds.
fn overlap_on(mesh: &Mesh, u: &[f64], mode: ContactModeName) -> Result<f64, Error> {
    let sets = &mesh.node_sets;
    if !(sets.contains_key(CRACK_UPPER) && sets.contains_key(CRACK_LOWER)) {
        return Ok(0.0);
    }
    let faces = CrackFaces::from_mesh(mesh)?;
    let normals = faces.normals(u)?;
    let gaps = faces.gaps(u, &normals);
    let gaps = match mode {
        ContactModeName::TwoBody => faces.weighted_gaps(&gaps),
        ContactModeName::Thesis => gaps,
    };
    Ok(gaps.iter().fold(0.0, |m: f64, &g| m.max(-g)))
}
