//! Draws a `figures::Figure` on screen: the same figure data the SVG/PNG export renders,
//! so what a researcher inspects is what ends up in the paper. Charts and bars go through
//! egui_plot (hover values, zoom); heatmaps and image grids are painted cell by cell with a
//! colour bar and hover values.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Vec2};
use egui_plot::{
    AxisHints, Bar, BarChart, ColorConflictHandling, Corner, FilledArea, GridInput, GridMark,
    HLine, HoverPosition, Legend, Line, MarkerShape, Plot, PlotPoint, PlotPoints, Points, Text,
    VLine,
};

use super::heatmap::rgb;
use crate::figures::{
    self, ColorMap, ColorScale, ErrorDisplay, Figure, FigureKind, Orientation, Scale, SeriesStyle,
    series_color,
};

/// Map a value to plot coordinates (log10 on log axes); None where it cannot be drawn.
fn coord(scale: Scale, v: f64) -> Option<f64> {
    scale
        .can_draw(v)
        .then(|| if scale == Scale::Log { v.log10() } else { v })
}

/// A plot coordinate back to data units.
fn value(scale: Scale, coord: f64) -> f64 {
    if scale == Scale::Log {
        10f64.powf(coord)
    } else {
        coord
    }
}

/// egui_plot's default minimum grid spacing, in points: its `GridInput::base_step_size` is
/// this many points in plot units.
const GRID_SPACING_MIN: f64 = 8.0;

/// Grid marks at the export's ticks (1, 2, 5 × 10^k; round values on a log axis), about
/// one per `px_per_label` points and never fewer than three, so that the screen shows the
/// same ticks as the paper at any tile size.
fn tick_spacer(scale: Scale, px_per_label: f64) -> impl Fn(GridInput) -> Vec<GridMark> {
    move |input: GridInput| {
        let (lo, hi) = input.bounds;
        let px = (hi - lo) * GRID_SPACING_MIN / input.base_step_size.max(f64::MIN_POSITIVE);
        let max = (px / px_per_label).floor().clamp(3.0, 10.0) as usize;
        let coords: Vec<f64> = figures::axis_ticks(value(scale, lo), value(scale, hi), scale, max)
            .into_iter()
            .filter_map(|(v, _)| coord(scale, v))
            .collect();
        // Labels are drawn when marks are this far apart: the closest pair.
        let step = coords
            .windows(2)
            .map(|w| w[1] - w[0])
            .fold(f64::INFINITY, f64::min);
        let step = if step.is_finite() { step } else { hi - lo };
        coords
            .into_iter()
            .map(|value| GridMark {
                value,
                step_size: step,
            })
            .collect()
    }
}

fn tick_text(scale: Scale, mark: GridMark) -> String {
    figures::tick_label(value(scale, mark.value), mark.step_size, scale)
}

/// An axis whose tick labels show even when a tile is small (egui_plot hides labels
/// closer than 60 points by default).
fn axis_hints(x: bool, title: String, scale: Scale) -> AxisHints<'static> {
    let hints = if x {
        AxisHints::new_x().label_spacing(24.0..=32.0)
    } else {
        AxisHints::new_y().label_spacing(12.0..=16.0)
    };
    hints
        .label(title)
        .formatter(move |mark, _| tick_text(scale, mark))
}

