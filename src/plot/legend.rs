//! A legend panel beside a chart (never over the data): one row per entry, an icon drawn as
//! the chart draws it and a text of one or more lines; and the look of plotters' own legend
//! of a chart's labelled series ([`series_legend`]).

use super::{Area, Drawn, text};
use plotters::chart::SeriesLabelStyle;
use plotters::coord::CoordTranslate;
use plotters::element::DashedPathElement;
use plotters::prelude::*;

/// What an entry's icon shows.
#[derive(Debug, Clone, Copy)]
pub enum Icon {
    /// A solid line in a level's colour.
    Line(RGBAColor),
    /// A dashed line (a threshold).
    Dashed(RGBAColor),
    /// A filled circle: faces open.
    Open,
    /// A hollow circle on a dashed line: faces overlapped.
    Overlapped,
    /// A filled triangle: faces held closed by contact.
    Closed,
    /// A cross: the onset of growth.
    Onset,
}

/// One row of a legend.
#[derive(Debug, Clone)]
pub struct Entry {
    icon: Icon,
    text: String,
}

impl Entry {
    /// An entry; `text` may hold line breaks.
    pub fn new(icon: Icon, text: &str) -> Self {
        Self {
            icon,
            text: text.into(),
        }
    }
}

/// Pixel height of one text line.
const LINE: i32 = 17;

/// Draws `entries` top down in `area`, in a box.
pub fn draw_legend(area: &Area, entries: &[Entry]) -> Drawn {
    let font = ("sans-serif", 13).into_font().color(&BLACK);
    let lines: i32 = entries.iter().map(|e| e.text.lines().count() as i32).sum();
    let (top, left) = (40, 8);
    let height = lines * LINE + 6 * entries.len() as i32 + 10;
    let width = area.dim_in_pixel().0 as i32 - 2 * left;
    area.draw(&Rectangle::new(
        [(left, top), (left + width, top + height)],
        BLACK.stroke_width(1),
    ))
    .map_err(text)?;
    let mut y = top + 12;
    for e in entries {
        let (x, c) = (left + 10, (left + 30, y));
        let black = BLACK.to_rgba();
        match e.icon {
            Icon::Line(colour) => area.draw(&PathElement::new(
                vec![(x, y), (x + 40, y)],
                colour.stroke_width(2),
            )),
            Icon::Dashed(colour) => area.draw(&DashedPathElement::new(
                vec![(x, y), (x + 40, y)],
                6,
                4,
                colour.stroke_width(1),
            )),
            Icon::Open => area.draw(&Circle::new(c, 3, black.filled())),
            Icon::Overlapped => area
                .draw(&DashedPathElement::new(
                    vec![(x, y), (x + 40, y)],
                    6,
                    4,
                    black.stroke_width(2),
                ))
                .and_then(|_| area.draw(&Circle::new(c, 3, WHITE.filled())))
                .and_then(|_| area.draw(&Circle::new(c, 3, black.stroke_width(1)))),
            Icon::Closed => area.draw(&TriangleMarker::new(c, 4, black.filled())),
            Icon::Onset => area.draw(&Cross::new(c, 7, black.stroke_width(2))),
        }
        .map_err(text)?;
        for (k, line) in e.text.lines().enumerate() {
            area.draw(&Text::new(
                line.to_string(),
                (x + 52, y - 7 + k as i32 * LINE),
                font.clone(),
            ))
            .map_err(text)?;
        }
        y += e.text.lines().count() as i32 * LINE + 6;
    }
    Ok(())
}

/// Plotters' legend of `chart`'s labelled series (`.label(…).legend(…)`) at `position`, in a
/// black-bordered box of white at 80 % opacity over the data; the caller may restyle it
/// further, then `.draw()`s it.
pub(crate) fn series_legend<'a, 'b, DB: DrawingBackend + 'a, CT: CoordTranslate>(
    chart: &'b mut ChartContext<'a, DB, CT>,
    position: SeriesLabelPosition,
) -> SeriesLabelStyle<'a, 'b, DB, CT> {
    let mut style = chart.configure_series_labels();
    style
        .position(position)
        .background_style(WHITE.mix(0.8))
        .border_style(BLACK);
    style
}
