//! Output requests of a deck: `*NODE PRINT` / `*NODE FILE` (U, RF) and `*EL PRINT` / `*EL FILE`
//! (S) at every increment CalculiX would write them (every `FREQUENCY`-th increment of a step
//! and its last), as CSV tables, and the files `nonlin3d solve` writes.
//!
//! - Node tables: `increment, step_time, total_time, node`, then `ux, uy, uz` and/or
//!   `rfx, rfy, rfz` in the order listed. RF is CalculiX's: the internal nodal force (the
//!   reaction at constrained DOFs, the applied load at loaded free ones, ≈ 0 elsewhere).
//!   `TOTALS=YES|ONLY` adds (or gives only) `…-totals.csv` with the sums over the set.
//! - Element tables: `increment, step_time, total_time, element, point, sxx, syy, szz, sxy,
//!   sxz, syz` (CalculiX's order) at the integration points in CalculiX's numbering. Cauchy
//!   stresses in NLGEOM steps (σ = C ε in linear ones), in each element's material axes for
//!   `*EL PRINT` (CalculiX's default; global with `GLOBAL=YES`), global for `*EL FILE`.
//!   CalculiX's .frd holds `*EL FILE` stresses extrapolated to the nodes; nonlin3d writes the
//!   integration-point values.

use super::StepResult;
use super::drive::Converged;
use super::loads::Frame;
use crate::Error;
use nonlin3d_assembly::{StressRules, station_stresses};
use nonlin3d_element::{ElementKind, Material};
use nonlin3d_mesh::{InpModel, Mesh, OutputKind, OutputVariable, ReadStep, Totals};
use std::fmt::Write as _;
use std::path::Path;

/// One output request of a step, filled increment by increment.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputTable {
    /// The keyword, e.g. `*NODE PRINT`.
    pub keyword: String,
    /// Deck line of the request.
    pub line: usize,
    /// File name within `step-K/`.
    pub file: String,
    /// CSV text (header and rows).
    pub csv: String,
    /// Increments written.
    pub increments: Vec<usize>,
    /// Axes of element variables: "material" or "global" (empty for node variables).
    pub axes: &'static str,
    request: usize,
    totals_only: bool,
}

fn keyword(kind: OutputKind) -> &'static str {
    match kind {
        OutputKind::NodePrint => "*NODE PRINT",
        OutputKind::NodeFile => "*NODE FILE",
        OutputKind::ElPrint => "*EL PRINT",
        OutputKind::ElFile => "*EL FILE",
    }
}

/// Empty tables for the requests in force in `step`.
pub(crate) fn tables(_model: &InpModel, step: &ReadStep) -> Vec<OutputTable> {
    let mut out: Vec<OutputTable> = Vec::new();
    for (i, o) in step.outputs.iter().enumerate() {
        let stem = match o.kind {
            OutputKind::NodePrint => "node-print",
            OutputKind::NodeFile => "node-file",
            OutputKind::ElPrint => "el-print",
            OutputKind::ElFile => "el-file",
        };
        let base = match &o.set {
            Some(s) => format!("{stem}-{s}"),
            None => stem.to_string(),
        };
        let mut name = base.clone();
        let mut k = 2;
        while out.iter().any(|t| t.file.starts_with(&format!("{name}."))) {
            name = format!("{base}-{k}");
            k += 1;
        }
        let element = matches!(o.kind, OutputKind::ElPrint | OutputKind::ElFile);
        let mut header = String::from("increment,step_time,total_time,");
        if element {
            header.push_str("element,point,sxx,syy,szz,sxy,sxz,syz");
        } else {
            header.push_str("node");
            for v in &o.variables {
                header.push_str(match v {
                    OutputVariable::U => ",ux,uy,uz",
                    _ => ",rfx,rfy,rfz",
                });
            }
        }
        let table = |file: String, csv: String, totals_only: bool| OutputTable {
            keyword: keyword(o.kind).into(),
            line: o.line,
            file,
            csv,
            increments: Vec::new(),
            axes: match (element, o.local_axes) {
                (false, _) => "",
                (true, true) => "material",
                (true, false) => "global",
            },
            request: i,
            totals_only,
        };
        if o.totals != Totals::Only {
            out.push(table(format!("{name}.csv"), format!("{header}\n"), false));
        }
        if o.totals != Totals::No {
            out.push(table(
                format!("{name}-totals.csv"),
                "increment,step_time,total_time,rfx,rfy,rfz\n".into(),
                true,
            ));
        }
    }
    out
}

/// σ in the axes `r` (columns: local axes in global coordinates): Rᵀ σ R; Voigt xx, yy, zz,
/// xy, yz, xz in and out.
fn to_local(s: &[f64; 6], r: &[[f64; 3]; 3]) -> [f64; 6] {
    let t = [[s[0], s[3], s[5]], [s[3], s[1], s[4]], [s[5], s[4], s[2]]];
    let mut l = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            for a in 0..3 {
                for b in 0..3 {
                    l[i][j] += r[a][i] * t[a][b] * r[b][j];
                }
            }
        }
    }
    [l[0][0], l[1][1], l[2][2], l[0][1], l[1][2], l[0][2]]
}

