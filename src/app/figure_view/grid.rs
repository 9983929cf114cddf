//! Heatmaps and image grids, painted cell by cell with a colour bar and hover values.

use super::*;

pub(super) fn show_heatmap(
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

/// The width a colour bar takes: the bar, its ticks and its title.
const COLOUR_BAR_W: f32 = 170.0;

pub(super) fn show_image_grid(
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
    // As many images a row as the tile holds beside the colour bar (the bar goes below
    // when fewer than three would), so that no image is cut off at a narrow tile.
    let image_w = g
        .images
        .iter()
        .map(|img| {
            let rows = img.values.len();
            let cols = img.values.first().map_or(0, Vec::len);
            (56.0 / rows.max(cols).max(1) as f32).max(3.0) * cols as f32
        })
        .fold(40.0_f32, f32::max)
        + ui.spacing().item_spacing.x;
    let fit = |w: f32| ((w / image_w).floor() as usize).max(1);
    let avail = ui.available_width();
    let beside = fit(avail - COLOUR_BAR_W - ui.spacing().item_spacing.x);
    let fitted = if beside >= 3 { beside } else { fit(avail) };
    let per_row = (if g.columns > 0 { g.columns } else { 10 }).min(fitted);
    ui.horizontal_wrapped(|ui| {
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
    let (rect, _) = ui.allocate_exact_size(Vec2::new(COLOUR_BAR_W, height), Sense::hover());
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
