//! Heatmaps: a matrix of coloured cells with row and column labels.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::categories::{CategoryLabels, category_labels, draw_category_label};
use super::colorbar::{colorbar_span, colorbar_width, draw_colorbar, light, value_decimals};
use super::scale::format_tick;
use super::{AXIS_TITLE_EM, Rect, TICK_EM, fitting_em, too_small, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas, TEXT, WHITE};
use crate::figures::colormap::Rgb;
use crate::figures::model::Heatmap;

/// Colour of missing heatmap cells.
const MISSING: Rgb = Rgb(0xd9, 0xd9, 0xd9);

pub(super) fn draw_heatmap<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    h: &Heatmap,
    area: Rect,
) -> Result<(), FigureError> {
    let (nr, nc) = (h.rows.len(), h.columns.len());
    let finite = h.values.iter().flatten().copied().filter(|v| v.is_finite());
    let limits = h.colors.resolve(finite.clone());
    let axis_title_h = c.px(AXIS_TITLE_EM * 1.3);
    let (cb_w, cb_ticks) = colorbar_width(c, &h.colors, limits, area.h() * 0.7)?;
    let mut row_w: f64 = 0.0;
    for l in &h.rows {
        row_w = row_w.max(c.text_size(l, TICK_EM)?.0);
    }
    let left = area.l + axis_title_h + c.px(6.0) + row_w.min(area.w() * 0.3) + c.px(8.0);
    let right = area.r - cb_w;
    let avail_w = right - left;
    let max_h = c.px(160.0).min(area.h() * 0.3);
    let col_layout = category_labels(c, &h.columns, avail_w / nc as f64, TICK_EM, max_h)?;
    let bottom = area.b - axis_title_h - c.px(6.0) - col_layout.height - c.px(8.0);
    let avail_h = bottom - area.t;
    if avail_w <= 0.0 || avail_h <= 0.0 {
        return Err(too_small());
    }
    // Square cells unless that wastes most of the space.
    let (mut cw, mut ch) = (avail_w / nc as f64, avail_h / nr as f64);
    let square = cw.min(ch);
    if square / cw.max(ch) >= 0.5 {
        cw = square;
        ch = square;
    } else {
        cw = cw.min(2.0 * ch);
        ch = ch.min(2.0 * cw);
    }
    let grid = Rect {
        l: left + (avail_w - cw * nc as f64) / 2.0,
        t: area.t,
        r: left + (avail_w - cw * nc as f64) / 2.0 + cw * nc as f64,
        b: area.t + ch * nr as f64,
    };
    let col_layout = col_layout.for_slot(cw);
    let xe = |k: usize| grid.l + cw * k as f64;
    let ye = |k: usize| grid.t + ch * k as f64;
    let decimals = value_decimals(finite);
    for (r, row) in h.values.iter().enumerate() {
        for (k, &v) in row.iter().enumerate() {
            let color = if v.is_finite() {
                h.colors.map.color(v, limits)
            } else {
                MISSING
            };
            c.fill_rect((xe(k), ye(r)), (xe(k + 1), ye(r + 1)), color)?;
            if h.annotate {
                let text = if v.is_finite() {
                    format_tick(v, decimals)
                } else {
                    "n/a".to_string()
                };
                let (tw, th) = c.text_size(&text, TICK_EM)?;
                if tw + c.px(4.0) <= cw && th <= ch {
                    let ink = if light(color) { TEXT } else { WHITE };
                    c.text(
                        &text,
                        ((xe(k) + xe(k + 1)) / 2.0, (ye(r) + ye(r + 1)) / 2.0),
                        TICK_EM,
                        ink,
                        HPos::Center,
                        false,
                    )?;
                }
            }
        }
    }
    for &[r, k] in &h.marked {
        c.stroke_rect((xe(k), ye(r)), (xe(k + 1), ye(r + 1)), Rgb(0, 0, 0), 3.0)?;
        let i = c.px(1.5);
        c.stroke_rect(
            (xe(k) + i, ye(r) + i),
            (xe(k + 1) - i, ye(r + 1) - i),
            WHITE,
            1.0,
        )?;
    }
    c.stroke_rect((grid.l, grid.t), (grid.r, grid.b), AXIS, 1.0)?;
    // Row labels, thinned out when rows are shorter than a line of text.
    let row_layout = CategoryLabels::level(nr, c.px(TICK_EM * 1.1), TICK_EM).for_slot(ch);
    c.note_axis(&h.y.text(), Some(nr), &row_layout.shown(&h.rows));
    c.note_axis(&h.x.text(), Some(nc), &col_layout.shown(&h.columns));
    for (r, label) in h.rows.iter().enumerate().step_by(row_layout.step) {
        let label = truncated(c, label, row_layout.em, area.w() * 0.3)?;
        c.text(
            &label,
            (grid.l - c.px(6.0), (ye(r) + ye(r + 1)) / 2.0),
            row_layout.em,
            TEXT,
            HPos::Right,
            false,
        )?;
    }
    for (k, label) in h.columns.iter().enumerate().step_by(col_layout.step) {
        draw_category_label(
            c,
            label,
            (xe(k) + xe(k + 1)) / 2.0,
            grid.b + c.px(6.0),
            &col_layout,
        )?;
    }
    let x_title = h.x.text();
    let em = fitting_em(c, &x_title, AXIS_TITLE_EM, area.w())?;
    c.text(
        &x_title,
        (
            (grid.l + grid.r) / 2.0,
            grid.b + c.px(6.0) + col_layout.height + c.px(8.0) + axis_title_h / 2.0,
        ),
        em,
        TEXT,
        HPos::Center,
        false,
    )?;
    // Centred on the rows, but within the body: cut to its height.
    let em = fitting_em(c, &h.y.text(), AXIS_TITLE_EM, grid.h().max(c.px(100.0)))?;
    let y_title = truncated(c, &h.y.text(), em, area.h())?;
    let half = c.text_size(&y_title, em)?.0 / 2.0;
    let title_y =
        ((grid.t + grid.b) / 2.0).clamp(area.t + half, (area.b - half).max(area.t + half));
    // Beside the row labels, not at the far left when square cells leave room.
    let title_x = (grid.l - c.px(14.0) - row_w.min(area.w() * 0.3) - axis_title_h / 2.0)
        .max(area.l + axis_title_h / 2.0);
    c.text(&y_title, (title_x, title_y), em, TEXT, HPos::Center, true)?;
    let (cb_top, cb_bottom) = colorbar_span(c, grid, area);
    draw_colorbar(
        c, &h.colors, limits, &cb_ticks, grid.r, cb_top, cb_bottom, cb_w,
    )
}
