//! The shaded band of the error estimate around each level's G along the front
//! (`[mesh] error_estimate`, docs/ACCURACY.md §3): G ± the estimated discretisation error at
//! every front point, in the level's colour, under its line.

use super::legend::{Entry, Icon};
use super::{COLOURS, text};
use crate::results::{FrontRow, GError, Results};
use plotters::coord::types::RangedCoordf64;
use plotters::prelude::*;

/// The chart the release-rate plots draw on.
type Chart<'a, 'b> = ChartContext<'a, SVGBackend<'b>, Cartesian2d<RangedCoordf64, RangedCoordf64>>;

/// A front row's G of one mode, and its error.
type Mode = (fn(&FrontRow) -> f64, fn(&GError) -> f64);

/// Which G a chart shows, from its y-axis description (`G_T, energy release rate …`).
fn mode(y_desc: &str) -> Option<Mode> {
    let name = y_desc.split(',').next()?;
    match name {
        "G_I" => Some((|r| r.g_i, |e| e.g_i)),
        "G_II" => Some((|r| r.g_ii, |e| e.g_ii)),
        "G_III" => Some((|r| r.g_iii, |e| e.g_iii)),
        "G_T" => Some((|r| r.g_t, |e| e.g_t)),
        _ => None,
    }
}

/// Draws G ± its estimated error for every level that carries an estimate, and returns the
/// legend entry that explains the band (none when nothing was drawn: a chart of another
/// quantity, or a run without an estimate).
pub(super) fn draw(
    chart: &mut Chart,
    results: &Results,
    y_desc: &str,
) -> Result<Vec<Entry>, String> {
    let Some((g, e)) = mode(y_desc) else {
        return Ok(Vec::new());
    };
    let mut drawn = false;
    for (k, level) in results.levels.iter().enumerate() {
        let band: Option<Vec<(f64, f64, f64)>> = level
            .front
            .iter()
            .map(|r| r.error.map(|err| (r.s_mm, g(r), e(&err))))
            .collect();
        let Some(band) = band.filter(|b| b.len() >= 2) else {
            continue;
        };
        // Inside the chart's range (the band is drawn, not clipped, by the backend).
        let ys = chart.y_range();
        let clip = |v: f64| v.clamp(ys.start, ys.end);
        let upper = band.iter().map(|&(s, v, d)| (s, clip(v + d)));
        let lower = band.iter().rev().map(|&(s, v, d)| (s, clip(v - d)));
        let colour = COLOURS[k % COLOURS.len()].mix(0.18);
        chart
            .draw_series([Polygon::new(
                upper.chain(lower).collect::<Vec<_>>(),
                colour.filled(),
            )])
            .map_err(text)?;
        drawn = true;
    }
    Ok(if drawn {
        vec![Entry::new(
            Icon::Line(RGBColor(190, 190, 190).to_rgba()),
            "shaded: ± estimated discretisation error\n(companion mesh, docs/ACCURACY.md §3)",
        )]
    } else {
        Vec::new()
    })
}
