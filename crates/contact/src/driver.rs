//! The contact loop of thesis Fig. 2.7.2 around one load level: solve, update the normals, the
//! gaps and the active set, re-solve at the same level, until the set does not change.
//!
//! Each pass reads the gaps g = n·(x_up − x_low) with the normals of the deformed lower face and
//! the contact forces p = R_s/n_k of the tied pairs (the slave reactions, `tie`), changes the set
//! ([`update`]), installs the ties of the new set with the current normals as one replaced tie
//! group (within couplings reserved once: no new pattern, no new symbolic analysis) and solves
//! again at the same load factor; a set seen before at the level is a cycle and ends the level
//! with [`ContactError::Cycle`].

use crate::tie::{contact_force, slave_component, weighted_tie};
use crate::{ALPHA, ContactError, CrackFaces};
use nonlin3d_mesh::Mesh;
use nonlin3d_newton::{
    LevelReport, NewtonSettings, NonlinearProblem, PathSolver, StructuralProblem, solve_level,
};
use std::time::Instant;

mod settings;

/// Refresh passes over which the overlap must shrink tenfold ([`Contact::check_refresh`]).
const REFRESH_WINDOW: usize = 5;
pub use settings::{ContactSettings, LevelSettings, Mode, Reserve};

/// Gaps, forces and the set at a state: the results of contact.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactState {
    /// Contact normal of each pair (deformed lower face).
    pub normals: Vec<[f64; 3]>,
    /// Gap of each pair, m (negative: overlap).
    pub gaps: Vec<f64>,
    /// Gaps in the basis of the recovered forces, g̃ = T⁻ᵀ g, m
    /// ([`CrackFaces::weighted_gaps`]; the gaps themselves in [`Mode::External`]): the
    /// closing test's quantity, conjugate to `recovered` (f̂·g̃ = f·g).
    pub weighted_gaps: Vec<f64>,
    /// Contact force of each pair, N (compressive positive): the nodal force, which on a
    /// quadratic face is tensile at the corners of a compressed patch, and is −α p at an open
    /// corner pair at the end of a closed mid-edge pair's edge (its tie reads that corner's
    /// gap); 0 at other open pairs.
    pub forces: Vec<f64>,
    /// Recovered nodal contact forces f̂ = T f, N ([`CrackFaces::recovered`]): positive at every
    /// node of a compressed face; the release test's quantity.
    pub recovered: Vec<f64>,
    /// Recovered contact pressure of each pair, Pa ([`CrackFaces::pressures`]).
    pub pressures: Vec<f64>,
    /// Whether each pair is closed (in the active set).
    pub active: Vec<bool>,
    /// The force tolerance used (N).
    pub force_tolerance: f64,
    /// ‖r‖∞ of the constrained residual at the state, N.
    pub residual: f64,
    /// Σ p·n over the ties' forces, each along the normal it acts on (the normal its tie was
    /// installed with), N.
    total: [f64; 3],
}

impl ContactState {
    /// The largest overlap −g over the pairs, m (0: none).
    pub fn penetration(&self) -> f64 {
        self.gaps.iter().fold(0.0, |m: f64, &g| m.max(-g))
    }

    /// The largest overlap −g̃ in the weighted gaps, m (0: none): the closing test's
    /// quantity ([`CrackFaces::weighted_gaps`]).
    pub fn weighted_penetration(&self) -> f64 {
        self.weighted_gaps.iter().fold(0.0, |m: f64, &g| m.max(-g))
    }

    /// Σ f_i·n_i over the pairs, each nodal force along the normal it acts on: the total force
    /// the base exerts on the sublaminate (N).
    pub fn total_force(&self) -> [f64; 3] {
        self.total
    }
}

