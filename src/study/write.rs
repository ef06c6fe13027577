//! A study's outputs: `study.json`, `study.csv`, `study.svg` (the Pareto plot) and the
//! terminal table.

use super::{CaseResult, G_QUANTITIES, QUANTITIES, Study};
use crate::Error;
use crate::plot::{series_legend, svg_file, text};
use crate::report::Csv;
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::Path;

/// Writes `study.json`, `study.csv` and `study.svg` into `dir` (made if absent).
pub fn write_all(study: &Study, dir: &Path) -> Result<(), Error> {
    std::fs::create_dir_all(dir).map_err(|source| Error::Io {
        path: dir.to_path_buf(),
        source,
    })?;
    let json = serde_json::to_string_pretty(study).map_err(|e| Error::Io {
        path: dir.join("study.json"),
        source: std::io::Error::other(e),
    })?;
    crate::atomic::write_atomic(&dir.join("study.json"), json.as_bytes())?;
    crate::atomic::write_atomic(&dir.join("study.csv"), csv(study).as_bytes())?;
    svg(study, &dir.join("study.svg"))
}

fn opt(x: Option<f64>) -> String {
    x.map(|v| format!("{v:.8e}")).unwrap_or_default()
}

/// One row per case: name, family, h, DOFs, times, the quantities, their relative errors, the
/// worst G error, whether on the Pareto front, why it failed, the knobs (RFC 4180 quoting).
pub fn csv(study: &Study) -> String {
    let errors: Vec<String> = QUANTITIES
        .iter()
        .map(|(name, _)| format!("error_{name}"))
        .collect();
    let mut header = vec![
        "case",
        "family",
        "h",
        "dofs",
        "wall_s",
        "cpu_s",
        "iterations",
    ];
    header.extend(QUANTITIES.iter().map(|(name, _)| *name));
    header.extend(errors.iter().map(String::as_str));
    header.extend(["worst_g_error", "pareto", "failed", "knobs"]);
    let mut t = Csv::new(&header);
    for c in &study.cases {
        let mut row = vec![
            c.name.clone(),
            c.family.to_string(),
            opt(c.h),
            c.dofs.to_string(),
            format!("{:.4}", c.wall_s),
            c.cpu_s.map(|t| format!("{t:.4}")).unwrap_or_default(),
            c.iterations.to_string(),
        ];
        row.extend(
            c.values
                .values()
                .into_iter()
                .chain(c.errors.values())
                .map(opt),
        );
        row.extend([
            opt(c.worst_g_error),
            c.pareto.to_string(),
            c.failed.clone().unwrap_or_default(),
            c.knobs.clone(),
        ]);
        t.row(row);
    }
    t.finish()
}

/// The labels of the quantities the worst G error is taken over.
fn worst_labels(study: &Study) -> String {
    let labels: Vec<&str> = QUANTITIES
        .iter()
        .filter(|(n, _)| study.worst_over.contains(n))
        .map(|(_, l)| *l)
        .collect();
    labels.join(", ")
}

fn percent(x: Option<f64>) -> String {
    x.map(|e| format!("{:+.1}%", 100.0 * e))
        .unwrap_or_else(|| "—".into())
}

/// The terminal table: a row per case (values and relative errors), then the references and
/// what is known of their convergence.
pub fn table(study: &Study) -> String {
    let mut out = format!("{}\n", study.title);
    let _ = write!(
        out,
        "{:<18} {:>7} {:>7} {:>7}",
        "case", "DOF", "wall s", "CPU s"
    );
    for (_, label) in QUANTITIES {
        let _ = write!(out, " {label:>16}");
    }
    out.push_str("   worst G  front\n");
    for c in &study.cases {
        let _ = write!(
            out,
            "{:<18} {:>7} {:>7.2} {:>7}",
            c.name,
            c.dofs,
            c.wall_s,
            c.cpu_s
                .map(|t| format!("{t:.2}"))
                .unwrap_or_else(|| "—".into())
        );
        if let Some(f) = &c.failed {
            let _ = writeln!(out, "  failed: {f}");
            continue;
        }
        for (i, (v, e)) in c.values.values().iter().zip(c.errors.values()).enumerate() {
            let value = match v {
                Some(v) if i < G_QUANTITIES => format!("{v:.2}"),
                Some(v) => format!("{v:.5}"),
                None => "—".into(),
            };
            let _ = write!(out, " {:>16}", format!("{value} {}", percent(e)));
        }
        let _ = writeln!(
            out,
            " {:>9}  {}",
            percent(c.worst_g_error).trim_start_matches('+'),
            if c.pareto { "*" } else { "" }
        );
    }
    let _ = writeln!(
        out,
        "references (family of {} meshes, h = {}):",
        study
            .cases
            .iter()
            .filter(|c| c.family && c.failed.is_none())
            .count(),
        study.family_size
    );
    for (r, (_, label)) in study.references.iter().zip(QUANTITIES) {
        let Some(f) = &r.fit else {
            let _ = writeln!(out, "  {label:<10} none");
            continue;
        };
        let orders: Vec<String> = f
            .orders
            .iter()
            .map(|p| p.map_or("—".into(), |p| format!("{p:.2}")))
            .collect();
        let _ = writeln!(
            out,
            "  {label:<10} {:.6} ({}{}){}",
            f.reference,
            f.method,
            if orders.is_empty() {
                String::new()
            } else {
                format!(", observed orders {}", orders.join(", "))
            },
            match &f.note {
                Some(n) => format!(" — not asymptotic: {n}"),
                None => String::new(),
            }
        );
    }
    let _ = writeln!(
        out,
        "worst G: the largest |error| of {}",
        worst_labels(study)
    );
    out.push_str("* on the Pareto front: no other case is both faster (CPU) and more accurate\n");
    out
}

