//! Lays out and draws a [`Figure`] on a [`Canvas`]: title, axes with ticks and light
//! gridlines, data, legends outside the data area, colour bars.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::FigureError;
use super::canvas::{AXIS, Canvas, GRID, MUTED, Marker, TEXT, WHITE};
use super::colormap::{ColorMap, Rgb, series_color};
use super::model::{
    Axis, BarChart, Chart, ColorScale, ErrorDisplay, Figure, FigureKind, Heatmap, ImageGrid,
    Orientation, Scale, Series, SeriesStyle,
};

// Font sizes (em, CSS pixels at 96 DPI).
const TITLE_EM: f64 = 15.0;
const SUBTITLE_EM: f64 = 11.0;
const AXIS_TITLE_EM: f64 = 12.0;
const TICK_EM: f64 = 10.5;
const LEGEND_EM: f64 = 11.0;
const NOTE_EM: f64 = 9.5;

/// Colour of missing heatmap cells.
const MISSING: Rgb = Rgb(0xd9, 0xd9, 0xd9);

/// Pixel rectangle: left, top, right, bottom.
#[derive(Clone, Copy, Debug)]
struct Rect {
    l: f64,
    t: f64,
    r: f64,
    b: f64,
}

impl Rect {
    fn w(&self) -> f64 {
        self.r - self.l
    }
    fn h(&self) -> f64 {
        self.b - self.t
    }
    fn overlaps(&self, o: &Rect) -> bool {
        self.l < o.r && o.l < self.r && self.t < o.b && o.t < self.b
    }
    fn contains(&self, o: &Rect) -> bool {
        o.l >= self.l && o.r <= self.r && o.t >= self.t && o.b <= self.b
    }
}

/// One numeric axis mapped onto a pixel span.
#[derive(Clone, Copy, Debug)]
struct Span {
    lo: f64,
    hi: f64,
    log: bool,
    p0: f64,
    p1: f64,
}

impl Span {
    fn map(&self, v: f64) -> f64 {
        let t = if self.log {
            (v.log10() - self.lo.log10()) / (self.hi.log10() - self.lo.log10())
        } else {
            (v - self.lo) / (self.hi - self.lo)
        };
        self.p0 + t * (self.p1 - self.p0)
    }
}

