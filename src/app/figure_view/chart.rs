//! Line and marker charts on screen through egui_plot, with hover values and clickable markers.

use super::axes::{
    TITLE_INSET, axis_hints, category_axis_hints, category_spacer, inset, legend, tick_spacer,
    x_label_room, y_label_room,
};
use super::*;

/// The hover text of a chart point: series, point label, both values with units.
fn point_tooltip(chart: &figures::Chart, name: &str, at: PlotPoint) -> Option<String> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    // The series drawn under this legend name that has this point (a front's points are
    // its owner's too, and the owner has their labels).
    let s = chart
        .series
        .iter()
        .filter(|s| s.legend_name() == name)
        .min_by_key(|s| s.part_of.is_some())?;
    let k = s.x.iter().zip(&s.y).position(|(&x, &y)| {
        coord(xs, x).is_some_and(|c| (c - at.x).abs() < 1e-9)
            && coord(ys, y).is_some_and(|c| (c - at.y).abs() < 1e-9)
    });
    let label = k
        .and_then(|k| s.point_labels.get(k))
        .filter(|l| !l.is_empty())
        .map_or(String::new(), |l| format!(" · {l}"));
    let (x, y) = (value(xs, at.x), value(ys, at.y));
    // On a category axis the slot's name, not the point's place in it.
    let x = match chart.x.category_at(x) {
        Some(c) if !chart.x.categories.is_empty() => c.to_string(),
        _ => format!("{} {}", exact(x), chart.x.unit),
    };
    Some(format!(
        "{name}{label}\n{}: {}\n{}: {} {}",
        chart.x.title,
        x.trim_end(),
        chart.y.title,
        exact(y),
        chart.y.unit
    ))
}

