//! `nonlin3d sweep merge`: one row per case from its results.json, whatever is complete, into
//! `study.csv`, `study.json` and `study.svg` (G_T max, critical strain and buckling strain
//! against the swept parameter `x`, one series per combination of the other parameters).
//! Every number is read back from the cases' results.json and printed the same way, so the
//! tables do not depend on how (or in how many workers, or on which machines) the cases ran;
//! the one thing that does, each case's wall time, goes to `study-wall.csv` alone.

use super::plan::Plan;
use super::row::Row;
use super::run::{CaseState, case_state};
use crate::Error;
use crate::output::write_atomic;
use crate::report::Csv;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The row of case `id` in state `state` from its results.json `v`.
fn row(id: usize, parameters: BTreeMap<String, Value>, state: &CaseState, v: &Value) -> Row {
    let mut r = Row {
        case: id,
        status: state.name().into(),
        parameters,
        strain: None,
        g_t_max: None,
        g_t_max_s_mm: None,
        g_i_s0: None,
        g_ii_s0: None,
        faces_s0: None,
        buckling_from: None,
        buckling_to: None,
        critical_strain: None,
        critical_s_mm: None,
        wall_s: None,
        error: state.error().map(str::to_string),
    };
    if *state != CaseState::Complete {
        return r;
    }
    let levels = v["levels"].as_array().map_or(&[][..], Vec::as_slice);
    if let Some(last) = levels.last() {
        r.strain = last["value"].as_f64();
        let front = last["front"].as_array().map_or(&[][..], Vec::as_slice);
        let peak = front
            .iter()
            .filter(|p| p["faces"].as_str() != Some("overlapped"))
            .filter_map(|p| Some((p["g_t"].as_f64()?, p["s_mm"].as_f64()?)))
            .max_by(|a, b| a.0.total_cmp(&b.0));
        (r.g_t_max, r.g_t_max_s_mm) = (peak.map(|p| p.0), peak.map(|p| p.1));
        if let Some(p0) = front.iter().find(|p| p["s_mm"].as_f64() == Some(0.0)) {
            r.g_i_s0 = p0["g_i"].as_f64();
            r.g_ii_s0 = p0["g_ii"].as_f64();
            r.faces_s0 = p0["faces"].as_str().map(str::to_string);
        }
    }
    let crossing = levels
        .iter()
        .find_map(|l| l["convergence"]["bifurcation"].as_object());
    if let Some(c) = crossing {
        r.buckling_from = c.get("from").and_then(Value::as_f64);
        r.buckling_to = c.get("to").and_then(Value::as_f64);
    } else if let Some(at) = v["model"]["perturbed_at"].as_f64() {
        let k = levels.iter().position(|l| l["value"].as_f64() == Some(at));
        r.buckling_from = Some(
            k.and_then(|k| k.checked_sub(1))
                .map_or(0.0, |j| levels[j]["value"].as_f64().unwrap_or(0.0)),
        );
        r.buckling_to = Some(at);
    }
    r.critical_strain = v["critical"]["strain"].as_f64();
    r.critical_s_mm = v["critical"]["s_mm"].as_f64();
    r.wall_s = v["provenance"]["wall_s"]["total"].as_f64();
    r
}

/// The study table of `dir`: one row per case of its plan.
pub fn rows(dir: &Path) -> Result<(Plan, Vec<Row>), Error> {
    let plan = Plan::read(dir)?;
    let rows = plan
        .cases
        .iter()
        .map(|c| {
            let folder = plan.case_dir(dir, c);
            let state = case_state(&folder);
            let v = std::fs::read_to_string(folder.join("results.json"))
                .ok()
                .and_then(|t| serde_json::from_str(&t).ok())
                .unwrap_or(Value::Null);
            row(c.id, c.parameters.clone(), &state, &v)
        })
        .collect();
    Ok((plan, rows))
}

/// A parameter as a cell: strings bare, numbers and lists as JSON.
fn parameter(v: Option<&Value>) -> String {
    match v {
        Some(Value::String(s)) => s.clone(),
        Some(v) => v.to_string(),
        None => String::new(),
    }
}

/// `study.csv`: a header, then one line per case (quoted by the csv crate where a cell needs
/// it). No wall time: the table is the same byte for byte however the cases ran.
pub fn csv(plan: &Plan, rows: &[Row]) -> String {
    let num = |x: Option<f64>| x.map(|x| x.to_string()).unwrap_or_default();
    let mut header = vec!["case", "status"];
    header.extend(plan.fields.iter().map(String::as_str));
    header.extend([
        "strain",
        "g_t_max",
        "g_t_max_s_mm",
        "g_i_s0",
        "g_ii_s0",
        "faces_s0",
        "buckling_from",
        "buckling_to",
        "critical_strain",
        "critical_s_mm",
        "error",
    ]);
    let mut t = Csv::new(&header);
    for r in rows {
        let mut cells = vec![r.case.to_string(), r.status.clone()];
        cells.extend(plan.fields.iter().map(|f| parameter(r.parameters.get(f))));
        cells.extend([
            num(r.strain),
            num(r.g_t_max),
            num(r.g_t_max_s_mm),
            num(r.g_i_s0),
            num(r.g_ii_s0),
            r.faces_s0.clone().unwrap_or_default(),
            num(r.buckling_from),
            num(r.buckling_to),
            num(r.critical_strain),
            num(r.critical_s_mm),
            r.error.clone().unwrap_or_default(),
        ]);
        t.row(cells);
    }
    t.finish()
}

/// `study-wall.csv`: each case's wall time, s (what differs between runs of one study).
pub fn wall_csv(rows: &[Row]) -> String {
    let mut t = Csv::new(&["case", "status", "wall_s"]);
    for r in rows {
        t.row([
            r.case.to_string(),
            r.status.clone(),
            r.wall_s.map(|x| x.to_string()).unwrap_or_default(),
        ]);
    }
    t.finish()
}

/// What [`merge`] wrote.
#[derive(Debug, Clone, PartialEq)]
pub struct Merged {
    /// Cases by state name.
    pub counts: BTreeMap<&'static str, usize>,
    /// The rows.
    pub rows: Vec<Row>,
}

/// Writes `study.csv`, `study.json`, `study.svg` and `study-wall.csv` in `dir` from whatever cases are complete
/// (failed ones with their errors).
pub fn merge(dir: &Path) -> Result<Merged, Error> {
    let (plan, rows) = rows(dir)?;
    write_atomic(&dir.join("study.csv"), csv(&plan, &rows).as_bytes())?;
    write_atomic(&dir.join("study-wall.csv"), wall_csv(&rows).as_bytes())?;
    let json = serde_json::json!({
        "title": plan.title,
        "fields": plan.fields,
        "zip": plan.zip,
        "x": plan.x,
        "units": "G in J/m², S in mm, strains as applied (compression negative); G at each \
                  case's last level (wall times in study-wall.csv)",
        "cases": rows,
    });
    write_atomic(
        &dir.join("study.json"),
        serde_json::to_string_pretty(&json)?.as_bytes(),
    )?;
    let path = dir.join("study.svg");
    crate::output::atomically(&path, |tmp| super::plot::study(&plan, &rows, tmp))?;
    let mut counts = BTreeMap::new();
    for r in &rows {
        let name = match r.status.as_str() {
            "complete" => "complete",
            "failed" => "failed",
            "incomplete" => "incomplete",
            _ => "missing",
        };
        *counts.entry(name).or_insert(0) += 1;
    }
    Ok(Merged { counts, rows })
}