/// The legend's place: the plot corner with the fewest points (in the data's own box).
fn emptiest_corner(points: &[[f64; 2]]) -> Corner {
    let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
    for p in points {
        for a in 0..2 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    let t = |p: &[f64; 2], a: usize| {
        if hi[a] > lo[a] {
            (p[a] - lo[a]) / (hi[a] - lo[a])
        } else {
            0.5
        }
    };
    // A corner box of 40 % × 45 % of the data's extent.
    let count = |right: bool, top: bool| {
        points
            .iter()
            .filter(|p| {
                let (x, y) = (t(p, 0), t(p, 1));
                (if right { x >= 0.6 } else { x <= 0.4 })
                    && (if top { y >= 0.55 } else { y <= 0.45 })
            })
            .count()
    };
    [
        (Corner::RightTop, count(true, true)),
        (Corner::LeftTop, count(false, true)),
        (Corner::RightBottom, count(true, false)),
        (Corner::LeftBottom, count(false, false)),
    ]
    .into_iter()
    .min_by_key(|&(_, n)| n)
    .map_or(Corner::RightTop, |(c, _)| c)
}

/// The legend in the emptiest corner, one entry per series in the series' colour (a
/// series' band and error bars share its entry; the solid line or markers, drawn last,
/// give the swatch its colour).
fn legend(points: &[[f64; 2]]) -> Legend {
    Legend::default()
        .position(emptiest_corner(points))
        .color_conflict_handling(ColorConflictHandling::PickLast)
        .follow_insertion_order(true)
}

/// Title, subtitle and, for figures with a legend, a button that hides or shows it.
/// Returns whether the legend is shown.
fn header(ui: &mut egui::Ui, id: &str, figure: &Figure) -> bool {
    let has_legend = match &figure.kind {
        FigureKind::Chart(c) => c.series.len() > 1,
        FigureKind::Bars(b) => b.groups.len() > 1,
        _ => false,
    };
    let key = egui::Id::unique(("figure-legend-hidden", id));
    let mut hidden = ui.ctx().data(|d| d.get_temp::<bool>(key)).unwrap_or(false);
    ui.horizontal_wrapped(|ui| {
        ui.strong(&figure.title);
        if has_legend {
            let text = if hidden { "show legend" } else { "hide legend" };
            if ui.small_button(text).clicked() {
                hidden = !hidden;
                ui.ctx().data_mut(|d| d.insert_temp(key, hidden));
            }
        }
    });
    if let Some(sub) = &figure.subtitle {
        ui.label(sub);
    }
    has_legend && !hidden
}

/// What a figure lets the user select, and what is selected now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Selection {
    /// Nothing to select.
    None,
    /// Images of an image grid can be clicked; this one (if any) is highlighted.
    Image(Option<usize>),
    /// A chart carries a marker at this x value (data units) that the pointer drags.
    Marker(f64),
    /// A heatmap's cells can be clicked; this one (if any) is outlined.
    Cell(Option<[usize; 2]>),
}

/// What the user did to a figure this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Interaction {
    pub clicked_image: Option<usize>,
    /// Where the marker was dragged or clicked to (data units).
    pub marker_x: Option<f64>,
    /// A marker point of a chart was clicked: (series, point) indices.
    pub clicked_point: Option<(usize, usize)>,
    /// The marker point of a chart under the pointer: (series, point) indices.
    pub hovered_point: Option<(usize, usize)>,
    /// A heatmap cell was clicked: [row, column].
    pub clicked_cell: Option<[usize; 2]>,
}

/// Draw `figure` in the available width, `height` points tall.
pub fn show(
    ui: &mut egui::Ui,
    id: &str,
    figure: &Figure,
    height: f32,
    selection: Selection,
) -> Interaction {
    let mut interaction = Interaction::default();
    let legend_shown = header(ui, id, figure);
    match &figure.kind {
        FigureKind::Chart(chart) => {
            show_chart(
                ui,
                id,
                chart,
                height,
                selection,
                legend_shown,
                &mut interaction,
            );
        }
        FigureKind::Bars(bars) => show_bars(ui, id, bars, height, legend_shown),
        FigureKind::Heatmap(h) => show_heatmap(ui, id, h, height, selection, &mut interaction),
        FigureKind::ImageGrid(g) => show_image_grid(ui, g, selection, &mut interaction),
    }
    interaction
}

/// The hover text of a chart point: series, point label, both values with units.
fn point_tooltip(chart: &figures::Chart, name: &str, at: PlotPoint) -> Option<String> {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let s = chart.series.iter().find(|s| s.name == name)?;
    let k = s.x.iter().zip(&s.y).position(|(&x, &y)| {
        coord(xs, x).is_some_and(|c| (c - at.x).abs() < 1e-9)
            && coord(ys, y).is_some_and(|c| (c - at.y).abs() < 1e-9)
    });
    let label = k
        .and_then(|k| s.point_labels.get(k))
        .filter(|l| !l.is_empty())
        .map_or(String::new(), |l| format!(" · {l}"));
    let (x, y) = (value(xs, at.x), value(ys, at.y));
    Some(format!(
        "{name}{label}\n{}: {} {}\n{}: {} {}",
        chart.x.title,
        exact(x),
        chart.x.unit,
        chart.y.title,
        exact(y),
        chart.y.unit
    ))
}