/// One pass of the loop: the change made and the re-solve it cost.
#[derive(Debug, Clone, PartialEq)]
pub struct PassReport {
    /// Pairs closed (indices into [`CrackFaces::pairs`]).
    pub closed: Vec<usize>,
    /// Pairs opened.
    pub opened: Vec<usize>,
    /// Whether the set stayed and was held again with the current normals (the deformed
    /// gap of a held pair overlapped beyond the gap tolerance along them).
    pub refresh: bool,
    /// Newton iterations of the re-solve.
    pub iterations: usize,
    /// Whether the re-solve was stopped after one Newton iteration to read the set again (an
    /// inexact update, [`ContactSettings::inexact_passes`]); the iterations that then converge
    /// the set the updates settled on are counted with the last of them.
    pub inexact: bool,
    /// Whether the re-solve at the level failed and the level was followed again from its start
    /// with the new set.
    pub redone: bool,
    /// Wall time of the pass (install and re-solve), s.
    pub seconds: f64,
}

/// What one level of [`Contact::solve_level`] did.
#[derive(Debug, Clone, PartialEq)]
pub struct ContactLevel {
    /// The level's load factor.
    pub lambda: f64,
    /// The first solve (path following to the level with the set of the previous level).
    pub first: LevelReport,
    /// Wall time of the first solve, s.
    pub first_seconds: f64,
    /// The passes that changed the set, in order.
    pub passes: Vec<PassReport>,
    /// Newton iterations of the first solve made by the passes' loop before any pass: a level
    /// settled from an iterate ([`Contact::settle_iterate`]) whose set stayed there and was
    /// converged first (0 otherwise).
    pub first_iterations: usize,
    /// Contact results at the converged state.
    pub state: ContactState,
}

impl ContactLevel {
    /// Newton iterations of the level: the first solve's and every re-solve's.
    pub fn newton_iterations(&self) -> usize {
        self.first
            .attempts
            .iter()
            .map(|a| a.iterations.len())
            .sum::<usize>()
            + self.first_iterations
            + self.passes.iter().map(|p| p.iterations).sum::<usize>()
    }

    /// This level followed by `later`, a level that continues it (the next sub-level): the
    /// attempts and passes of both, in order; the later one's load factor, state and
    /// negative pivots; perturbed if either applied the perturbation.
    pub fn then(mut self, later: ContactLevel) -> ContactLevel {
        self.first.attempts.extend(later.first.attempts);
        self.first.perturbed |= later.first.perturbed;
        self.first.negative_pivots = later.first.negative_pivots;
        self.first_seconds += later.first_seconds;
        self.first_iterations += later.first_iterations;
        self.passes.extend(later.passes);
        self.lambda = later.lambda;
        self.state = later.state;
        self
    }

    /// Pairs closed over the level (counted at each pass).
    pub fn closed(&self) -> usize {
        self.passes.iter().map(|p| p.closed.len()).sum()
    }

    /// Pairs opened over the level (counted at each pass).
    pub fn opened(&self) -> usize {
        self.passes.iter().map(|p| p.opened.len()).sum()
    }
}

/// The constraint installed for an active pair: the constrained component, the normal, and
/// the open end corners its tie reads (mid-edge pairs of quadratic faces: g̃_m = 0).
#[derive(Debug, Clone, PartialEq)]
struct Held {
    component: usize,
    normal: [f64; 3],
    /// The open end corners and the normals their gaps are read along.
    ends: Vec<(usize, [f64; 3])>,
}

/// Crack-face contact of one model: the pairs, the settings, the active set and what holds it.
#[derive(Debug, Clone)]
pub struct Contact {
    faces: CrackFaces,
    settings: ContactSettings,
    /// The installed constraint of each pair (None: open).
    held: Vec<Option<Held>>,
    /// Whether each pair's tie is reserved in the pattern ([`Reserve`]).
    reserved: Vec<bool>,
    /// Whether a re-solve that converges unstable ends the level ([`Self::set_stable_only`]).
    stable_only: bool,
}