#[allow(clippy::too_many_arguments)]
pub(super) fn show_chart(
    ui: &mut egui::Ui,
    id: &str,
    chart: &figures::Chart,
    size: Vec2,
    selection: Selection,
    legend_corner: Option<Corner>,
    link: Option<egui::Id>,
    interaction: &mut Interaction,
) {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let entries = legend_entries(ui.ctx(), chart);
    // Views scroll as pages: the wheel scrolls the page, it does not pan the plot.
    let mut plot = Plot::new(id)
        .allow_scroll(false)
        // Room right of the frame for half the last tick label, which centres on its edge.
        .width((size.x - 20.0 - TITLE_INSET).max(0.0))
        .height(size.y)
        .custom_y_axes(vec![axis_hints(
            ui,
            false,
            &chart.y.text(),
            size.y - 50.0,
            ys,
        )])
        .y_grid_spacer(tick_spacer(ys, 36.0, Y_EDGE, y_label_room(ui)))
        .label_formatter(move |pos| match pos {
            HoverPosition::NearDataPoint {
                plot_name,
                position,
                ..
            } => point_tooltip(chart, plot_name, *position),
            HoverPosition::Elsewhere { .. } => None,
        });
    plot = if chart.x.categories.is_empty() {
        plot.custom_x_axes(vec![axis_hints(
            ui,
            true,
            &chart.x.text(),
            size.x - 80.0,
            xs,
        )])
        .x_grid_spacer(tick_spacer(xs, 70.0, X_EDGE, x_label_room(ui)))
    } else {
        let names = chart.x.categories.clone();
        plot.custom_x_axes(vec![category_axis_hints(
            ui,
            &chart.x.text(),
            size.x - 80.0,
            names,
        )])
        .x_grid_spacer(category_spacer(ui, &chart.x.categories))
    };
    if let Some(corner) = legend_corner {
        plot = plot.legend(legend(corner));
    }
    if let Some(link) = link {
        // Zoom or pan one plot of the group and every plot of it follows along x.
        plot = plot
            .link_axis(link, [true, false])
            .link_cursor(link, [true, false]);
    }
    // The export's limits: the data, its error bounds and reference lines, and the axes'
    // natural bounds (a share stops at 1).
    if let Ok([(xlo, xhi), (ylo, yhi)]) = figures::chart_limits(chart)
        && let (Some(xlo), Some(xhi), Some(ylo), Some(yhi)) = (
            coord(xs, xlo),
            coord(xs, xhi),
            coord(ys, ylo),
            coord(ys, yhi),
        )
    {
        plot = (plot.set_margin_fraction(Vec2::ZERO))
            .include_x(xlo)
            .include_x(xhi)
            .include_y(ylo)
            .include_y(yhi);
    }
    // A chart that carries a marker takes clicks as moving it, also before it has a
    // position (NaN: nothing chosen yet).
    let marker_mode = matches!(selection, Selection::Marker(_));
    let marker = match selection {
        Selection::Marker(x) => coord(xs, x),
        _ => None,
    };
    if marker_mode {
        // A drag moves the marker instead of panning the plot; a linked plot pans with the
        // middle button, so that its group's time axis can still move.
        plot = match link {
            Some(_) => plot.pan_pointer_button(egui::PointerButton::Middle),
            None => plot.allow_drag(false),
        };
    }
    let accent = ui.visuals().selection.bg_fill;
    // egui_plot draws the value axis' title a little left of its rectangle: inset it.
    let mut plot_id = egui::Id::NULL;
    let shown = inset(ui, |ui| {
        // egui_plot's own id for the plot, to read its memory below.
        plot_id = ui.make_persistent_id(egui::IdSalt::new(id));
        plot.show(ui, |p| {
            if let Some(x) = marker {
                p.vline(
                    VLine::new(format!("selected {}", chart.x.title), x)
                        .color(accent)
                        .width(2.5),
                );
            }
            for (i, s) in chart.series.iter().enumerate() {
                plot_series(p, chart, s, i);
            }
            for r in &chart.ref_lines {
                match r.orientation {
                    Orientation::Vertical => {
                        if let Some(v) = coord(xs, r.value) {
                            p.vline(VLine::new(r.label.clone(), v).color(Color32::GRAY));
                        }
                    }
                    Orientation::Horizontal => {
                        if let Some(v) = coord(ys, r.value) {
                            p.hline(HLine::new(r.label.clone(), v).color(Color32::GRAY));
                        }
                    }
                }
            }
        })
    });
    let legend_box = legend_corner.map(|corner| (corner, entries.as_slice()));
    paint_point_labels(ui, chart, &shown.transform, legend_box);
    let r = &shown.response;
    ui.ctx()
        .data_mut(|d| d.insert_temp(transform_id(id), shown.transform));
    if let Some(link) = link {
        // The group's x range once the user zoomed or panned (None while it fits the data),
        // for what follows the group without being a plot (a heatmap's time columns).
        let auto = egui_plot::PlotMemory::load(ui.ctx(), plot_id).is_none_or(|m| m.auto_bounds.x);
        let b = shown.transform.bounds();
        let range = (!auto).then(|| (value(xs, b.min()[0]), value(xs, b.max()[0])));
        ui.ctx().data_mut(|d| d.insert_temp(range_id(link), range));
    }
    if let Some(pos) = r.hover_pos() {
        interaction.hovered_point = nearest_marker(chart, &shown.transform, pos, 12.0);
    }
    if marker_mode
        && (r.dragged_by(egui::PointerButton::Primary) || r.clicked())
        && let Some(pos) = r.interact_pointer_pos()
    {
        let x = shown.transform.value_from_position(pos).x;
        interaction.marker_x = Some(value(xs, x));
    } else if r.clicked()
        && let Some(pos) = r.interact_pointer_pos()
    {
        interaction.clicked_point = nearest_marker(chart, &shown.transform, pos, 12.0);
    }
}

/// The chart's legend entries as the plot's legend shows them: one per series (a front
/// joins its owner's) and one per reference line.
pub(super) fn legend_entries(
    ctx: &egui::Context,
    chart: &figures::Chart,
) -> Vec<(String, Color32)> {
    let series = (chart.series.iter().enumerate())
        .filter(|(_, s)| s.part_of.is_none())
        .map(|(i, s)| (s.name.clone(), series_rgb(ctx, s.color, i)));
    let refs = (chart.ref_lines.iter()).map(|r| (r.label.clone(), Color32::GRAY));
    series.chain(refs).filter(|(n, _)| !n.is_empty()).collect()
}