/// A value with up to six significant digits.
fn exact(v: f64) -> String {
    if v == 0.0 || !v.is_finite() {
        return format!("{v}");
    }
    let decimals = (5.0 - v.abs().log10().floor()).clamp(0.0, 12.0) as usize;
    let s = format!("{v:.decimals$}");
    if s.contains('.') {
        s.trim_end_matches('0').trim_end_matches('.').to_string()
    } else {
        s
    }
}

#[allow(clippy::too_many_arguments)]
fn show_chart(
    ui: &mut egui::Ui,
    id: &str,
    chart: &figures::Chart,
    height: f32,
    selection: Selection,
    legend_shown: bool,
    interaction: &mut Interaction,
) {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let all_points: Vec<[f64; 2]> = chart
        .series
        .iter()
        .flat_map(|s| {
            s.x.iter()
                .zip(&s.y)
                .filter_map(|(&x, &y)| Some([coord(xs, x)?, coord(ys, y)?]))
        })
        .collect();
    // Views scroll as pages: the wheel scrolls the page, it does not pan the plot.
    let mut plot = Plot::new(id)
        .allow_scroll(false)
        .height(height)
        .custom_x_axes(vec![axis_hints(true, chart.x.text(), xs)])
        .custom_y_axes(vec![axis_hints(false, chart.y.text(), ys)])
        .x_grid_spacer(tick_spacer(xs, 70.0))
        .y_grid_spacer(tick_spacer(ys, 36.0))
        .label_formatter(move |pos| match pos {
            HoverPosition::NearDataPoint {
                plot_name,
                position,
                ..
            } => point_tooltip(chart, plot_name, *position),
            HoverPosition::Elsewhere { .. } => None,
        });
    if legend_shown {
        plot = plot.legend(legend(&all_points));
    }
    if let Some([lo, hi]) = chart.x.include {
        plot = plot
            .include_x(coord(xs, lo).unwrap_or(lo))
            .include_x(coord(xs, hi).unwrap_or(hi));
    }
    if let Some([lo, hi]) = chart.y.include {
        plot = plot
            .include_y(coord(ys, lo).unwrap_or(lo))
            .include_y(coord(ys, hi).unwrap_or(hi));
    }
    let marker = match selection {
        Selection::Marker(x) => coord(xs, x),
        _ => None,
    };
    if marker.is_some() {
        // A drag moves the marker instead of panning the plot.
        plot = plot.allow_drag(false);
    }
    let accent = ui.visuals().selection.bg_fill;
    let shown = plot.show(ui, |p| {
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
    });
    let r = &shown.response;
    ui.ctx()
        .data_mut(|d| d.insert_temp(transform_id(id), shown.transform));
    if let Some(pos) = r.hover_pos() {
        interaction.hovered_point = nearest_marker(chart, &shown.transform, pos, 12.0);
    }
    if marker.is_some()
        && (r.dragged() || r.clicked())
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

/// One series: its band or error bars, line, markers and point labels. Everything but the
/// labels carries the series' name, so that the legend has one entry per series.
fn plot_series(
    p: &mut egui_plot::PlotUi<'_>,
    chart: &figures::Chart,
    s: &figures::Series,
    i: usize,
) {
    let (xs, ys) = (chart.x.scale, chart.y.scale);
    let color = rgb(s.color.unwrap_or_else(|| series_color(i)));
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
                    FilledArea::new(s.name.clone(), &x, &lo, &hi)
                        .fill_color(color.gamma_multiply(0.25)),
                );
            }
            ErrorDisplay::Bars => {
                for (x, lo, hi) in rows {
                    p.line(
                        Line::new(s.name.clone(), PlotPoints::new(vec![[x, lo], [x, hi]]))
                            .color(color)
                            .width(1.0),
                    );
                }
            }
        }
    }
    if matches!(s.style, SeriesStyle::Line | SeriesStyle::LineMarkers) {
        p.line(
            Line::new(s.name.clone(), PlotPoints::new(pts.clone()))
                .color(color)
                .width(2.0),
        );
    }
    // Markers on every series, so that every point has a hover value.
    let radius = if s.style == SeriesStyle::Line {
        1.5
    } else {
        3.5
    };
    p.points(
        Points::new(s.name.clone(), PlotPoints::new(pts))
            .color(color)
            .shape(MarkerShape::Circle)
            .filled(true)
            .radius(radius),
    );
    for (k, label) in s.point_labels.iter().enumerate() {
        if let (Some(&x), Some(&y)) = (s.x.get(k), s.y.get(k))
            && let (Some(x), Some(y)) = (coord(xs, x), coord(ys, y))
            && !label.is_empty()
        {
            // Unnamed: point labels are no legend entry.
            p.text(Text::new("", PlotPoint::new(x, y), label.clone()).anchor(Align2::LEFT_BOTTOM));
        }
    }
}

