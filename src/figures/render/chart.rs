//! Line and scatter charts, with error bands and bars, reference lines and point labels.

use plotters::prelude::DrawingBackend;
use plotters::style::text_anchor::HPos;

use super::frame::{Frame, axes, draw_grid, frame};
use super::legend::{Legend, LegendEntry, Obstacles, Placement};
use super::scale::limits;
use super::{NOTE_EM, Rect, TICK_EM, missing_note};
use crate::figures::FigureError;
use crate::figures::canvas::{Canvas, MUTED, Marker, TEXT};
use crate::figures::colormap::{Rgb, series_color};
use crate::figures::layout::Bounds;
use crate::figures::model::{Chart, ErrorDisplay, Orientation, Series, SeriesStyle};

pub(super) fn draw_chart<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    area: Rect,
) -> Result<(), FigureError> {
    let [(xlo, xhi), (ylo, yhi)] = chart_limits(chart)?;
    let entries = legend_entries(chart);
    let colors: Vec<Rgb> = (chart.series.iter().enumerate())
        .map(|(i, s)| s.color.unwrap_or(series_color(i)))
        .collect();
    let show_legend = entries.len() > 1 || entries.iter().any(|e| e.name != chart.series[0].name);
    let tick_label_h = c.px(TICK_EM * 1.2);
    let layout = |body: Rect| {
        frame(
            c,
            body,
            &chart.y,
            (ylo, yhi),
            Some((&chart.x, xlo, xhi)),
            tick_label_h,
        )
    };
    let mut f = layout(area)?;
    let mut legend = None;
    let mut body = area;
    if show_legend {
        let mut l = Legend::new(c, entries, area.w() * 0.45)?;
        let placement = match l.inside(f.plot, &obstacles(c, chart, &f), c.px(4.0)) {
            Some((x, y)) => Placement::Inside(x, y),
            None => {
                let placement;
                (body, placement) = l.outside(c, area)?;
                f = layout(body)?;
                placement
            }
        };
        legend = Some((l, placement));
    }
    draw_grid(c, &f)?;
    draw_bands(c, chart, &f, &colors)?;
    for (i, s) in chart.series.iter().enumerate() {
        draw_series(c, chart, s, i, &f, colors[i])?;
    }
    axes(c, &f, body, &chart.x.text(), &chart.y.text())?;
    // Labels avoid the legend, then each other.
    let mut placed = Vec::new();
    if let Some((l, placement)) = &legend {
        let at = l.origin(*placement, f.plot, area);
        placed.push(l.draw(c, at, matches!(placement, Placement::Inside(..)))?);
    }
    draw_ref_lines(c, chart, &f, &mut placed)?;
    draw_point_labels(c, chart, &f, &mut placed)
}

