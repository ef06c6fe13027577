//! What mixed precision did in a run (results.json `timings.mixed_precision`).

use serde::Serialize;

/// The factorisations of a run's solvers (the level loop's and the contact system's, each
/// since its last symbolic analysis) by precision: the f32 factor refined in f64, or the f64
/// factor where f32 was refused (an entry beyond f32, a pivot too small to trust its sign, a
/// changed negative pivot count, refinement and then conjugate gradients stalling; and for 8,
/// 16, 32, … factorisations before f32 is tried again, once f32 was refused before it
/// served, or twice in a row).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MixedSummary {
    /// Factorisations kept in f32.
    pub f32_factorisations: usize,
    /// Factorisations made (or redone) in f64.
    pub f64_factorisations: usize,
    /// Refinement steps over all solves (one f32 solve and one f64 product each).
    pub refinement_steps: usize,
    /// Of those, conjugate-gradient steps (the f32 factor as preconditioner) where plain
    /// refinement stalled.
    pub conjugate_gradient_steps: usize,
    /// f32 solves of Newton's directions taken without the f64 product that checks them
    /// (the factor's checked solves had met their bounds with room to spare).
    pub unchecked_solves: usize,
    /// Why the last f64 factorisation was made, if one was.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub last_fallback: Option<String>,
}

impl MixedSummary {
    /// The sum over the solvers that report mixed precision (None if none does).
    pub fn of(
        stats: impl IntoIterator<Item = Option<nonlin3d_solver::MixedStats>>,
    ) -> Option<Self> {
        stats.into_iter().flatten().fold(None, |sum, m| {
            let mut s = sum.unwrap_or(Self {
                f32_factorisations: 0,
                f64_factorisations: 0,
                refinement_steps: 0,
                conjugate_gradient_steps: 0,
                unchecked_solves: 0,
                last_fallback: None,
            });
            s.f32_factorisations += m.single_factorizations;
            s.f64_factorisations += m.double_factorizations;
            s.refinement_steps += m.refinement_steps;
            s.conjugate_gradient_steps += m.conjugate_gradient_steps;
            s.unchecked_solves += m.unchecked_solves;
            if let Some(r) = m.last_fallback {
                s.last_fallback = Some(r.to_string());
            }
            Some(s)
        })
    }
}
