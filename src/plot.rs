//! SVG plots of a run (plotters' SVG backend: text is left to the viewer, no font files or
//! system libraries needed): G against S per level (thesis Figs. 5.1.3–5.1.5), the failure
//! index against S per level, deflection against strain (Fig. 5.1.1), and one overview figure
//! of the two for a report ([`overview_plot`]).
//!
//! Every figure's title names the scene and the applied levels; every axis says its quantity
//! and unit; a legend beside the chart explains every line and marker drawn: one colour per
//! level, filled circles where the crack faces are open (G physical), hollow circles on dashed
//! stretches where they overlap (G not physical without contact, §2.7), triangles where contact
//! holds them closed (G_I = 0).

mod band;
mod legend;

use crate::Error;
use crate::results::{Faces, FrontRow, Results};
pub(crate) use legend::series_legend;
use legend::{Entry, Icon, draw_legend};
use plotters::coord::Shift;
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;
use std::ops::Range;
use std::path::Path;

/// The drawing surface of every plot.
pub(crate) type Area<'a> = DrawingArea<SVGBackend<'a>, Shift>;

/// A chart of f64 against f64 on an [`Area`] borrowed for `'a`.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// Points of a curve, (x, y) in the chart's units.
type Curve = [(f64, f64)];

/// A drawing error, as text (plotters' error types are generic over the backend).
pub(crate) type Drawn = Result<(), String>;

/// One colour per level, cycled (matplotlib's "tab10": distinct on white and in grey print).
const COLOURS: [RGBColor; 10] = [
    RGBColor(31, 119, 180),
    RGBColor(255, 127, 14),
    RGBColor(44, 160, 44),
    RGBColor(214, 39, 40),
    RGBColor(148, 103, 189),
    RGBColor(140, 86, 75),
    RGBColor(227, 119, 194),
    RGBColor(127, 127, 127),
    RGBColor(188, 189, 34),
    RGBColor(23, 190, 207),
];

/// Width of the legend panel beside a chart, px.
const LEGEND_W: u32 = 370;

/// The error of a plot that could not be drawn or written to `path`: what plotters said.
pub(crate) fn plot_err(path: &Path, reason: impl std::fmt::Display) -> Error {
    Error::Plot {
        path: path.to_path_buf(),
        reason: reason.to_string(),
    }
}

/// Maps any displayable drawing error to text.
pub(crate) fn text<E: std::fmt::Display>(e: E) -> String {
    e.to_string()
}

/// Range of `values` with a margin, never empty; 0 always inside.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |m, v| (m.0.min(v), m.1.max(v)));
    if lo > hi {
        return (0.0, 1.0);
    }
    let (lo, hi) = (lo.min(0.0), hi.max(0.0));
    let pad = 0.05 * (hi - lo).max(1e-12);
    (lo - pad, hi + pad)
}

/// A level's label: `ε_x = -0.003` or `P = 100 N`.
pub fn level_label(results: &Results, value: f64) -> String {
    if results.quantity == "strain" {
        format!("ε_x = {value}")
    } else {
        format!("P = {value} N")
    }
}

/// The applied levels in a title: `ε_x = -0.001 … -0.005 (5 levels)`.
pub fn applied(results: &Results) -> String {
    let values: Vec<f64> = results.levels.iter().map(|l| l.value).collect();
    match values.as_slice() {
        [] => "no level converged".into(),
        [v] => level_label(results, *v),
        [first, .., last] => {
            let unit = if results.quantity == "strain" {
                ""
            } else {
                " N"
            };
            format!(
                "{} … {last}{unit} ({} levels)",
                level_label(results, *first).trim_end_matches(" N"),
                values.len()
            )
        }
    }
}

/// `v` to 5 significant digits (an interpolated onset strain, printed whole otherwise).
fn round5(v: f64) -> f64 {
    format!("{v:.4e}").parse().unwrap_or(v)
}

/// The x axis of deflection plots.
fn applied_axis(results: &Results) -> &'static str {
    if results.quantity == "strain" {
        "applied compressive strain |ε_x| (–)"
    } else {
        "applied load P (N)"
    }
}

/// The legend entries of the front's markers that occur in `rows` (open, overlapped, closed).
fn marker_entries<'a>(rows: impl Iterator<Item = &'a FrontRow> + Clone) -> Vec<Entry> {
    let has = |f: Faces| rows.clone().any(|r| r.faces == f);
    let mut out = Vec::new();
    if has(Faces::Open) {
        out.push(Entry::new(Icon::Open, "faces open: G physical"));
    }
    if has(Faces::Overlapped) {
        out.push(Entry::new(
            Icon::Overlapped,
            "faces overlap (dashed): G not physical,\nno contact modelled",
        ));
    }
    if has(Faces::Closed) {
        out.push(Entry::new(
            Icon::Closed,
            "faces held closed by contact: G_I = 0",
        ));
    }
    out
}

