//! Grouped bar charts and their category labels.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::frame::{axes, frame};
use super::legend::{LegendEntry, draw_legend, fit_legend};
use super::scale::limits;
use super::{Rect, TICK_EM, missing_note, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas, TEXT};
use crate::figures::colormap::{ColorMap, series_color};
use crate::figures::model::BarChart;

/// Which category labels to draw: every `step`-th, rotated or not, and the height taken.
#[derive(Clone, Copy)]
pub(super) struct CategoryLabels {
    pub(super) step: usize,
    pub(super) rotated: bool,
    pub(super) height: f64,
    /// Room one label needs along the axis.
    pub(super) needed: f64,
}

impl CategoryLabels {
    /// The same layout for the final slot width: only how many labels are skipped changes,
    /// so that the height already reserved stays right.
    pub(super) fn for_slot(self, slot: f64) -> Self {
        let step = (self.needed / slot.max(1e-9)).ceil().max(1.0) as usize;
        CategoryLabels { step, ..self }
    }
}

pub(super) fn category_labels<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    labels: &[String],
    slot: f64,
    em: f64,
) -> Result<CategoryLabels, FigureError> {
    let mut widest: f64 = 0.0;
    for l in labels {
        widest = widest.max(c.text_size(l, em)?.0);
    }
    let line_h = c.px(em * 1.2);
    let gap = c.px(6.0);
    // Long names that do not fit read better rotated; short ones (indices) are thinned out.
    let rotated = widest + gap > slot && widest > c.px(em * 3.0);
    let layout = if rotated {
        CategoryLabels {
            step: 1,
            rotated,
            height: widest.min(c.px(160.0)),
            needed: line_h,
        }
    } else {
        CategoryLabels {
            step: 1,
            rotated,
            height: line_h,
            needed: widest + gap,
        }
    };
    Ok(layout.for_slot(slot))
}

pub(super) fn draw_category_label<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    label: &str,
    x: f64,
    top: f64,
    em: f64,
    layout: &CategoryLabels,
) -> Result<(), FigureError> {
    if layout.rotated {
        let label = truncated(c, label, em, layout.height)?;
        c.text(&label, (x, top), em, TEXT, HPos::Right, true)
    } else {
        c.text(
            label,
            (x, top + c.px(em * 0.6)),
            em,
            TEXT,
            HPos::Center,
            false,
        )
    }
}

pub(super) fn draw_bars<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    bars: &BarChart,
    area: Rect,
) -> Result<(), FigureError> {
    let n = bars.categories.len();
    let ng = bars.groups.len();
    let mut values = vec![0.0];
    for g in &bars.groups {
        for (k, &v) in g.values.iter().enumerate() {
            if v.is_finite() {
                values.push(v);
                if let Some(e) = g.error.as_ref().map(|e| e[k]).filter(|e| e.is_finite()) {
                    values.extend([v - e.abs(), v + e.abs()]);
                }
            }
        }
    }
    let (ylo, yhi) = limits(&values, &bars.y, 0.05);
    let sign_pos = ColorMap::Diverging.at(0.85);
    let sign_neg = ColorMap::Diverging.at(0.15);
    let mut entries: Vec<LegendEntry> = if bars.sign_colors {
        let missing = bars.groups[0]
            .values
            .iter()
            .filter(|v| !v.is_finite())
            .count();
        vec![
            LegendEntry {
                name: missing_note(&format!("{} > 0", bars.groups[0].name), missing),
                color: sign_pos,
                line: false,
                marker: None,
                band: false,
                bar: true,
            },
            LegendEntry {
                name: format!("{} < 0", bars.groups[0].name),
                color: sign_neg,
                line: false,
                marker: None,
                band: false,
                bar: true,
            },
        ]
    } else {
        bars.groups
            .iter()
            .enumerate()
            .map(|(i, g)| LegendEntry {
                name: missing_note(&g.name, g.values.iter().filter(|v| !v.is_finite()).count()),
                color: g.color.unwrap_or(series_color(i)),
                line: false,
                marker: None,
                band: false,
                bar: true,
            })
            .collect()
    };
    let show_legend = ng > 1 || bars.sign_colors || entries[0].name != bars.groups[0].name;
    let mut body = area;
    if show_legend {
        let lw = fit_legend(c, &mut entries, area.w() * 0.4)?;
        body.r -= lw + c.px(12.0);
    }
    // The label layout needs the slot width, which needs the y-label width: estimate the
    // slot from the body, then lay out the frame with the labels' height.
    let slot_estimate = (body.w() - c.px(60.0)) / n as f64;
    let labels = category_labels(c, &bars.categories, slot_estimate, TICK_EM)?;
    let f = frame(c, body, &bars.y, (ylo, yhi), None, labels.height)?;
    let slot = f.plot.w() / n as f64;
    let labels = labels.for_slot(slot);
    let bar_w = slot * 0.8 / ng as f64;
    let inset = if bar_w > c.px(4.0) { c.px(0.5) } else { 0.0 };
    let y0 = f.y.map(0.0);
    for (gi, g) in bars.groups.iter().enumerate() {
        for (k, &v) in g.values.iter().enumerate() {
            if !v.is_finite() {
                continue;
            }
            let x0 = f.plot.l + slot * (k as f64 + 0.1) + bar_w * gi as f64;
            let color = if bars.sign_colors {
                if v >= 0.0 { sign_pos } else { sign_neg }
            } else {
                entries[gi].color
            };
            c.fill_rect((x0 + inset, y0), (x0 + bar_w - inset, f.y.map(v)), color)?;
            if let Some(e) = g
                .error
                .as_ref()
                .map(|e| e[k].abs())
                .filter(|e| e.is_finite() && *e > 0.0)
            {
                let x = x0 + bar_w / 2.0;
                let (ya, yb) = (f.y.map(v - e), f.y.map(v + e));
                let cap = (bar_w * 0.25).min(c.px(4.0));
                c.line((x, ya), (x, yb), AXIS, 1.0)?;
                c.line((x - cap, ya), (x + cap, ya), AXIS, 1.0)?;
                c.line((x - cap, yb), (x + cap, yb), AXIS, 1.0)?;
            }
        }
    }
    if ylo < 0.0 {
        c.line((f.plot.l, y0), (f.plot.r, y0), AXIS, 1.0)?;
    }
    axes(c, &f, area, &bars.x.text(), &bars.y.text())?;
    let tick = c.px(4.0);
    for (k, label) in bars.categories.iter().enumerate().step_by(labels.step) {
        let x = f.plot.l + slot * (k as f64 + 0.5);
        c.line((x, f.plot.b), (x, f.plot.b + tick), AXIS, 1.0)?;
        draw_category_label(c, label, x, f.plot.b + tick + c.px(4.0), TICK_EM, &labels)?;
    }
    if show_legend {
        draw_legend(c, &entries, body.r + c.px(12.0), f.plot.t)?;
    }
    Ok(())
}
