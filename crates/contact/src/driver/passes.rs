//! The passes of the contact loop (Fig. 2.7.2) after a level's first solve: read the state,
//! change the set, install, re-solve at the same load, until the set is stable; the refresh
//! passes, the cycle, pass and refresh limits, and the door for callers that follow the load
//! themselves ([`Contact::settle`]).

use super::{Contact, ContactLevel, ContactState, LevelSettings, Mode, PassReport, REFRESH_WINDOW};
use crate::active::{Change, Tolerances, update};
use crate::{ContactError, Pair};
use nonlin3d_newton::{
    LevelReport, NewtonSettings, PathSolver, Stepping, StructuralProblem, Termination,
    follow_path_with, perturbed_redo_with,
};
use std::time::Instant;

/// How a level is followed again from its start when a pass's re-solve fails.
pub(super) struct Fallback<'a> {
    /// The state at the level's start.
    pub(super) start: &'a [f64],
    /// Its load factor.
    pub(super) from: f64,
    /// The stepping to follow the level with.
    pub(super) stepping: &'a Stepping,
    /// The §3.2 perturbation to follow it with (empty: plain path following).
    pub(super) perturbation: &'a [(usize, f64)],
}

/// What every re-solve of a level's passes shares: the load factor, Newton's settings, the
/// solver session and how to follow the level again if a re-solve fails.
pub(super) struct Resolve<'a, 'b> {
    to: f64,
    /// Newton iterations already made towards this re-solve (one at a time, reading the set).
    spent: usize,
    newton: &'a NewtonSettings,
    session: &'a mut PathSolver,
    fallback: Option<&'a Fallback<'b>>,
}

impl Resolve<'_, '_> {
    /// The error of a pass (1-based) whose re-solve did not converge and had no fallback.
    fn failed(&self, pass: usize, change: &Change) -> ContactError {
        ContactError::Resolve {
            lambda: self.to,
            pass,
            closed: change.added.len(),
            opened: change.released.len(),
            why: "no convergence at the same load".into(),
        }
    }
}

/// The state of the inexact updates of a level ([`Contact::passes`]).
#[derive(Debug, Default)]
struct Inexact {
    /// Updates left.
    left: usize,
    /// The sets tried since the last converged state.
    tried: Vec<Vec<bool>>,
    /// Whether the current state is an iterate of a re-solve (not converged).
    pending: bool,
    /// Newton iterations made one at a time at the current set.
    steps: usize,
    /// ‖r‖∞ at the iterate, N: the inaccuracy of its contact forces.
    residual: f64,
    /// The force tolerance of the converged state the updates started from, N (an iterate
    /// far from equilibrium has large reactions, and so a large force scale of its own).
    tolerance: f64,
}

/// Newton iterations at one set made one at a time, reading the set at each iterate, before
/// the set is converged ([`Contact::passes`]): the first iterate after closing many pairs is
/// far from equilibrium (‖r‖∞ 22 N against contact forces below 1 N on the 13 533-DOF
/// mesh), the second close to it (0.06 N).
const STEPS: usize = 2;

/// An iterate is read only when ‖r‖∞ ≤ NEAR × the force tolerance of the converged state the
/// updates started from (with ε_r = 1e-8: 1e-3 of its force scale F), in the basin of
/// Newton's quadratic convergence: on the very thin hard case (h = 0.1 mm over 60 mm) the
/// iterates after a change reach ‖r‖∞ = 1e5 to 1e10 N, whose overlaps closed pairs that
/// settled the level flat on the base (its located error at level 3 was lost); on the 13 533-DOF mesh the iterates read
/// are at 0.1 N and below (tolerance 1e-5 N).
const NEAR: f64 = 1e5;

/// A level's first solve made elsewhere ([`Contact::continue_level`]): converged at `to` with
/// the current set, from the state `start` at `from`.
#[derive(Debug, Clone)]
pub struct Resumed<'a> {
    /// The state at `from` (followed again from if a re-solve fails).
    pub start: &'a [f64],
    /// Load factor of `start`.
    pub from: f64,
    /// Load factor the first solve reached.
    pub to: f64,
    /// What the first solve reported.
    pub first: LevelReport,
    /// Its wall time, s.
    pub first_seconds: f64,
}

