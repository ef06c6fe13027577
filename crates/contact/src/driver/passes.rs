//! The passes of the contact loop (Fig. 2.7.2) after a level's first solve: read the state,
//! change the set, install, re-solve at the same load, until the set is stable; the refresh
//! passes, the cycle, pass and refresh limits, and the door for callers that follow the load
//! themselves ([`Contact::settle`]).

use super::{Contact, ContactLevel, ContactState, LevelSettings, Mode, PassReport, REFRESH_WINDOW};
use crate::active::{Change, Tolerances, update};
use crate::{ContactError, Pair};
use nonlin3d_newton::{
    LevelReport, NewtonSettings, PathSolver, Stepping, StructuralProblem, follow_path_with,
    perturbed_redo,
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
        let first = LevelReport {
            attempts: Vec::new(),
            perturbed: false,
            negative_pivots: None,
        };
        self.passes(problem, u, lambda, (first, 0.0), newton, session, None)
    }

    /// The loop of passes after the first solve (module docs); `fallback`: how to follow the
    /// level again when a re-solve fails (None: the failure is [`ContactError::Resolve`]).
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
    ) -> Result<ContactLevel, ContactError> {
        let mut passes = Vec::new();
        let mut seen = vec![self.active()];
        // The overlap at each pass of the current run of refresh passes.
        let mut refreshes: Vec<f64> = Vec::new();
        loop {
            let state = self.state(problem, u, to, newton)?;
            let tol = Tolerances {
                gap: self.settings.gap_tolerance,
                force: state.force_tolerance,
            };
            let change = update(&state.weighted_gaps, &state.recovered, &state.active, tol);
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
                    state,
                });
            }
            let t = Instant::now();
            let mut next = state.active.clone();
            change.apply(&mut next);
            if refresh {
                self.check_progress(to, &[], &next, passes.len(), &change)?;
                refreshes.push(state.penetration().max(state.weighted_penetration()));
                self.check_refresh(to, &state, &refreshes)?;
            } else {
                refreshes.clear();
                self.check_progress(to, &seen, &next, passes.len(), &change)?;
                seen.push(next.clone());
            }
            self.install(problem, u, &next)?;
            let Some((iterations, redone)) =
                self.resolve(problem, u, to, newton, session, fallback.as_ref())?
            else {
                return Err(ContactError::Resolve {
                    lambda: to,
                    pass: passes.len() + 1,
                    closed: change.added.len(),
                    opened: change.released.len(),
                    why: "no convergence at the same load".into(),
                });
            };
            passes.push(PassReport {
                closed: change.added,
                opened: change.released,
                refresh,
                iterations,
                redone,
                seconds: t.elapsed().as_secs_f64(),
            });
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

    /// The re-solve of a pass at λ = `to`: Newton from `u` with the session's solver; if it
    /// does not converge, path following from the level's start (`fallback`; by the §3.2
    /// protocol when it carries a perturbation), or None without a fallback (`u` is then the
    /// last iterate).
    /// Returns the Newton iterations and whether the level was followed again.
    fn resolve(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        to: f64,
        newton: &NewtonSettings,
        session: &mut PathSolver,
        fallback: Option<&Fallback>,
    ) -> Result<Option<(usize, bool)>, ContactError> {
        let mut trial = u.clone();
        let report = session.solve_at(problem, &mut trial, to, newton)?;
        let mut iterations = report.iterations.len();
        if report.converged() {
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
            perturbed_redo(problem, u, (f.from, to), f.perturbation, newton, f.stepping)?
        };
        iterations += attempts.iter().map(|a| a.iterations.len()).sum::<usize>();
        Ok(Some((iterations, true)))
    }
}
