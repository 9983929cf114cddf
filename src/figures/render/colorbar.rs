//! The colour bar of heatmaps and image grids, and cell-value formatting.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::scale::{Span, Ticks, ticks_for};
use super::{AXIS_TITLE_EM, Rect, TICK_EM, fitting_em, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas, TEXT};
use crate::figures::colormap::Rgb;
use crate::figures::model::ColorScale;

/// Space a vertical colour bar takes at the right of a figure.
pub(super) fn colorbar_width<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    scale: &ColorScale,
    limits: (f64, f64),
    bar_h: f64,
) -> Result<(f64, Ticks), FigureError> {
    let ticks = ticks_for(
        limits.0,
        limits.1,
        false,
        (bar_h / c.px(50.0)).floor().clamp(2.0, 6.0) as usize,
    );
    let mut widest: f64 = 0.0;
    for l in &ticks.labels {
        widest = widest.max(c.text_size(l, TICK_EM)?.0);
    }
    let title_h = if scale.text().is_empty() {
        0.0
    } else {
        c.px(AXIS_TITLE_EM * 1.3)
    };
    Ok((
        c.px(16.0 + 14.0 + 4.0 + 4.0) + widest + c.px(8.0) + title_h,
        ticks,
    ))
}

/// Colour bar: gradient, ticks and the rotated title, from `left`, spanning `top..bottom`.
#[allow(clippy::too_many_arguments)]
pub(super) fn draw_colorbar<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    scale: &ColorScale,
    limits: (f64, f64),
    ticks: &Ticks,
    left: f64,
    top: f64,
    bottom: f64,
    width: f64,
) -> Result<(), FigureError> {
    let l = left + c.px(16.0);
    let r = l + c.px(14.0);
    let steps = ((bottom - top).round() as usize).clamp(2, 256);
    let span = Span {
        lo: limits.0,
        hi: limits.1,
        log: false,
        p0: bottom,
        p1: top,
    };
    for i in 0..steps {
        let t0 = i as f64 / steps as f64;
        let t1 = (i + 1) as f64 / steps as f64;
        let (y0, y1) = (bottom - t0 * (bottom - top), bottom - t1 * (bottom - top));
        c.fill_rect((l, y1), (r, y0), scale.map.at((t0 + t1) / 2.0))?;
    }
    c.stroke_rect((l, top), (r, bottom), AXIS, 1.0)?;
    let tick = c.px(4.0);
    for (v, label) in ticks.values.iter().zip(&ticks.labels) {
        let y = span.map(*v);
        c.line((r, y), (r + tick, y), AXIS, 1.0)?;
        c.text(
            label,
            (r + tick + c.px(4.0), y),
            TICK_EM,
            TEXT,
            HPos::Left,
            false,
        )?;
    }
    let title = scale.text();
    c.note_axis(&title, None, &ticks.labels);
    if !title.is_empty() {
        let title_h = c.px(AXIS_TITLE_EM * 1.3);
        // Smaller to fit the bar's length, then cut (a long unit on a short tile).
        let em = fitting_em(c, &title, AXIS_TITLE_EM, bottom - top)?;
        let title = truncated(c, &title, em, bottom - top)?;
        c.text(
            &title,
            (left + width - title_h / 2.0, (top + bottom) / 2.0),
            em,
            TEXT,
            HPos::Center,
            true,
        )?;
    }
    Ok(())
}

/// Relative luminance, to pick readable text on a coloured cell.
pub(super) fn light(c: Rgb) -> bool {
    0.2126 * c.0 as f64 + 0.7152 * c.1 as f64 + 0.0722 * c.2 as f64 > 140.0
}

/// Decimals to show ~3 significant digits of the largest value (integers as integers).
pub(super) fn value_decimals(values: impl Iterator<Item = f64> + Clone) -> usize {
    if values.clone().all(|v| v.fract() == 0.0) {
        return 0;
    }
    let max = values.fold(0.0f64, |m, v| m.max(v.abs()));
    if max == 0.0 {
        2
    } else {
        (2.0 - max.log10().floor()).clamp(0.0, 4.0) as usize
    }
}

/// The colour bar spans the data's height, but at least 150 px (when there is room).
pub(super) fn colorbar_span<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    data: Rect,
    area: Rect,
) -> (f64, f64) {
    let min_h = c.px(150.0).min(area.h());
    if data.h() >= min_h {
        return (data.t, data.b);
    }
    let mid = (data.t + data.b) / 2.0;
    let top = (mid - min_h / 2.0).max(area.t);
    (top, top + min_h)
}
