//! Solving an Abaqus/CalculiX deck (the subset `nonlin3d_mesh::read_inp` reads, docs/DECKS.md):
//! linear or NLGEOM static steps, as the `nonlin3d solve` command does, with CalculiX's step
//! semantics (module `loads`), time incrementation (module `drive`) and output requests
//! (module `output`), after the checks a scene gets (module `check`: a step, positive element
//! Jacobians, …) and, with `*CONTACT PAIR`s, the contact active set at every increment (module
//! `contact`, thesis §2.7). [`solve_deck_with`] reports each converged increment; [`DeckOutput`] writes
//! the command's files from those reports as the solve goes (module `files`).
//!
//! C3D20 cells are integrated with 3×3×3 points, C3D20R and C3D8 with 2×2×2 (a deck mixing
//! C3D20 and C3D20R is refused). Each cell's material is rotated to its `*ORIENTATION` axes
//! (exact tensor rotation): once for a rectangular system, at each integration point for a
//! cylindrical one (`nonlin3d_element::Material::Cylindrical`). NLGEOM steps use the nonlinear kernels (total Lagrangian, St.
//! Venant–Kirchhoff), other steps the linear kernels (one Newton iteration solves them).

mod background;
mod check;
mod contact;
mod drive;
mod files;
mod loads;
mod output;
mod riks;

pub use background::write_in_background;
pub use check::{Checked, check};
pub use contact::IncrementContact;
pub use files::DeckOutput;
pub use output::{OutputTable, write_results};

use crate::Error;
use crate::results::FactorSummary;
use nonlin3d_assembly::{Assembler, Constraints, StressRules};
use nonlin3d_element::{IntegrationRule, Kinematics};
use nonlin3d_laminate::ShearCoupling;
use nonlin3d_mesh::InpModel;
use nonlin3d_newton::{IncrementReport, NewtonSettings, StructuralProblem};
use nonlin3d_solver::MixedStats;
use serde::Serialize;
use std::collections::BTreeMap;

/// Options of a deck solve that the deck does not set.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepOptions {
    /// Newton settings; a deck's `*CONTROLS` replaces the iteration limit (I_C) and the
    /// tolerances (R_n → relative, C_n → displacement correction), and `start.line_search`
    /// replaces `line_search`.
    pub newton: NewtonSettings,
    /// First increment of every NLGEOM step as a fraction of its period, instead of the
    /// `*STATIC` initial increment.
    pub initial_increment: Option<f64>,
    /// How each increment starts and iterates.
    pub start: IncrementStart,
    /// How often the tangent is factorised in the increments of a static step.
    pub strategy: Strategy,
    /// The solver of the NLGEOM static steps whose strategy keeps a tangent (BFGS, modified
    /// Newton: each factorisation serves many directions); None: `newton.solver` in every
    /// step. `nonlin3d solve --solver auto` (the default) gives
    /// [`SolverKind::FaerLdltKept`](nonlin3d_solver::SolverKind::FaerLdltKept) here.
    pub kept_solver: Option<nonlin3d_solver::SolverKind>,
}

/// How often the tangent is factorised in a static deck step (thesis §2.1: full or modified
/// Newton; quasi-Newton after Matthies & Strang 1979). Measured on the plate decks and on
/// `tests/decks/` in docs/PERFORMANCE.md, "Fewer factorisations in deck steps". A `*STATIC,
/// RIKS` step always iterates with full Newton.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Strategy {
    /// [`Bfgs`](Self::Bfgs) in `*STATIC, DIRECT` steps, [`Full`](Self::Full) where the
    /// increment size follows the iteration count (CalculiX's I_G / I_L are Newton
    /// iterations: counted on BFGS iterations they shrank `static_control`'s increments, 10
    /// instead of CalculiX's 6). The default.
    #[default]
    Auto,
    /// A new tangent at every iteration (Newton–Raphson, as CalculiX).
    Full,
    /// The factorised tangent kept across iterations and increments, factorised anew when an
    /// iteration reduced ‖r‖∞ by less than half.
    Modified,
    /// The kept tangent updated by up to 20 BFGS pairs, factorised anew when an iteration
    /// more than doubled ‖r‖∞ ([`nonlin3d_newton::BFGS_REFACTOR_RATIO`]).
    Bfgs,
}