/// Axis limits covering `values` and the axis' included range, padded by `pad` of the span
/// on each side (in log space on a log axis). Falls back to a unit range when empty.
fn limits(values: &[f64], axis: &Axis, pad: f64) -> (f64, f64) {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    for &v in values.iter().filter(|&&v| axis.scale.can_draw(v)) {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if let Some([a, b]) = axis.include {
        lo = lo.min(a);
        hi = hi.max(b);
    }
    match axis.scale {
        Scale::Log => {
            if !(lo.is_finite() && hi.is_finite()) {
                return (1.0, 10.0);
            }
            let (l, h) = if hi > lo {
                (lo.log10(), hi.log10())
            } else {
                (lo.log10() - 0.5, lo.log10() + 0.5)
            };
            let p = (h - l) * pad;
            (10f64.powf(l - p), 10f64.powf(h + p))
        }
        Scale::Linear => {
            if !(lo.is_finite() && hi.is_finite()) {
                return (0.0, 1.0);
            }
            if hi <= lo {
                let d = if lo == 0.0 { 1.0 } else { lo.abs() * 0.1 };
                return (lo - d, lo + d);
            }
            let p = (hi - lo) * pad;
            // Padding never pushes a non-negative range below 0 (counts, scores).
            let l = if lo >= 0.0 { (lo - p).max(0.0) } else { lo - p };
            (l, hi + p)
        }
    }
}

/// "Nice" ticks (steps of 1, 2, 2.5 or 5 × 10^k) within `lo..=hi`, at most about `max`,
/// with the number of decimals their labels need.
fn linear_ticks(lo: f64, hi: f64, max: usize) -> (Vec<f64>, usize) {
    let raw = (hi - lo) / max.max(1) as f64;
    let exp = raw.log10().floor();
    let mag = 10f64.powf(exp);
    let (mant, extra) = [(1.0, 0), (2.0, 0), (2.5, 1), (5.0, 0), (10.0, 0)]
        .into_iter()
        .find(|(m, _)| m * mag >= raw * (1.0 - 1e-9))
        .unwrap_or((10.0, 0));
    let step = mant * mag;
    let decimals = (-(exp + if mant >= 10.0 { 1.0 } else { 0.0 })).max(0.0) as usize + extra;
    let first = (lo / step - 1e-9).ceil() as i64;
    let mut ticks = Vec::new();
    for k in first.. {
        let v = k as f64 * step;
        if v > hi + step * 1e-9 {
            break;
        }
        ticks.push(if v.abs() < step * 1e-9 { 0.0 } else { v });
    }
    (ticks, decimals)
}

fn log_ticks(lo: f64, hi: f64) -> Vec<f64> {
    let (a, b) = (lo.log10().ceil() as i32, hi.log10().floor() as i32);
    let decade = |k: i32| format!("1e{k}").parse::<f64>().unwrap_or(f64::NAN);
    let mut ticks: Vec<f64> = (a..=b).map(decade).collect();
    if ticks.len() < 3 {
        // Less than three decades: also 2× and 5× each decade.
        ticks = (a - 1..=b)
            .flat_map(|k| [1.0, 2.0, 5.0].map(|m| m * decade(k)))
            .filter(|&v| v >= lo && v <= hi)
            .collect();
    }
    ticks
}

fn format_tick(v: f64, decimals: usize) -> String {
    // Scientific notation for large values and for steps finer than 1e-4.
    let big = v != 0.0 && (v.abs() >= 1e5 || decimals > 4);
    let s = if big {
        format!("{v:e}")
    } else {
        format!("{v:.decimals$}")
    };
    // No "-0" or "-0.0".
    if s.starts_with('-') && s[1..].chars().all(|c| c == '0' || c == '.') {
        s[1..].to_string()
    } else {
        s
    }
}

fn format_log_tick(v: f64) -> String {
    let k = v.log10();
    if (k - k.round()).abs() < 1e-9 && !(-4.0..=4.0).contains(&k) {
        format!("1e{}", k.round())
    } else {
        format!("{v}")
    }
}

struct Ticks {
    values: Vec<f64>,
    labels: Vec<String>,
}

fn ticks_for(lo: f64, hi: f64, log: bool, max: usize) -> Ticks {
    if log {
        let values = log_ticks(lo, hi);
        let labels = values.iter().map(|&v| format_log_tick(v)).collect();
        Ticks { values, labels }
    } else {
        let (values, decimals) = linear_ticks(lo, hi, max);
        let labels = values.iter().map(|&v| format_tick(v, decimals)).collect();
        Ticks { values, labels }
    }
}

/// Draw any figure on the canvas (already filled with white).
pub(super) fn draw<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    fig: &Figure,
) -> Result<(), FigureError> {
    fig.validate()?;
    let area = draw_title(c, fig)?;
    if area.w() < c.px(120.0) || area.h() < c.px(80.0) {
        return Err(too_small());
    }
    match &fig.kind {
        FigureKind::Chart(chart) => draw_chart(c, chart, area),
        FigureKind::Bars(bars) => draw_bars(c, bars, area),
        FigureKind::Heatmap(h) => draw_heatmap(c, h, area),
        FigureKind::ImageGrid(g) => draw_image_grid(c, g, area),
    }
}

fn too_small() -> FigureError {
    FigureError::Options(
        "the image is too small for this figure at this DPI: enlarge it or lower the DPI".into(),
    )
}

/// Text scaled down (to at most 60%) so that it fits `max_w`.
fn fitting_em<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    text: &str,
    em: f64,
    max_w: f64,
) -> Result<f64, FigureError> {
    let (w, _) = c.text_size(text, em)?;
    Ok(if w > max_w && w > 0.0 {
        (em * max_w / w).max(em * 0.6)
    } else {
        em
    })
}

