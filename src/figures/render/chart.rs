//! Line and scatter charts, with error bands and bars, reference lines and point labels.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::frame::{Frame, axes, frame};
use super::legend::{LegendEntry, draw_legend, fit_legend};
use super::scale::limits;
use super::{NOTE_EM, Rect, TICK_EM, missing_note};
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, MUTED, Marker, TEXT};
use crate::figures::colormap::series_color;
use crate::figures::model::{Chart, ErrorDisplay, Orientation, Series, SeriesStyle};

pub(super) fn draw_chart<DB: DrawingBackend>(
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
pub(super) fn segment_hits(r: &Rect, a: (f64, f64), b: (f64, f64)) -> bool {
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
pub(super) fn draw_point_labels<DB: DrawingBackend>(
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
