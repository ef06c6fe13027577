//! The analysis pipeline (thesis §3.2, chapter 5): scene → mesh → constraints → Newton with the
//! perturbation load and the strain sweep → VCCT at each level → [`Results`].
//!
//! Each stage is callable alone: [`build_model`], [`build_problem`], [`solve_level`],
//! [`front_table`]; [`run`] (or [`Analysis::run`]) strings them together and times them.

use crate::contact::ContactStage;
pub use crate::model::{Model, ModelKind, build_model, perturbation_force, perturbation_loads};
pub use crate::problem::{build_problem, constraints, load_factors, settings};
use crate::scene::{PartitionName, PathName, Scene};
use crate::substructure::Substructured;
use crate::{Error, results::*};
pub use nonlin3d_newton::solve_level;
use nonlin3d_newton::{ArcLength, PathSolver, SignRule, StructuralProblem};
use nonlin3d_vcct::FrontRelease;
use std::time::Instant;

#[path = "analysis_estimate.rs"]
pub(crate) mod estimate;
#[path = "analysis_level.rs"]
mod level;
#[path = "analysis_seed.rs"]
pub(crate) mod seed;
use level::{Strategy, follow_level, record_level};
pub use level::{deflections, front_table};

/// What [`run`] reports as it goes.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// The model is built: nodes, cells, DOFs, levels to solve.
    Built {
        /// The model (mesh and front).
        model: &'a Model,
        /// DOFs.
        dofs: usize,
        /// Levels.
        levels: usize,
    },
    /// Level `index` (0-based) converged at `value` (strain or load).
    Level {
        /// Index.
        index: usize,
        /// Applied strain (or load, N).
        value: f64,
        /// The level's record, as it will appear in the results (without the criterion).
        result: &'a LevelResult,
    },
}

/// Runs a scene end to end; `progress` is told after the model is built and after each level
/// (to show progress, or to write each level's output as it converges: [`crate::output`]); an
/// error it returns stops the run.
///
/// Stages: the budget check, [`build_model`], [`build_problem`], the sweep over the levels
/// (each solved by [`solve_level`], its front by [`front_table`]), the scene's criterion on
/// every front point and the critical strain, the [`Results`].
pub fn run(
    scene: &Scene,
    progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
) -> Result<Results, Error> {
    run_at(scene, progress, 0)
}