impl Strategy {
    /// `auto`, `full`, `modified` or `bfgs`.
    pub fn name(self) -> &'static str {
        match self {
            Self::Auto => "auto",
            Self::Full => "full",
            Self::Modified => "modified",
            Self::Bfgs => "bfgs",
        }
    }

    /// What [`Auto`](Self::Auto) is in a step with (`direct`) or without fixed increments.
    pub fn in_step(self, direct: bool) -> Self {
        match (self, direct) {
            (Self::Auto, true) => Self::Bfgs,
            (Self::Auto, false) => Self::Full,
            (s, _) => s,
        }
    }

    /// `base` with this strategy's refactorisation rule ([`Auto`](Self::Auto): full Newton's;
    /// see [`in_step`](Self::in_step)).
    pub fn apply(self, base: &NewtonSettings) -> NewtonSettings {
        let kept = NewtonSettings {
            keep_tangent: true,
            refactor_every: usize::MAX,
            ..base.clone()
        };
        match self {
            Self::Auto | Self::Full => NewtonSettings {
                keep_tangent: false,
                refactor_every: 1,
                quasi_newton: 0,
                ..base.clone()
            },
            Self::Modified => NewtonSettings {
                refactor_ratio: 0.5,
                quasi_newton: 0,
                ..kept
            },
            Self::Bfgs => NewtonSettings {
                refactor_ratio: nonlin3d_newton::BFGS_REFACTOR_RATIO,
                quasi_newton: 20,
                ..kept
            },
        }
    }
}

impl std::str::FromStr for Strategy {
    type Err = String;
    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "auto" => Ok(Self::Auto),
            "full" => Ok(Self::Full),
            "modified" => Ok(Self::Modified),
            "bfgs" => Ok(Self::Bfgs),
            _ => Err(format!("{s}: expected auto, full, modified or bfgs")),
        }
    }
}

/// How each increment of a deck step starts and iterates (docs/PERFORMANCE.md, "Fewer
/// iterations in deck steps"). The default — quadratic extrapolation, unguarded, no line
/// search, as CalculiX iterates — took fewer or as many iterations as the old linear start
/// with a line search on every deck in `tests/decks/` (147 → 63 on the elastica).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IncrementStart {
    /// Order of the polynomial in step time through the last converged states of the step
    /// that gives the start of an increment without prescribed-value changes: 0 = the last
    /// state, 1 = linear (the old start), 2 = quadratic (default; from the step's third
    /// increment, linear in its second).
    pub extrapolation: usize,
    /// Keep the extrapolated start only if ‖r‖∞ there is no larger than at the last state
    /// (off by default: it rejects good starts on bending decks, whose first Newton step from
    /// the last state has a residual 10³–10⁴ times the start's).
    pub guarded: bool,
    /// Newton's backtracking line search on ‖r‖∞ (off by default, as CalculiX: on the elastica
    /// it accepted steps of α ≤ 1/32 for twenty iterations).
    pub line_search: bool,
}

impl Default for IncrementStart {
    fn default() -> Self {
        Self {
            extrapolation: 2,
            guarded: false,
            line_search: false,
        }
    }
}

/// The record of one attempt at one increment, for the JSON summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IncrementSummary {
    /// Increment number within the step (1-based; a cut-back attempt and its retry share it).
    pub increment: usize,
    /// Step time at the end of the increment tried.
    pub step_time: f64,
    /// Total time at the end of the increment tried.
    pub total_time: f64,
    /// Newton iterations.
    pub iterations: usize,
    /// Residual history ‖r‖∞ (N), starting with the initial residual.
    pub residuals: Vec<f64>,
    /// Whether it converged (failed attempts are followed by a cutback).
    pub converged: bool,
    /// How it ended.
    pub termination: String,
    /// Negative pivots of the last factorisation (of a Riks increment: at its start); with a
    /// kept tangent ([`Strategy`]) of one made at the converged state if its last iteration
    /// made none.
    pub negative_pivots: Option<usize>,
    /// Tangents factorised in the attempt: by its iterations, and at its converged state for
    /// its negative pivots (the tangent predictor's are not counted).
    pub factorisations: usize,
    /// `*STATIC, RIKS`: the load proportionality factor at the end of the increment.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lpf: Option<f64>,
    /// `*STATIC, RIKS`: the increment's arc length (the step time advances by it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub arc_length: Option<f64>,
    /// The contact state at the end of a converged increment (decks with `*CONTACT PAIR`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub contact: Option<IncrementContact>,
    /// `--solver faer-mixed`: what the f32 factor did in this attempt (with a redo by full
    /// Newton and the inertia factorisation at the converged state counted in).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mixed_precision: Option<MixedPrecision>,
}