/// A state that is not yet converged: `u` after `steps` Newton iterations at the level's load
/// with the current set, at ‖r‖∞ = `residual`; `tolerance` is the force tolerance of the
/// contact state read there ([`ContactState::force_tolerance`]). See
/// [`Contact::settle_iterate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Iterate {
    /// Newton iterations made at the set (they count against Newton's limit).
    pub steps: usize,
    /// ‖r‖∞ at `u`, N.
    pub residual: f64,
    /// The force tolerance of the contact state at `u`, N.
    pub tolerance: f64,
}

impl Contact {
    /// The passes of a level whose first solve was made elsewhere, then the rest of the level:
    /// `u` is a converged state at `first.to` with the current set (typically a solve without
    /// contact whose faces overlap, which `auto` would otherwise repeat with the loop from the
    /// level's start), `first.start` the state at `first.from` to follow again from if a
    /// re-solve fails. The passes as in [`solve_level`](Self::solve_level); then, if the
    /// level goes on to `end` (the first solve covered one of its sub-levels), the loop's
    /// [`solve_level`](Self::solve_level) from `first.to` to `end` (the perturbation offered
    /// only if the first solve did not apply it). The result is the whole level.
    pub fn continue_level(
        &mut self,
        problem: &mut StructuralProblem,
        session: &mut PathSolver,
        u: &mut Vec<f64>,
        first: Resumed<'_>,
        end: f64,
        settings: &LevelSettings<'_>,
    ) -> Result<ContactLevel, ContactError> {
        let perturbed = first.first.perturbed;
        let again = if perturbed {
            settings.perturbation
        } else {
            &[]
        };
        let level = self.passes(
            problem,
            u,
            first.to,
            (first.first, first.first_seconds),
            settings.newton,
            session,
            Some(Fallback {
                start: first.start,
                from: first.from,
                stepping: settings.stepping,
                perturbation: again,
            }),
            None,
        )?;
        if end == first.to {
            return Ok(level);
        }
        let rest = LevelSettings {
            perturbation: if perturbed {
                &[]
            } else {
                settings.perturbation
            },
            ..*settings
        };
        let later = self.solve_level(problem, session, u, (first.to, end), &rest)?;
        Ok(level.then(later))
    }

    /// The passes at a state `u` converged at λ = `lambda` with the current set, each re-solve
    /// Newton at the same λ and nothing else: a re-solve that does not converge is
    /// [`ContactError::Resolve`] (the caller cuts its increment back; `u` is then the failed
    /// iterate). The door for callers that follow the load themselves (a deck's increments).
    /// Otherwise as [`continue_level`](Self::continue_level), the first solve reported as an
    /// empty level report.
    pub fn settle(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        lambda: f64,
        newton: &NewtonSettings,
        session: &mut PathSolver,
    ) -> Result<ContactLevel, ContactError> {
        self.settle_from(problem, u, lambda, newton, session, None)
    }

    /// [`settle`](Self::settle) from an iterate of the level's first solve instead of its
    /// converged state (a start carried from another mesh: its first Newton iterations at the
    /// carried set leave it near equilibrium, where the set is read as at the iterates of an
    /// inexact re-solve, [`ContactSettings::inexact_passes`](super::ContactSettings)): the
    /// set changes one iteration earlier than after converging it first. The iterate is read
    /// only near equilibrium (‖r‖∞ ≤ `NEAR` × `iterate.tolerance`); otherwise Newton goes on
    /// at the set, as after any inexact change. Ends as `settle` does, on a converged state
    /// whose set stays.
    pub fn settle_iterate(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        lambda: f64,
        newton: &NewtonSettings,
        session: &mut PathSolver,
        iterate: Iterate,
    ) -> Result<ContactLevel, ContactError> {
        self.settle_from(problem, u, lambda, newton, session, Some(iterate))
    }

    /// [`settle`](Self::settle) (`pending` None) or [`settle_iterate`](Self::settle_iterate):
    /// the passes with no fallback, the first solve reported as an empty level report.
    fn settle_from(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        lambda: f64,
        newton: &NewtonSettings,
        session: &mut PathSolver,
        pending: Option<Iterate>,
    ) -> Result<ContactLevel, ContactError> {
        let first = LevelReport {
            attempts: Vec::new(),
            perturbed: false,
            negative_pivots: None,
        };
        let first = (first, 0.0);
        self.passes(problem, u, lambda, first, newton, session, None, pending)
    }

