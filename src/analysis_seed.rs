//! Nested iteration (`[analysis] start = "companion"`): the levels past the buckling level start
//! from the error estimate's companion mesh's converged states.
//!
//! The companion follows the path (the bifurcation, the §3.2 perturbation, the contact passes) on
//! its coarser mesh and sends each converged level here ([`SeedLevel`], through a channel: it runs
//! first on one thread and beside the sweep on two or more, staying ahead since it is smaller). The
//! sweep solves each of this mesh's levels, from the first the companion perturbed at on, from the
//! companion's state carried onto this mesh's nodes ([`nonlin3d_mesh::Transfer`]) with a contact
//! set from it (this mesh's own gaps at the carried state where the companion has
//! [`CARRIED_SET_FROM_DOFS`] or more, else the companion's set mapped onto this mesh's pairs): one
//! Newton solve at the level's λ, then the contact loop's passes, which end only on a converged
//! state whose set does not change. Newton converges to the equilibrium nearest the start: the same
//! one the path reaches (docs/PERFORMANCE.md, "Nested iteration from the companion": ten scenes,
//! the same closed pairs and pivots at every level, G within 3.1e-5 of G_T max). A start is dropped
//! and the level followed on this mesh as without seeding when its contact set would change at more
//! than a quarter of the pairs at the first read, needs more than 10 passes, or a pass converges
//! with negative pivots where the companion is stable (src/contact.rs, `Contact::set_stable_only`);
//! when it needs contact where the companion did not with another count of negative pivots than the
//! companion's, when it does not converge, or when it converges on another branch than the
//! companion's (a centre deflection of the other sign, or unstable where the companion is stable).
//! After a seeded level, the next is seeded only if this one's start was close ([`KEEP_SEEDING`]);
//! a level this mesh then follows itself starts from the companion's contact set at that level
//! where the companion is fine enough to predict it ([`Seeds::followed_set`], [`SET_FROM_DOFS`]).
//!
//! **Nested companions.** A companion of [`NESTED_FROM_DOFS`] or more starts its own levels
//! from a coarser companion of its own in the same way (its slices halved, the rest kept but
//! for the rings where the slices fall to two: `EmbeddedParams::coarsened_along_front`,
//! src/analysis_estimate.rs `companion_scene`), which follows the path itself ([`DEEPEST`]):
//! three meshes, the path followed on the cheapest. The coarser companion's levels also go up
//! with the companion's to the error estimate, whose rule for the default mesh's companion
//! takes their difference into account (src/analysis_estimate.rs, docs/ACCURACY.md §3d).

use super::deflections;
use super::level::{Solved, engage_contact};
use crate::Error;
use crate::contact::ContactStage;
use crate::model::{Model, ModelKind};
use crate::results::{ContactSummary, Crossing, LevelResult};
use crate::scene::{ContactModeName, PathName, Scene, StartName};
use nonlin3d_contact::CrackFaces;
use nonlin3d_mesh::Transfer;
use nonlin3d_newton::{NewtonSettings, PathSolver, Stepping, StructuralProblem};
use std::sync::mpsc::{Receiver, Sender, TryRecvError};
use std::time::Instant;

/// After a seeded level, the next one is seeded only if this one's carried start u⁰ was within
/// this fraction of its step: ‖u − u⁰‖∞ ≤ 0.15 ‖u − u_prev‖∞ (u the converged state, u_prev
/// the previous level's). A start that close beat the level's own path on the measured scenes,
/// a farther one did not (a coarse companion's contact set costs more passes than this mesh's
/// own): over nine committed scenes 291 of this mesh's iterations against 326 seeding every
/// level, 305 seeding the buckling level only and 502 following the path (docs/PERFORMANCE.md,
/// "Nested iteration from the companion"). Speed only: every choice reaches the same states.
const KEEP_SEEDING: f64 = 0.15;

/// Companion DOFs from which a level this mesh follows itself starts from the companion's
/// contact set ([`Seeds::followed_set`]): the size from which a companion is nested itself
/// (the default mesh's, 7 581 DOF on the reference circle, with the front band; 6 405 when
/// this was measured). Measured over eleven scenes (docs/PERFORMANCE.md, "The companion's
/// contact set, kept for fine companions"): the companions of 6 405 DOF took the reference
/// scene from 33 to 26 of this mesh's iterations and the 60 mm circle from 58 to 54, or left
/// them unchanged; those of 1 773 DOF and less (2–4 coarse slices) cost 2–8 more.
const SET_FROM_DOFS: usize = NESTED_FROM_DOFS;