/// Mixed precision over one attempt (the solver's `MixedStats`, counted from the attempt's
/// start): whether the f32 factor held or the f64 one was made.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MixedPrecision {
    /// Factorisations kept in f32.
    pub f32_factorisations: usize,
    /// Factorisations made in f64 because the f32 one was in doubt (`fallback` says why).
    pub f64_factorisations: usize,
    /// Iterative-refinement steps (one f32 solve and one f64 product each).
    pub refinement_steps: usize,
    /// Of those, conjugate-gradient steps (the f32 factor as preconditioner) where plain
    /// refinement stalled.
    pub conjugate_gradient_steps: usize,
    /// f32 solves of Newton's directions taken without the f64 product that checks them
    /// (the factor's checked solves had met their bounds with room to spare).
    pub unchecked_solves: usize,
    /// The normwise backward error ‖b − A x‖∞ / (‖A‖∞‖x‖∞ + ‖b‖∞) the last checked
    /// solution reached (null if none was checked: unchecked solves have no residual).
    pub backward_error: Option<f64>,
    /// Why the last f64 factorisation of the attempt was made, if one was.
    pub fallback: Option<String>,
}

impl MixedPrecision {
    /// The change from `before` to `now`; a new analysis in between (the counts restart)
    /// counts from zero.
    pub fn between(before: Option<MixedStats>, now: MixedStats) -> Self {
        let b = before
            .filter(|b| {
                b.single_factorizations <= now.single_factorizations
                    && b.double_factorizations <= now.double_factorizations
                    && b.refinement_steps <= now.refinement_steps
                    && b.conjugate_gradient_steps <= now.conjugate_gradient_steps
                    && b.unchecked_solves <= now.unchecked_solves
            })
            .unwrap_or_default();
        let f64_factorisations = now.double_factorizations - b.double_factorizations;
        let refinement_steps = now.refinement_steps - b.refinement_steps;
        let conjugate_gradient_steps = now.conjugate_gradient_steps - b.conjugate_gradient_steps;
        Self {
            f32_factorisations: now.single_factorizations - b.single_factorizations,
            f64_factorisations,
            refinement_steps,
            conjugate_gradient_steps,
            unchecked_solves: now.unchecked_solves - b.unchecked_solves,
            backward_error: (refinement_steps > 0).then_some(now.last_backward_error),
            fallback: now
                .last_fallback
                .filter(|_| f64_factorisations > 0)
                .map(str::to_string),
        }
    }

    /// A line for the terminal: "f32 factor held (1 factorisation, 3 refinement steps,
    /// backward error 2.1e-15)" or "f64 fall-back: … (…)".
    pub fn line(&self) -> String {
        let s = |n: usize| if n == 1 { "" } else { "s" };
        let unchecked = match self.unchecked_solves {
            0 => String::new(),
            u => format!(", {u} unchecked solve{}", s(u)),
        };
        let refined = match self.backward_error {
            Some(e) => format!(
                ", {} refinement step{}{}{}, backward error {e:.1e}",
                self.refinement_steps,
                s(self.refinement_steps),
                match self.conjugate_gradient_steps {
                    0 => String::new(),
                    cg => format!(" ({cg} by conjugate gradients)"),
                },
                unchecked,
            ),
            // An attempt on a factor an earlier one checked may have no checked solve.
            None => unchecked,
        };
        let (single, double) = (self.f32_factorisations, self.f64_factorisations);
        match &self.fallback {
            None => format!(
                "f32 factor held ({single} factorisation{}{refined})",
                s(single)
            ),
            Some(why) => format!(
                "f64 fall-back ({why}): {double} f64 and {single} f32 factorisation{}{refined}",
                s(single + double)
            ),
        }
    }
}

impl IncrementSummary {
    fn of(a: &IncrementReport, increment: usize, step_time: f64, start: f64) -> Self {
        Self {
            increment,
            step_time,
            total_time: start + step_time,
            iterations: a.iterations.len(),
            residuals: std::iter::once(a.initial_residual)
                .chain(a.iterations.iter().map(|i| i.residual))
                .collect(),
            converged: a.converged(),
            termination: a.termination.to_string(),
            negative_pivots: a.negative_pivots(),
            factorisations: a
                .iterations
                .iter()
                .filter(|i| i.negative_pivots.is_some())
                .count(),
            lpf: None,
            arc_length: None,
            contact: None,
            mixed_precision: None,
        }
    }
}