/// A legend as a row of names in their colours, above a plot; returns the row's rectangle.
pub(crate) fn legend_row(ui: &mut egui::Ui, entries: &[(String, Color32)]) -> Rect {
    ui.horizontal_wrapped(|ui| {
        for (name, color) in entries {
            // Whole entries move to the next line; an entry is not broken across two.
            let text = egui::RichText::new(format!("— {name}")).color(*color);
            ui.add(egui::Label::new(text).truncate());
        }
    })
    .response
    .rect
}

/// One series: its band or error bars, line, markers and point labels. Everything but the
/// labels carries the series' name, so that the legend has one entry per series.
fn plot_series(
    p: &mut egui_plot::PlotUi<'_>,
    chart: &figures::Chart,
    s: &figures::Series,
    i: usize,
) {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let color = series_rgb(p.ctx(), s.color, i);
    let name = s.legend_name().to_string();
    let pts: Vec<[f64; 2]> =
        s.x.iter()
            .zip(&s.y)
            .filter_map(|(&x, &y)| Some([coord(xs, x)?, coord(ys, y)?]))
            .collect();
    if let Some(err) = &s.error {
        let rows: Vec<(f64, f64, f64)> = s
            .x
            .iter()
            .zip(err.lower.iter().zip(&err.upper))
            .filter_map(|(&x, (&lo, &hi))| Some((coord(xs, x)?, coord(ys, lo)?, coord(ys, hi)?)))
            .collect();
        match err.display {
            ErrorDisplay::Band => {
                let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
                let lo: Vec<f64> = rows.iter().map(|r| r.1).collect();
                let hi: Vec<f64> = rows.iter().map(|r| r.2).collect();
                p.add(
                    FilledArea::new(name.clone(), &x, &lo, &hi)
                        .fill_color(color.gamma_multiply(0.25)),
                );
            }
            ErrorDisplay::Bars => {
                for (x, lo, hi) in rows {
                    p.line(
                        Line::new(name.clone(), PlotPoints::new(vec![[x, lo], [x, hi]]))
                            .color(color)
                            .width(1.0),
                    );
                }
            }
        }
    }
    if matches!(s.style, SeriesStyle::Line | SeriesStyle::LineMarkers) {
        p.line(
            Line::new(name.clone(), PlotPoints::new(pts.clone()))
                .color(color)
                .width(2.0),
        );
    }
    // Markers on every series, so that every point has a hover value; a marked series takes
    // the export's shape for its index, so that series of one colour stay apart.
    let (radius, shape) = if s.style == SeriesStyle::Line {
        (1.5, MarkerShape::Circle)
    } else {
        let shapes = [
            MarkerShape::Circle,
            MarkerShape::Square,
            MarkerShape::Up,
            MarkerShape::Diamond,
        ];
        (3.5, shapes[i % shapes.len()])
    };
    p.points(
        Points::new(name.clone(), PlotPoints::new(pts))
            .color(color)
            .shape(shape)
            .filled(true)
            .radius(radius),
    );
}