/// Companion DOFs from which a seeded level's contact set is read on this mesh's own pairs at the
/// carried state ([`Seeds::carried_set`]) rather than taken from the companion's nearest pair
/// ([`Seeds::set`]). The nearest pair closes this mesh's pairs out to the coarse zone's edge, one
/// coarse spacing too far, and the contact loop then opens them ring by ring (model 6: 8–11 pairs
/// too many at three of its four seeded levels, 3–4 passes). Measured (docs/PERFORMANCE.md, "A
/// seeded level's set read on this mesh's pairs"): with companions of 3 951 and 7 581 DOF, this
/// mesh's iterations 22 → 18 (model 6), 16 → 14 (reference circle) and 186 → 176 over seven random
/// embedded ellipses on the default mesh; with the thesis mesh's 1 773-DOF companions 128 → 131
/// over its four contact scenes whose sets change (−10 to +10 each), so not there.
const CARRIED_SET_FROM_DOFS: usize = 3_000;

/// The gap, as a share of the largest gap over the pairs, up to which a pair counts as closed at
/// a carried state ([`closed_at`]): the carried state interpolates the companion's, so this
/// mesh's pairs inside the coarse zone are closed only to the interpolation's error. Model 6:
/// 18 of this mesh's iterations at 1e-4 and at 5e-4 (22 with the nearest pair); the reference
/// circle: 14 at 1e-4, 17 at 5e-4.
const CARRIED_GAP_SHARE: f64 = 1e-4;

/// Which pairs are closed at a state with (weighted) gaps `gaps` (m): g ≤ max(`tolerance`,
/// `share`·max g). NaN gaps are open.
fn closed_at(gaps: &[f64], tolerance: f64, share: f64) -> Vec<bool> {
    let largest = gaps.iter().fold(0.0_f64, |m, &g| m.max(g));
    let bound = tolerance.max(share * largest);
    gaps.iter().map(|&g| g <= bound).collect()
}

/// One converged level of the companion, as the sweep needs it.
#[derive(Debug, Clone)]
pub(crate) struct SeedLevel {
    /// Level index (0-based).
    index: usize,
    /// The companion's displacements (node-major, m).
    displacements: Vec<f64>,
    /// Centre deflection, m.
    centre: f64,
    /// Whether the contact stage acted at the level.
    contact: bool,
    /// Whether the companion applied the §3.2 perturbation at the level, or started it from
    /// a perturbed state of its own companion's (nested companions: a level is seeded only
    /// from the level its companion perturbed at on).
    perturbed: bool,
    /// The bifurcation the companion crossed in the level.
    bifurcation: Option<Crossing>,
    /// Negative pivots of the companion's tangent at the level.
    pivots: Option<usize>,
}

impl SeedLevel {
    /// The record of the companion's level `index`.
    pub(crate) fn of(index: usize, level: &LevelResult) -> Self {
        Self {
            index,
            displacements: level.displacements.clone(),
            centre: level.centre_deflection_mm * 1e-3,
            contact: level.contact.is_some(),
            perturbed: level.convergence.perturbed || level.convergence.seeded,
            bifurcation: level.convergence.bifurcation,
            pivots: level.convergence.negative_pivots,
        }
    }

    /// Sends it (a sweep that stopped listening is not an error of the companion's run).
    pub(crate) fn send(index: usize, level: &LevelResult, to: &Sender<SeedLevel>) {
        let _ = to.send(Self::of(index, level));
    }
}

/// From this many DOFs on, a companion mesh starts its levels from a coarser companion of
/// its own (module docs, "Nested companions"). Measured in docs/PERFORMANCE.md, "Nested
/// companions".
pub(crate) const NESTED_FROM_DOFS: usize = 5_000;

/// The deepest companion: the run is depth 0, its companion 1, the companion's own 2, which
/// follows its path itself.
pub(crate) const DEEPEST: usize = 2;