/// [`run`] at `depth` in a chain of companions (0: the run itself; 1: its error estimate's
/// companion; 2: the companion's own, src/analysis_seed.rs "Nested companions"): a companion
/// runs beside (or before) it where [`seed::companion_runs`] says so; only the run itself
/// attaches the estimate, a companion's serves its levels' starts alone.
pub(crate) fn run_at(
    scene: &Scene,
    progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
    depth: usize,
) -> Result<Results, Error> {
    // `[mesh] accuracy` or the default mesh turned into knobs before anything is sized.
    let (resolved, choice) = estimate::resolve_mesh(scene)?;
    // The whole run (tangent and factor too) estimated before meshing.
    crate::budget::check_scene(&resolved, &crate::budget::limit())?;
    let t0 = Instant::now();
    let model = build_model(&resolved)?;
    let asked = resolved.analysis.threads;
    let scene = &resolved;
    let t_mesh = t0.elapsed().as_secs_f64();
    // Whether a companion runs (the error estimate's, or a coarser one whose levels this run
    // starts from) is decided on the mesh alone, so that it starts before this run's setup:
    // down a chain of companions the deepest, which the others wait for, starts first.
    let substructured = scene.substructure.partition != PartitionName::None;
    let runs = seed::companion_runs(scene, &model, substructured, depth);
    let seeding = runs && seed::wanted(scene, &model, substructured);
    // A companion's own companion serves its seeds only: none, no run.
    let runs = runs && (depth == 0 || seeding);
    let beside = runs && asked != 1 && rayon::current_num_threads() >= 2;
    let deeper = depth + 1;
    // Nested iteration (src/analysis_seed.rs): the companion sends its levels as they converge
    // and the sweep starts its levels from them.
    let (to, from) = std::sync::mpsc::channel();
    let from = seeding.then_some(from);
    let mut companion = None;
    // With two or more threads the companion (an independent run) goes on beside this one,
    // in the same pool; sequentially it runs before the sweep when it seeds it, else after it
    // (in the estimate). The bits are the same either way (tests/concurrent_estimate.rs).
    let (mut sweep, sub, t_setup) = if beside {
        rayon::in_place_scope(|s| {
            s.spawn(|_| {
                companion = Some(match seeding {
                    true => estimate::run_companion_sending(scene, to, deeper),
                    false => estimate::run_companion(scene, deeper),
                })
            });
            set_up_and_sweep(scene, &model, from, deeper, None, progress)
        })
    } else {
        let before = runs.then_some((to, &mut companion));
        set_up_and_sweep(scene, &model, from, deeper, before, progress)
    }?;
    let dofs = 3 * model.mesh.nodes.len();
    let critical = criterion(scene, model.kind, &mut sweep.levels)?;
    let mut results = Results {
        title: scene.title.clone(),
        complete: true,
        stopped: None,
        quantity: if model.kind == ModelKind::Plate {
            "load_n"
        } else {
            "strain"
        }
        .into(),
        model: ModelSummary {
            nodes: model.mesh.nodes.len(),
            cells: model.mesh.cells.len(),
            dofs,
            front_points: sweep.levels.first().map_or(0, |l| l.front.len()),
            perturbation_n: (sweep.force != 0.0).then_some(sweep.force),
            perturbed_at: sweep.perturbed_at,
            substructure: sub.map(|s| s.summary),
        },
        levels: sweep.levels,
        critical,
        timings: Timings {
            mesh_s: t_mesh,
            setup_s: t_setup,
            solve_s: sweep.solve_s,
            vcct_s: sweep.vcct_s,
            output_s: 0.0,
            threads: match scene.analysis.threads {
                0 => rayon::current_num_threads(),
                n => n,
            },
            mixed_precision: sweep.mixed.take(),
            factor: std::mem::take(&mut sweep.factor),
        },
        model_data: Some(model),
        coarser: None,
        accuracy: None,
        warnings: Vec::new(),
        provenance: None,
    };
    // The error estimate of every level (the companion mesh) and the target's verdict; its
    // warnings after the scene's and before the stability ones (a run's end says last).
    if depth == 0 {
        estimate::attach(scene, choice, companion, &mut results)?;
    } else if let Some((run, _)) = companion {
        // A companion's own companion: its levels go up with the companion's, to the
        // estimate's second term (src/analysis_estimate.rs), or why it has none.
        results.coarser = Some(match run {
            Ok(coarser) => CoarserRun {
                dofs: coarser.model.dofs,
                levels: coarser.levels,
                failure: None,
            },
            Err(e) => CoarserRun {
                dofs: 0,
                levels: Vec::new(),
                failure: Some(e.to_string()),
            },
        });
    }
    let estimated = std::mem::take(&mut results.warnings);
    results.warnings = scene.warnings();
    results.warnings.extend(estimated);
    results.warnings.extend(results.stability_warnings());
    Ok(results)
}

/// This run's setup (the problem, or the nonlinear sub-mesh and its superelement with
/// `[substructure]`) and its [`sweep`], its levels started from the companion's arriving on
/// `from` where they can be carried onto this mesh ([`seeds`]; the companion at `deeper`).
/// `before`: the companion to run here first when it seeds the levels (one thread), its run
/// stored beside the sender.
/// Returns the sweep, the substructure and the setup's seconds.
fn set_up_and_sweep(
    scene: &Scene,
    model: &Model,
    from: Option<std::sync::mpsc::Receiver<seed::SeedLevel>>,
    deeper: usize,
    before: Option<(
        std::sync::mpsc::Sender<seed::SeedLevel>,
        &mut Option<estimate::CompanionRun>,
    )>,
    progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
) -> Result<(Sweep, Option<Substructured>, f64), Error> {
    let t1 = Instant::now();
    let (mut problem, mut sub) = match crate::substructure::build(scene, model)? {
        Some((p, s)) => (p, Some(s)),
        None => (build_problem(scene, model)?, None),
    };
    let t_setup = t1.elapsed().as_secs_f64();
    progress(Progress::Built {
        model,
        dofs: 3 * model.mesh.nodes.len(),
        levels: load_factors(scene).0.len(),
    })?;
    let mut seeds = from.and_then(|f| seeds(scene, model, f, deeper));
    if let (Some(_), Some((to, companion))) = (&seeds, before) {
        *companion = Some(estimate::run_companion_sending(scene, to, deeper));
    }
    let sweep = sweep(
        scene,
        model,
        &mut problem,
        sub.as_mut(),
        progress,
        seeds.as_mut(),
    )?;
    Ok((sweep, sub, t_setup))
}