impl Contact {
    /// Contact of the mesh's paired crack faces ([`CrackFaces::from_mesh`]), all pairs open.
    pub fn new(mesh: &Mesh, settings: ContactSettings) -> Result<Self, ContactError> {
        Self::with_faces(CrackFaces::from_mesh(mesh)?, settings)
    }

    /// Contact of given crack faces, all pairs open.
    pub fn with_faces(faces: CrackFaces, settings: ContactSettings) -> Result<Self, ContactError> {
        let bad = |name, reason: String| Err(ContactError::Setting { name, reason });
        if !(settings.gap_tolerance >= 0.0 && settings.gap_tolerance.is_finite()) {
            return bad("gap_tolerance", format!("{} m", settings.gap_tolerance));
        }
        if !(settings.force_tolerance >= 0.0 && settings.force_tolerance.is_finite()) {
            return bad("force_tolerance", format!("{} N", settings.force_tolerance));
        }
        if settings.max_passes == 0 {
            return bad("max_passes", "at least one pass".into());
        }
        if !(settings.max_step > 0.0 && settings.max_step.is_finite()) {
            return bad("max_step", format!("{} (load factor)", settings.max_step));
        }
        if let Reserve::Grow { gap_share, .. } = settings.reserve
            && !(gap_share >= 0.0 && gap_share.is_finite())
        {
            return bad(
                "reserve.gap_share",
                format!("{gap_share} (a share of the largest gap)"),
            );
        }
        let all = settings.reserve == Reserve::All && settings.mode == Mode::TwoBody;
        Ok(Self {
            held: vec![None; faces.len()],
            reserved: vec![all; faces.len()],
            faces,
            settings,
            stable_only: false,
        })
    }

    /// The crack faces.
    pub fn faces(&self) -> &CrackFaces {
        &self.faces
    }

    /// The settings.
    pub fn settings(&self) -> &ContactSettings {
        &self.settings
    }

    /// Sets the most passes at one level ([`ContactSettings::max_passes`]) and returns the
    /// previous limit: a caller that starts a level from a predicted set (nested iteration)
    /// bounds what a wrong prediction may cost, then puts the limit back.
    pub fn set_max_passes(&mut self, passes: usize) -> usize {
        std::mem::replace(&mut self.settings.max_passes, passes)
    }

    /// Sets whether a pass's re-solve that converges on a state with negative pivots ends the
    /// level with [`ContactError::Unstable`] (default off) and returns the previous setting: a
    /// caller that starts a level from a state predicted on a stable branch (nested iteration)
    /// drops the prediction as soon as the passes leave that branch, then puts it back.
    pub fn set_stable_only(&mut self, stable_only: bool) -> bool {
        std::mem::replace(&mut self.stable_only, stable_only)
    }

    /// Whether each pair is closed.
    pub fn active(&self) -> Vec<bool> {
        self.held.iter().map(Option::is_some).collect()
    }