/// The x and y limits: every drawable point, error bound and reference line.
pub fn chart_limits(chart: &Chart) -> Result<[(f64, f64); 2], FigureError> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let mut all_x = Vec::new();
    let mut all_y = Vec::new();
    for s in &chart.series {
        for i in 0..s.x.len() {
            if xs.can_draw(s.x[i]) && ys.can_draw(s.y[i]) {
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
    Ok([
        limits(&all_x, &chart.x, 0.04)?,
        limits(&all_y, &chart.y, 0.06)?,
    ])
}

/// One entry per series, its swatch in the series' colour: the line, the marker and the
/// band (a series' range is part of its entry, not an entry of its own; so is a line drawn
/// for it, such as its Pareto front).
fn legend_entries(chart: &Chart) -> Vec<LegendEntry> {
    let ok = |x: f64, y: f64| chart.x.scale.can_draw(x) && chart.y.scale.can_draw(y);
    let drawn_for = |s: &Series| {
        chart
            .series
            .iter()
            .any(|o| o.part_of.as_ref() == Some(&s.name) && o.style != SeriesStyle::Markers)
    };
    chart
        .series
        .iter()
        .enumerate()
        .filter(|(_, s)| s.part_of.is_none())
        .map(|(i, s)| {
            let missing = (0..s.x.len()).filter(|&k| !ok(s.x[k], s.y[k])).count();
            LegendEntry {
                name: missing_note(&s.name, missing),
                color: s.color.unwrap_or(series_color(i)),
                line: s.style != SeriesStyle::Markers || drawn_for(s),
                marker: (s.style != SeriesStyle::Line).then(|| Marker::nth(i)),
                band: s
                    .error
                    .as_ref()
                    .is_some_and(|e| e.display == ErrorDisplay::Band),
                bar: false,
            }
        })
        .collect()
}

/// The pixels the data takes: a box per point, the lines between points, error bars and
/// reference lines.
fn obstacles<DB: DrawingBackend>(c: &Canvas<'_, DB>, chart: &Chart, f: &Frame) -> Obstacles {
    let ok =
        |s: &Series, k: usize| chart.x.scale.can_draw(s.x[k]) && chart.y.scale.can_draw(s.y[k]);
    let mut o = Obstacles::default();
    let m = c.px(4.0);
    for s in &chart.series {
        let pixel = |k: usize| (f.x.map(s.x[k]), f.y.map(s.y[k]));
        for k in (0..s.x.len()).filter(|&k| ok(s, k)) {
            let (x, y) = pixel(k);
            o.marks.push(Rect {
                l: x - m,
                r: x + m,
                t: y - m,
                b: y + m,
            });
            if s.style != SeriesStyle::Markers && k + 1 < s.x.len() && ok(s, k + 1) {
                o.segments.push((pixel(k), pixel(k + 1)));
            }
            if let Some(e) = s.error.as_ref()
                && chart.y.scale.can_draw(e.lower[k])
                && chart.y.scale.can_draw(e.upper[k])
            {
                o.segments
                    .push(((x, f.y.map(e.lower[k])), (x, f.y.map(e.upper[k]))));
            }
        }
    }
    let p = f.plot;
    for r in &chart.ref_lines {
        o.segments.push(match r.orientation {
            Orientation::Vertical => ((f.x.map(r.value), p.t), (f.x.map(r.value), p.b)),
            Orientation::Horizontal => ((p.l, f.y.map(r.value)), (p.r, f.y.map(r.value))),
        });
    }
    o
}

/// Error bands, under everything else.
fn draw_bands<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    f: &Frame,
    colors: &[Rgb],
) -> Result<(), FigureError> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    for (i, s) in chart.series.iter().enumerate() {
        let Some(e) = s.error.as_ref().filter(|e| e.display == ErrorDisplay::Band) else {
            continue;
        };
        let mut run: Vec<usize> = Vec::new();
        for k in 0..=s.x.len() {
            let good = k < s.x.len()
                && xs.can_draw(s.x[k])
                && ys.can_draw(s.y[k])
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
                c.polygon(&poly, colors[i], 0.2)?;
                run.clear();
            }
        }
    }
    Ok(())
}

/// Dashed reference lines; each label at the first free place along its line (top then
/// lower rows; right then left of a vertical line), dropped when none is free.
fn draw_ref_lines<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    f: &Frame,
    placed: &mut Vec<Rect>,
) -> Result<(), FigureError> {
    let p = f.plot;
    let (gap, row) = (c.px(4.0), c.px(NOTE_EM * 1.3));
    for r in &chart.ref_lines {
        let (w, h) = c.text_size(&r.label, NOTE_EM)?;
        let candidates: Vec<Rect> = match r.orientation {
            Orientation::Vertical => {
                let x = f.x.map(r.value);
                c.dashed_line((x, p.t), (x, p.b), MUTED, 1.2)?;
                (0..3)
                    .flat_map(|k| {
                        let t = p.t + gap + k as f64 * row;
                        [x + gap, x - gap - w].map(|l| Rect {
                            l,
                            t,
                            r: l + w,
                            b: t + h,
                        })
                    })
                    .collect()
            }
            Orientation::Horizontal => {
                let y = f.y.map(r.value);
                c.dashed_line((p.l, y), (p.r, y), MUTED, 1.2)?;
                [y - gap - h, y + gap]
                    .into_iter()
                    .flat_map(|t| {
                        [p.r - gap - w, p.l + gap].map(|l| Rect {
                            l,
                            t,
                            r: l + w,
                            b: t + h,
                        })
                    })
                    .collect()
            }
        };
        if r.label.is_empty() {
            continue;
        }
        let free = candidates
            .into_iter()
            .find(|b| p.contains(b) && !placed.iter().any(|q| q.overlaps(b)));
        if let Some(b) = free {
            c.text(
                &r.label,
                (b.l, (b.t + b.b) / 2.0),
                NOTE_EM,
                MUTED,
                HPos::Left,
                false,
            )?;
            placed.push(b);
        }
    }
    Ok(())
}

