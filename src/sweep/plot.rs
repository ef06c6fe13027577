//! `study.svg`: three panels against the swept parameter `x` — G_T max at the last level,
//! |critical strain| of the growth criterion, |buckling strain| (the first value found
//! unstable) — one series per combination of the values of the swept parameters that do not
//! vary with `x` (its `zip` group does). An `x` whose
//! values are not numbers (layups) is plotted at its values' positions 0, 1, 2, …

use super::plan::Plan;
use super::row::Row;
use crate::Error;
use crate::plot::{plot_err, series_legend};
use plotters::prelude::*;
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::Path;

/// The panels: title, y label, the quantity.
type Panel = (&'static str, &'static str, fn(&Row) -> Option<f64>);

const PANELS: [Panel; 3] = [
    ("largest G_T at the last level", "G_T max (J/m²)", |r| {
        r.g_t_max
    }),
    ("onset of growth (criterion)", "|critical strain|", |r| {
        r.critical_strain.map(f64::abs)
    }),
    (
        "buckling (first unstable value)",
        "|buckling strain|",
        |r| r.buckling_to.map(f64::abs),
    ),
];

/// Writes the study plot of `rows` to `path`.
pub fn study(plan: &Plan, rows: &[Row], path: &Path) -> Result<(), Error> {
    // x of each row: its value, or the value's position in the order met when not a number.
    let mut seen: Vec<Value> = Vec::new();
    let numeric = rows
        .iter()
        .all(|r| r.parameters.get(&plan.x).is_some_and(Value::is_number));
    let x_of = |r: &Row, seen: &mut Vec<Value>| -> f64 {
        let v = r.parameters.get(&plan.x).cloned().unwrap_or(Value::Null);
        if numeric {
            return v.as_f64().unwrap_or(0.0);
        }
        match seen.iter().position(|s| *s == v) {
            Some(k) => k as f64,
            None => {
                seen.push(v);
                (seen.len() - 1) as f64
            }
        }
    };
    // Series: the values of the parameters that do not vary with x (x's zip group does).
    let with_x: Vec<&String> = plan
        .zip
        .iter()
        .find(|g| g.contains(&plan.x))
        .map_or_else(|| vec![&plan.x], |g| g.iter().collect());
    let mut series: BTreeMap<String, Vec<(f64, &Row)>> = BTreeMap::new();
    for r in rows {
        let key = r
            .parameters
            .iter()
            .filter(|(k, _)| !with_x.contains(k))
            .map(|(k, v)| format!("{} = {v}", k.rsplit('.').next().unwrap_or(k)))
            .collect::<Vec<_>>()
            .join(", ");
        let x = x_of(r, &mut seen);
        series.entry(key).or_default().push((x, r));
    }
    let xs: Vec<f64> = series.values().flatten().map(|p| p.0).collect();
    let x_lo = xs.iter().copied().fold(f64::MAX, f64::min).min(0.0);
    let x_hi = xs
        .iter()
        .copied()
        .fold(f64::MIN, f64::max)
        .max(x_lo + 1e-12);
    let pad = 0.05 * (x_hi - x_lo);
    let root = SVGBackend::new(path, (720, 960)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let panels = root.split_evenly((3, 1));
    let x_desc = if numeric {
        plan.x.clone()
    } else {
        format!("{} (position in its list)", plan.x)
    };
    for (area, (caption, y_desc, value)) in panels.iter().zip(PANELS) {
        let ys: Vec<f64> = rows
            .iter()
            .filter_map(value)
            .filter(|y| y.is_finite())
            .collect();
        let y_hi = ys.iter().copied().fold(0.0, f64::max).max(1e-12) * 1.08;
        let mut chart = ChartBuilder::on(area)
            .caption(format!("{caption} — {}", plan.title), ("sans-serif", 14))
            .margin(10)
            .x_label_area_size(36)
            .y_label_area_size(64)
            .build_cartesian_2d(x_lo - pad..x_hi + pad, 0.0..y_hi)
            .map_err(|e| plot_err(path, e))?;
        chart
            .configure_mesh()
            .x_desc(x_desc.as_str())
            .y_desc(y_desc)
            .draw()
            .map_err(|e| plot_err(path, e))?;
        for (k, (label, points)) in series.iter().enumerate() {
            let colour = Palette99::pick(k).to_rgba();
            let pts: Vec<(f64, f64)> = points
                .iter()
                .filter_map(|(x, r)| value(r).filter(|y| y.is_finite()).map(|y| (*x, y)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), colour.stroke_width(2)))
                .map_err(|e| plot_err(path, e))?;
            let drawn = chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
                .map_err(|e| plot_err(path, e))?;
            if !label.is_empty() {
                drawn
                    .label(label.clone())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
            }
        }
        if series.keys().any(|k| !k.is_empty()) {
            // Upper left: x starts at 0, the data sit to the right.
            series_legend(&mut chart, SeriesLabelPosition::UpperLeft)
                .draw()
                .map_err(|e| plot_err(path, e))?;
        }
    }
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}
