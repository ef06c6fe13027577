//! Frictionless contact of a deck's `*CONTACT PAIR`s (node pairs on matching faces, read by
//! `nonlin3d_mesh::read_inp`) in a deck solve: the active-set loop of thesis §2.7 (Fig. 2.7.2)
//! at the end of every increment.
//!
//! The pairs are one [`Contact`] (slave node = "upper", master node = "lower": the gap is
//! g = n·(x_slave − x_master), n the outward normal of the deformed master face). Every
//! candidate pair is reserved in the pattern once, so a change of the set costs no new
//! symbolic analysis. An increment converged by Newton is followed by passes: gaps and contact
//! forces read, the set changed by [`update`] (pairs with g < −1e-9, in the deck's length unit,
//! close; pairs whose recovered force f̂ — the release quantity of `run`'s contact, positive
//! at every node of a compressed quadratic face (`nonlin3d_contact::CrackFaces::recovered`) —
//! is tensile beyond the Newton tolerance open), the ties installed
//! with the current normals and Newton re-run at the same step time, until the set does not
//! change. A set seen before within the increment (a cycle) or more than
//! [`MAX_PASSES`] passes fail the increment, which is then cut back as a non-converged one,
//! and so is a re-solve that does not converge. The set carries from increment to increment
//! and from step to step (CalculiX's contact pairs are model data: they act in every step).

use crate::Error;
use nonlin3d_contact::{Contact, ContactSettings, CrackFaces, Tolerances, update};
use nonlin3d_mesh::{InpModel, Mesh};
use nonlin3d_newton::{NewtonSettings, PathSolver, StructuralProblem};
use serde::Serialize;

/// Most passes (re-solves) within one increment.
pub const MAX_PASSES: usize = 50;

/// The contact state at the end of a converged increment, for the JSON summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IncrementContact {
    /// Pairs closed (in the active set).
    pub pairs_closed: usize,
    /// Passes (re-solves) the set needed in this increment.
    pub passes: usize,
    /// Newton iterations of those re-solves.
    pub iterations: usize,
    /// Largest contact force, in the deck's force unit (compressive positive; 0 when none).
    pub max_force: f64,
    /// Largest overlap left, −min(g, 0), in the deck's length unit.
    pub max_overlap: f64,
}

/// What the passes of one increment came to.
pub(crate) enum Settled {
    /// The set is stable at the converged state.
    Stable(IncrementContact),
    /// A re-solve did not converge, the set cycled or needed too many passes: why.
    Failed(String),
}

/// The deck's contact: the pairs and their active set.
pub(crate) struct DeckContact {
    contact: Contact,
}

impl DeckContact {
    /// The contact of `model`'s pairs on `mesh` (the prepared mesh, same nodes); None without
    /// pairs. A pair set the contact crate refuses (a master node on no face of its cells)
    /// is an error naming the `*CONTACT PAIR` line.
    pub(crate) fn new(model: &InpModel, mesh: &Mesh) -> Result<Option<Self>, Error> {
        if model.contact.iter().all(|p| p.slave.is_empty()) {
            return Ok(None);
        }
        let slave: Vec<usize> = model.contact.iter().flat_map(|p| p.slave.clone()).collect();
        let master: Vec<usize> = model
            .contact
            .iter()
            .flat_map(|p| p.master.clone())
            .collect();
        let at = model
            .contact
            .iter()
            .map(|p| p.at.as_str())
            .collect::<Vec<_>>()
            .join(", ");
        let faces = CrackFaces::from_sets(mesh, &slave, &master).map_err(|e| {
            nonlin3d_mesh::MeshError::Deck {
                at: at.clone(),
                what: "*CONTACT PAIR data".into(),
                reason: format!("{e} (node indices from 0)"),
            }
        })?;
        let settings = ContactSettings {
            max_passes: MAX_PASSES,
            ..ContactSettings::default()
        };
        Ok(Some(Self {
            contact: Contact::with_faces(faces, settings)?,
        }))
    }

    /// The problem of a step: the solid under empty constraints, every candidate pair's
    /// couplings reserved.
    pub(crate) fn problem(
        &self,
        assembler: nonlin3d_assembly::Assembler,
        n: usize,
    ) -> Result<StructuralProblem, Error> {
        Ok(StructuralProblem::with_contributions(
            assembler,
            Vec::new(),
            nonlin3d_assembly::Constraints::new(n),
            |b| self.contact.reserve(b),
        )?)
    }

    /// Installs the current set again after the increment's constraints replaced the ties
    /// (normals from `u`); the session's kept factorisation is then stale.
    pub(crate) fn reinstall(
        &mut self,
        problem: &mut StructuralProblem,
        u: &[f64],
        session: &mut PathSolver,
    ) -> Result<(), Error> {
        let active = self.contact.active();
        self.contact.install(problem, u, &active)?;
        if active.iter().any(|&a| a) {
            session.invalidate();
        }
        Ok(())
    }

    /// The passes at a converged increment (state `u` at λ = 1 of the increment). On failure
    /// the set is back to what it was at the start, installed with the normals of `start`,
    /// and `u` is `start`.
    pub(crate) fn settle(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        start: &[f64],
        newton: &NewtonSettings,
        session: &mut PathSolver,
    ) -> Result<Settled, Error> {
        let initial = self.contact.active();
        let mut seen = vec![initial.clone()];
        let (mut passes, mut iterations) = (0, 0);
        let failed = loop {
            let state = self.contact.state(problem, u, 1.0, newton)?;
            let tol = Tolerances {
                gap: self.contact.settings().gap_tolerance,
                force: state.force_tolerance,
            };
            let change = update(&state.gaps, &state.recovered, &state.active, tol);
            if change.is_empty() {
                return Ok(Settled::Stable(IncrementContact {
                    pairs_closed: state.active.iter().filter(|&&a| a).count(),
                    passes,
                    iterations,
                    max_force: state.forces.iter().copied().fold(0.0, f64::max),
                    max_overlap: state.gaps.iter().map(|&g| -g).fold(0.0, f64::max),
                }));
            }
            let mut next = state.active.clone();
            change.apply(&mut next);
            if seen.contains(&next) {
                break format!("the contact set repeats after {passes} passes (a cycle)");
            }
            if passes >= MAX_PASSES {
                break format!("the contact set still changes after {passes} passes");
            }
            seen.push(next.clone());
            self.contact.install(problem, u, &next)?;
            let report = session.solve_at(problem, u, 1.0, newton)?;
            passes += 1;
            iterations += report.iterations.len();
            if !report.converged() {
                break format!(
                    "the re-solve of contact pass {passes} ({} closed, {} opened) did not \
                     converge ({})",
                    change.added.len(),
                    change.released.len(),
                    report.termination
                );
            }
        };
        u.clear();
        u.extend_from_slice(start);
        self.contact.install(problem, u, &initial)?;
        session.invalidate();
        Ok(Settled::Failed(failed))
    }

    /// The slave nodes (mesh indices) of the closed pairs.
    pub(crate) fn closed(&self) -> Vec<usize> {
        self.contact
            .faces()
            .pairs()
            .iter()
            .zip(self.contact.active())
            .filter(|(_, a)| *a)
            .map(|(p, _)| p.upper)
            .collect()
    }
}
