//! The frame of a numeric chart: axes, ticks, gridlines and axis titles.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::scale::{Span, Ticks, ticks_for};
use super::{AXIS_TITLE_EM, Rect, TICK_EM, fitting_em};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas, GRID, TEXT};
use crate::figures::model::{Axis, Scale};

/// Frame of a numeric chart: y axis on the left, x axis at the bottom.
pub(super) struct Frame {
    pub(super) plot: Rect,
    pub(super) x: Span,
    pub(super) y: Span,
    pub(super) xt: Ticks,
    pub(super) yt: Ticks,
}

/// Lay out the axes in `area` and draw gridlines (before the data).
pub(super) fn frame<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    area: Rect,
    y_axis: &Axis,
    (ylo, yhi): (f64, f64),
    x_numeric: Option<(&Axis, f64, f64)>,
    x_label_h: f64,
) -> Result<Frame, FigureError> {
    let y_log = y_axis.scale == Scale::Log;
    let axis_title_h = c.px(AXIS_TITLE_EM * 1.3);
    let bottom = area.b - axis_title_h - c.px(6.0) - x_label_h - c.px(8.0);
    let top = area.t + c.px(4.0);
    let y_max = ((bottom - top) / c.px(42.0)).floor().clamp(2.0, 10.0) as usize;
    let yt = ticks_for(ylo, yhi, y_log, y_max);
    let mut label_w: f64 = 0.0;
    for l in &yt.labels {
        label_w = label_w.max(c.text_size(l, TICK_EM)?.0);
    }
    let left = area.l + axis_title_h + c.px(6.0) + label_w + c.px(8.0);
    let plot = Rect {
        l: left,
        t: top,
        r: area.r,
        b: bottom,
    };
    let y = Span {
        lo: ylo,
        hi: yhi,
        log: y_log,
        p0: plot.b,
        p1: plot.t,
    };
    let (x, xt) = match x_numeric {
        Some((axis, lo, hi)) => {
            let log = axis.scale == Scale::Log;
            let mut max = (plot.w() / c.px(55.0)).floor().clamp(3.0, 10.0) as usize;
            // Fewer ticks until their labels do not touch.
            let xt = loop {
                let t = ticks_for(lo, hi, log, max);
                let mut widest: f64 = 0.0;
                for l in &t.labels {
                    widest = widest.max(c.text_size(l, TICK_EM)?.0);
                }
                if log || max <= 2 || (widest + c.px(12.0)) * t.values.len() as f64 <= plot.w() {
                    break t;
                }
                max -= 1;
            };
            (
                Span {
                    lo,
                    hi,
                    log,
                    p0: plot.l,
                    p1: plot.r,
                },
                xt,
            )
        }
        None => (
            Span {
                lo: 0.0,
                hi: 1.0,
                log: false,
                p0: plot.l,
                p1: plot.r,
            },
            Ticks {
                values: Vec::new(),
                labels: Vec::new(),
            },
        ),
    };
    for &v in &yt.values {
        let py = y.map(v);
        c.line((plot.l, py), (plot.r, py), GRID, 1.0)?;
    }
    for &v in &xt.values {
        let px = x.map(v);
        c.line((px, plot.t), (px, plot.b), GRID, 1.0)?;
    }
    Ok(Frame { plot, x, y, xt, yt })
}

/// Spines, ticks, tick labels and axis titles (after the data).
pub(super) fn axes<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    f: &Frame,
    area: Rect,
    x_title: &str,
    y_title: &str,
) -> Result<(), FigureError> {
    let p = f.plot;
    let tick = c.px(4.0);
    c.line((p.l, p.t), (p.l, p.b), AXIS, 1.0)?;
    c.line((p.l, p.b), (p.r, p.b), AXIS, 1.0)?;
    for (v, l) in f.yt.values.iter().zip(&f.yt.labels) {
        let y = f.y.map(*v);
        c.line((p.l - tick, y), (p.l, y), AXIS, 1.0)?;
        c.text(
            l,
            (p.l - tick - c.px(4.0), y),
            TICK_EM,
            TEXT,
            HPos::Right,
            false,
        )?;
    }
    let label_y = p.b + tick + c.px(4.0) + c.px(TICK_EM * 0.6);
    for (v, l) in f.xt.values.iter().zip(&f.xt.labels) {
        let x = f.x.map(*v);
        c.line((x, p.b), (x, p.b + tick), AXIS, 1.0)?;
        c.text(l, (x, label_y), TICK_EM, TEXT, HPos::Center, false)?;
    }
    let title_h = c.px(AXIS_TITLE_EM * 1.3);
    let em = fitting_em(c, x_title, AXIS_TITLE_EM, p.w())?;
    c.text(
        x_title,
        ((p.l + p.r) / 2.0, area.b - title_h / 2.0),
        em,
        TEXT,
        HPos::Center,
        false,
    )?;
    let em = fitting_em(c, y_title, AXIS_TITLE_EM, p.h())?;
    c.text(
        y_title,
        (area.l + title_h / 2.0, (p.t + p.b) / 2.0),
        em,
        TEXT,
        HPos::Center,
        true,
    )?;
    Ok(())
}
