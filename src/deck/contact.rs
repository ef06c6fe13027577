//! Frictionless contact of a deck's `*CONTACT PAIR`s (node pairs on matching faces, read by
//! `nonlin3d_mesh::read_inp`) in a deck solve: the active-set loop of thesis §2.7 (Fig. 2.7.2)
//! at the end of every increment.
//!
//! The pairs are one [`Contact`] (slave node = "upper", master node = "lower": the gap is
//! g = n·(x_slave − x_master), n the outward normal of the deformed master face). The pattern
//! reserves the pairs that have closed, their neighbours and the pairs whose faces are near
//! (`nonlin3d_contact::Reserve`): a set within them costs no new symbolic analysis, a pair
//! closing outside them grows the reserve (one new pattern and analysis). An increment
//! converged by Newton is followed by the contact crate's passes ([`Contact::settle`], the
//! loop `run` uses: pairs whose weighted gap g̃ < −1e-9, in
//! the deck's length unit, close; pairs whose recovered force f̂ is tensile beyond the Newton
//! tolerance open — one complementarity, `nonlin3d_contact::update`; a stable set that
//! overlaps along the current normals is held again with them), Newton re-run at the same
//! step time, until the set does not change. A set seen before within the increment (a
//! cycle) or more than [`MAX_PASSES`] passes fail the increment, which is then cut back as a
//! non-converged one, and so is a re-solve that does not converge. The set carries from
//! increment to increment and from step to step (CalculiX's contact pairs are model data:
//! they act in every step).

use crate::Error;
use nonlin3d_contact::{Contact, ContactError, ContactSettings, CrackFaces};
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

    /// The passes at a converged increment (state `u` at λ = 1 of the increment): the
    /// contact crate's loop ([`Contact::settle`]: set changes, refresh passes, cycle and pass
    /// limits, Newton re-solves at the same step time). A cycle, the pass limit or a re-solve
    /// that does not converge is a failed attempt: the set is back to what it was at the
    /// start, installed with the normals of `start`, and `u` is `start`.
    pub(crate) fn settle(
        &mut self,
        problem: &mut StructuralProblem,
        u: &mut Vec<f64>,
        start: &[f64],
        newton: &NewtonSettings,
        session: &mut PathSolver,
    ) -> Result<Settled, Error> {
        let initial = self.contact.active();
        let failed = match self.contact.settle(problem, u, 1.0, newton, session) {
            Ok(level) => {
                let s = &level.state;
                return Ok(Settled::Stable(IncrementContact {
                    pairs_closed: s.active.iter().filter(|&&a| a).count(),
                    passes: level.passes.len(),
                    iterations: level.passes.iter().map(|p| p.iterations).sum(),
                    max_force: s.forces.iter().copied().fold(0.0, f64::max),
                    max_overlap: s.penetration(),
                }));
            }
            Err(
                e @ (ContactError::Cycle { .. }
                | ContactError::Passes { .. }
                | ContactError::Resolve { .. }),
            ) => e.to_string(),
            Err(e) => return Err(e.into()),
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