/// A category name cut to `max` characters (the full name is in the bar's tooltip).
fn abbreviated(name: &str, max: usize) -> String {
    if name.chars().count() <= max {
        name.to_string()
    } else {
        name.chars().take(max.saturating_sub(1)).collect::<String>() + "…"
    }
}

fn show_bars(
    ui: &mut egui::Ui,
    id: &str,
    bars: &figures::BarChart,
    height: f32,
    legend_shown: bool,
) {
    let categories = bars.categories.clone();
    let n = categories.len().max(1);
    let n_groups = bars.groups.len().max(1) as f64;
    let width = 0.8 / n_groups;
    // Every category labelled when there is room, else every k-th, abbreviated to fit.
    let slot = (ui.available_width() - 60.0).max(40.0) / n as f32;
    let chars = ((slot / 6.5).floor() as usize).clamp(3, 14);
    let longest = categories
        .iter()
        .map(|c| c.chars().count())
        .max()
        .unwrap_or(1);
    let every = if longest <= chars {
        1
    } else {
        ((longest.min(8) as f32 * 6.5) / slot).ceil().max(1.0) as usize
    };
    let y_title = bars.y.text();
    let y_unit = bars.y.unit.clone();
    let x_title = bars.x.title.clone();
    let mut plot = Plot::new(id)
        .allow_scroll(false)
        .height(height)
        .custom_x_axes(vec![
            AxisHints::new_x()
                .label(figures_axis_text(&bars.x.title, &bars.x.unit))
                .label_spacing(8.0..=10.0)
                .formatter(move |m, _| {
                    let i = m.value.round();
                    if (m.value - i).abs() < 1e-6 && i >= 0.0 {
                        categories
                            .get(i as usize)
                            .map(|c| abbreviated(c, chars.max(longest.min(8))))
                            .unwrap_or_default()
                    } else {
                        String::new()
                    }
                }),
        ])
        .custom_y_axes(vec![axis_hints(false, y_title, bars.y.scale)])
        .x_grid_spacer(move |input: GridInput| {
            let (lo, hi) = input.bounds;
            (0..n)
                .step_by(every)
                .map(|k| k as f64)
                .filter(|&k| k >= lo && k <= hi)
                .map(|value| GridMark {
                    value,
                    step_size: every as f64,
                })
                .collect()
        })
        .y_grid_spacer(tick_spacer(bars.y.scale, 36.0));
    if legend_shown {
        plot = plot.legend(
            Legend::default()
                .position(Corner::RightTop)
                .color_conflict_handling(ColorConflictHandling::PickLast),
        );
    }
    plot.show(ui, |p| {
        for (g, group) in bars.groups.iter().enumerate() {
            let color = rgb(group.color.unwrap_or_else(|| series_color(g)));
            let offset = (g as f64 - (n_groups - 1.0) / 2.0) * width;
            let items: Vec<Bar> = group
                .values
                .iter()
                .enumerate()
                .filter(|(_, v)| v.is_finite())
                .map(|(c, &v)| {
                    let fill = if bars.sign_colors {
                        rgb(ColorMap::Diverging.at(if v >= 0.0 { 0.85 } else { 0.15 }))
                    } else {
                        color
                    };
                    Bar::new(c as f64 + offset, v)
                        .width(width * 0.95)
                        .fill(fill)
                        .name(bars.categories.get(c).cloned().unwrap_or_default())
                })
                .collect();
            let (group_name, x_title, y_unit) =
                (group.name.clone(), x_title.clone(), y_unit.clone());
            p.bar_chart(
                BarChart::new(group.name.clone(), items)
                    .color(color)
                    .element_formatter(Box::new(move |bar, _| {
                        format!(
                            "{group_name}\n{x_title}: {}\n{} {y_unit}",
                            bar.name,
                            exact(bar.value)
                        )
                    })),
            );
        }
    });
}