    /// Makes `active` the set, held with the normals of the state `u` (ties in the contact
    /// group, or prescribed heights in [`Mode::External`]). Errors: a pair with no free
    /// component to hold it, or constraints that refuse the ties.
    pub fn install(
        &mut self,
        problem: &mut StructuralProblem,
        u: &[f64],
        active: &[bool],
    ) -> Result<(), ContactError> {
        if active.len() != self.faces.len() {
            return Err(ContactError::Length {
                what: "active set",
                expected: self.faces.len(),
                got: active.len(),
            });
        }
        self.grow_reserve(problem, u, active)?;
        let normals = self.faces.normals(u)?;
        let g0 = self.faces.initial_gaps(&normals);
        let group = self.settings.group;
        let pairs = self.faces.pairs();
        // Release what contact itself prescribed, so that those DOFs count as free again.
        for (p, h) in pairs.iter().zip(&self.held) {
            if let (Mode::External, Some(h)) = (self.settings.mode, h) {
                problem.system_mut().release(3 * p.upper + h.component);
            }
        }
        let mut held = vec![None; pairs.len()];
        let mut ties = Vec::new();
        for (i, &p) in pairs.iter().enumerate().filter(|(i, _)| active[*i]) {
            let constraints = problem.constraints();
            let unheld = |node: usize| ContactError::Node {
                node,
                reason: "every component of this upper-face node is prescribed: contact \
                         cannot hold it"
                    .into(),
            };
            match self.settings.mode {
                Mode::TwoBody => {
                    let n = normals[i];
                    let k = slave_component(p, n, |d| !constraints.is_constrained(d))
                        .ok_or_else(|| unheld(p.upper))?;
                    // g̃_i = 0: a mid-edge pair reads the gaps of its open end corners (the
                    // closed ones are zero by their own ties).
                    let ends: Vec<(usize, [f64; 3])> = self
                        .faces
                        .ends(i)
                        .iter()
                        .filter(|&&c| !active[c])
                        .map(|&c| (c, normals[c]))
                        .collect();
                    let others: Vec<_> = ends
                        .iter()
                        .map(|&(c, m)| (pairs[c], m, g0[c], -ALPHA))
                        .collect();
                    ties.push(weighted_tie(p, n, g0[i], k, &others));
                    held[i] = Some(Held {
                        component: k,
                        normal: n,
                        ends,
                    });
                }
                Mode::External => {
                    let d = 3 * p.upper + 2;
                    if constraints.is_constrained(d) {
                        return Err(unheld(p.upper));
                    }
                    let (xu, xl) = (self.faces.position(p.upper), self.faces.position(p.lower));
                    let value = xl[2] + u[3 * p.lower + 2] - xu[2];
                    problem
                        .system_mut()
                        .constraints_mut()
                        .prescribe_ramp(d, value, value)?;
                    held[i] = Some(Held {
                        component: 2,
                        normal: [0.0, 0.0, 1.0],
                        ends: Vec::new(),
                    });
                }
            }
        }
        let system = problem.system_mut();
        system.constraints_mut().hold_offsets(group, true);
        system.replace_tie_group(group, &ties)?;
        self.held = held;
        Ok(())
    }

    /// Gaps, forces and the set at the converged state (u, λ): one evaluation of the problem
    /// (for the reactions); the force tolerance max(setting, ε_r·F) with ε_r `newton`'s relative
    /// tolerance and F the state's force scale.
    pub fn state(
        &self,
        problem: &mut StructuralProblem,
        u: &[f64],
        lambda: f64,
        newton: &NewtonSettings,
    ) -> Result<ContactState, ContactError> {
        let mut r = vec![0.0; problem.n()];
        let scale = problem.evaluate(u, lambda, &mut r, None)?;
        let reactions = problem.reactions();
        // The nodal forces: p = R_s/n_k on a held pair, and −α p on each open end corner its
        // tie reads (the tie g_m − α Σ g_c = 0 pulls on them with weight −α).
        let mut forces = vec![0.0; self.faces.len()];
        let mut total = [0.0; 3];
        for ((&p, h), i) in self.faces.pairs().iter().zip(&self.held).zip(0..) {
            if let Some(h) = h {
                let f = contact_force(reactions, p, h.normal, h.component);
                forces[i] += f;
                for k in 0..3 {
                    total[k] += f * h.normal[k];
                }
                for &(c, n) in &h.ends {
                    forces[c] -= ALPHA * f;
                    for k in 0..3 {
                        total[k] -= ALPHA * f * n[k];
                    }
                }
            }
        }
        // In External mode the normal of a closed pair is the direction it is held in (z), and
        // its gap is measured along it.
        let normals: Vec<[f64; 3]> = self
            .faces
            .normals(u)?
            .iter()
            .zip(&self.held)
            .map(|(&n, h)| match (self.settings.mode, h) {
                (Mode::External, Some(h)) => h.normal,
                _ => n,
            })
            .collect();
        let gaps = self.faces.gaps(u, &normals);
        let weighted_gaps = match self.settings.mode {
            Mode::TwoBody => self.faces.weighted_gaps(&gaps),
            Mode::External => gaps.clone(),
        };
        Ok(ContactState {
            normals,
            gaps,
            weighted_gaps,
            recovered: self.faces.recovered(&forces),
            pressures: self.faces.pressures(&forces),
            forces,
            active: self.active(),
            total,
            force_tolerance: self
                .settings
                .force_tolerance
                .max(newton.relative_tolerance * scale),
            residual: r.iter().fold(0.0, |m: f64, v| m.max(v.abs())),
        })
    }