/// Whether a run at `depth` (0 the run itself, 1 its companion, …) has a companion run beside
/// or before it: the run when the scene asks for the error estimate; the run without the
/// estimate, and a companion that is not the deepest, when its levels can start from a coarser
/// mesh's ([`seeds_pay`]). Without the estimate the companion's run serves the seeds alone:
/// turning the estimate off must not cost the nested iteration (it doubled model 6's time).
pub(crate) fn companion_runs(
    scene: &Scene,
    model: &Model,
    substructured: bool,
    depth: usize,
) -> bool {
    match depth {
        0 => super::estimate::wanted(scene) || seeds_pay(scene, model, substructured),
        d => d < DEEPEST && seeds_pay(scene, model, substructured),
    }
}

/// Whether a run's levels should start from a coarser companion's for speed alone: they can
/// ([`wanted`]), the mesh has [`NESTED_FROM_DOFS`] or more, and it is not a through-width
/// model.
fn seeds_pay(scene: &Scene, model: &Model, substructured: bool) -> bool {
    3 * model.mesh.nodes.len() >= NESTED_FROM_DOFS
        && model.kind != ModelKind::ThroughWidth
        && wanted(scene, model, substructured)
}

/// Whether a scene's levels can start from a companion's: `start = "companion"`, load
/// control, no substructure, an embedded, edge or through-width model (the models whose
/// companion mesh covers the same body). They do where a companion runs ([`companion_runs`]).
pub(crate) fn wanted(scene: &Scene, model: &Model, substructured: bool) -> bool {
    scene.analysis.start == StartName::Companion
        && scene.analysis.path == PathName::Load
        && !substructured
        && matches!(
            model.kind,
            ModelKind::Embedded | ModelKind::Edge | ModelKind::ThroughWidth
        )
}

/// The companion's levels as they arrive, carried onto this mesh.
pub(crate) struct Seeds {
    transfer: Transfer,
    /// For each of this mesh's crack pairs, the companion's nearest pair (in the crack plane).
    nearest: Vec<usize>,
    /// The companion's crack faces (None: no crack pairs).
    faces: Option<CrackFaces>,
    /// This mesh's crack faces (None: no crack pairs).
    own: Option<CrackFaces>,
    /// The companion's levels received so far, in order.
    received: Vec<SeedLevel>,
    from: Receiver<SeedLevel>,
    /// Weighted gaps (two-body) or gaps (thesis mode).
    weighted: bool,
    /// Whether the next level is seeded ([`KEEP_SEEDING`]; true until a level is seeded).
    pays: bool,
    /// The companion's DOFs.
    coarse_dofs: usize,
}

impl Seeds {
    /// From the companion's model `coarse` onto `model`, its levels arriving on `from`.
    pub(crate) fn new(
        scene: &Scene,
        coarse: &Model,
        model: &Model,
        from: Receiver<SeedLevel>,
    ) -> Result<Self, Error> {
        let transfer = Transfer::between(&coarse.mesh, &model.mesh)?;
        let faces = crack_faces(coarse)?;
        let own = crack_faces(model)?;
        let nearest = match (&faces, &own) {
            (Some(c), Some(f)) => nearest_pairs(c, &coarse.mesh.nodes, f, &model.mesh.nodes),
            _ => Vec::new(),
        };
        Ok(Self {
            transfer,
            nearest,
            faces,
            own,
            received: Vec::new(),
            from,
            weighted: scene.contact.mode == ContactModeName::TwoBody,
            pays: true,
            coarse_dofs: 3 * coarse.mesh.nodes.len(),
        })
    }

    /// The contact set to start level `k` with when this mesh follows it itself (seeding has
    /// stopped paying): the companion's at the same level, mapped onto this mesh's pairs, if
    /// the companion is fine enough to predict this mesh's set ([`SET_FROM_DOFS`]) and acted
    /// at that level; None otherwise. Waits for the companion's level (it is usually ahead:
    /// about a third of this mesh's size): whether the set is used must not depend on which
    /// run got there first, or the bits would depend on timing.
    pub(crate) fn followed_set(&mut self, k: usize, tolerance: f64) -> Option<Vec<bool>> {
        if self.pays || self.coarse_dofs < SET_FROM_DOFS {
            return None;
        }
        let level = self.level(k)?.clone();
        if !level.contact {
            return None;
        }
        self.set(&level, tolerance).ok()
    }