/// The material axes of `cell` at each integration point of its rule (columns: local axes in
/// global coordinates): the same at every point for a rectangular orientation; for a
/// cylindrical one, the axes at the point's position x = Σ_m N^m(ξ) x^m in the undeformed
/// configuration, where CalculiX evaluates them too.
fn material_axes(
    model: &InpModel,
    mesh: &Mesh,
    rules: &StressRules<'_, Material>,
    cell: usize,
) -> Vec<[[f64; 3]; 3]> {
    let Some(axes) = model.cylindrical.get(cell).copied().flatten() else {
        return vec![model.orientations[cell]];
    };
    let kind = mesh.cells[cell].kind;
    let rule = match kind {
        ElementKind::Hex20 => rules.hex20_rule,
        ElementKind::Hex8 => rules.hex8_rule,
    };
    let x = mesh.cell_coordinates(cell);
    let mut n = vec![0.0; kind.nodes()];
    rule.stations()
        .iter()
        .map(|st| {
            kind.shape_values(st.xi, &mut n);
            let mut p = [0.0; 3];
            for (nm, xm) in n.iter().zip(&x) {
                for r in 0..3 {
                    p[r] += nm * xm[r];
                }
            }
            axes.axes_at(p)
        })
        .collect()
}

/// Appends the converged increment `c` to the tables that are due.
pub(crate) fn record(
    model: &InpModel,
    mesh: &Mesh,
    rules: &StressRules<'_, Material>,
    step: &ReadStep,
    frame: Frame,
    tables: &mut [OutputTable],
    c: Converged<'_>,
) -> Result<(), Error> {
    if !(c.last || c.increment.is_multiple_of(step.output_frequency.max(1))) {
        return Ok(());
    }
    let wants_rf = tables.iter().any(|t| {
        step.outputs[t.request]
            .variables
            .contains(&OutputVariable::Rf)
    });
    let rf = if wants_rf {
        Some(c.problem.assembler().assemble(c.u, None)?.internal)
    } else {
        None
    };
    let time = format!(
        "{},{:e},{:e}",
        c.increment,
        c.step_time,
        frame.start + c.step_time
    );
    for t in tables.iter_mut() {
        let o = &step.outputs[t.request];
        t.increments.push(c.increment);
        let nodes: Vec<usize> = match &o.set {
            Some(s) if matches!(o.kind, OutputKind::NodePrint | OutputKind::NodeFile) => {
                mesh.node_sets.get(s).cloned().unwrap_or_default()
            }
            Some(s) => mesh.cell_sets.get(s).cloned().unwrap_or_default(),
            None if matches!(o.kind, OutputKind::NodePrint | OutputKind::NodeFile) => {
                (0..mesh.nodes.len()).collect()
            }
            None => (0..mesh.cells.len()).collect(),
        };
        match o.kind {
            OutputKind::NodePrint | OutputKind::NodeFile => {
                let mut sum = [0.0; 3];
                for &n in &nodes {
                    let mut row = format!("{time},{}", model.node_ids[n]);
                    for v in &o.variables {
                        let src = match v {
                            OutputVariable::U => c.u,
                            _ => rf.as_deref().unwrap_or(&[]),
                        };
                        for r in 0..3 {
                            let x = src.get(3 * n + r).copied().unwrap_or(f64::NAN);
                            let _ = write!(row, ",{x:e}");
                            if *v == OutputVariable::Rf {
                                sum[r] += x;
                            }
                        }
                    }
                    if !t.totals_only {
                        t.csv.push_str(&row);
                        t.csv.push('\n');
                    }
                }
                if t.totals_only {
                    let _ = writeln!(t.csv, "{time},{:e},{:e},{:e}", sum[0], sum[1], sum[2]);
                }
            }
            OutputKind::ElPrint | OutputKind::ElFile => {
                let stresses = station_stresses(mesh, rules, c.u, &nodes)?;
                for (&cell, points) in nodes.iter().zip(&stresses) {
                    let axes = (o.local_axes && model.orientation_names[cell].is_some())
                        .then(|| material_axes(model, mesh, rules, cell));
                    for (g, s) in points.iter().enumerate() {
                        let s = match &axes {
                            Some(r) => to_local(s, &r[g.min(r.len() - 1)]),
                            None => *s,
                        };
                        let _ = writeln!(
                            t.csv,
                            "{time},{},{},{:e},{:e},{:e},{:e},{:e},{:e}",
                            model.element_ids[cell],
                            g + 1,
                            s[0],
                            s[1],
                            s[2],
                            s[3],
                            s[5],
                            s[4]
                        );
                    }
                }
            }
        }
    }
    Ok(())
}

/// Writes the results of a whole solve as `nonlin3d solve` does ([`DeckOutput`](super::DeckOutput),
/// which writes them increment by increment): for each step K `dir/step-K/displacements.csv`
/// (deck node id, ux, uy, uz at the end of the step) and the step's output tables
/// (`dir/step-K/node-print-SET.csv`, …); the last step's displacements also as
/// `dir/displacements.csv`; and `dir/summary.json`: `complete`, `stopped`, steps (increments
/// with step and total time, iterations, residuals, convergence, negative pivots; the output
/// files with the increments written) and `not_used`, what the deck gave that the analysis did
/// not use, with its line.
pub fn write_results(dir: &Path, model: &InpModel, results: &[StepResult]) -> Result<(), Error> {
    let mut out = super::DeckOutput::create(dir, model)?;
    for r in results {
        out.progress(super::Progress::Step(r))?;
    }
    out.finish(results)
}
