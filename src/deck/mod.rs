//! Solving an Abaqus/CalculiX deck (the subset `nonlin3d_mesh::read_inp` reads, docs/DECKS.md):
//! linear or NLGEOM static steps, as the `nonlin3d solve` command does, with CalculiX's step
//! semantics (module `loads`), time incrementation (module `drive`) and output requests
//! (module `output`).
//!
//! C3D20 cells are integrated with 3×3×3 points, C3D20R and C3D8 with 2×2×2 (a deck mixing
//! C3D20 and C3D20R is refused). Each cell's material is rotated to its `*ORIENTATION` axes
//! (exact tensor rotation). NLGEOM steps use the nonlinear kernels (total Lagrangian, St.
//! Venant–Kirchhoff), other steps the linear kernels (one Newton iteration solves them).

mod drive;
mod loads;
mod output;

pub use output::{OutputTable, write_results};

use crate::Error;
use nonlin3d_assembly::{Assembler, Constraints, StressRules};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{Orthotropic, ShearCoupling, Stiffness};
use nonlin3d_mesh::inp::InpElastic;
use nonlin3d_mesh::{InpModel, Mesh};
use nonlin3d_newton::{IncrementReport, NewtonSettings, StructuralProblem};
use serde::Serialize;
use std::collections::BTreeMap;

/// Options of a deck solve that the deck does not set.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct StepOptions {
    /// Newton settings; a deck's `*CONTROLS` replaces the iteration limit (I_C) and the
    /// tolerances (R_n → relative, C_n → displacement correction).
    pub newton: NewtonSettings,
    /// First increment of every NLGEOM step as a fraction of its period, instead of the
    /// `*STATIC` initial increment.
    pub initial_increment: Option<f64>,
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
    /// Negative pivots of the last factorisation.
    pub negative_pivots: Option<usize>,
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
            termination: format!("{:?}", a.termination),
            negative_pivots: a.negative_pivots(),
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
    /// Displacements at the end of the step, by mesh node (deck ids in `InpModel::node_ids`).
    #[serde(skip)]
    pub displacements: Vec<[f64; 3]>,
    /// The step's output requests, filled at the increments they were due.
    #[serde(skip)]
    pub outputs: Vec<OutputTable>,
}

/// The stiffness of a deck material.
fn stiffness(e: &InpElastic) -> Result<Stiffness, Error> {
    Ok(match e {
        InpElastic::Isotropic { e, nu } => Orthotropic::isotropic(*e, *nu).stiffness()?,
        InpElastic::Engineering(o) => o.stiffness()?,
        InpElastic::Orthotropic(s) | InpElastic::Anisotropic(s) => **s,
    })
}

/// The mesh with one material per distinct (deck material, orientation), each rotated to its
/// axes, and no ply angles; and those materials.
fn oriented(model: &InpModel) -> Result<(Mesh, Vec<Stiffness>), Error> {
    let base: Vec<Stiffness> = model
        .materials
        .iter()
        .map(|m| stiffness(&m.elastic))
        .collect::<Result<_, _>>()?;
    let mut mesh = model.mesh.clone();
    let mut index: BTreeMap<(usize, [u64; 9]), usize> = BTreeMap::new();
    let mut materials = Vec::new();
    for (c, cell) in mesh.cells.iter_mut().enumerate() {
        let r = model.orientations.get(c).copied().unwrap_or([
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ]);
        let bits: Vec<u64> = r.iter().flatten().map(|v| v.to_bits()).collect();
        let key = (cell.material, bits.try_into().unwrap_or([0; 9]));
        let id = match index.get(&key) {
            Some(&id) => id,
            None => {
                materials.push(base[cell.material].rotated(&r)?);
                index.insert(key, materials.len() - 1);
                materials.len() - 1
            }
        };
        cell.material = id;
        cell.ply_angle_deg = 0.0;
    }
    Ok((mesh, materials))
}

/// The integration rule of Hex20 cells: 2×2×2 for C3D20R, 3×3×3 for C3D20.
fn hex20_rule(model: &InpModel) -> Result<IntegrationRule, Error> {
    let hex20: Vec<bool> = model
        .mesh
        .cells
        .iter()
        .zip(&model.reduced)
        .filter(|(c, _)| c.kind == ElementKind::Hex20)
        .map(|(_, &r)| r)
        .collect();
    if hex20.iter().any(|&r| r) && hex20.iter().any(|&r| !r) {
        return Err(Error::Numerical(
            "the deck mixes C3D20 and C3D20R; nonlin3d uses one rule per element kind".into(),
        ));
    }
    Ok(if hex20.first().copied().unwrap_or(false) {
        IntegrationRule::Gauss2
    } else {
        IntegrationRule::Gauss3
    })
}

/// Solves every step of `model` in order.
pub fn solve_deck(model: &InpModel, options: &StepOptions) -> Result<Vec<StepResult>, Error> {
    crate::budget::check_deck(&model.mesh, &crate::budget::limit())?;
    let (mesh, materials) = oriented(model)?;
    let rule = hex20_rule(model)?;
    let n = 3 * mesh.nodes.len();
    let mut u = vec![0.0; n];
    let mut history = loads::History::new(model);
    let mut results = Vec::new();
    let mut assemblers: BTreeMap<bool, Assembler> = BTreeMap::new();
    let mut start = 0.0;
    for (k, step) in model.steps.iter().enumerate() {
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
        let mut problem = StructuralProblem::new(assembler, Constraints::new(n))?;
        let rules = StressRules {
            materials: &materials,
            coupling: ShearCoupling::Exact,
            hex20_rule: rule,
            hex8_rule: IntegrationRule::Gauss2,
            kinematics,
        };
        let mut tables = output::tables(model, step);
        let increments = drive::run_step(
            model,
            k,
            &history,
            frame,
            &mut problem,
            &mut u,
            options,
            &mut |c| output::record(model, &mesh, &rules, step, frame, &mut tables, c),
        )?;
        history.end_step(model, frame);
        results.push(StepResult {
            step: k + 1,
            nlgeom: step.nlgeom,
            period: frame.period,
            start_time: start,
            increments,
            displacements: u.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
            outputs: tables,
        });
        assemblers.insert(step.nlgeom, problem.assembler);
        start += frame.period;
    }
    Ok(results)
}