    /// One level with contact (Fig. 2.7.2), in [`sublevels`](Self::sublevels) steps of at
    /// most `max_step` (the perturbation of `settings` offered to each until one applies it);
    /// each step: path following from the converged state `u` at its start to its end with
    /// the current set ([`solve_level`]: stability test and perturbation as there), then
    /// passes — the set updated from the gaps and forces, installed with the current normals,
    /// and the level re-solved at `to` (Newton from the current state; if that fails, path
    /// following again from the step's start with the new set) — until the set does not
    /// change. Errors: a set seen before at this level ([`ContactError::Cycle`], naming λ and
    /// the pairs that flip), more than `max_passes` passes, and what path following returns.
    pub fn solve_level(
        &mut self,
        problem: &mut StructuralProblem,
        session: &mut PathSolver,
        u: &mut Vec<f64>,
        (from, to): (f64, f64),
        settings: &LevelSettings<'_>,
    ) -> Result<ContactLevel, ContactError> {
        let count = self.sublevels(from, to);
        let mut settings = *settings;
        let mut merged: Option<ContactLevel> = None;
        for j in 1..=count {
            let a = ContactSettings::sublevel_end(from, to, j - 1, count);
            let b = ContactSettings::sublevel_end(from, to, j, count);
            let level = self.solve_step(problem, session, u, (a, b), &settings)?;
            if level.first.perturbed {
                settings.perturbation = &[];
            }
            merged = Some(match merged {
                None => level,
                Some(m) => m.then(level),
            });
        }
        merged.ok_or(ContactError::Setting {
            name: "max_step",
            reason: "no sub-level".into(),
        })
    }

    /// How many sub-levels [`solve_level`](Self::solve_level) makes of the level `from` → `to`:
    /// the fewest equal steps of at most `max_step` in load factor
    /// ([`ContactSettings::sublevels`]). The set changes only between solves, so it must
    /// follow the load in steps: passes started from a state far past the first contact can
    /// settle on another equilibrium than the loading path's (see
    /// [`ContactSettings::max_step`]).
    pub fn sublevels(&self, from: f64, to: f64) -> usize {
        self.settings.sublevels(from, to)
    }

    /// One sub-level of [`solve_level`](Self::solve_level): path following with the current
    /// set, then the passes.
    fn solve_step(
        &mut self,
        problem: &mut StructuralProblem,
        session: &mut PathSolver,
        u: &mut Vec<f64>,
        (from, to): (f64, f64),
        settings: &LevelSettings<'_>,
    ) -> Result<ContactLevel, ContactError> {
        let t = Instant::now();
        let start = u.clone();
        let first = solve_level(
            problem,
            u,
            from,
            to,
            settings.perturbation,
            settings.newton,
            settings.stepping,
            session,
        )?;
        let first_seconds = t.elapsed().as_secs_f64();
        let again = if first.perturbed {
            settings.perturbation
        } else {
            &[]
        };
        self.passes(
            problem,
            u,
            to,
            (first, first_seconds),
            settings.newton,
            session,
            Some(passes::Fallback {
                start: &start,
                from,
                stepping: settings.stepping,
                perturbation: again,
            }),
            None,
        )
    }
}

mod holding;
mod passes;
mod reserve;
pub use passes::{Iterate, Resumed};

#[cfg(test)]
mod tests;