fn show_heatmap(
    ui: &mut egui::Ui,
    id: &str,
    h: &figures::Heatmap,
    height: f32,
    selection: Selection,
    interaction: &mut Interaction,
) {
    let values: Vec<f64> = h.values.iter().flatten().copied().collect();
    let limits = h.colors.resolve(values.iter().copied());
    let rows = h.values.len();
    let cols = h.values.first().map_or(0, Vec::len);
    ui.horizontal(|ui| {
        let label_w = 110.0;
        let avail = (ui.available_width() - 180.0 - label_w).max(100.0);
        let cell = (avail / cols.max(1) as f32)
            .min((height - 40.0) / rows.max(1) as f32)
            .clamp(2.0, 60.0);
        let text = ui.visuals().text_color();
        let font = FontId::proportional(10.0);
        let columns = ColumnLabels::new(ui, &h.columns, cell, &font, text);
        let size = Vec2::new(
            label_w + cell * cols as f32,
            cell * rows as f32 + columns.height + 18.0,
        );
        let (rect, response) = ui.allocate_exact_size(size, Sense::hover());
        let painter = ui.painter_at(rect);
        let origin = rect.min + Vec2::new(label_w, 0.0);
        let mut hover = None;
        for (r, row) in h.values.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                let cr = Rect::from_min_size(
                    origin + Vec2::new(c as f32 * cell, r as f32 * cell),
                    Vec2::splat(cell),
                );
                let fill = if v.is_finite() {
                    rgb(h.colors.map.color(v, limits))
                } else {
                    Color32::from_gray(90)
                };
                painter.rect_filled(cr.shrink(0.5), 0.0, fill);
                if let Selection::Cell(chosen) = selection {
                    // Each cell is a button of its own, so it can be found by name.
                    let cell_response =
                        ui.interact(cr, ui.scope_id().with((id, r, c)), Sense::click());
                    let name = format!(
                        "{} {} × {} {}",
                        h.y.title,
                        h.rows.get(r).map_or("", String::as_str),
                        h.x.title,
                        h.columns.get(c).map_or("", String::as_str)
                    );
                    cell_response
                        .widget_info(|| egui::WidgetInfo::labeled(egui::Role::Button, true, &name));
                    if cell_response.clicked() {
                        interaction.clicked_cell = Some([r, c]);
                    }
                    if chosen == Some([r, c]) {
                        painter.rect_stroke(
                            cr.shrink(1.0),
                            0.0,
                            Stroke::new(3.0, ui.visuals().selection.bg_fill),
                            egui::StrokeKind::Inside,
                        );
                    }
                }
                if h.marked.contains(&[r, c]) {
                    painter.rect_stroke(
                        cr.shrink(1.0),
                        0.0,
                        Stroke::new(2.0, Color32::WHITE),
                        egui::StrokeKind::Inside,
                    );
                }
                if h.annotate && cell >= 22.0 && v.is_finite() {
                    let t = h.colors.map.color(v, limits);
                    let lum = 0.299 * t.0 as f32 + 0.587 * t.1 as f32 + 0.114 * t.2 as f32;
                    let tc = if lum > 140.0 {
                        Color32::BLACK
                    } else {
                        Color32::WHITE
                    };
                    painter.text(
                        cr.center(),
                        Align2::CENTER_CENTER,
                        short(v),
                        font.clone(),
                        tc,
                    );
                }
                if response.hover_pos().is_some_and(|p| cr.contains(p)) {
                    hover = Some((r, c, v));
                }
            }
        }
        // Rows shorter than a line of text label every k-th row (all are in the tooltip).
        let every_row = ((12.0 / cell).ceil() as usize).max(1);
        for (r, name) in h.rows.iter().enumerate().step_by(every_row) {
            painter.text(
                Pos2::new(origin.x - 4.0, origin.y + (r as f32 + 0.5) * cell),
                Align2::RIGHT_CENTER,
                abbreviated(name, 16),
                font.clone(),
                text,
            );
        }
        columns.paint(
            &painter,
            origin + Vec2::new(0.0, rows as f32 * cell + 4.0),
            cell,
        );
        painter.text(
            Pos2::new(origin.x + cols as f32 * cell / 2.0, rect.max.y - 2.0),
            Align2::CENTER_BOTTOM,
            figures_axis_text(&h.x.title, &h.x.unit),
            FontId::proportional(12.0),
            text,
        );
        if let Some((r, c, v)) = hover {
            response.on_hover_text_at_pointer(format!(
                "{}: {}\n{}: {}\n{}: {}",
                h.y.title,
                h.rows.get(r).map_or("", String::as_str),
                h.x.title,
                h.columns.get(c).map_or("", String::as_str),
                h.colors.title,
                if v.is_finite() {
                    format!("{v:.4}")
                } else {
                    "n/a".into()
                }
            ));
        }
        colour_bar(ui, &h.colors, limits, size.y);
    });
    ui.label(format!(
        "rows: {}",
        figures_axis_text(&h.y.title, &h.y.unit)
    ));
}

