//! Grouped bar charts and their category labels.

use plotters::prelude::DrawingBackend;

use super::categories::{CategoryLabels, category_labels, draw_category_label};
use super::frame::{Frame, axes, draw_grid, frame};
use super::legend::{Legend, LegendEntry, Obstacles, Placement};
use super::scale::limits;
use super::{Rect, TICK_EM, missing_note};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas};
use crate::figures::colormap::{ColorMap, Rgb, series_color};
use crate::figures::layout::Bounds;
use crate::figures::model::{BarChart, BarGroup};

/// The value axis' limits: from 0 to every bar and error bound.
pub fn bar_limits(bars: &BarChart) -> Result<(f64, f64), FigureError> {
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
    limits(&values, &bars.y, 0.05)
}

pub(super) fn draw_bars<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    bars: &BarChart,
    area: Rect,
) -> Result<(), FigureError> {
    let n = bars.categories.len();
    let (ylo, yhi) = bar_limits(bars)?;
    let entries = legend_entries(bars);
    let colors: Vec<Rgb> = entries.iter().map(|e| e.color).collect();
    let show_legend =
        bars.groups.len() > 1 || bars.sign_colors || entries[0].name != bars.groups[0].name;
    // The label layout needs the slot width, which needs the y-label width: estimate the
    // slot from the body, then lay out the frame with the labels' height.
    let layout = |body: Rect| -> Result<(Frame, CategoryLabels), FigureError> {
        let slot_estimate = (body.w() - c.px(60.0)) / n as f64;
        let max_h = c.px(160.0).min(body.h() * 0.3);
        let labels = category_labels(c, &bars.categories, slot_estimate, TICK_EM, max_h)?;
        let f = frame(c, body, &bars.y, (ylo, yhi), None, labels.height)?;
        let labels = labels.for_slot(f.plot.w() / n as f64);
        Ok((f, labels))
    };
    let (mut f, mut labels) = layout(area)?;
    let mut legend = None;
    let mut body = area;
    if show_legend {
        let mut l = Legend::new(c, entries, area.w() * 0.45)?;
        let data = Obstacles {
            marks: bar_rects(bars, &f).into_iter().map(|(_, _, r)| r).collect(),
            segments: Vec::new(),
        };
        let placement = match l.inside(f.plot, &data, c.px(4.0)) {
            Some((x, y)) => Placement::Inside(x, y),
            None => {
                let placement;
                (body, placement) = l.outside(c, area)?;
                (f, labels) = layout(body)?;
                placement
            }
        };
        legend = Some((l, placement));
    }
    draw_grid(c, &f)?;
    let y0 = f.y.map(0.0);
    for (gi, k, r) in bar_rects(bars, &f) {
        let v = bars.groups[gi].values[k];
        let color = if bars.sign_colors {
            colors[if v >= 0.0 { 0 } else { 1 }]
        } else {
            colors[gi]
        };
        let inset = if r.w() > c.px(4.0) { c.px(0.5) } else { 0.0 };
        c.note_data(Bounds::new(r.l + inset, r.t, r.r - inset, r.b));
        c.fill_rect((r.l + inset, r.t), (r.r - inset, r.b), color)?;
        if let Some(e) = bars.groups[gi].error.as_ref().map(|e| e[k].abs())
            && e.is_finite()
            && e > 0.0
        {
            let x = (r.l + r.r) / 2.0;
            let (ya, yb) = (f.y.map(v - e), f.y.map(v + e));
            let cap = (r.w() * 0.25).min(c.px(4.0));
            c.line((x, ya), (x, yb), AXIS, 1.0)?;
            c.line((x - cap, ya), (x + cap, ya), AXIS, 1.0)?;
            c.line((x - cap, yb), (x + cap, yb), AXIS, 1.0)?;
        }
    }
    if ylo < 0.0 {
        c.line((f.plot.l, y0), (f.plot.r, y0), AXIS, 1.0)?;
    }
    axes(c, &f, body, &bars.x.text(), &bars.y.text())?;
    let tick = c.px(4.0);
    let slot = f.plot.w() / n as f64;
    let shown: Vec<String> = bars
        .categories
        .iter()
        .step_by(labels.step)
        .cloned()
        .collect();
    c.note_axis(&bars.x.text(), Some(n), &shown);
    for (k, label) in bars.categories.iter().enumerate().step_by(labels.step) {
        let x = f.plot.l + slot * (k as f64 + 0.5);
        c.line((x, f.plot.b), (x, f.plot.b + tick), AXIS, 1.0)?;
        draw_category_label(c, label, x, f.plot.b + tick + c.px(4.0), &labels)?;
    }
    if let Some((l, placement)) = &legend {
        let at = l.origin(*placement, f.plot, area);
        l.draw(c, at, matches!(placement, Placement::Inside(..)))?;
    }
    Ok(())
}

/// Every drawn bar as (group, category, its rectangle from 0 to the value).
fn bar_rects(bars: &BarChart, f: &Frame) -> Vec<(usize, usize, Rect)> {
    let n = bars.categories.len();
    let slot = f.plot.w() / n as f64;
    let bar_w = slot * 0.8 / bars.groups.len() as f64;
    let y0 = f.y.map(0.0);
    let mut out = Vec::new();
    for (gi, g) in bars.groups.iter().enumerate() {
        for (k, &v) in g.values.iter().enumerate() {
            if v.is_finite() {
                let l = f.plot.l + slot * (k as f64 + 0.1) + bar_w * gi as f64;
                let y = f.y.map(v);
                out.push((
                    gi,
                    k,
                    Rect {
                        l,
                        r: l + bar_w,
                        t: y.min(y0),
                        b: y.max(y0),
                    },
                ));
            }
        }
    }
    out
}

/// One entry per group in its colour; with sign colours, one per sign.
fn legend_entries(bars: &BarChart) -> Vec<LegendEntry> {
    let entry = |name: String, color: Rgb| LegendEntry {
        name,
        color,
        line: false,
        marker: None,
        band: false,
        bar: true,
    };
    let missing = |g: &BarGroup| g.values.iter().filter(|v| !v.is_finite()).count();
    if bars.sign_colors {
        let g = &bars.groups[0];
        vec![
            entry(
                missing_note(&format!("{} > 0", g.name), missing(g)),
                ColorMap::Diverging.at(0.85),
            ),
            entry(format!("{} < 0", g.name), ColorMap::Diverging.at(0.15)),
        ]
    } else {
        bars.groups
            .iter()
            .enumerate()
            .map(|(i, g)| {
                entry(
                    missing_note(&g.name, missing(g)),
                    g.color.unwrap_or(series_color(i)),
                )
            })
            .collect()
    }
}
