//! SVG plots of a run (plotters' SVG backend: text is left to the viewer, no font files or
//! system libraries needed): G against S per level (thesis Figs. 5.1.3–5.1.5) and deflection
//! against strain (Fig. 5.1.1).

use crate::Error;
use crate::results::{FrontRow, Results};
use plotters::element::DashedPathElement;
use plotters::prelude::*;
use std::path::Path;

fn plot_err(path: &Path, e: impl std::fmt::Display) -> Error {
    Error::Plot {
        path: path.to_path_buf(),
        reason: e.to_string(),
    }
}

/// Range of `values` with a margin, never empty.
fn range(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::MAX, f64::MIN), |m, v| (m.0.min(v), m.1.max(v)));
    if lo > hi {
        return (0.0, 1.0);
    }
    let lo = lo.min(0.0);
    let pad = 0.05 * (hi - lo).max(1e-12);
    (lo - pad, hi + pad)
}

/// One line per level: `g` of each front row against S. Stretches where the crack faces
/// overlap are dashed and their markers hollow (the thesis's dashed stretches, §5.1), with a
/// legend entry saying that G there is not physical without contact.
pub fn release_rate_plot(
    results: &Results,
    path: &Path,
    label: &str,
    g: impl Fn(&FrontRow) -> f64,
) -> Result<(), Error> {
    let root = SVGBackend::new(path, (720, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let s_max = range(
        results
            .levels
            .iter()
            .flat_map(|l| l.front.iter().map(|r| r.s_mm)),
    )
    .1;
    let (g_lo, g_hi) = range(results.levels.iter().flat_map(|l| l.front.iter().map(&g)));
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("{label} along the front — {}", results.title),
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..s_max, g_lo..g_hi)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc("S (mm)")
        .y_desc(format!("{label} (J/m²)"))
        .draw()
        .map_err(|e| plot_err(path, e))?;
    for (k, level) in results.levels.iter().enumerate() {
        let colour = Palette99::pick(k).to_rgba();
        // Consecutive pairs: solid where both ends are open, dashed where either overlaps.
        for pair in level.front.windows(2) {
            let pts = [(pair[0].s_mm, g(&pair[0])), (pair[1].s_mm, g(&pair[1]))];
            if pair[0].is_open() && pair[1].is_open() {
                chart.draw_series(LineSeries::new(pts, colour.stroke_width(2)))
            } else {
                chart.draw_series(DashedLineSeries::new(pts, 6, 4, colour.stroke_width(2)))
            }
            .map_err(|e| plot_err(path, e))?;
        }
        chart
            .draw_series(level.front.iter().map(|r| {
                let style = if r.is_open() {
                    colour.filled()
                } else {
                    colour.stroke_width(1)
                };
                Circle::new((r.s_mm, g(r)), 3, style)
            }))
            .map_err(|e| plot_err(path, e))?
            .label(format!("{} = {}", results.quantity, level.value))
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour));
    }
    if results.levels.iter().any(|l| l.overlapped() > 0) {
        chart
            .draw_series(std::iter::empty::<Circle<(f64, f64), i32>>())
            .map_err(|e| plot_err(path, e))?
            .label("dashed, hollow: faces overlap — G not physical (no contact)")
            .legend(|(x, y)| {
                EmptyElement::at((x, y))
                    + DashedPathElement::new(vec![(0, 0), (20, 0)], 4, 3, BLACK.stroke_width(2))
                    + Circle::new((10, 0), 3, BLACK.stroke_width(1))
            });
    }
    chart
        .configure_series_labels()
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK)
        .draw()
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}

/// Largest crack-face separation against |strain| (or load), Fig. 5.1.1.
pub fn deflection_plot(results: &Results, path: &Path) -> Result<(), Error> {
    let root = SVGBackend::new(path, (720, 480)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| plot_err(path, e))?;
    let pts: Vec<(f64, f64)> = std::iter::once((0.0, 0.0))
        .chain(
            results
                .levels
                .iter()
                .map(|l| (l.value.abs(), l.max_face_separation_mm.abs())),
        )
        .collect();
    let (_, x_hi) = range(pts.iter().map(|p| p.0));
    let (_, y_hi) = range(pts.iter().map(|p| p.1));
    let x_desc = if results.quantity == "strain" {
        "|ε_x|"
    } else {
        "P (N)"
    };
    let mut chart = ChartBuilder::on(&root)
        .caption(
            format!("Sublaminate deflection off the base — {}", results.title),
            ("sans-serif", 16),
        )
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(60)
        .build_cartesian_2d(0.0..x_hi, 0.0..y_hi)
        .map_err(|e| plot_err(path, e))?;
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("largest crack-face separation |w_upper − w_lower| (mm)")
        .draw()
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(2)))
        .map_err(|e| plot_err(path, e))?;
    chart
        .draw_series(pts.iter().map(|&p| Circle::new(p, 3, BLUE.filled())))
        .map_err(|e| plot_err(path, e))?;
    root.present().map_err(|e| plot_err(path, e))?;
    Ok(())
}