/// Point labels, painted over the drawn plot where they fit (see [`place_labels`]) and
/// clear of the in-plot legend, when there is one in `legend`'s corner.
fn paint_point_labels(
    ui: &egui::Ui,
    chart: &figures::Chart,
    t: &egui_plot::PlotTransform,
    legend: Option<(Corner, &[(String, Color32)])>,
) {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let frame = *t.frame();
    let painter = ui.painter_at(frame);
    let legend =
        legend.map(|(corner, entries)| legend_rect(frame, corner, legend_size(ui, entries)));
    let font = FontId::proportional(11.0);
    let color = ui.visuals().text_color();
    let on_screen =
        |x: f64, y: f64| Some(t.position_from_point(&PlotPoint::new(coord(xs, x)?, coord(ys, y)?)));
    let points: Vec<Pos2> = chart
        .series
        .iter()
        .flat_map(|s| s.x.iter().zip(&s.y).filter_map(|(&x, &y)| on_screen(x, y)))
        .collect();
    let mut labels = Vec::new();
    for s in &chart.series {
        for (k, text) in s.point_labels.iter().enumerate() {
            if let (Some(&x), Some(&y)) = (s.x.get(k), s.y.get(k))
                && let Some(at) = on_screen(x, y)
                && !text.is_empty()
            {
                let galley = painter.layout_no_wrap(text.clone(), font.clone(), color);
                labels.push((at, galley));
            }
        }
    }
    let wanted: Vec<(Pos2, Vec2)> = labels.iter().map(|(at, g)| (*at, g.size())).collect();
    for ((_, galley), place) in
        labels
            .into_iter()
            .zip(place_labels(frame, &wanted, &points, legend.as_slice()))
    {
        if let Some(r) = place {
            painter.galley(r.min, galley, color);
        }
    }
}

/// Points of a chart the legend test looks at, at most (a long trace is read every k-th).
const LEGEND_TEST_POINTS: usize = 4000;

/// The corner of a chart of `size` whose legend of `entries` covers the fewest of the
/// chart's points, and how many it covers there. The points are placed in the plot frame
/// the chart will get (its size less the axes' room) within the export's limits, as the
/// plot draws them; a line's segments count by their midpoints too, so that a line
/// crossing the corner between two points is seen.
pub(super) fn legend_corner(
    ui: &egui::Ui,
    chart: &figures::Chart,
    entries: &[(String, Color32)],
    size: Vec2,
) -> (Corner, usize) {
    let corners = [
        Corner::RightTop,
        Corner::LeftTop,
        Corner::RightBottom,
        Corner::LeftBottom,
    ];
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let Ok([(xlo, xhi), (ylo, yhi)]) = figures::chart_limits(chart) else {
        return (Corner::RightTop, 0);
    };
    let (Some(xlo), Some(xhi), Some(ylo), Some(yhi)) = (
        coord(xs, xlo),
        coord(xs, xhi),
        coord(ys, ylo),
        coord(ys, yhi),
    ) else {
        return (Corner::RightTop, 0);
    };
    // The frame: the y axis' labels and title left of it, the x axis' below (as in
    // `show_chart`'s plot of `size`).
    let frame = Rect::from_min_size(
        Pos2::ZERO,
        Vec2::new(
            (size.x - 20.0 - TITLE_INSET - 50.0).max(1.0),
            (size.y - 40.0).max(1.0),
        ),
    );
    let at = |x: f64, y: f64| -> Option<Pos2> {
        let (x, y) = (coord(xs, x)?, coord(ys, y)?);
        let tx = if xhi > xlo {
            (x - xlo) / (xhi - xlo)
        } else {
            0.5
        };
        let ty = if yhi > ylo {
            (y - ylo) / (yhi - ylo)
        } else {
            0.5
        };
        Some(Pos2::new(
            frame.width() * tx as f32,
            frame.height() * (1.0 - ty as f32),
        ))
    };
    let total: usize = chart.series.iter().map(|s| s.x.len()).sum();
    let every = total.div_ceil(LEGEND_TEST_POINTS).max(1);
    let mut points = Vec::new();
    for s in &chart.series {
        let line = s.style != figures::SeriesStyle::Markers;
        let mut last: Option<Pos2> = None;
        for (k, (&x, &y)) in s.x.iter().zip(&s.y).enumerate().step_by(every) {
            let p = at(x, y);
            if let (Some(a), Some(b), true) = (last, p, line) {
                points.push(a.lerp(b, 0.5));
            }
            points.extend(p);
            last = p;
            // A band's or error bar's ends are drawn data too.
            if let Some(e) = &s.error {
                for v in [e.lower.get(k), e.upper.get(k)].into_iter().flatten() {
                    points.extend(at(x, *v));
                }
            }
        }
    }
    let size = legend_size(ui, entries);
    corners
        .into_iter()
        .map(|c| {
            let r = legend_rect(frame, c, size);
            (c, points.iter().filter(|p| r.contains(**p)).count())
        })
        .min_by_key(|&(_, n)| n)
        .unwrap_or((Corner::RightTop, 0))
}