/// Title and subtitle; returns the area left for the figure body.
fn draw_title<DB: DrawingBackend>(c: &Canvas<'_, DB>, fig: &Figure) -> Result<Rect, FigureError> {
    let (w, h) = c.size();
    let m = c.px(14.0);
    let mut top = m;
    if !fig.title.is_empty() {
        let em = fitting_em(c, &fig.title, TITLE_EM, w - 2.0 * m)?;
        let lh = c.px(em * 1.3);
        c.text(
            &fig.title,
            (w / 2.0, top + lh / 2.0),
            em,
            TEXT,
            HPos::Center,
            false,
        )?;
        top += lh;
    }
    if let Some(sub) = fig.subtitle.as_deref().filter(|s| !s.is_empty()) {
        let em = fitting_em(c, sub, SUBTITLE_EM, w - 2.0 * m)?;
        let lh = c.px(em * 1.4);
        c.text(
            sub,
            (w / 2.0, top + lh / 2.0),
            em,
            MUTED,
            HPos::Center,
            false,
        )?;
        top += lh;
    }
    Ok(Rect {
        l: m,
        t: top + c.px(8.0),
        r: w - m,
        b: h - m,
    })
}

/// A legend entry: what its swatch shows.
struct LegendEntry {
    name: String,
    color: Rgb,
    line: bool,
    marker: Option<Marker>,
    band: bool,
    bar: bool,
}

/// `text`, cut with an ellipsis to fit `max_w` at size `em`.
fn truncated<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    text: &str,
    em: f64,
    max_w: f64,
) -> Result<String, FigureError> {
    if c.text_size(text, em)?.0 <= max_w {
        return Ok(text.to_string());
    }
    let chars: Vec<char> = text.chars().collect();
    for n in (1..chars.len()).rev() {
        let cut: String = chars[..n].iter().collect::<String>() + "…";
        if c.text_size(&cut, em)?.0 <= max_w {
            return Ok(cut);
        }
    }
    Ok("…".to_string())
}