/// One solved step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepResult {
    /// Step number, 1-based.
    pub step: usize,
    /// NLGEOM.
    pub nlgeom: bool,
    /// Step period and total time at its start.
    pub period: f64,
    /// Total time at the start of the step.
    pub start_time: f64,
    /// Increments (all attempts).
    pub increments: Vec<IncrementSummary>,
    /// Whether the step reached the end of its period (false while it is being solved, and for
    /// a step that failed).
    pub complete: bool,
    /// Displacements at the end of the step (at its last converged increment while it is being
    /// solved), by mesh node (deck ids in `InpModel::node_ids`).
    #[serde(skip)]
    pub displacements: Vec<[f64; 3]>,
    /// The step's output requests, filled at the increments they were due.
    #[serde(skip)]
    pub outputs: Vec<OutputTable>,
    /// The slave nodes (mesh indices) of the contact pairs closed at the end of the step.
    #[serde(skip)]
    pub contact_closed: Vec<usize>,
    /// What the step's symbolic analysis found: equations, ordering, the factor's entries and
    /// flops, its supernode tree (absent for a Riks step).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub factor: Option<FactorSummary>,
}

/// What [`solve_deck_with`] reports as it goes.
#[derive(Debug, Clone, Copy)]
pub enum Progress<'a> {
    /// An increment converged: the step so far (every attempt, the output tables filled so
    /// far, the displacements now; `complete` false).
    Increment(&'a StepResult),
    /// The step reached the end of its period (`complete` true).
    Step(&'a StepResult),
    /// The step failed: every attempt (the failed ones too) and the tables so far; the error
    /// follows as the solve's result.
    Failed(&'a StepResult),
}

/// Checks `model` ([`check`]) and solves every step in order; writes nothing.
pub fn solve_deck(model: &InpModel, options: &StepOptions) -> Result<Vec<StepResult>, Error> {
    solve_deck_with(model, options, &mut |_| Ok(()))
}

/// [`solve_deck`], calling `observer` after every converged increment, at the end of every
/// step and on a failed step (an observer's error stops the solve). [`DeckOutput::progress`]
/// writes the files of `nonlin3d solve` from these.
pub fn solve_deck_with(
    model: &InpModel,
    options: &StepOptions,
    observer: &mut dyn FnMut(Progress<'_>) -> Result<(), Error>,
) -> Result<Vec<StepResult>, Error> {
    crate::budget::check_deck(&model.mesh, &crate::budget::limit())?;
    let checked = check(model, options)?;
    solve_checked_with(model, options, checked, observer)
}

/// [`solve_deck_with`] on a deck [`check`] has passed with the same `options`: its checks are
/// not repeated (a `Checked` of a deck with other node or element counts is checked again).
pub fn solve_checked_with(
    model: &InpModel,
    options: &StepOptions,
    checked: Checked,
    observer: &mut dyn FnMut(Progress<'_>) -> Result<(), Error>,
) -> Result<Vec<StepResult>, Error> {
    crate::budget::check_deck(&model.mesh, &crate::budget::limit())?;
    let checked = match checked.counts == (model.mesh.nodes.len(), model.mesh.cells.len()) {
        true => checked,
        false => check(model, options)?,
    };
    let check::Prepared {
        mesh,
        materials,
        rule,
    } = checked.prepared;
    let n = 3 * mesh.nodes.len();
    let mut contact = contact::DeckContact::new(model, &mesh)?;
    let mut u = vec![0.0; n];
    let mut history = loads::History::new(model);
    let mut results = Vec::new();
    let mut assemblers: BTreeMap<bool, Assembler> = BTreeMap::new();
    let mut start = 0.0;
    for (k, step) in model.steps.iter().enumerate() {
        // Newton's `attempt` spans and events (crate::log) nest in it.
        let _step = tracing::debug_span!("step", step = k + 1).entered();
        let kinematics = if step.nlgeom {
            Kinematics::Nonlinear
        } else {
            Kinematics::Linear
        };
        let assembler = match assemblers.remove(&step.nlgeom) {
            Some(a) => a,
            None => Assembler::new(
                &mesh,
                &materials,
                ShearCoupling::Exact,
                rule,
                IntegrationRule::Gauss2,
                kinematics,
            )?,
        };
        // CalculiX: TOTAL TIME AT START sets the total time at the start; TIME RESET runs the
        // step's total time from there minus the period, so that it ends where it began.
        if let Some(t) = step.procedure.total_time_at_start {
            start = t;
        }
        if step.procedure.time_reset {
            start -= step.procedure.period;
        }
        let frame = loads::Frame {
            period: step.procedure.period,
            start,
        };
        history.begin_step(model, step, &u)?;
        let mut problem = match &contact {
            Some(c) => c.problem(assembler, n)?,
            None => StructuralProblem::new(assembler, Constraints::new(n))?,
        };
        let rules = StressRules {
            materials: &materials,
            coupling: ShearCoupling::Exact,
            hex20_rule: rule,
            hex8_rule: IntegrationRule::Gauss2,
            kinematics,
        };
        let mut current = StepResult {
            step: k + 1,
            nlgeom: step.nlgeom,
            period: frame.period,
            start_time: start,
            increments: Vec::new(),
            complete: false,
            displacements: Vec::new(),
            outputs: output::tables(model, step),
            contact_closed: Vec::new(),
            factor: None,
        };
        let mut attempts = Vec::new();
        // The step's one system: with *CONTACT PAIR its pattern reserves every candidate pair.
        let system = if contact.is_some() {
            "contact"
        } else {
            "solid"
        };
        let mut record = |c: drive::Converged<'_>| {
            let (u, tried) = (c.u, c.attempts);
            current.factor = c
                .analysis
                .map(|a| FactorSummary::of(system, c.problem.assembler().n(), &a));
            output::record(model, &mesh, &rules, step, frame, &mut current.outputs, c)?;
            current.increments = tried.to_vec();
            current.displacements = nodal(u);
            observer(Progress::Increment(&current))
        };
        let (problem_, u_) = (&mut problem, &mut u);
        let run = match (&step.procedure.riks, contact.as_mut()) {
            (Some(_), Some(_)) => Err(Error::Step {
                step: k + 1,
                line: step.line,
                reason: "a *STATIC, RIKS step in a deck with *CONTACT PAIR: arc-length path \
                         following does not hold the contact active set; use *STATIC without \
                         RIKS"
                    .into(),
            }),
            (Some(r), None) => riks::run_step(
                model,
                k,
                &history,
                frame,
                problem_,
                u_,
                options,
                r,
                &mut attempts,
                &mut record,
            ),
            (None, contact_) => drive::run_step(
                model,
                k,
                &history,
                frame,
                problem_,
                u_,
                options,
                contact_,
                &mut attempts,
                &mut record,
            ),
        };
        current.increments = attempts;
        if let Err(e) = run {
            // The solve's error is the one to report; the observer's own (a file that could not
            // be written) would hide it.
            let _ = observer(Progress::Failed(&current));
            return Err(e);
        }
        history.end_step(model, frame);
        current.complete = true;
        current.displacements = nodal(&u);
        current.contact_closed = contact.as_ref().map(|c| c.closed()).unwrap_or_default();
        observer(Progress::Step(&current))?;
        results.push(current);
        assemblers.insert(step.nlgeom, problem.into_parts()?.0);
        start += frame.period;
    }
    Ok(results)
}

/// Displacements by node.
fn nodal(u: &[f64]) -> Vec<[f64; 3]> {
    u.chunks(3).map(|c| [c[0], c[1], c[2]]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The terminal line names the unchecked solves, also in an attempt whose solves were all
    /// unchecked (a factor an earlier attempt checked: no backward error to give).
    #[test]
    fn the_mixed_precision_line_names_unchecked_solves() {
        let now = MixedStats {
            single_factorizations: 1,
            refinement_steps: 2,
            unchecked_solves: 5,
            last_backward_error: 4.0e-8,
            ..MixedStats::default()
        };
        let line = MixedPrecision::between(None, now).line();
        assert_eq!(
            line,
            "f32 factor held (1 factorisation, 2 refinement steps, 5 unchecked solves, \
             backward error 4.0e-8)"
        );
        let later = MixedStats {
            unchecked_solves: 9,
            ..now
        };
        let line = MixedPrecision::between(Some(now), later).line();
        assert_eq!(
            line,
            "f32 factor held (0 factorisations, 4 unchecked solves)"
        );
    }
}