/// The companion's levels carried onto `model` (the companion's mesh rebuilt here: the
/// generators are deterministic); None, with the reason in the log, when they cannot be (the
/// levels are then followed on this mesh).
fn seeds(
    scene: &Scene,
    model: &Model,
    from: std::sync::mpsc::Receiver<seed::SeedLevel>,
    depth: usize,
) -> Option<seed::Seeds> {
    let built = estimate::companion_scene(scene, depth)
        .and_then(|c| build_model(&c))
        .and_then(|coarse| seed::Seeds::new(scene, &coarse, model, from));
    built
        .inspect_err(|e| tracing::debug!(%e, "no nested iteration: the levels are followed"))
        .ok()
}

/// What the sweep over the levels gives [`run`].
struct Sweep {
    /// One record per level, in order.
    levels: Vec<LevelResult>,
    /// The perturbation force, N (0: none).
    force: f64,
    /// The level value at which the perturbation was applied, if it was.
    perturbed_at: Option<f64>,
    /// Seconds in the solves and in VCCT.
    solve_s: f64,
    vcct_s: f64,
    /// What mixed precision did (None with an f64 solver).
    mixed: Option<MixedSummary>,
    /// What the main mesh's systems' analyses found (the level loop's, the contact loop's).
    factor: Vec<FactorSummary>,
}

