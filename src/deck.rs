//! Solving an Abaqus/CalculiX deck (the subset `nonlin3d_mesh::read_inp` reads): linear or
//! NLGEOM static steps with `*BOUNDARY` and `*CLOAD`, as the `nonlin3d solve` command does.
//!
//! Step semantics follow Abaqus/CalculiX: within a step, boundary values and loads ramp
//! linearly from their values at the end of the previous step to the step's values; a value
//! listed in a step replaces the earlier one for that DOF, and everything not listed keeps its
//! value. Model-data `*BOUNDARY` lines hold from the start. C3D20 cells are integrated with
//! 3×3×3 points, C3D20R and C3D8 with 2×2×2 (a deck mixing C3D20 and C3D20R is refused).
//! NLGEOM steps use the nonlinear kernels and Newton path following; other steps the linear
//! kernels (one Newton iteration then solves them exactly).

use crate::Error;
use nonlin3d_assembly::{Assembler, Constraints};
use nonlin3d_element::{ElementKind, IntegrationRule, Kinematics};
use nonlin3d_laminate::{Orthotropic, ShearCoupling, Stiffness};
use nonlin3d_mesh::inp::InpElastic;
use nonlin3d_mesh::{InpModel, NodeRef};
use nonlin3d_newton::{NewtonSettings, Stepping, StructuralProblem, follow_path};
use serde::Serialize;
use std::collections::BTreeMap;

/// The record of one increment of a step, for the JSON summary.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct IncrementSummary {
    /// Load factor within the step (1 = end of step).
    pub lambda: f64,
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

/// One solved step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StepResult {
    /// Step number, 1-based.
    pub step: usize,
    /// NLGEOM.
    pub nlgeom: bool,
    /// Increments (all attempts).
    pub increments: Vec<IncrementSummary>,
    /// Displacements at the end of the step, by mesh node (deck ids in `InpModel::node_ids`).
    #[serde(skip)]
    pub displacements: Vec<[f64; 3]>,
}

/// The stiffness of a deck material.
fn stiffness(e: &InpElastic) -> Result<Stiffness, Error> {
    Ok(match e {
        InpElastic::Isotropic { e, nu } => Orthotropic::isotropic(*e, *nu).stiffness()?,
        InpElastic::Engineering(o) => o.stiffness()?,
        InpElastic::Orthotropic(s) | InpElastic::Anisotropic(s) => **s,
    })
}

/// Mesh-node indices a boundary or load refers to.
fn nodes_of(model: &InpModel, target: &NodeRef) -> Vec<usize> {
    match target {
        NodeRef::Node(n) => vec![*n],
        NodeRef::Set(name) => model.mesh.node_sets.get(name).cloned().unwrap_or_default(),
    }
}