/// `v` with three significant digits and no trailing zeros (axis labels).
fn significant(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let digits = (2 - v.abs().log10().floor() as i32).max(0) as usize;
    let text = format!("{v:.digits$}");
    if text.contains('.') {
        text.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        text
    }
}

/// The Pareto plot: CPU seconds (log) against the worst |relative error| of the G quantities
/// in %, each case a hollow circle named beside it (the family's filled grey), the front
/// red and joined by its staircase.
pub fn svg(study: &Study, path: &Path) -> Result<(), Error> {
    let pts: Vec<(&CaseResult, f64, f64)> = study
        .cases
        .iter()
        .filter_map(|c| {
            let e = 100.0 * c.worst_g_error?;
            Some((c, c.cpu_s.unwrap_or(c.wall_s), e))
        })
        .collect();
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v
            .filter(|x| x.is_finite() && *x > 0.0)
            .fold((f64::MAX, f64::MIN), |m, x| (m.0.min(x), m.1.max(x)));
        if lo > hi {
            (0.1, 10.0)
        } else {
            (lo / 1.5, hi * 1.5)
        }
    };
    let (t_lo, t_hi) = span(&mut pts.iter().map(|p| p.1));
    let e_hi = 1.1 * pts.iter().map(|p| p.2).fold(0.0, f64::max).max(1e-3);
    svg_file(path, (800, 560), |root| {
        let mut chart = ChartBuilder::on(root)
            .caption(
                format!("Speed against error — {}", study.title),
                ("sans-serif", 16),
            )
            .margin(14)
            .x_label_area_size(44)
            .y_label_area_size(70)
            .build_cartesian_2d((t_lo..t_hi).log_scale(), 0.0..e_hi)
            .map_err(text)?;
        chart
            .configure_mesh()
            .x_labels(8)
            .y_labels(8)
            .x_label_formatter(&|v| significant(*v))
            .y_label_formatter(&|v| significant(*v))
            .light_line_style(WHITE)
            .x_desc("CPU time of the case, one thread (s)")
            .y_desc(format!("largest |error| of {} (%)", worst_labels(study)))
            .draw()
            .map_err(text)?;
        let grey = RGBColor(120, 120, 120);
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| !p.0.pareto)
                    .map(|p| Circle::new((p.1, p.2), 4, BLUE.stroke_width(1))),
            )
            .map_err(text)?
            .label("case")
            .legend(|(x, y)| Circle::new((x + 10, y), 4, BLUE.stroke_width(1)));
        chart
            .draw_series(
                pts.iter()
                    .filter(|p| p.0.family)
                    .map(|p| Circle::new((p.1, p.2), 2, grey.filled())),
            )
            .map_err(text)?
            .label("refinement family (the references)")
            .legend(move |(x, y)| Circle::new((x + 10, y), 2, grey.filled()));
        let mut front: Vec<(f64, f64)> = pts
            .iter()
            .filter(|p| p.0.pareto)
            .map(|p| (p.1, p.2))
            .collect();
        front.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut stairs = Vec::new();
        for w in front.windows(2) {
            stairs.extend([w[0], (w[1].0, w[0].1)]);
        }
        stairs.extend(front.last());
        chart
            .draw_series(LineSeries::new(stairs, RED.stroke_width(1)))
            .map_err(text)?;
        chart
            .draw_series(front.iter().map(|&p| Circle::new(p, 5, RED.filled())))
            .map_err(text)?
            .label("Pareto front: no case faster and more accurate")
            .legend(|(x, y)| Circle::new((x + 10, y), 5, RED.filled()));
        chart
            .draw_series(
                pts.iter().map(|p| {
                    Text::new(p.0.name.clone(), (p.1, p.2), ("sans-serif", 11).into_font())
                }),
            )
            .map_err(text)?;
        series_legend(&mut chart, SeriesLabelPosition::UpperRight)
            .draw()
            .map_err(text)
    })
}