/// The levels solved in order from the unloaded state, each from the previous converged
/// state, with the perturbation offered until one level takes it (§3.2); `progress` is told
/// after each level.
fn sweep(
    scene: &Scene,
    model: &Model,
    problem: &mut StructuralProblem,
    mut sub: Option<&mut Substructured>,
    progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
    mut seeds: Option<&mut seed::Seeds>,
) -> Result<Sweep, Error> {
    let plate = model.kind == ModelKind::Plate;
    let (factors, reference) = load_factors(scene);
    // Levels are reported with the scene's own values (λ·reference may differ in the last bit).
    let values = if plate {
        &scene.loads.transverse_n
    } else {
        &scene.loads.strains
    };
    let (strategy, stepping) = Strategy::of(scene);
    // The force is looked up (and its node set needed) only when one is wanted.
    let force = if plate {
        0.0
    } else {
        perturbation_force(scene, model)?
    };
    let mut perturbation = perturbation_loads(model, force)?;
    if let Some(s) = &sub {
        perturbation = s.to_nonlinear(&perturbation)?;
    }
    let mut u = vec![0.0; problem.assembler().n()];
    // One solver for every level: analysed once; with BFGS each level starts from the
    // factorisation its predecessor's stability test left. Analysed at its first use where
    // memory leaves room (a seeded one-level run may never use it: its levels start in the
    // contact system); else now, where the factor's size is checked against the limit.
    let mut session = if crate::budget::analysis_may_wait(scene, &crate::budget::limit()) {
        PathSolver::deferred(problem, strategy.solver())
    } else {
        PathSolver::new(problem, strategy.solver())?
    };
    let mut out = Sweep {
        levels: Vec::with_capacity(factors.len()),
        force,
        perturbed_at: None,
        solve_s: 0.0,
        vcct_s: 0.0,
        mixed: None,
        factor: Vec::new(),
    };
    let host = sub
        .as_deref_mut()
        .and_then(Substructured::take_contact_host);
    let mut stage = ContactStage::new(scene, host);
    let arc = arc_length(scene);
    // `on` solves every level in the contact loop (load control); `auto` only the levels
    // whose faces overlap, the others by arc length.
    if arc.is_some() && stage.active() {
        return Err(Error::Scene(
            "[analysis] path = \"arc-length\" with [contact] crack_faces = \"on\": the \
             contact loop follows the path by load control; choose one"
                .into(),
        ));
    }
    let mut from = 0.0;
    // Negative pivots at the last converged state (the unloaded one: none).
    let mut before = 0;
    for (k, (&lambda, &value)) in factors.iter().zip(values).enumerate() {
        // Newton's `attempt` spans and events (crate::log) nest in it.
        let _level = tracing::debug_span!("level", level = k + 1, value).entered();
        let t = Instant::now();
        let pert: &[(usize, f64)] = if out.perturbed_at.is_none() {
            &perturbation
        } else {
            &[]
        };
        let newton = strategy.level(!pert.is_empty());
        let level_error = |e: Error| Error::Level {
            index: k,
            quantity: if plate { "load" } else { "strain" },
            value,
            source: Box::new(e),
        };
        // Buckled into the base: judged on the full field (recovered with a superelement); with
        // contact (`auto`/`on`) the contact stage corrects that branch instead.
        let redo_inward = !stage.enabled();
        let mut inward = |u: &[f64]| {
            redo_inward
                && !plate
                && match sub.as_deref_mut() {
                    Some(s) => s.recover(u, lambda).map(|f| deflections(model, &f).1),
                    None => Ok(deflections(model, u).1),
                }
                .is_ok_and(|peak| peak < -0.01 * model.h)
        };
        let mut companion_set = false;
        let seeded = match seeds.as_deref_mut() {
            Some(seeds) => seed::solve_seeded(
                seeds,
                k,
                (scene, model),
                problem,
                &mut session,
                &mut stage,
                &mut u,
                lambda,
                (newton, &stepping),
            )
            .map_err(level_error)?,
            None => None,
        };
        // A seeded level: the companion's perturbation, and its crossing if this mesh has not
        // crossed one itself (it may bifurcate a level earlier than its companion).
        let (solved, contact, companion) = match seeded {
            Some(s) => {
                let crossing = s.bifurcation.filter(|_| out.perturbed_at.is_none());
                (s.solved, s.contact, Some((s.perturbed, crossing)))
            }
            None => {
                // Followed here after seeding stopped paying: the companion's set at this
                // level, where it predicts this mesh's (src/analysis_seed.rs).
                let set = match seeds.as_deref_mut() {
                    Some(s) if stage.active() => {
                        s.followed_set(k, scene.contact.tolerance() * 1e-3)
                    }
                    _ => None,
                };
                companion_set = set.is_some();
                if set.is_some() {
                    stage.reset(set, &u).map_err(level_error)?;
                }
                let (solved, contact) = follow_level(
                    &mut stage,
                    (scene, model),
                    &mut inward,
                    problem,
                    &mut u,
                    (from, lambda),
                    pert,
                    (newton, &stepping, arc.as_ref()),
                    (&mut session, before, t),
                )
                .map_err(level_error)?;
                (solved, contact, None)
            }
        };
        if solved.perturbed || (companion.is_some_and(|c| c.0) && out.perturbed_at.is_none()) {
            out.perturbed_at = Some(value);
        }
        before = solved.pivots.unwrap_or(before);
        out.solve_s += t.elapsed().as_secs_f64();
        let (mut level, vcct_s) = record_level(
            scene,
            model,
            problem,
            sub.as_deref_mut(),
            &stage,
            (&u, lambda),
            (k, value, reference),
            solved,
            contact,
        )?;
        if let Some((_, crossing)) = companion {
            level.convergence.seeded = true;
            level.convergence.bifurcation = crossing;
        }
        level.convergence.companion_set = companion_set;
        push_level(&mut out, progress, (k, value, vcct_s), level)?;
        from = lambda;
    }
    out.mixed = MixedSummary::of([session.mixed_stats(), stage.mixed_stats()]);
    let solid = session
        .analysis()
        .map(|a| FactorSummary::of("solid", problem.assembler().n(), &a));
    out.factor = solid.into_iter().chain(stage.factor()).collect();
    Ok(out)
}