/// Shorten legend names so that the legend takes at most `max_w`; returns its width.
fn fit_legend<DB: DrawingBackend>(
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

fn legend_width<DB: DrawingBackend>(
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
fn draw_legend<DB: DrawingBackend>(
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

/// Frame of a numeric chart: y axis on the left, x axis at the bottom.
struct Frame {
    plot: Rect,
    x: Span,
    y: Span,
    xt: Ticks,
    yt: Ticks,
}

/// Lay out the axes in `area` and draw gridlines (before the data).
fn frame<DB: DrawingBackend>(
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
fn axes<DB: DrawingBackend>(
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

fn missing_note(name: &str, missing: usize) -> String {
    if missing == 0 {
        name.to_string()
    } else {
        format!("{name} ({missing} missing)")
    }
}

fn draw_chart<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    area: Rect,
) -> Result<(), FigureError> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let ok = |x: f64, y: f64| xs.can_draw(x) && ys.can_draw(y);
    let mut all_x = Vec::new();
    let mut all_y = Vec::new();
    for s in &chart.series {
        for i in 0..s.x.len() {
            if ok(s.x[i], s.y[i]) {
                all_x.push(s.x[i]);
                all_y.push(s.y[i]);
                if let Some(e) = &s.error {
                    all_y.extend([e.lower[i], e.upper[i]]);
                }
            }
        }
    }
    if all_x.is_empty() {
        return Err(FigureError::Invalid(
            "the chart has no drawable point (all missing)".into(),
        ));
    }
    for r in &chart.ref_lines {
        match r.orientation {
            Orientation::Vertical => all_x.push(r.value),
            Orientation::Horizontal => all_y.push(r.value),
        }
    }
    let (xlo, xhi) = limits(&all_x, &chart.x, 0.04);
    let (ylo, yhi) = limits(&all_y, &chart.y, 0.06);

    let mut entries: Vec<LegendEntry> = chart
        .series
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let missing = (0..s.x.len()).filter(|&k| !ok(s.x[k], s.y[k])).count();
            LegendEntry {
                name: missing_note(&s.name, missing),
                color: s.color.unwrap_or(series_color(i)),
                line: s.style != SeriesStyle::Markers,
                marker: (s.style != SeriesStyle::Line).then(|| Marker::nth(i)),
                band: s
                    .error
                    .as_ref()
                    .is_some_and(|e| e.display == ErrorDisplay::Band),
                bar: false,
            }
        })
        .collect();
    let show_legend =
        chart.series.len() > 1 || entries.iter().any(|e| e.name != chart.series[0].name);
    let mut body = area;
    if show_legend {
        let lw = fit_legend(c, &mut entries, area.w() * 0.4)?;
        body.r -= lw + c.px(12.0);
    }
    let tick_label_h = c.px(TICK_EM * 1.2);
    let f = frame(
        c,
        body,
        &chart.y,
        (ylo, yhi),
        Some((&chart.x, xlo, xhi)),
        tick_label_h,
    )?;

    // Error bands under everything else.
    for (i, s) in chart.series.iter().enumerate() {
        let Some(e) = s.error.as_ref().filter(|e| e.display == ErrorDisplay::Band) else {
            continue;
        };
        let color = entries[i].color;
        let mut run: Vec<usize> = Vec::new();
        for k in 0..=s.x.len() {
            let good = k < s.x.len()
                && ok(s.x[k], s.y[k])
                && ys.can_draw(e.lower[k])
                && ys.can_draw(e.upper[k]);
            if good {
                run.push(k);
            } else if !run.is_empty() {
                let mut poly: Vec<(f64, f64)> = run
                    .iter()
                    .map(|&j| (f.x.map(s.x[j]), f.y.map(e.upper[j])))
                    .collect();
                poly.extend(
                    run.iter()
                        .rev()
                        .map(|&j| (f.x.map(s.x[j]), f.y.map(e.lower[j]))),
                );
                c.polygon(&poly, color, 0.2)?;
                run.clear();
            }
        }
    }
    for r in &chart.ref_lines {
        let p = f.plot;
        match r.orientation {
            Orientation::Vertical => {
                let x = f.x.map(r.value);
                c.dashed_line((x, p.t), (x, p.b), MUTED, 1.2)?;
                c.text(
                    &r.label,
                    (x + c.px(4.0), p.t + c.px(8.0)),
                    NOTE_EM,
                    MUTED,
                    HPos::Left,
                    false,
                )?;
            }
            Orientation::Horizontal => {
                let y = f.y.map(r.value);
                c.dashed_line((p.l, y), (p.r, y), MUTED, 1.2)?;
                c.text(
                    &r.label,
                    (p.r - c.px(4.0), y - c.px(8.0)),
                    NOTE_EM,
                    MUTED,
                    HPos::Right,
                    false,
                )?;
            }
        }
    }
    for (i, s) in chart.series.iter().enumerate() {
        let color = entries[i].color;
        if s.style != SeriesStyle::Markers {
            // The line breaks at missing points.
            let mut run = Vec::new();
            for k in 0..=s.x.len() {
                if k < s.x.len() && ok(s.x[k], s.y[k]) {
                    run.push((f.x.map(s.x[k]), f.y.map(s.y[k])));
                } else {
                    c.polyline(&run, color, 2.0)?;
                    run.clear();
                }
            }
        }
        if let Some(e) = s.error.as_ref().filter(|e| e.display == ErrorDisplay::Bars) {
            for k in (0..s.x.len()).filter(|&k| ok(s.x[k], s.y[k])) {
                if ys.can_draw(e.lower[k]) && ys.can_draw(e.upper[k]) {
                    let x = f.x.map(s.x[k]);
                    let (y0, y1) = (f.y.map(e.lower[k]), f.y.map(e.upper[k]));
                    let cap = c.px(3.0);
                    c.line((x, y0), (x, y1), color, 1.2)?;
                    c.line((x - cap, y0), (x + cap, y0), color, 1.2)?;
                    c.line((x - cap, y1), (x + cap, y1), color, 1.2)?;
                }
            }
        }
        if let Some(m) = entries[i].marker {
            for k in (0..s.x.len()).filter(|&k| ok(s.x[k], s.y[k])) {
                c.marker(m, (f.x.map(s.x[k]), f.y.map(s.y[k])), 3.5, color)?;
            }
        }
    }
    axes(c, &f, area, &chart.x.text(), &chart.y.text())?;
    draw_point_labels(c, chart, &f)?;
    if show_legend {
        draw_legend(c, &entries, body.r + c.px(12.0), f.plot.t)?;
    }
    Ok(())
}

/// Does the segment `a`–`b` cross the rectangle? (Liang–Barsky clipping.)
fn segment_hits(r: &Rect, a: (f64, f64), b: (f64, f64)) -> bool {
    let (dx, dy) = (b.0 - a.0, b.1 - a.1);
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-dx, a.0 - r.l),
        (dx, r.r - a.0),
        (-dy, a.1 - r.t),
        (dy, r.b - a.1),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
        } else {
            let t = q / p;
            if p < 0.0 {
                t0 = t0.max(t);
            } else {
                t1 = t1.min(t);
            }
            if t0 > t1 {
                return false;
            }
        }
    }
    true
}

