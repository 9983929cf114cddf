//! The frame of a numeric chart: axes, ticks, gridlines and axis titles.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::scale::{Span, Ticks, linear_on_log, ticks_for};
use super::{AXIS_TITLE_EM, Rect, TICK_EM, fitting_em, truncated};
use crate::figures::FigureError;
use crate::figures::canvas::{AXIS, Canvas, GRID, TEXT};
use crate::figures::legibility::thin_categories;
use crate::figures::model::{Axis, Scale};

/// Frame of a numeric chart: y axis on the left, x axis at the bottom.
pub(super) struct Frame {
    pub(super) plot: Rect,
    pub(super) x: Span,
    pub(super) y: Span,
    pub(super) xt: Ticks,
    pub(super) yt: Ticks,
    /// How many categories the x axis names (a category axis), for the layout record.
    pub(super) x_categories: Option<usize>,
}

/// Lay out the axes in `area` (nothing is drawn: see [`draw_grid`] and [`axes`]).
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
    let y_max = ((bottom - top) / c.px(36.0)).floor().clamp(3.0, 10.0) as usize;
    let label_h = c.px(TICK_EM);
    let y_span = |plot_t: f64, plot_b: f64| Span {
        lo: ylo,
        hi: yhi,
        log: y_log,
        p0: plot_b,
        p1: plot_t,
    };
    // Labels a line apart at most (a log axis can offer 1…9 per decade).
    let yt = thinned(
        ticks_for(ylo, yhi, y_log, y_max),
        &y_span(top, bottom),
        |_| Ok(label_h * 1.15),
        None,
    )?;
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
    let y = y_span(plot.t, plot.b);
    let (x, xt) = match x_numeric {
        Some((axis, lo, hi)) => {
            let x = Span {
                lo,
                hi,
                log: axis.scale == Scale::Log,
                p0: plot.l,
                p1: plot.r,
            };
            let max = (plot.w() / c.px(55.0)).floor().clamp(3.0, 10.0) as usize;
            let gap = c.px(10.0);
            let room = |l: &str| Ok(c.text_size(l, TICK_EM)?.0 + gap);
            // A label centred on its tick stays on the image (the plot reaches its edge).
            let image = Some((-gap / 2.0, c.size().0 + gap / 2.0));
            let xt = if axis.categories.is_empty() {
                fitted_ticks(&x, max, room, image)?
            } else {
                category_ticks(&x, &axis.categories, room)?
            };
            (x, xt)
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
    let x_categories = x_numeric
        .map(|(axis, _, _)| axis.categories.len())
        .filter(|&n| n > 0);
    Ok(Frame {
        plot,
        x,
        y,
        xt,
        yt,
        x_categories,
    })
}

/// A category axis' ticks: each name at its position (1, 2, …), every k-th when the names
/// would touch (the rule bars and heatmaps follow), so that each drawn name fits.
fn category_ticks(
    span: &Span,
    names: &[String],
    room: impl Fn(&str) -> Result<f64, FigureError>,
) -> Result<Ticks, FigureError> {
    let mut needed: f64 = 0.0;
    for n in names {
        needed = needed.max(room(n)?);
    }
    let slot = (span.map(2.0) - span.map(1.0)).abs();
    let thin = thin_categories(names.len(), slot, needed);
    let shown: Vec<usize> = (0..names.len()).filter(|&i| thin.shows(i)).collect();
    Ok(Ticks {
        values: shown.iter().map(|&i| (i + 1) as f64).collect(),
        labels: shown.iter().map(|&i| names[i].clone()).collect(),
    })
}

/// The ticks of a numeric axis drawn along `span`: about `max` round values, thinned until
/// no two labels touch (`room`: the extent a label needs along the axis). Where a log span's
/// round values bunch in one corner and leave fewer than three labels (8e-6, 9e-6, 1e-5 on
/// 7.5e-6 … 1.8e-5; 0.06 … 0.1 on 0.05 … 0.17), round linear values spread across it.
fn fitted_ticks(
    span: &Span,
    max: usize,
    room: impl Fn(&str) -> Result<f64, FigureError>,
    within: Option<(f64, f64)>,
) -> Result<Ticks, FigureError> {
    let mut ticks = thinned(
        ticks_for(span.lo, span.hi, span.log, max),
        span,
        &room,
        within,
    )?;
    if span.log && ticks.values.len() < 3 {
        let spread = thinned(linear_on_log(span.lo, span.hi, max), span, &room, within)?;
        if spread.values.len() > ticks.values.len() {
            ticks = spread;
        }
    }
    Ok(ticks)
}

/// The ticks a screen axis from `lo` to `hi`, `length` pixels long, shows: the export's
/// rule ([`fitted_ticks`]), so that a tile and the page show the same labels, none
/// touching (`room`: a label's extent along the axis, in the same pixels).
pub fn fitted_axis_ticks(
    lo: f64,
    hi: f64,
    scale: Scale,
    length: f64,
    max: usize,
    room: impl Fn(&str) -> f64,
) -> Vec<(f64, String)> {
    let log = scale == Scale::Log;
    if !(lo.is_finite() && hi.is_finite() && hi > lo && length > 0.0) || (log && lo <= 0.0) {
        return Vec::new();
    }
    let span = Span {
        lo,
        hi,
        log,
        p0: 0.0,
        p1: length,
    };
    let Ok(ticks) = fitted_ticks(&span, max, |l: &str| Ok(room(l)), None) else {
        return Vec::new();
    };
    ticks.values.into_iter().zip(ticks.labels).collect()
}

/// Drop tick labels that would touch their neighbour (`room` is the extent a label needs
/// along the axis): every other one until none touch, so that the kept ones stay evenly
/// spaced; never below three when three fit at all. With `within` (pixels along the axis),
/// first drop the labels that would reach beyond it.
fn thinned(
    ticks: Ticks,
    span: &Span,
    room: impl Fn(&str) -> Result<f64, FigureError>,
    within: Option<(f64, f64)>,
) -> Result<Ticks, FigureError> {
    let mut need = Vec::with_capacity(ticks.labels.len());
    for l in &ticks.labels {
        need.push(room(l)?);
    }
    let inside: Vec<usize> = (0..need.len())
        .filter(|&i| {
            let p = span.map(ticks.values[i]);
            within.is_none_or(|(a, b)| p - need[i] / 2.0 >= a && p + need[i] / 2.0 <= b)
        })
        .collect();
    let ticks = Ticks {
        values: inside.iter().map(|&i| ticks.values[i]).collect(),
        labels: inside.iter().map(|&i| ticks.labels[i].clone()).collect(),
    };
    let need: Vec<f64> = inside.iter().map(|&i| need[i]).collect();
    let pos: Vec<f64> = ticks.values.iter().map(|&v| span.map(v)).collect();
    let fits = |keep: &[usize]| {
        keep.windows(2)
            .all(|w| (pos[w[1]] - pos[w[0]]).abs() >= (need[w[0]] + need[w[1]]) / 2.0)
    };
    let all: Vec<usize> = (0..pos.len()).collect();
    let mut keep = all.clone();
    let mut every = 1;
    while !fits(&keep) && pos.len().div_ceil(every + 1) >= 3 {
        every += 1;
        keep = all.iter().copied().step_by(every).collect();
    }
    if !fits(&keep) && keep.len() > 2 {
        // Unevenly spaced ticks (a log axis within a decade): the three that fit with the
        // widest margin, else the ends (better than a smear).
        let n = pos.len();
        let margin = |t: &[usize]| {
            t.windows(2)
                .map(|w| (pos[w[1]] - pos[w[0]]).abs() - (need[w[0]] + need[w[1]]) / 2.0)
                .fold(f64::INFINITY, f64::min)
        };
        let best = (0..n)
            .flat_map(|a| (a + 1..n).flat_map(move |b| (b + 1..n).map(move |c| [a, b, c])))
            .filter(|t| fits(t))
            .max_by(|s, t| margin(s).total_cmp(&margin(t)));
        keep = best.map_or_else(|| vec![0, n - 1], |t| t.to_vec());
    }
    Ok(Ticks {
        values: keep.iter().map(|&i| ticks.values[i]).collect(),
        labels: keep.iter().map(|&i| ticks.labels[i].clone()).collect(),
    })
}

/// Light gridlines at the ticks (before the data).
pub(super) fn draw_grid<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    f: &Frame,
) -> Result<(), FigureError> {
    for &v in &f.yt.values {
        let py = f.y.map(v);
        c.line((f.plot.l, py), (f.plot.r, py), GRID, 1.0)?;
    }
    for &v in &f.xt.values {
        let px = f.x.map(v);
        c.line((px, f.plot.t), (px, f.plot.b), GRID, 1.0)?;
    }
    Ok(())
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
    c.note_axis(y_title, None, &f.yt.labels);
    if !f.xt.values.is_empty() {
        c.note_axis(x_title, f.x_categories, &f.xt.labels);
    }
    // Axis titles shrink, then are cut, to their axis' length.
    let title_h = c.px(AXIS_TITLE_EM * 1.3);
    let em = fitting_em(c, x_title, AXIS_TITLE_EM, p.w())?;
    let x_title = &truncated(c, x_title, em, area.w())?;
    c.text(
        x_title,
        ((p.l + p.r) / 2.0, area.b - title_h / 2.0),
        em,
        TEXT,
        HPos::Center,
        false,
    )?;
    let em = fitting_em(c, y_title, AXIS_TITLE_EM, p.h())?;
    let y_title = &truncated(c, y_title, em, p.h())?;
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

#[cfg(test)]
mod tests {
    use super::*;

    /// Log ticks within a decade crowd towards the top: 4, 5, 6, 7 × 10⁻⁵ on a 300 px axis
    /// from 4e-5 to 7.2e-5 sit at 0, 113.9, 206.9 and 285.6 px. With labels needing 85 px
    /// only the last gap (78.7 px) is too narrow, so 4, 5 and 7 fit; the ends alone do not
    /// make three.
    #[test]
    fn uneven_ticks_keep_three_that_fit() {
        let values = vec![4e-5, 5e-5, 6e-5, 7e-5];
        let ticks = Ticks {
            labels: values.iter().map(|v| format!("{v:e}")).collect(),
            values,
        };
        let span = Span {
            lo: 4e-5,
            hi: 7.2e-5,
            log: true,
            p0: 0.0,
            p1: 300.0,
        };
        let kept = thinned(ticks, &span, |_| Ok(85.0), None).unwrap();
        assert_eq!(kept.values, vec![4e-5, 5e-5, 7e-5]);
        // When no three fit, the ends.
        let ticks = Ticks {
            values: vec![4e-5, 5e-5, 6e-5, 7e-5],
            labels: vec!["a".into(), "b".into(), "c".into(), "d".into()],
        };
        let kept = thinned(ticks, &span, |_| Ok(150.0), None).unwrap();
        assert_eq!(kept.labels, vec!["a", "d"]);
    }

    #[test]
    fn a_category_axis_names_its_categories_not_positions() {
        use crate::figures::{Figure, RenderOptions, Series, SeriesStyle, layout_of};
        let names = vec!["success".to_string(), "failure".to_string()];
        let fig = Figure::chart(
            "mf taxel 7 by outcome",
            Axis::new("outcome", "").categories(names.clone()),
            Axis::new("mf taxel 7", ""),
            vec![
                Series::new("points", vec![1.1, 1.9, 2.2], vec![1.0, 2.0, 3.0])
                    .style(SeriesStyle::Markers),
            ],
        );
        let tile = RenderOptions {
            width: 300,
            height: 200,
            dpi: 96.0,
        };
        for opts in [RenderOptions::default(), RenderOptions::column(), tile] {
            let layout = layout_of(&fig, &opts).unwrap();
            let x = (layout.axes.iter())
                .find(|a| a.title == "outcome")
                .expect("the x axis is recorded");
            assert_eq!(x.categories, Some(2));
            assert_eq!(x.labels, names);
        }
    }
}