/// Level `k` of value `value` recorded (its VCCT seconds `vcct_s`) and reported.
fn push_level(
    out: &mut Sweep,
    progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
    (k, value, vcct_s): (usize, f64, f64),
    level: LevelResult,
) -> Result<(), Error> {
    out.vcct_s += vcct_s;
    progress(Progress::Level {
        index: k,
        value,
        result: &level,
    })?;
    out.levels.push(level);
    Ok(())
}

/// The arc-length control of a scene with `path = "arc-length"` (None for `load`): the first
/// arc of a level moves the load factor by at most `max_increment` (the load path's largest
/// step), arcs grow up to that (in units of the load factor at the level's start), at most
/// `max_attempts` increments a level; the predictor's sign by newton's default
/// ([`SignRule::Combined`]): the trivial path crosses a bifurcation (one eigenvalue through
/// zero, λ still rising) where det K_T's sign alone would turn back.
pub fn arc_length(scene: &Scene) -> Option<ArcLength> {
    let a = &scene.analysis;
    (a.path == PathName::ArcLength).then(|| ArcLength {
        initial: a.max_increment,
        max: a.max_increment,
        min: 1e-4 * a.max_increment,
        max_increments: a.max_attempts.max(1),
        sign: SignRule::Combined,
        ..ArcLength::default()
    })
}

/// The scene's mixed-mode criterion, if any, on every open front point of every level (no
/// index where the faces overlap: not physical without contact), and the critical strain of
/// the sweep (none for the plate).
fn criterion(
    scene: &Scene,
    kind: ModelKind,
    levels: &mut [LevelResult],
) -> Result<Option<Critical>, Error> {
    let Some(c) = &scene.criterion else {
        return Ok(None);
    };
    let criterion = c.criterion();
    for l in levels.iter_mut() {
        for row in &mut l.front {
            row.failure_index = row.is_open().then(|| criterion.index(&row.release()));
        }
    }
    if kind == ModelKind::Plate {
        return Ok(None);
    }
    let sweep: Vec<(f64, Vec<FrontRelease>)> = levels
        .iter()
        .map(|l| (l.value, l.front.iter().map(FrontRow::release).collect()))
        .collect();
    Ok(
        nonlin3d_vcct::critical_strain(&criterion, &sweep)?.map(|c| {
            let r = &sweep[c.level].1[c.point];
            Critical {
                strain: c.strain,
                after: c.after,
                s_mm: c.s * 1e3,
                level: c.level,
                index: c.index,
                mode_mix: nonlin3d_vcct::MixedMode::mode_mix(r),
                g_i: r.g_i,
                g_ii: r.g_ii,
                g_iii: r.g_iii,
            }
        }),
    )
}

/// A scene ready to run, stage by stage or all at once: `Analysis::new(scene)?.run()`.
#[derive(Debug, Clone)]
pub struct Analysis {
    scene: Scene,
}

impl Analysis {
    /// Validates `scene`.
    pub fn new(scene: Scene) -> Result<Self, Error> {
        scene.validate()?;
        Ok(Self { scene })
    }

    /// The scene.
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Stage 1: the mesh and front ([`build_model`]).
    pub fn model(&self) -> Result<Model, Error> {
        build_model(&self.scene)
    }

    /// Stage 2: assembler and constraints for a model ([`build_problem`]).
    pub fn problem(&self, model: &Model) -> Result<StructuralProblem, Error> {
        build_problem(&self.scene, model)
    }

    /// Stage 4: G along the front of `model` at state `u` ([`front_table`]).
    pub fn front_table(
        &self,
        model: &Model,
        problem: &StructuralProblem,
        u: &[f64],
    ) -> Result<Vec<FrontRelease>, Error> {
        front_table(&self.scene, model, problem, u)
    }

    /// All stages ([`run`]), silently.
    pub fn run(&self) -> Result<Results, Error> {
        run(&self.scene, &mut |_| Ok(()))
    }

    /// All stages, reporting [`Progress`]; an error from `progress` stops the run.
    pub fn run_with(
        &self,
        progress: &mut dyn FnMut(Progress) -> Result<(), Error>,
    ) -> Result<Results, Error> {
        run(&self.scene, progress)
    }
}