/// Where egui_plot draws a legend of `size` in `corner` of `frame`: 4 points in from the
/// corner.
fn legend_rect(frame: Rect, corner: Corner, size: Vec2) -> Rect {
    let inner = frame.shrink(4.0);
    let min = match corner {
        Corner::LeftTop => inner.left_top(),
        Corner::RightTop => Pos2::new(inner.right() - size.x, inner.top()),
        Corner::LeftBottom => Pos2::new(inner.left(), inner.bottom() - size.y),
        Corner::RightBottom => inner.right_bottom() - size,
    };
    Rect::from_min_size(min, size)
}

/// The size of egui_plot's legend of `entries`: a frame with margins of 8 × 4, and one
/// row of the body font per entry with a swatch a row high (and a fifth of it apart)
/// before each name.
fn legend_size(ui: &egui::Ui, entries: &[(String, Color32)]) -> Vec2 {
    let font = egui::TextStyle::Body.resolve(ui.style());
    let galleys: Vec<_> = (entries.iter())
        .map(|(name, _)| {
            ui.painter()
                .layout_no_wrap(name.clone(), font.clone(), Color32::WHITE)
        })
        .collect();
    let row = galleys.first().map_or(0.0, |g| g.size().y);
    let width = galleys.iter().map(|g| g.size().x).fold(0.0f32, f32::max);
    let gaps = galleys.len().saturating_sub(1) as f32 * ui.spacing().item_spacing.y;
    Vec2::new(
        width + 1.2 * row + 16.0,
        galleys.len() as f32 * row + gaps + 8.0,
    )
}

/// Where each label (its point and size) goes: beside its point, above right, above left,
/// below right or below left, the first of these inside `frame` that overlaps no label
/// placed before it, no rectangle of `avoid` (the legend) and covers no point of `points`;
/// None (dropped) when none does, as the export drops it. The point's tooltip still names
/// it.
fn place_labels(
    frame: Rect,
    labels: &[(Pos2, Vec2)],
    points: &[Pos2],
    avoid: &[Rect],
) -> Vec<Option<Rect>> {
    const GAP: f32 = 4.0;
    let mut placed: Vec<Rect> = Vec::new();
    labels
        .iter()
        .map(|&(at, size)| {
            let candidates = [
                at + Vec2::new(GAP, -GAP - size.y),
                at + Vec2::new(-GAP - size.x, -GAP - size.y),
                at + Vec2::new(GAP, GAP),
                at + Vec2::new(-GAP - size.x, GAP),
            ];
            let fits = |r: &Rect| {
                frame.contains_rect(*r)
                    && !placed.iter().chain(avoid).any(|q| q.intersects(*r))
                    && !points.iter().any(|p| r.expand(2.0).contains(*p))
            };
            let r = candidates
                .into_iter()
                .map(|min| Rect::from_min_size(min, size))
                .find(fits)?;
            placed.push(r);
            Some(r)
        })
        .collect()
}

fn transform_id(figure_id: &str) -> egui::Id {
    egui::Id::unique(("chart-transform", figure_id))
}

fn range_id(link: egui::Id) -> egui::Id {
    link.with("linked-x-range")
}

/// The x range (data units) the plots linked by `link` were zoomed or panned to, None
/// while they fit their data.
pub fn linked_x_range(ctx: &egui::Context, link: egui::Id) -> Option<(f64, f64)> {
    ctx.data(|d| d.get_temp::<Option<(f64, f64)>>(range_id(link)))
        .flatten()
}

/// The x range (data units) chart `id` showed in the last frame.
pub fn shown_x_range(ctx: &egui::Context, id: &str, chart: &figures::Chart) -> Option<(f64, f64)> {
    let t: egui_plot::PlotTransform = ctx.data(|d| d.get_temp(transform_id(id)))?;
    let b = t.bounds();
    Some((
        value(chart.x.scale, b.min()[0]),
        value(chart.x.scale, b.max()[0]),
    ))
}