/// A chart on `area` under `caption` (none if empty) with its x and y ranges and axis labels.
fn axes<'a, 'b>(
    area: &'a Area<'b>,
    caption: &str,
    (x, x_desc): (Range<f64>, &str),
    (y, y_desc): (Range<f64>, &str),
) -> Result<Chart<'a, 'b>, String> {
    let mut builder = ChartBuilder::on(area);
    if !caption.is_empty() {
        builder.caption(caption, ("sans-serif", 15));
    }
    let mut chart = builder
        .margin(12)
        .x_label_area_size(45)
        .y_label_area_size(70)
        .build_cartesian_2d(x, y)
        .map_err(text)?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc(y_desc)
        .draw()
        .map_err(text)?;
    Ok(chart)
}

/// One front quantity against S, a line per level, markers by face state: `y` of each row
/// (None: not drawn, e.g. no failure index where the faces overlap); a dashed red line at
/// `threshold` when given. Returns the largest `y` drawn.
fn front_chart(
    area: &Area,
    results: &Results,
    caption: &str,
    y_desc: &str,
    y: &dyn Fn(&FrontRow) -> Option<f64>,
    threshold: Option<(f64, &str)>,
    onset: Option<(f64, f64, String)>,
) -> Drawn {
    let (chart_area, legend_area) = area.split_horizontally(area.dim_in_pixel().0 - LEGEND_W);
    let rows = || results.levels.iter().flat_map(|l| l.front.iter());
    let s_hi = range(rows().map(|r| r.s_mm)).1;
    let largest = rows().filter_map(y).fold(f64::MIN, f64::max);
    // The onset line only where the curves come near it (else it would flatten them).
    let threshold = threshold.filter(|(t, _)| largest >= 0.2 * t);
    let (y_lo, y_hi) = range(rows().filter_map(y).chain(threshold.map(|(t, _)| 1.05 * t)));
    let mut chart = axes(
        &chart_area,
        caption,
        (
            0.0..s_hi,
            "S, arc length along the front from the x axis (mm)",
        ),
        (y_lo..y_hi, y_desc),
    )?;
    let mut entries = band::draw(&mut chart, results, y_desc)?;
    for (k, level) in results.levels.iter().enumerate() {
        let colour = COLOURS[k % COLOURS.len()].to_rgba();
        entries.push(Entry::new(
            Icon::Line(colour),
            &level_label(results, level.value),
        ));
        // Consecutive pairs: solid where neither end overlaps, dashed where either does.
        for pair in level.front.windows(2) {
            let (Some(y0), Some(y1)) = (y(&pair[0]), y(&pair[1])) else {
                continue;
            };
            let pts = [(pair[0].s_mm, y0), (pair[1].s_mm, y1)];
            if pair[0].is_open() && pair[1].is_open() {
                chart.draw_series(LineSeries::new(pts, colour.stroke_width(2)))
            } else {
                chart.draw_series(DashedLineSeries::new(pts, 6, 4, colour.stroke_width(2)))
            }
            .map_err(text)?;
        }
        for r in &level.front {
            let Some(v) = y(r) else { continue };
            match r.faces {
                Faces::Open => chart.draw_series([Circle::new((r.s_mm, v), 3, colour.filled())]),
                Faces::Overlapped => {
                    chart.draw_series([Circle::new((r.s_mm, v), 3, colour.stroke_width(1))])
                }
                Faces::Closed => {
                    chart.draw_series([TriangleMarker::new((r.s_mm, v), 4, colour.filled())])
                }
            }
            .map_err(text)?;
        }
    }
    entries.extend(marker_entries(rows().filter(|r| y(r).is_some())));
    if let Some((t, label)) = threshold {
        chart
            .draw_series(DashedLineSeries::new(
                [(0.0, t), (s_hi, t)],
                8,
                4,
                RED.stroke_width(1),
            ))
            .map_err(text)?;
        entries.push(Entry::new(Icon::Dashed(RED.to_rgba()), label));
    }
    if let Some((s, v, label)) = onset {
        chart
            .draw_series([Cross::new((s, v), 7, BLACK.stroke_width(2))])
            .map_err(text)?;
        entries.push(Entry::new(Icon::Onset, &label));
    }
    draw_legend(&legend_area, &entries)
}