/// Point labels beside their points: of eight positions around the point, the one that
/// crosses the fewest lines, markers and earlier labels, and stays inside the plot.
fn draw_point_labels<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    f: &Frame,
) -> Result<(), FigureError> {
    let ok =
        |s: &Series, k: usize| chart.x.scale.can_draw(s.x[k]) && chart.y.scale.can_draw(s.y[k]);
    let mut segments = Vec::new();
    let mut markers = Vec::new();
    for s in &chart.series {
        let pixel = |k: usize| (f.x.map(s.x[k]), f.y.map(s.y[k]));
        for k in (0..s.x.len()).filter(|&k| ok(s, k)) {
            let (x, y) = pixel(k);
            let m = c.px(4.0);
            markers.push(Rect {
                l: x - m,
                r: x + m,
                t: y - m,
                b: y + m,
            });
            if s.style != SeriesStyle::Markers && k + 1 < s.x.len() && ok(s, k + 1) {
                segments.push((pixel(k), pixel(k + 1)));
            }
        }
    }
    let mut placed: Vec<Rect> = Vec::new();
    let (gap, lift) = (c.px(7.0), c.px(2.0));
    for s in &chart.series {
        for (k, label) in s.point_labels.iter().enumerate() {
            if label.is_empty() || !ok(s, k) {
                continue;
            }
            let (px, py) = (f.x.map(s.x[k]), f.y.map(s.y[k]));
            let (w, h) = c.text_size(label, NOTE_EM)?;
            let at = |l: f64, t: f64| Rect {
                l,
                r: l + w,
                t,
                b: t + h,
            };
            let candidates = [
                at(px + gap, py - h / 2.0),
                at(px + gap, py - lift - h),
                at(px + gap, py + lift),
                at(px - gap - w, py - h / 2.0),
                at(px - gap - w, py - lift - h),
                at(px - gap - w, py + lift),
                at(px - w / 2.0, py - gap - h),
                at(px - w / 2.0, py + gap),
            ];
            let cost = |r: &Rect| {
                let outside = if f.plot.contains(r) { 0 } else { 100 };
                let labels = placed.iter().filter(|p| p.overlaps(r)).count() * 3;
                let marks = markers.iter().filter(|m| m.overlaps(r)).count() * 2;
                let lines = segments
                    .iter()
                    .filter(|(a, b)| segment_hits(r, *a, *b))
                    .count();
                outside + labels + marks + lines
            };
            let chosen = candidates
                .iter()
                .enumerate()
                .min_by_key(|(i, r)| (cost(r), *i))
                .map_or(candidates[0], |(_, r)| *r);
            c.text(
                label,
                (chosen.l, (chosen.t + chosen.b) / 2.0),
                NOTE_EM,
                TEXT,
                HPos::Left,
                false,
            )?;
            placed.push(chosen);
        }
    }
    Ok(())
}

/// Which category labels to draw: every `step`-th, rotated or not, and the height taken.
#[derive(Clone, Copy)]
struct CategoryLabels {
    step: usize,
    rotated: bool,
    height: f64,
    /// Room one label needs along the axis.
    needed: f64,
}

impl CategoryLabels {
    /// The same layout for the final slot width: only how many labels are skipped changes,
    /// so that the height already reserved stays right.
    fn for_slot(self, slot: f64) -> Self {
        let step = (self.needed / slot.max(1e-9)).ceil().max(1.0) as usize;
        CategoryLabels { step, ..self }
    }
}