/// Solves every step of `model` in order.
pub fn solve_deck(
    model: &InpModel,
    settings: &NewtonSettings,
    stepping: &Stepping,
) -> Result<Vec<StepResult>, Error> {
    let materials: Vec<Stiffness> = model
        .materials
        .iter()
        .map(|m| stiffness(&m.elastic))
        .collect::<Result<_, _>>()?;
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
    let hex20_rule = if hex20.first().copied().unwrap_or(false) {
        IntegrationRule::Gauss2
    } else {
        IntegrationRule::Gauss3
    };
    let n = 3 * model.mesh.nodes.len();
    let mut u = vec![0.0; n];
    // Current values of prescribed DOFs and loads (persisting across steps).
    let mut bc: BTreeMap<usize, f64> = BTreeMap::new();
    for b in &model.initial_boundaries {
        for node in nodes_of(model, &b.target) {
            for dof in b.first..=b.last {
                bc.insert(3 * node + dof as usize - 1, b.value);
            }
        }
    }
    let mut loads: BTreeMap<usize, f64> = BTreeMap::new();
    let mut results = Vec::new();
    let mut assemblers: BTreeMap<bool, Assembler> = BTreeMap::new();
    for (k, step) in model.steps.iter().enumerate() {
        let mut new_bc = bc.clone();
        for b in &step.boundaries {
            for node in nodes_of(model, &b.target) {
                for dof in b.first..=b.last {
                    new_bc.insert(3 * node + dof as usize - 1, b.value);
                }
            }
        }
        let mut new_loads = loads.clone();
        for l in &step.cloads {
            for node in nodes_of(model, &l.target) {
                new_loads.insert(3 * node + l.dof as usize - 1, l.value);
            }
        }
        let assembler = match assemblers.remove(&step.nlgeom) {
            Some(a) => a,
            None => {
                let kin = if step.nlgeom {
                    Kinematics::Nonlinear
                } else {
                    Kinematics::Linear
                };
                Assembler::new(
                    &model.mesh,
                    &materials,
                    ShearCoupling::Exact,
                    hex20_rule,
                    IntegrationRule::Gauss2,
                    kin,
                )?
            }
        };
        let mut c = Constraints::new(n);
        for (&d, &to) in &new_bc {
            // A DOF constrained for the first time starts from where it is.
            let from = bc.get(&d).copied().unwrap_or(u[d]);
            c.prescribe_ramp(d, from, to)?;
        }
        // Every DOF loaded before or now, once.
        let loaded: std::collections::BTreeSet<usize> =
            new_loads.keys().chain(loads.keys()).copied().collect();
        for d in loaded {
            let (from, to) = (
                loads.get(&d).copied().unwrap_or(0.0),
                new_loads.get(&d).copied().unwrap_or(0.0),
            );
            c.set_dead_load(d, from)?;
            if to != from {
                c.add_load(d, to - from)?;
            }
        }
        let mut problem = StructuralProblem::new(assembler, c)?;
        let path = follow_path(&mut problem, &mut u, &[1.0], settings, stepping)?;
        let increments = path
            .attempts
            .iter()
            .map(|a| IncrementSummary {
                lambda: a.lambda,
                iterations: a.iterations.len(),
                residuals: std::iter::once(a.initial_residual)
                    .chain(a.iterations.iter().map(|i| i.residual))
                    .collect(),
                converged: a.converged(),
                termination: format!("{:?}", a.termination),
                negative_pivots: a.negative_pivots(),
            })
            .collect();
        results.push(StepResult {
            step: k + 1,
            nlgeom: step.nlgeom,
            increments,
            displacements: u.chunks(3).map(|c| [c[0], c[1], c[2]]).collect(),
        });
        assemblers.insert(step.nlgeom, problem.assembler);
        bc = new_bc;
        loads = new_loads;
    }
    Ok(results)
}

/// Writes `displacements.csv` (deck node id, ux, uy, uz) for each step into `dir/step-K/`, the
/// last step's also into `dir/`, and `dir/summary.json` (steps, increments, iterations,
/// residuals, convergence, negative pivots).
pub fn write_results(
    dir: &std::path::Path,
    model: &InpModel,
    results: &[StepResult],
) -> Result<(), Error> {
    let io =
        |e: std::io::Error| Error::Numerical(format!("writing results to {}: {e}", dir.display()));
    std::fs::create_dir_all(dir).map_err(io)?;
    let csv = |r: &StepResult| {
        let mut s = String::from("node,ux,uy,uz\n");
        for (id, d) in model.node_ids.iter().zip(&r.displacements) {
            s.push_str(&format!("{id},{:e},{:e},{:e}\n", d[0], d[1], d[2]));
        }
        s
    };
    for r in results {
        let sub = dir.join(format!("step-{}", r.step));
        std::fs::create_dir_all(&sub).map_err(io)?;
        std::fs::write(sub.join("displacements.csv"), csv(r)).map_err(io)?;
    }
    if let Some(last) = results.last() {
        std::fs::write(dir.join("displacements.csv"), csv(last)).map_err(io)?;
    }
    let json = serde_json::to_string_pretty(&serde_json::json!({ "steps": results }))
        .map_err(|e| Error::Numerical(e.to_string()))?;
    std::fs::write(dir.join("summary.json"), json).map_err(io)?;
    Ok(())
}