/// Where point `k` of series `series` of `chart`, drawn with figure id `id`, was on the
/// screen in the last frame (to point at a marker from outside the chart).
pub fn marker_position(
    ctx: &egui::Context,
    id: &str,
    chart: &figures::Chart,
    series: usize,
    k: usize,
) -> Option<Pos2> {
    let t: egui_plot::PlotTransform = ctx.data(|d| d.get_temp(transform_id(id)))?;
    let s = chart.series.get(series)?;
    let x = coord(chart.x.scale, *s.x.get(k)?)?;
    let y = coord(chart.y.scale, *s.y.get(k)?)?;
    Some(t.position_from_point(&PlotPoint::new(x, y)))
}

/// The marker point of `chart` drawn nearest to `pos`, if within `radius` points.
fn nearest_marker(
    chart: &figures::Chart,
    transform: &egui_plot::PlotTransform,
    pos: Pos2,
    radius: f32,
) -> Option<(usize, usize)> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let mut best: Option<(f32, (usize, usize))> = None;
    for (i, s) in chart.series.iter().enumerate() {
        if !matches!(s.style, SeriesStyle::Markers | SeriesStyle::LineMarkers) {
            continue;
        }
        for (k, (&x, &y)) in s.x.iter().zip(&s.y).enumerate() {
            let (Some(x), Some(y)) = (coord(xs, x), coord(ys, y)) else {
                continue;
            };
            let d = transform
                .position_from_point(&PlotPoint::new(x, y))
                .distance(pos);
            if d <= radius && best.is_none_or(|(b, _)| d < b) {
                best = Some((d, (i, k)));
            }
        }
    }
    best.map(|(_, hit)| hit)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn crowded_labels_never_overlap_cover_points_or_leave_the_plot() {
        let frame = Rect::from_min_size(Pos2::ZERO, Vec2::new(300.0, 200.0));
        let size = Vec2::new(90.0, 12.0);
        // Twelve labelled points within a few pixels of each other, and one at a corner.
        let mut points: Vec<Pos2> = (0..12)
            .map(|i| Pos2::new(150.0 + i as f32, 100.0 + (i % 3) as f32))
            .collect();
        points.push(Pos2::new(298.0, 2.0));
        let labels: Vec<(Pos2, Vec2)> = points.iter().map(|&p| (p, size)).collect();
        let placed = place_labels(frame, &labels, &points, &[]);
        let shown: Vec<Rect> = placed.iter().flatten().copied().collect();
        // Four sides of the crowd, the corner point's label inside the plot.
        assert_eq!(shown.len(), 5, "{placed:?}");
        for (i, a) in shown.iter().enumerate() {
            assert!(frame.contains_rect(*a));
            assert!(
                !points.iter().any(|p| a.contains(*p)),
                "{a:?} covers a point"
            );
            for b in &shown[i + 1..] {
                assert!(!a.intersects(*b), "{a:?} overlaps {b:?}");
            }
        }
        let corner = placed[12].expect("the lone point's label has room");
        assert!(corner.max.x <= 298.0 && corner.min.y >= 2.0);
    }

    #[test]
    fn labels_keep_clear_of_the_legend() {
        let frame = Rect::from_min_size(Pos2::ZERO, Vec2::new(300.0, 200.0));
        let size = Vec2::new(60.0, 12.0);
        let legend = Rect::from_min_max(Pos2::new(200.0, 4.0), Pos2::new(296.0, 60.0));
        // A point just left of the legend: its first choice (above right) runs into it.
        let point = Pos2::new(180.0, 40.0);
        let placed = place_labels(frame, &[(point, size)], &[point], &[legend]);
        let r = placed[0].expect("room to the left");
        assert!(!r.intersects(legend), "{r:?}");
        assert!(r.max.x <= point.x, "placed to the left: {r:?}");
        // Without the legend the first choice stands.
        let free = place_labels(frame, &[(point, size)], &[point], &[])[0].unwrap();
        assert!(free.min.x > point.x && free.intersects(legend));
    }
}