    /// Whether the companion's level `k` has arrived (those that have are taken in).
    fn arrived(&mut self, k: usize) -> bool {
        while self.received.len() <= k {
            match self.from.try_recv() {
                Ok(next) => self.received.push(next),
                Err(_) => return false,
            }
        }
        true
    }

    /// The companion's level `k`, waiting for it; None if the companion stopped before it.
    fn level(&mut self, k: usize) -> Option<&SeedLevel> {
        while self.received.len() <= k {
            let next = wait(&self.from)?;
            debug_assert_eq!(next.index, self.received.len());
            self.received.push(next);
        }
        self.received.get(k)
    }

    /// This mesh's contact set from the companion's state: a pair is closed where its
    /// nearest companion pair's (weighted) gap is within `tolerance` (m).
    fn set(&self, level: &SeedLevel, tolerance: f64) -> Result<Vec<bool>, Error> {
        let Some(faces) = &self.faces else {
            return Ok(Vec::new());
        };
        let gaps = self.gaps(faces, &level.displacements)?;
        Ok(self.nearest.iter().map(|&c| gaps[c] <= tolerance).collect())
    }

    /// The gaps of `faces`' pairs at state `u`, weighted (two-body) or plain (thesis mode), m.
    fn gaps(&self, faces: &CrackFaces, u: &[f64]) -> Result<Vec<f64>, Error> {
        let gaps = faces.gaps(u, &faces.normals(u)?);
        Ok(if self.weighted {
            faces.weighted_gaps(&gaps)
        } else {
            gaps
        })
    }

    /// This mesh's contact set at `carried`, the companion's state carried onto this mesh: a
    /// pair is closed where its own (weighted) gap is within `tolerance` (m) or
    /// [`CARRIED_GAP_SHARE`] of the largest gap ([`closed_at`]).
    fn carried_set(&self, carried: &[f64], tolerance: f64) -> Result<Vec<bool>, Error> {
        let Some(faces) = &self.own else {
            return Ok(Vec::new());
        };
        Ok(closed_at(
            &self.gaps(faces, carried)?,
            tolerance,
            CARRIED_GAP_SHARE,
        ))
    }
}

/// The next level from the companion; None when it has stopped. A rayon worker waiting here
/// runs pending jobs meanwhile (`rayon::yield_now`): blocked, it could hold the only thread
/// that would run the companion — two study cases on two workers, each waiting for its
/// companion queued behind the other, wait for ever. Elsewhere it sleeps between looks.
fn wait(from: &Receiver<SeedLevel>) -> Option<SeedLevel> {
    loop {
        match from.try_recv() {
            Ok(level) => return Some(level),
            Err(TryRecvError::Disconnected) => return None,
            Err(TryRecvError::Empty) => {
                if rayon::yield_now() != Some(rayon::Yield::Executed) {
                    std::thread::sleep(std::time::Duration::from_micros(200));
                }
            }
        }
    }
}

fn crack_faces(model: &Model) -> Result<Option<CrackFaces>, Error> {
    let sets = &model.mesh.node_sets;
    let paired = [
        nonlin3d_mesh::names::CRACK_UPPER,
        nonlin3d_mesh::names::CRACK_LOWER,
    ]
    .iter()
    .all(|s| sets.get(*s).is_some_and(|v| !v.is_empty()));
    Ok(if paired {
        Some(CrackFaces::from_mesh(&model.mesh)?)
    } else {
        None
    })
}

/// For each pair of `fine`, the index of the pair of `coarse` whose lower node is nearest in
/// (x, y) (the first on ties).
fn nearest_pairs(
    coarse: &CrackFaces,
    coarse_nodes: &[[f64; 3]],
    fine: &CrackFaces,
    fine_nodes: &[[f64; 3]],
) -> Vec<usize> {
    let at: Vec<[f64; 2]> = coarse
        .pairs()
        .iter()
        .map(|p| [coarse_nodes[p.lower][0], coarse_nodes[p.lower][1]])
        .collect();
    fine.pairs()
        .iter()
        .map(|p| {
            let x = fine_nodes[p.lower];
            let d = |c: &[f64; 2]| (c[0] - x[0]).powi(2) + (c[1] - x[1]).powi(2);
            (0..at.len())
                .min_by(|&a, &b| d(&at[a]).total_cmp(&d(&at[b])))
                .unwrap_or(0)
        })
        .collect()
}

