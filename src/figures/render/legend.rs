//! Legends: entries with swatches in the series' colours, placed beside the data.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::{LEGEND_EM, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, Marker, TEXT};
use crate::figures::colormap::Rgb;

/// A legend entry: what its swatch shows.
pub(super) struct LegendEntry {
    pub(super) name: String,
    pub(super) color: Rgb,
    pub(super) line: bool,
    pub(super) marker: Option<Marker>,
    pub(super) band: bool,
    pub(super) bar: bool,
}

/// Shorten legend names so that the legend takes at most `max_w`; returns its width.
pub(super) fn fit_legend<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    entries: &mut [LegendEntry],
    max_w: f64,
) -> Result<f64, FigureError> {
    let swatch = c.px(30.0);
    for e in entries.iter_mut() {
        e.name = truncated(c, &e.name, LEGEND_EM, max_w - swatch)?;
    }
    legend_width(c, entries)
}

pub(super) fn legend_width<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    entries: &[LegendEntry],
) -> Result<f64, FigureError> {
    let mut w: f64 = 0.0;
    for e in entries {
        w = w.max(c.text_size(&e.name, LEGEND_EM)?.0);
    }
    Ok(w + c.px(30.0))
}

/// Legend as a column at the top right of `area`, outside the data.
pub(super) fn draw_legend<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    entries: &[LegendEntry],
    l: f64,
    t: f64,
) -> Result<(), FigureError> {
    let row = c.px(LEGEND_EM * 1.7);
    for (i, e) in entries.iter().enumerate() {
        let y = t + row * (i as f64 + 0.5);
        let (x0, x1) = (l, l + c.px(22.0));
        if e.band {
            c.polygon(
                &[
                    (x0, y - c.px(5.0)),
                    (x1, y - c.px(5.0)),
                    (x1, y + c.px(5.0)),
                    (x0, y + c.px(5.0)),
                ],
                e.color,
                0.2,
            )?;
        }
        if e.bar {
            c.fill_rect(
                (x0 + c.px(4.0), y - c.px(6.0)),
                (x1 - c.px(4.0), y + c.px(6.0)),
                e.color,
            )?;
        }
        if e.line {
            c.line((x0, y), (x1, y), e.color, 2.0)?;
        }
        if let Some(m) = e.marker {
            c.marker(m, ((x0 + x1) / 2.0, y), 3.5, e.color)?;
        }
        c.text(
            &e.name,
            (x1 + c.px(8.0), y),
            LEGEND_EM,
            TEXT,
            HPos::Left,
            false,
        )?;
    }
    Ok(())
}