fn category_labels<DB: DrawingBackend>(
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

fn draw_category_label<DB: DrawingBackend>(
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

fn draw_bars<DB: DrawingBackend>(
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

/// Space a vertical colour bar takes at the right of a figure.
fn colorbar_width<DB: DrawingBackend>(
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
fn draw_colorbar<DB: DrawingBackend>(
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
    if !title.is_empty() {
        let title_h = c.px(AXIS_TITLE_EM * 1.3);
        let em = fitting_em(c, &title, AXIS_TITLE_EM, bottom - top)?;
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
fn light(c: Rgb) -> bool {
    0.2126 * c.0 as f64 + 0.7152 * c.1 as f64 + 0.0722 * c.2 as f64 > 140.0
}

/// Decimals to show ~3 significant digits of the largest value (integers as integers).
fn value_decimals(values: impl Iterator<Item = f64> + Clone) -> usize {
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

fn draw_heatmap<DB: DrawingBackend>(
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
    let col_layout = category_labels(c, &h.columns, avail_w / nc as f64, TICK_EM)?;
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
    let row_step = (c.px(TICK_EM * 1.2) / ch).ceil().max(1.0) as usize;
    for (r, label) in h.rows.iter().enumerate().step_by(row_step) {
        let label = truncated(c, label, TICK_EM, area.w() * 0.3)?;
        c.text(
            &label,
            (grid.l - c.px(6.0), (ye(r) + ye(r + 1)) / 2.0),
            TICK_EM,
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
            TICK_EM,
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
    let y_title = h.y.text();
    let em = fitting_em(c, &y_title, AXIS_TITLE_EM, grid.h().max(c.px(100.0)))?;
    // Beside the row labels, not at the far left when square cells leave room.
    let title_x = (grid.l - c.px(14.0) - row_w.min(area.w() * 0.3) - axis_title_h / 2.0)
        .max(area.l + axis_title_h / 2.0);
    c.text(
        &y_title,
        (title_x, (grid.t + grid.b) / 2.0),
        em,
        TEXT,
        HPos::Center,
        true,
    )?;
    let (cb_top, cb_bottom) = colorbar_span(c, grid, area);
    draw_colorbar(
        c, &h.colors, limits, &cb_ticks, grid.r, cb_top, cb_bottom, cb_w,
    )
}

/// The colour bar spans the data's height, but at least 150 px (when there is room).
fn colorbar_span<DB: DrawingBackend>(c: &Canvas<'_, DB>, data: Rect, area: Rect) -> (f64, f64) {
    let min_h = c.px(150.0).min(area.h());
    if data.h() >= min_h {
        return (data.t, data.b);
    }
    let mid = (data.t + data.b) / 2.0;
    let top = (mid - min_h / 2.0).max(area.t);
    (top, top + min_h)
}

fn draw_image_grid<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    g: &ImageGrid,
    area: Rect,
) -> Result<(), FigureError> {
    let n = g.images.len();
    let (ih, iw) = (g.images[0].values.len(), g.images[0].values[0].len());
    let limits = g.colors.resolve(
        g.images
            .iter()
            .flat_map(|im| im.values.iter().flatten().copied()),
    );
    let (cb_w, cb_ticks) = colorbar_width(c, &g.colors, limits, area.h() * 0.7)?;
    let avail = Rect {
        l: area.l,
        t: area.t,
        r: area.r - cb_w,
        b: area.b,
    };
    let has_caption = g.images.iter().any(|im| !im.caption.is_empty());
    let cap_h = if has_caption {
        c.px(NOTE_EM * 1.8)
    } else {
        0.0
    };
    let gap = c.px(16.0);
    let cell_for = |cols: usize| {
        let rows = n.div_ceil(cols);
        let by_w = (avail.w() - gap * (cols - 1) as f64) / (cols * iw) as f64;
        let by_h = (avail.h() - gap * (rows - 1) as f64 - cap_h * rows as f64) / (rows * ih) as f64;
        by_w.min(by_h)
    };
    let cols = if g.columns > 0 {
        g.columns.min(n)
    } else {
        (1..=n)
            .max_by(|&a, &b| cell_for(a).total_cmp(&cell_for(b)))
            .unwrap_or(1)
    };
    let cs = cell_for(cols);
    if cs <= 0.0 {
        return Err(too_small());
    }
    let rows = n.div_ceil(cols);
    let (img_w, img_h) = (cs * iw as f64, cs * ih as f64);
    let total_w = img_w * cols as f64 + gap * (cols - 1) as f64;
    let total_h = (img_h + cap_h) * rows as f64 + gap * (rows - 1) as f64;
    let x0 = avail.l + (avail.w() - total_w) / 2.0;
    let y0 = avail.t + (avail.h() - total_h) / 2.0;
    let outline = cs >= c.px(8.0);
    for (i, im) in g.images.iter().enumerate() {
        let (gr, gc) = (i / cols, i % cols);
        let left = x0 + gc as f64 * (img_w + gap);
        let top = y0 + gr as f64 * (img_h + cap_h + gap);
        for (r, row) in im.values.iter().enumerate() {
            for (k, &v) in row.iter().enumerate() {
                // A missing cell has no taxel: left as background.
                if !v.is_finite() {
                    continue;
                }
                let (a, b) = (
                    (left + cs * k as f64, top + cs * r as f64),
                    (left + cs * (k + 1) as f64, top + cs * (r + 1) as f64),
                );
                c.fill_rect(a, b, g.colors.map.color(v, limits))?;
                if outline {
                    c.stroke_rect(a, b, Rgb(0xbb, 0xbb, 0xbb), 0.5)?;
                }
            }
        }
        // The sensor's outline, so that sparse images stay apart.
        let pad = c.px(2.0);
        let frame = Rgb(0xcc, 0xcc, 0xcc);
        c.stroke_rect(
            (left - pad, top - pad),
            (left + img_w + pad, top + img_h + pad),
            frame,
            1.0,
        )?;
        if !im.caption.is_empty() {
            let em = fitting_em(c, &im.caption, NOTE_EM, img_w + gap * 0.8)?;
            c.text(
                &im.caption,
                (left + img_w / 2.0, top + img_h + cap_h / 2.0),
                em,
                TEXT,
                HPos::Center,
                false,
            )?;
        }
    }
    let data = Rect {
        l: x0,
        t: y0,
        r: x0 + total_w,
        b: y0 + total_h,
    };
    let (cb_top, cb_bottom) = colorbar_span(c, data, area);
    draw_colorbar(
        c, &g.colors, limits, &cb_ticks, avail.r, cb_top, cb_bottom, cb_w,
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn linear_ticks_are_nice() {
        let (t, d) = linear_ticks(0.0, 1.0, 5);
        assert_eq!(t, vec![0.0, 0.2, 0.4, 0.6000000000000001, 0.8, 1.0]);
        assert_eq!(d, 1);
        assert_eq!(format_tick(t[3], d), "0.6");
        let (t, d) = linear_ticks(-3.0, 7.0, 4);
        assert_eq!(
            (t.first().copied(), t.last().copied(), d),
            (Some(-2.5), Some(5.0), 1)
        );
        assert_eq!(format_tick(-0.00002, 5), "-2e-5");
        assert_eq!(format_tick(250000.0, 0), "2.5e5");
        assert_eq!(format_tick(-0.001, 2), "0.00");
    }

    #[test]
    fn log_ticks_cover_decades() {
        assert_eq!(log_ticks(0.005, 200.0), vec![0.01, 0.1, 1.0, 10.0, 100.0]);
        assert_eq!(log_ticks(1.5, 30.0), vec![2.0, 5.0, 10.0, 20.0]);
        assert_eq!(format_log_tick(1e-6), "1e-6");
        assert_eq!(format_log_tick(0.01), "0.01");
    }

    #[test]
    fn segments_hit_rectangles() {
        let r = Rect {
            l: 0.0,
            t: 0.0,
            r: 10.0,
            b: 10.0,
        };
        assert!(segment_hits(&r, (-5.0, 5.0), (15.0, 5.0)));
        assert!(segment_hits(&r, (5.0, 5.0), (50.0, 50.0)));
        assert!(!segment_hits(&r, (-5.0, -1.0), (15.0, -1.0)));
        assert!(!segment_hits(&r, (11.0, 0.0), (20.0, 10.0)));
    }

    #[test]
    fn limits_include_range_and_skip_bad_values() {
        let axis = Axis::new("a", "").including(0.0, 1.0);
        assert_eq!(limits(&[0.5, f64::NAN], &axis, 0.0), (0.0, 1.0));
        let log = Axis::new("t", "s").log();
        let (lo, hi) = limits(&[-1.0, 0.01, 100.0], &log, 0.0);
        assert!((lo - 0.01).abs() < 1e-12 && (hi - 100.0).abs() < 1e-9);
    }
}