/// A level solved from the companion's state.
pub(super) struct Seeded {
    /// What was solved (the first solve's attempt, the pivots).
    pub(super) solved: Solved,
    /// The contact stage's record, if it acted.
    pub(super) contact: Option<ContactSummary>,
    /// Whether the companion applied the §3.2 perturbation at this level.
    pub(super) perturbed: bool,
    /// The bifurcation the companion crossed in the level.
    pub(super) bifurcation: Option<Crossing>,
}

/// Level `k` at load factor `lambda` from the companion's state, if the companion has reached
/// its perturbed level by then and the last seeded level's start was close ([`KEEP_SEEDING`]);
/// `u` (this mesh's previous converged state) becomes the level's state. None: not seeded
/// (before the companion's perturbation, the last start too far, the companion stopped, or the
/// start did not converge or landed on another branch: `u` and the contact stage are as they
/// were, and the caller follows the level).
#[allow(clippy::too_many_arguments)]
pub(super) fn solve_seeded(
    seeds: &mut Seeds,
    k: usize,
    (scene, model): (&Scene, &Model),
    problem: &mut StructuralProblem,
    session: &mut PathSolver,
    stage: &mut ContactStage,
    u: &mut Vec<f64>,
    lambda: f64,
    (newton, stepping): (&NewtonSettings, &Stepping),
) -> Result<Option<Seeded>, Error> {
    let t = Instant::now();
    // From a carried start Newton takes 3–5 iterations: full Newton (a kept tangent, modified
    // Newton's or BFGS's, may fail to converge from it, and the contact loop runs full Newton).
    let full = newton.full_newton();
    let newton = &full;
    // The last seeded level's start was far: this one is followed, without waiting for the
    // companion's.
    if !seeds.pays {
        return Ok(None);
    }
    // The wait for the companion's level is spent building this mesh's contact system, which
    // a seeded level past the buckling level mostly needs (measured in docs/PERFORMANCE.md,
    // "Nested companions").
    if !seeds.arrived(k) {
        stage.prepare(scene, model, newton);
    }
    let Some(level) = seeds.level(k).cloned() else {
        return Ok(None);
    };
    if !seeds.received.iter().any(|l| l.perturbed) {
        return Ok(None);
    }
    let mut start = seeds.transfer.apply(&level.displacements, 3)?;
    let carried = start.clone();
    let mark = stage.mark();
    let mut solved = Solved::default();
    let attempt = if level.contact {
        let tolerance = scene.contact.tolerance() * 1e-3;
        let set = if seeds.coarse_dofs >= CARRIED_SET_FROM_DOFS {
            seeds.carried_set(&start, tolerance)
        } else {
            seeds.set(&level, tolerance)
        };
        set.and_then(|set| {
            let stable = level.pivots == Some(0);
            stage.seed(scene, model, &mut start, (&set, stable), lambda, newton)
        })
        .map(|(l, summary)| {
            solved.attempts.extend(l.first.attempts);
            solved.pivots = l.first.negative_pivots;
            Some(summary)
        })
    } else {
        plain(
            (problem, session, stage),
            (scene, model),
            &mut start,
            (lambda, level.pivots),
            newton,
            stepping,
        )
        .map(|(s, c)| {
            solved = s;
            c
        })
    };
    // The companion's branch: the centre deflection of its sign (where it is more than h/100:
    // not the branch buckled the other way), and stable where it is stable (not the unbuckled
    // state past the bifurcation). Its size is not compared: a coarse companion's may be half
    // this mesh's (513 against 1 773 DOF, tests/nested.rs).
    let landed = |state: &[f64], pivots: Option<usize>| {
        let (centre, _) = deflections(model, state);
        let sign = level.centre.abs() <= 0.01 * model.h || centre * level.centre > 0.0;
        let stable = level.pivots != Some(0) || pivots == Some(0);
        sign && stable
    };
    match attempt {
        Ok(contact) if landed(&start, solved.pivots) => {
            let off = |from: &[f64]| {
                start
                    .iter()
                    .zip(from)
                    .fold(0.0_f64, |m, (a, b)| m.max((a - b).abs()))
            };
            seeds.pays = off(&carried) <= KEEP_SEEDING * off(u);
            *u = start;
            tracing::debug!(level = k + 1, seconds = t.elapsed().as_secs_f64(), "seeded");
            Ok(Some(Seeded {
                solved,
                contact,
                perturbed: level.perturbed,
                bifurcation: level.bifurcation,
            }))
        }
        outcome => {
            let why = match outcome {
                Err(e) => e.to_string(),
                Ok(_) => "it landed on another branch than the companion's (centre deflection \
                          of the other sign, or unstable where the companion is stable)"
                    .into(),
            };
            tracing::debug!(level = k + 1, %why, "seed dropped: the level is followed");
            session.invalidate();
            stage.reset(mark, u)?;
            Ok(None)
        }
    }
}