/// Deflection against the applied value: the centre deflection w of the sublaminate's top and
/// the largest crack-face separation, from the unloaded state through every level.
fn deflection_chart(area: &Area, results: &Results, caption: &str) -> Drawn {
    let series = |f: fn(&crate::results::LevelResult) -> f64| -> Vec<(f64, f64)> {
        std::iter::once((0.0, 0.0))
            .chain(results.levels.iter().map(|l| (l.value.abs(), f(l).abs())))
            .collect()
    };
    let centre = series(|l| l.centre_deflection_mm);
    let separation = series(|l| l.max_face_separation_mm);
    let x_hi = range(centre.iter().map(|p| p.0)).1;
    let y_hi = range(centre.iter().chain(&separation).map(|p| p.1)).1;
    let mut chart = axes(
        area,
        caption,
        (0.0..x_hi, applied_axis(results)),
        (0.0..y_hi, "deflection (mm)"),
    )?;
    let lines: [(&str, &Curve, RGBAColor); 2] = [
        (
            "|w| at the centre, sublaminate top (base included)",
            &centre,
            COLOURS[0].to_rgba(),
        ),
        (
            "largest crack-face separation |w_upper − w_lower|",
            &separation,
            COLOURS[1].to_rgba(),
        ),
    ];
    for (label, pts, colour) in lines {
        chart
            .draw_series(LineSeries::new(pts.to_vec(), colour.stroke_width(2)))
            .map_err(text)?
            .label(label)
            .legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2))
            });
        chart
            .draw_series(pts.iter().map(|&p| Circle::new(p, 3, colour.filled())))
            .map_err(text)?;
    }
    series_legend(&mut chart, SeriesLabelPosition::UpperLeft)
        .background_style(WHITE.mix(0.85))
        .label_font(("sans-serif", 13))
        .draw()
        .map_err(text)
}

/// Draws into an SVG at `path` of `size` px, white, with `draw`, naming the file in any error.
pub(crate) fn svg_file(
    path: &Path,
    size: (u32, u32),
    draw: impl FnOnce(&Area) -> Drawn,
) -> Result<(), Error> {
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    draw(&root).map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))
}

/// Draws into an SVG at `path` of `size` px under `title` (across the whole width) with
/// `draw`, naming the file in any error.
fn svg(
    path: &Path,
    size: (u32, u32),
    title: &str,
    draw: impl FnOnce(&Area) -> Drawn,
) -> Result<(), Error> {
    svg_file(path, size, |root| {
        draw(&root.titled(title, ("sans-serif", 17)).map_err(text)?)
    })
}

/// `label` (J/m²) of each front row, `g`, against S, one line per level (Figs. 5.1.3–5.1.5).
/// Stretches where the crack faces overlap are dashed and their markers hollow (the thesis's
/// dashed stretches, §5.1), with a legend entry saying that G there is not physical.
pub fn release_rate_plot(
    results: &Results,
    path: &Path,
    label: &str,
    g: impl Fn(&FrontRow) -> f64,
) -> Result<(), Error> {
    let caption = format!(
        "{label} along the front — {} — {}",
        results.title,
        applied(results)
    );
    svg(path, (1000, 560), &caption, |root| {
        front_chart(
            root,
            results,
            "",
            &format!("{label}, energy release rate (J/m²)"),
            &|r| Some(g(r)),
            None,
            None,
        )
    })
}

/// The failure index of the scene's criterion against S, one line per level (no index where
/// the faces overlap), the onset line at 1 and the critical point marked.
pub fn failure_index_plot(results: &Results, path: &Path) -> Result<(), Error> {
    let caption = format!(
        "Failure index along the front — {} — {}",
        results.title,
        applied(results)
    );
    let onset = results.critical.map(|c| {
        (
            c.s_mm,
            c.index,
            format!(
                "growth onset {} at S = {:.2} mm\n(cross: index {:.2} at {},\nmode mix (G_II + G_III)/G_T = {:.2} there)",
                match c.after {
                    Some(after) => format!(
                        "between {} and {}",
                        level_label(results, after),
                        c.strain
                    ),
                    None => level_label(results, round5(c.strain)),
                },
                c.s_mm,
                c.index,
                level_label(results, results.levels.get(c.level).map_or(0.0, |l| l.value)),
                c.mode_mix
            ),
        )
    });
    svg(path, (1000, 560), &caption, |root| {
        front_chart(
            root,
            results,
            "",
            "failure index of the scene's criterion (–)",
            &|r| r.failure_index,
            Some((1.0, "index = 1: growth onset")),
            onset,
        )
    })
}

/// Largest crack-face separation and centre deflection against |strain| (or load), Fig. 5.1.1.
pub fn deflection_plot(results: &Results, path: &Path) -> Result<(), Error> {
    let caption = format!(
        "Deflection against applied {} — {}",
        if results.quantity == "strain" {
            "strain"
        } else {
            "load"
        },
        results.title
    );
    svg(path, (820, 560), &caption, |root| {
        deflection_chart(root, results, "")
    })
}

/// The figure for a report: G_T along the front for every level (left) and the deflections
/// against the applied strain (right), under one title naming the scene and the levels.
pub fn overview_plot(results: &Results, path: &Path) -> Result<(), Error> {
    let title = format!("{} — {}", results.title, applied(results));
    svg(path, (1640, 580), &title, |root| {
        let (left, right) = root.split_horizontally(1000);
        front_chart(
            &left,
            results,
            "G_T along the front, per level",
            "G_T, total energy release rate (J/m²)",
            &|r| Some(r.g_t),
            None,
            None,
        )?;
        deflection_chart(&right, results, "Deflection against the applied level")
    })
}

#[cfg(test)]
mod tests;