/// A heatmap's column labels: level when they fit their cells, else rotated to read
/// bottom to top (as the export does), every k-th when even a rotated line is too tall.
struct ColumnLabels {
    galleys: Vec<std::sync::Arc<egui::Galley>>,
    rotated: bool,
    every: usize,
    height: f32,
}

impl ColumnLabels {
    fn new(ui: &egui::Ui, names: &[String], cell: f32, font: &FontId, color: Color32) -> Self {
        let galleys: Vec<_> = names
            .iter()
            .map(|n| {
                ui.painter()
                    .layout_no_wrap(abbreviated(n, 14), font.clone(), color)
            })
            .collect();
        let widest = galleys.iter().map(|g| g.size().x).fold(0.0, f32::max);
        let line = galleys.first().map_or(12.0, |g| g.size().y);
        let rotated = widest + 4.0 > cell;
        let every = if rotated {
            ((line / cell).ceil() as usize).max(1)
        } else {
            1
        };
        let height = if rotated { widest } else { line };
        ColumnLabels {
            galleys,
            rotated,
            every,
            height,
        }
    }

    /// Paint under the grid, `top_left` the grid's bottom-left corner.
    fn paint(&self, painter: &egui::Painter, top_left: Pos2, cell: f32) {
        for (c, g) in self.galleys.iter().enumerate().step_by(self.every) {
            let centre = top_left.x + (c as f32 + 0.5) * cell;
            let size = g.size();
            let shape = if self.rotated {
                // Rotated about its top-left corner: the text then runs up from there.
                egui::epaint::TextShape::new(
                    Pos2::new(centre - size.y / 2.0, top_left.y + size.x),
                    g.clone(),
                    Color32::PLACEHOLDER,
                )
                .with_angle(-std::f32::consts::FRAC_PI_2)
            } else {
                egui::epaint::TextShape::new(
                    Pos2::new(centre - size.x / 2.0, top_left.y),
                    g.clone(),
                    Color32::PLACEHOLDER,
                )
            };
            painter.add(shape);
        }
    }
}

fn show_image_grid(
    ui: &mut egui::Ui,
    g: &figures::ImageGrid,
    selection: Selection,
    interaction: &mut Interaction,
) {
    let values: Vec<f64> = g
        .images
        .iter()
        .flat_map(|i| i.values.iter().flatten().copied())
        .collect();
    let limits = g.colors.resolve(values.iter().copied());
    let per_row = if g.columns > 0 { g.columns } else { 10 };
    ui.horizontal(|ui| {
        ui.vertical(|ui| {
            for (row, chunk) in g.images.chunks(per_row).enumerate() {
                ui.horizontal(|ui| {
                    for (k, img) in chunk.iter().enumerate() {
                        let i = row * per_row + k;
                        let state = match selection {
                            Selection::Image(sel) => Some(sel == Some(i)),
                            _ => None,
                        };
                        if image_cell(ui, img, g.colors.map, limits, state) {
                            interaction.clicked_image = Some(i);
                        }
                    }
                });
            }
        });
        colour_bar(ui, &g.colors, limits, 160.0);
    });
}