/// A seeded level the companion solved without contact: Newton at λ from `u`, then the
/// contact stage if this mesh's state overlaps (`auto`).
#[allow(clippy::too_many_arguments)]
fn plain(
    (problem, session, stage): (&mut StructuralProblem, &mut PathSolver, &mut ContactStage),
    (scene, model): (&Scene, &Model),
    u: &mut Vec<f64>,
    (lambda, companion_pivots): (f64, Option<usize>),
    newton: &NewtonSettings,
    stepping: &Stepping,
) -> Result<(Solved, Option<ContactSummary>), Error> {
    let t = Instant::now();
    let first = session.solve_at(problem, u, lambda, newton)?;
    if !first.converged() {
        return Err(Error::Scene(format!(
            "the start carried from the companion mesh did not converge at λ = {lambda}"
        )));
    }
    // The companion's state did not need contact here. One of this mesh's that does, with
    // another inertia, is another state (measured: model 6's companion mesh seeded from its
    // own companion ground through contact passes at 21 negative pivots before failing):
    // follow the level instead. With the companion's inertia it is the same state, finer
    // (the 15 mm edge on mesh S closes 3 pairs where its companion closes none: followed,
    // 36 iterations and 8 s; from here, 2.4 s to the same state, tests/nested.rs): the
    // contact loop goes on from it (`engage_contact` below).
    if !stage.active() && first.negative_pivots() != companion_pivots && stage.overlaps(model, u) {
        return Err(Error::Scene(format!(
            "the state carried from the companion mesh overlaps at λ = {lambda} where the \
             companion's did not, with {} negative pivots against the companion's {}",
            first
                .negative_pivots()
                .map_or("unknown".into(), |p| p.to_string()),
            companion_pivots.map_or("unknown".into(), |p| p.to_string())
        )));
    }
    let mut solved = Solved {
        pivots: first.negative_pivots(),
        attempts: vec![first],
        ..Solved::default()
    };
    let start = u.clone();
    let contact = engage_contact(
        stage,
        scene,
        model,
        u,
        (&start, (lambda, lambda), lambda),
        &[],
        (newton, stepping),
        (&mut solved, t),
    )?;
    Ok((solved, contact))
}

#[cfg(test)]
mod tests {
    use super::closed_at;

    /// Closed within the absolute tolerance or the share of the largest gap, whichever is
    /// larger; overlaps are closed, NaN is open.
    #[test]
    fn a_pair_is_closed_within_the_share_of_the_largest_gap() {
        let gaps = [-1e-9, 0.0, 5e-8, 1.5e-7, 1e-3, f64::NAN];
        // 1e-4 of the largest gap (1e-3 m) is 1e-7 m.
        assert_eq!(
            closed_at(&gaps, 1e-9, 1e-4),
            [true, true, true, false, false, false]
        );
        // A larger absolute tolerance wins over the share.
        assert_eq!(
            closed_at(&gaps, 2e-7, 1e-4),
            [true, true, true, true, false, false]
        );
        // Every gap within the absolute tolerance: all closed.
        assert_eq!(
            closed_at(&[-1e-8, 0.0, 5e-10], 1e-9, 1e-4),
            [true, true, true]
        );
        assert_eq!(closed_at(&[], 1e-9, 1e-4), Vec::<bool>::new());
    }
}