    /// The loop of passes after the first solve (module docs); `fallback`: how to follow the
    /// level again when a re-solve fails (None: the failure is [`ContactError::Resolve`]);
    /// `pending`: `u` is an iterate of the first solve, not its converged state
    /// ([`settle_iterate`](Self::settle_iterate)).
    ///
    /// With inexact updates ([`ContactSettings::inexact_passes`](super::ContactSettings)) the
    /// re-solve after a change of the set goes one Newton iteration at a time, and the set is
    /// read at each iterate (a primal–dual active-set, or semismooth Newton, step). An iterate
    /// is read only near equilibrium (‖r‖∞ ≤ [`NEAR`] × the force tolerance), and since its
    /// contact forces are off by about its residual, a pair is released there only at
    /// f̂ < −(tol_f + ‖r‖∞); closing is read as at a converged state, g̃ < −tol_g (a margin of
    /// the last correction ‖αΔu‖∞ on the gap kept pairs released by the first pass and
    /// overlapping again waiting for the converged state: 11 iterations against 9 at level 4
    /// of the 13 533-DOF mesh; a pair closed wrongly is released by a later pass). After
    /// [`STEPS`] iterations at one set without such a change (or once the updates are used up,
    /// or back at a set tried since the last converged state) the set is converged, those
    /// iterations counted against Newton's limit, and read again as in the exact loop: the
    /// loop ends only on a converged state whose set stays, and the cycle test compares the
    /// sets of converged states.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn passes(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        to: f64,
        (first, first_seconds): (LevelReport, f64),
        newton: &NewtonSettings,
        session: &mut PathSolver,
        fallback: Option<Fallback>,
        pending: Option<Iterate>,
    ) -> Result<ContactLevel, ContactError> {
        let mut passes: Vec<PassReport> = Vec::new();
        // The sets of the converged states read so far (none yet from an iterate).
        let mut seen = match pending {
            Some(_) => Vec::new(),
            None => vec![self.active()],
        };
        // The overlap at each pass of the current run of refresh passes.
        let mut refreshes: Vec<f64> = Vec::new();
        let mut inexact = Inexact {
            left: self.settings.inexact_passes,
            ..Inexact::default()
        };
        let mut first_iterations = 0;
        if let Some(it) = pending {
            inexact.pending = true;
            inexact.tried = vec![self.active()];
            inexact.steps = it.steps;
            inexact.residual = it.residual;
            inexact.tolerance = it.tolerance;
        }
        let mut solve = Resolve {
            to,
            spent: 0,
            newton,
            session,
            fallback: fallback.as_ref(),
        };
        loop {
            let state = self.state(problem, u, to, newton)?;
            let mut tol = Tolerances {
                gap: self.settings.gap_tolerance,
                force: state.force_tolerance,
            };
            if inexact.pending {
                tol.force += inexact.residual;
            }
            let change = update(&state.weighted_gaps, &state.recovered, &state.active, tol);
            let mut next = state.active.clone();
            change.apply(&mut next);
            if inexact.pending {
                // `u` is an iterate of the re-solve after the last change of the set.
                let t = Instant::now();
                let near = inexact.residual <= NEAR * inexact.tolerance;
                let more = if near
                    && !change.is_empty()
                    && inexact.left > 0
                    && !inexact.tried.contains(&next)
                {
                    self.check_progress(to, &[], &next, passes.len(), &change)?;
                    self.install(problem, u, &next)?;
                    inexact.left -= 1;
                    inexact.tried.push(next);
                    inexact.steps = 0;
                    passes.push(PassReport {
                        closed: change.added,
                        opened: change.released,
                        refresh: false,
                        iterations: 0,
                        inexact: true,
                        redone: false,
                        seconds: 0.0,
                    });
                    self.step(problem, u, &mut solve, &mut inexact)?
                } else if inexact.steps < STEPS {
                    self.step(problem, u, &mut solve, &mut inexact)?
                } else {
                    // The iterations made one at a time at this set count against
                    // Newton's limit: the re-solve fails (and falls back) where one
                    // whole re-solve from the last change would have.
                    inexact.pending = false;
                    solve.spent = inexact.steps;
                    let converged = self.resolve(problem, u, &mut solve);
                    solve.spent = 0;
                    converged?
                };
                let Some((iterations, redone)) = more else {
                    return Err(solve.failed(passes.len(), &Change::default()));
                };
                match passes.last_mut() {
                    Some(last) => {
                        last.iterations += iterations;
                        last.redone |= redone;
                        last.seconds += t.elapsed().as_secs_f64();
                    }
                    // Still the first solve (a start from an iterate).
                    None => first_iterations += iterations,
                }
                if !inexact.pending {
                    let set = self.active();
                    if seen.contains(&set) {
                        // Back at a set converged before: the exact loop from here on.
                        inexact.left = 0;
                    } else {
                        seen.push(set);
                    }
                }
                continue;
            }
            // A held pair's (weighted) gap is zero along the normals it was tied with; the
            // re-solve turns the lower face, so along the current normals it may overlap: such
            // a set is held again with the current normals (a refresh: same set, no cycle).
            let refresh = change.is_empty()
                && state.penetration().max(state.weighted_penetration()) > tol.gap;
            if change.is_empty() && !refresh {
                return Ok(ContactLevel {
                    lambda: to,
                    first,
                    first_seconds,
                    passes,
                    first_iterations,
                    state,
                });
            }
            let t = Instant::now();
            if refresh {
                self.check_progress(to, &[], &next, passes.len(), &change)?;
                refreshes.push(state.penetration().max(state.weighted_penetration()));
                self.check_refresh(to, &state, &refreshes)?;
            } else {
                refreshes.clear();
                self.check_progress(to, &seen, &next, passes.len(), &change)?;
            }
            self.install(problem, u, &next)?;
            let inexactly = !refresh && inexact.left > 0;
            let result = if inexactly {
                inexact.tried = vec![next.clone()];
                inexact.tolerance = state.force_tolerance;
                inexact.steps = 0;
                self.step(problem, u, &mut solve, &mut inexact)?
            } else {
                self.resolve(problem, u, &mut solve)?
            };
            let Some((iterations, redone)) = result else {
                return Err(solve.failed(passes.len() + 1, &change));
            };
            if !refresh && !inexact.pending {
                seen.push(next);
            }
            passes.push(PassReport {
                closed: change.added,
                opened: change.released,
                refresh,
                iterations,
                inexact: inexactly,
                redone,
                seconds: t.elapsed().as_secs_f64(),
            });
        }
    }

    /// One Newton iteration of a re-solve at the installed set (`inexact` records whether
    /// the iterate is still pending, its residual and correction). An iteration that fails (a
    /// singular tangent, a non-finite state) is followed by the exact re-solve from where it
    /// started. Returns the iterations and whether the level was followed again; None: that
    /// re-solve did not converge and there is no fallback (`u` is then its last iterate).
    fn step(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        solve: &mut Resolve<'_, '_>,
        inexact: &mut Inexact,
    ) -> Result<Option<(usize, bool)>, ContactError> {
        let once = NewtonSettings {
            max_iterations: 1,
            ..solve.newton.clone()
        };
        let mut trial = u.clone();
        let report = solve
            .session
            .solve_at(problem, &mut trial, solve.to, &once)?;
        let iterations = report.iterations.len();
        inexact.steps += iterations;
        inexact.pending = false;
        match (&report.termination, report.iterations.last()) {
            (Termination::Converged, _) => {
                self.check_stable(solve.to, report.negative_pivots())?;
                *u = trial;
                Ok(Some((iterations, false)))
            }
            (
                Termination::MaxIterations | Termination::Diverging | Termination::TooSlow { .. },
                Some(last),
            ) => {
                *u = trial;
                inexact.pending = true;
                inexact.residual = last.residual;
                Ok(Some((iterations, false)))
            }
            _ => Ok(self
                .resolve(problem, u, solve)?
                .map(|(more, redone)| (iterations + more, redone))),
        }
    }

    /// With [`set_stable_only`](Self::set_stable_only): a re-solve at λ = `lambda` converged
    /// with negative `pivots` (those of its last factorisation) ends the level
    /// ([`ContactError::Unstable`]).
    pub(super) fn check_stable(
        &self,
        lambda: f64,
        pivots: Option<usize>,
    ) -> Result<(), ContactError> {
        match pivots {
            Some(p) if self.stable_only && p > 0 => {
                Err(ContactError::Unstable { lambda, pivots: p })
            }
            _ => Ok(()),
        }
    }

    /// Refuses a run of refresh passes that does not converge: after [`REFRESH_WINDOW`] of them
    /// the overlap must have shrunk at least tenfold over the last [`REFRESH_WINDOW`] (a
    /// refresh of a two-body tie corrects the turn of the normal, a second-order quantity; in
    /// [`Mode::External`] a held upper node joined to its lower node through a short front
    /// cell drags it along, and the refresh is a fixed-point iteration that contracts by a few
    /// per cent a pass). The error names the pair that overlaps most and the overlaps.
    fn check_refresh(
        &self,
        lambda: f64,
        state: &ContactState,
        overlaps: &[f64],
    ) -> Result<(), ContactError> {
        let n = overlaps.len();
        if n <= REFRESH_WINDOW || overlaps[n - 1] * 10.0 <= overlaps[n - 1 - REFRESH_WINDOW] {
            return Ok(());
        }
        let worst = (0..state.gaps.len())
            .max_by(|&a, &b| {
                let o = |i: usize| (-state.gaps[i]).max(-state.weighted_gaps[i]);
                o(a).total_cmp(&o(b))
            })
            .unwrap_or(0);
        Err(ContactError::Refresh {
            lambda,
            passes: n,
            pair: self.faces.pairs()[worst],
            before: overlaps[n - 1 - REFRESH_WINDOW],
            overlap: overlaps[n - 1],
            external: self.settings.mode == Mode::External,
        })
    }

    /// Refuses a set `next` seen before at the level (a cycle: the pairs whose state differs
    /// among the sets since its first visit flip) and a pass beyond the limit.
    pub(super) fn check_progress(
        &self,
        lambda: f64,
        seen: &[Vec<bool>],
        next: &[bool],
        passes: usize,
        change: &Change,
    ) -> Result<(), ContactError> {
        if let Some(first) = seen.iter().position(|s| s == next) {
            let pairs: Vec<Pair> = (0..next.len())
                .filter(|&i| seen[first..].iter().any(|s| s[i] != next[i]))
                .map(|i| self.faces.pairs()[i])
                .collect();
            return Err(ContactError::Cycle {
                lambda,
                passes,
                pairs,
            });
        }
        if passes >= self.settings.max_passes {
            return Err(ContactError::Passes {
                lambda,
                passes,
                closed: change.added.len(),
                opened: change.released.len(),
            });
        }
        Ok(())
    }

    /// The re-solve of a pass at λ = `solve.to`: Newton from `u` with the session's solver; if
    /// it does not converge, path following from the level's start (`fallback`; by the §3.2
    /// protocol when it carries a perturbation, on the session's analysis), or None without a
    /// fallback (`u` is then the last iterate).
    /// Returns the Newton iterations and whether the level was followed again.
    fn resolve(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        solve: &mut Resolve<'_, '_>,
    ) -> Result<Option<(usize, bool)>, ContactError> {
        let (to, newton, fallback) = (solve.to, solve.newton, solve.fallback);
        let session = &mut *solve.session;
        let mut trial = u.clone();
        let rest = NewtonSettings {
            max_iterations: newton.max_iterations.saturating_sub(solve.spent).max(1),
            ..newton.clone()
        };
        let report = session.solve_at(problem, &mut trial, to, &rest)?;
        let mut iterations = report.iterations.len();
        if report.converged() {
            self.check_stable(solve.to, report.negative_pivots())?;
            *u = trial;
            return Ok(Some((iterations, false)));
        }
        let Some(f) = fallback else {
            *u = trial;
            return Ok(None);
        };
        u.clear();
        u.extend_from_slice(f.start);
        session.invalidate();
        let attempts = if f.perturbation.is_empty() {
            follow_path_with(problem, u, f.from, &[to], newton, f.stepping, session)?.attempts
        } else {
            perturbed_redo_with(
                problem,
                u,
                (f.from, to),
                f.perturbation,
                newton,
                f.stepping,
                session,
            )?
        };
        iterations += attempts.iter().map(|a| a.iterations.len()).sum::<usize>();
        Ok(Some((iterations, true)))
    }
}