/// The marker point of `chart` drawn nearest to `pos`, if within `radius` points.
fn transform_id(figure_id: &str) -> egui::Id {
    egui::Id::unique(("chart-transform", figure_id))
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

fn figures_axis_text(title: &str, unit: &str) -> String {
    if unit.is_empty() {
        title.to_string()
    } else {
        format!("{title} ({unit})")
    }
}

fn short(v: f64) -> String {
    if v.abs() >= 100.0 || v == v.round() {
        format!("{v:.0}")
    } else {
        format!("{v:.2}")
    }
}

/// One image of a grid; `selected` is None when images are not clickable, else whether
/// this one is the selected one. Returns whether it was clicked.
fn image_cell(
    ui: &mut egui::Ui,
    img: &figures::GridImage,
    map: ColorMap,
    limits: (f64, f64),
    selected: Option<bool>,
) -> bool {
    let rows = img.values.len();
    let cols = img.values.first().map_or(0, Vec::len);
    let cell = (56.0 / rows.max(cols).max(1) as f32).max(3.0);
    ui.vertical(|ui| {
        let sense = if selected.is_some() {
            Sense::click()
        } else {
            Sense::hover()
        };
        let (rect, response) =
            ui.allocate_exact_size(Vec2::new(cell * cols as f32, cell * rows as f32), sense);
        if selected.is_some() {
            let caption = img.caption.clone();
            response.widget_info(|| {
                egui::WidgetInfo::labeled(egui::Role::Button, true, format!("show {caption}"))
            });
        }
        let painter = ui.painter_at(rect);
        let mut hover = None;
        for (r, row) in img.values.iter().enumerate() {
            for (c, &v) in row.iter().enumerate() {
                let cr = Rect::from_min_size(
                    rect.min + Vec2::new(c as f32 * cell, r as f32 * cell),
                    Vec2::splat(cell),
                );
                // A missing value is a cell without a taxel: background, not a colour.
                let fill = if v.is_finite() {
                    rgb(map.color(v, limits))
                } else {
                    Color32::from_gray(40)
                };
                painter.rect_filled(cr, 0.0, fill);
                if v.is_finite() && response.hover_pos().is_some_and(|p| cr.contains(p)) {
                    hover = Some(v);
                }
            }
        }
        if selected == Some(true) {
            painter.rect_stroke(
                rect,
                0.0,
                Stroke::new(2.0, ui.visuals().selection.bg_fill),
                egui::StrokeKind::Outside,
            );
        }
        let clicked = response.clicked();
        if let Some(v) = hover {
            let response = if selected.is_some() {
                response.on_hover_cursor(egui::CursorIcon::PointingHand)
            } else {
                response
            };
            response.on_hover_text_at_pointer(format!("{}: {v:.4}", img.caption));
        }
        if !img.caption.is_empty() {
            ui.small(&img.caption);
        }
        clicked
    })
    .inner
}

fn colour_bar(ui: &mut egui::Ui, scale: &ColorScale, limits: (f64, f64), height: f32) {
    let (rect, _) = ui.allocate_exact_size(Vec2::new(170.0, height), Sense::hover());
    let painter = ui.painter_at(rect);
    let bar = Rect::from_min_size(
        rect.min + Vec2::new(4.0, 20.0),
        Vec2::new(14.0, (height - 40.0).max(20.0)),
    );
    let steps = 64;
    for k in 0..steps {
        let t = k as f32 / steps as f32;
        let seg = Rect::from_min_max(
            Pos2::new(
                bar.min.x,
                bar.max.y - (t + 1.0 / steps as f32) * bar.height(),
            ),
            Pos2::new(bar.max.x, bar.max.y - t * bar.height()),
        );
        painter.rect_filled(seg, 0.0, rgb(scale.map.at(t as f64 + 0.5 / steps as f64)));
    }
    let text = ui.visuals().text_color();
    let font = FontId::proportional(10.0);
    painter.text(
        Pos2::new(bar.max.x + 3.0, bar.min.y),
        Align2::LEFT_CENTER,
        short(limits.1),
        font.clone(),
        text,
    );
    painter.text(
        Pos2::new(bar.max.x + 3.0, bar.max.y),
        Align2::LEFT_CENTER,
        short(limits.0),
        font.clone(),
        text,
    );
    if scale.map == ColorMap::Diverging {
        painter.text(
            Pos2::new(bar.max.x + 3.0, bar.center().y),
            Align2::LEFT_CENTER,
            "0",
            font.clone(),
            text,
        );
    }
    painter.text(
        rect.min + Vec2::new(2.0, 8.0),
        Align2::LEFT_CENTER,
        scale.text(),
        font,
        text,
    );
}
