//! Draws a `figures::Figure` on screen: the same figure data the SVG/PNG export renders,
//! so what a researcher inspects is what ends up in the paper. Charts and bars go through
//! egui_plot (hover values, zoom); heatmaps and image grids are painted cell by cell with a
//! colour bar and hover values.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Vec2};
use egui_plot::{
    Bar, BarChart, FilledArea, HLine, Legend, Line, MarkerShape, Plot, PlotPoint, PlotPoints,
    Points, Text, VLine,
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

fn tick_text(scale: Scale, v: f64) -> String {
    match scale {
        Scale::Log => {
            let x = 10f64.powf(v);
            if (0.01..10_000.0).contains(&x) {
                format!("{}", (x * 1000.0).round() / 1000.0)
            } else {
                format!("{x:.0e}")
            }
        }
        Scale::Linear => format!("{}", (v * 1e6).round() / 1e6),
    }
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
    ui.strong(&figure.title);
    if let Some(sub) = &figure.subtitle {
        ui.label(sub);
    }
    match &figure.kind {
        FigureKind::Chart(chart) => {
            let (xs, ys) = (chart.x.scale, chart.y.scale);
            // Views scroll as pages: the wheel scrolls the page, it does not pan the plot.
            let mut plot = Plot::new(id)
                .allow_scroll(false)
                .height(height)
                .legend(Legend::default())
                .x_axis_label(chart.x.text())
                .y_axis_label(chart.y.text())
                .x_axis_formatter(move |m, _| tick_text(xs, m.value))
                .y_axis_formatter(move |m, _| tick_text(ys, m.value));
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
                    let color = rgb(s.color.unwrap_or_else(|| series_color(i)));
                    let pts: Vec<[f64; 2]> =
                        s.x.iter()
                            .zip(&s.y)
                            .filter_map(|(&x, &y)| Some([coord(xs, x)?, coord(ys, y)?]))
                            .collect();
                    if let Some(err) = &s.error {
                        let rows: Vec<(f64, f64, f64)> =
                            s.x.iter()
                                .zip(err.lower.iter().zip(&err.upper))
                                .filter_map(|(&x, (&lo, &hi))| {
                                    Some((coord(xs, x)?, coord(ys, lo)?, coord(ys, hi)?))
                                })
                                .collect();
                        match err.display {
                            ErrorDisplay::Band => {
                                let x: Vec<f64> = rows.iter().map(|r| r.0).collect();
                                let lo: Vec<f64> = rows.iter().map(|r| r.1).collect();
                                let hi: Vec<f64> = rows.iter().map(|r| r.2).collect();
                                p.add(
                                    FilledArea::new(format!("{} range", s.name), &x, &lo, &hi)
                                        .fill_color(color.gamma_multiply(0.25)),
                                );
                            }
                            ErrorDisplay::Bars => {
                                for (x, lo, hi) in rows {
                                    p.line(
                                        Line::new(
                                            s.name.clone(),
                                            PlotPoints::new(vec![[x, lo], [x, hi]]),
                                        )
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
                    if matches!(s.style, SeriesStyle::Markers | SeriesStyle::LineMarkers) {
                        p.points(
                            Points::new(s.name.clone(), PlotPoints::new(pts.clone()))
                                .color(color)
                                .shape(MarkerShape::Circle)
                                .filled(true)
                                .radius(3.5),
                        );
                    }
                    for (k, label) in s.point_labels.iter().enumerate() {
                        if let (Some(&x), Some(&y)) = (s.x.get(k), s.y.get(k))
                            && let (Some(x), Some(y)) = (coord(xs, x), coord(ys, y))
                            && !label.is_empty()
                        {
                            p.text(
                                Text::new(s.name.clone(), PlotPoint::new(x, y), label.clone())
                                    .anchor(Align2::LEFT_BOTTOM),
                            );
                        }
                    }
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
                interaction.marker_x = Some(if xs == Scale::Log { 10f64.powf(x) } else { x });
            } else if r.clicked()
                && let Some(pos) = r.interact_pointer_pos()
            {
                interaction.clicked_point = nearest_marker(chart, &shown.transform, pos, 12.0);
            }
        }
        FigureKind::Bars(bars) => {
            let categories = bars.categories.clone();
            let n_groups = bars.groups.len().max(1) as f64;
            let width = 0.8 / n_groups;
            Plot::new(id)
                .allow_scroll(false)
                .height(height)
                .legend(Legend::default())
                .x_axis_label(figures_axis_text(&bars.x.title, &bars.x.unit))
                .y_axis_label(bars.y.text())
                .x_axis_formatter(move |m, _| {
                    let i = m.value.round();
                    if (m.value - i).abs() < 1e-6 && i >= 0.0 {
                        categories.get(i as usize).cloned().unwrap_or_default()
                    } else {
                        String::new()
                    }
                })
                .show(ui, |p| {
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
                        p.bar_chart(BarChart::new(group.name.clone(), items).color(color));
                    }
                });
        }
        FigureKind::Heatmap(h) => {
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
                let size = Vec2::new(label_w + cell * cols as f32, cell * rows as f32 + 40.0);
                let (rect, response) = ui.allocate_exact_size(size, Sense::hover());
                let painter = ui.painter_at(rect);
                let origin = rect.min + Vec2::new(label_w, 0.0);
                let text = ui.visuals().text_color();
                let font = FontId::proportional(10.0);
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
                            cell_response.widget_info(|| {
                                egui::WidgetInfo::labeled(egui::Role::Button, true, &name)
                            });
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
                for (r, name) in h.rows.iter().enumerate() {
                    painter.text(
                        Pos2::new(origin.x - 4.0, origin.y + (r as f32 + 0.5) * cell),
                        Align2::RIGHT_CENTER,
                        name,
                        font.clone(),
                        text,
                    );
                }
                let every = ((12.0 / cell).ceil() as usize).max(1);
                for (c, name) in h.columns.iter().enumerate().filter(|(c, _)| c % every == 0) {
                    painter.text(
                        Pos2::new(
                            origin.x + (c as f32 + 0.5) * cell,
                            origin.y + rows as f32 * cell + 4.0,
                        ),
                        Align2::CENTER_TOP,
                        name,
                        font.clone(),
                        text,
                    );
                }
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
        FigureKind::ImageGrid(g) => {
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
    }
    interaction
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