/// A series' line (broken at missing points), error bars and markers.
fn draw_series<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    s: &Series,
    i: usize,
    f: &Frame,
    color: Rgb,
) -> Result<(), FigureError> {
    let ys = chart.y.scale;
    let ok = |k: usize| chart.x.scale.can_draw(s.x[k]) && ys.can_draw(s.y[k]);
    if s.style != SeriesStyle::Markers {
        let mut run = Vec::new();
        for k in 0..=s.x.len() {
            if k < s.x.len() && ok(k) {
                let (x, y) = (f.x.map(s.x[k]), f.y.map(s.y[k]));
                let r = c.px(1.5);
                c.note_data(Bounds::new(x - r, y - r, x + r, y + r));
                run.push((x, y));
            } else {
                c.polyline(&run, color, 2.0)?;
                run.clear();
            }
        }
    }
    if let Some(e) = s.error.as_ref().filter(|e| e.display == ErrorDisplay::Bars) {
        for k in (0..s.x.len()).filter(|&k| ok(k)) {
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
    if s.style != SeriesStyle::Line {
        let m = Marker::nth(i);
        for k in (0..s.x.len()).filter(|&k| ok(k)) {
            let (x, y) = (f.x.map(s.x[k]), f.y.map(s.y[k]));
            let r = c.px(3.5);
            c.note_data(Bounds::new(x - r, y - r, x + r, y + r));
            c.marker(m, (x, y), 3.5, color)?;
        }
    }
    Ok(())
}

/// Point labels beside their points: of eight positions around the point, the one that
/// crosses the fewest lines and markers, inside the plot and clear of earlier labels and
/// the legend; a label with no such place is dropped (its value is in the CSV).
fn draw_point_labels<DB: DrawingBackend>(
    c: &Canvas<'_, DB>,
    chart: &Chart,
    f: &Frame,
    placed: &mut Vec<Rect>,
) -> Result<(), FigureError> {
    let ok =
        |s: &Series, k: usize| chart.x.scale.can_draw(s.x[k]) && chart.y.scale.can_draw(s.y[k]);
    let data = obstacles(c, chart, f);
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
            let chosen = candidates
                .iter()
                .enumerate()
                .filter(|(_, r)| f.plot.contains(r) && !placed.iter().any(|p| p.overlaps(r)))
                .min_by_key(|(i, r)| (data.hit(r), *i))
                .map(|(_, r)| *r);
            if let Some(chosen) = chosen {
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
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_front_joins_its_series_legend_entry() {
        let points = Series::new("accuracy", vec![1.0, 2.0, 3.0], vec![0.5, 0.9, 0.7])
            .style(SeriesStyle::Markers);
        let front = Series::new("accuracy: Pareto front", vec![1.0, 2.0], vec![0.5, 0.9])
            .part_of("accuracy");
        let other = Series::new("NMI", vec![1.0], vec![0.4]).style(SeriesStyle::Markers);
        let chart = Chart {
            x: crate::figures::Axis::new("training time", "s"),
            y: crate::figures::Axis::new("score", ""),
            series: vec![front, points, other],
            ref_lines: Vec::new(),
        };
        let entries = legend_entries(&chart);
        let names: Vec<&str> = entries.iter().map(|e| e.name.as_str()).collect();
        assert_eq!(names, ["accuracy", "NMI"]);
        assert!(entries[0].line && entries[0].marker.is_some());
        assert!(!entries[1].line);
    }
}
