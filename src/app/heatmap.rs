//! A sensor's pressures drawn in its true layout (grid, sparse grid, or taxels at their
//! positions inside the fingertip outline), with a colour bar.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, StrokeKind, Vec2};

use crate::figures::{ColorMap, Rgb};
use crate::session::{Layout, Sensor};

pub fn rgb(c: Rgb) -> Color32 {
    Color32::from_rgb(c.0, c.1, c.2)
}

const BACKGROUND: Color32 = Color32::from_gray(45);

/// Draw one sensor's values in `map` over `range`. Hovering a taxel shows its index and value.
pub fn sensor_heatmap(
    ui: &mut egui::Ui,
    sensor: &Sensor,
    pressures: &[f64],
    range: (f64, f64),
    map: ColorMap,
    size: Vec2,
) -> egui::Response {
    draw_sensor(ui, sensor, pressures, range, map, size, Sense::hover()).0
}

/// A sensor's heatmap as [`sensor_heatmap`] draws it, that takes clicks: the taxel
/// clicked this frame, if any.
pub fn taxel_picker(
    ui: &mut egui::Ui,
    sensor: &Sensor,
    pressures: &[f64],
    range: (f64, f64),
    map: ColorMap,
    size: Vec2,
) -> Option<usize> {
    let (response, hovered) = draw_sensor(ui, sensor, pressures, range, map, size, Sense::click());
    hovered.filter(|_| response.clicked())
}

/// The heatmap, sensing `sense`, and the taxel under the pointer.
fn draw_sensor(
    ui: &mut egui::Ui,
    sensor: &Sensor,
    pressures: &[f64],
    range: (f64, f64),
    map: ColorMap,
    size: Vec2,
    sense: Sense,
) -> (egui::Response, Option<usize>) {
    let (rect, response) = ui.allocate_exact_size(size, sense);
    let painter = ui.painter_at(rect);
    let colour = |v: f64| rgb(map.color(v, range));
    // Taxel index under the pointer, with the shape drawn for it.
    let mut hovered: Option<usize> = None;
    let pointer = response.hover_pos();
    match &sensor.layout {
        Layout::Grid { rows, cols } | Layout::SparseGrid { rows, cols, .. } => {
            let (rows, cols) = (*rows, *cols);
            let cell = (rect.width() / cols as f32).min(rect.height() / rows as f32);
            let origin = rect.center() - Vec2::new(cell * cols as f32, cell * rows as f32) / 2.0;
            // Row 0 is at the base: draw it at the bottom.
            let cell_rect = |r: usize, c: usize| {
                Rect::from_min_size(
                    origin + Vec2::new(c as f32 * cell, (rows - 1 - r) as f32 * cell),
                    Vec2::splat(cell),
                )
                .shrink(1.0)
            };
            for r in 0..rows {
                for c in 0..cols {
                    painter.rect_filled(cell_rect(r, c), 2.0, BACKGROUND);
                }
            }
            for (i, &p) in pressures.iter().enumerate() {
                if let Some((r, c)) = sensor.layout.grid_cell(i) {
                    let cr = cell_rect(r, c);
                    painter.rect_filled(cr, 2.0, colour(p));
                    if pointer.is_some_and(|q| cr.contains(q)) {
                        hovered = Some(i);
                        painter.rect_stroke(
                            cr,
                            2.0,
                            Stroke::new(2.0, Color32::WHITE),
                            StrokeKind::Inside,
                        );
                    }
                }
            }
        }
        Layout::Points {
            positions,
            outline,
            radius,
        } => {
            let all = positions.iter().chain(outline.iter());
            let (mut lo, mut hi) = (Pos2::new(f32::MAX, f32::MAX), Pos2::new(f32::MIN, f32::MIN));
            for p in all {
                lo.x = lo.x.min((p.x - radius) as f32);
                lo.y = lo.y.min((p.y - radius) as f32);
                hi.x = hi.x.max((p.x + radius) as f32);
                hi.y = hi.y.max((p.y + radius) as f32);
            }
            let span = Vec2::new((hi.x - lo.x).max(1e-3), (hi.y - lo.y).max(1e-3));
            let scale = (rect.width() / span.x).min(rect.height() / span.y) * 0.95;
            let mid = Pos2::new((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0);
            // y grows towards the tip: screen y is flipped.
            let to_screen = |x: f64, y: f64| {
                rect.center() + Vec2::new((x as f32 - mid.x) * scale, -(y as f32 - mid.y) * scale)
            };
            if outline.len() >= 3 {
                let pts: Vec<Pos2> = outline.iter().map(|p| to_screen(p.x, p.y)).collect();
                painter.add(egui::Shape::convex_polygon(
                    pts,
                    BACKGROUND,
                    Stroke::new(1.0, Color32::GRAY),
                ));
            }
            let r = *radius as f32 * scale;
            for (i, (pos, &p)) in positions.iter().zip(pressures).enumerate() {
                let c = to_screen(pos.x, pos.y);
                painter.circle_filled(c, r, colour(p));
                if pointer.is_some_and(|q| q.distance(c) <= r) {
                    hovered = Some(i);
                    painter.circle_stroke(c, r, Stroke::new(2.0, Color32::WHITE));
                }
            }
        }
    }
    let response = match hovered {
        Some(i) => response.on_hover_text_at_pointer(format!(
            "{} taxel {i}: {:.1}",
            sensor.name,
            pressures.get(i).copied().unwrap_or(f64::NAN)
        )),
        None => response,
    };
    (response, hovered)
}

/// A vertical colour bar of `map` with its range, and its title and unit on two lines
/// above it.
pub fn colour_bar(
    ui: &mut egui::Ui,
    range: (f64, f64),
    map: ColorMap,
    title: &str,
    unit: &str,
    height: f32,
) {
    let width = 120.0;
    let (rect, _) = ui.allocate_exact_size(Vec2::new(width, height), Sense::hover());
    let painter = ui.painter_at(rect);
    let bar = Rect::from_min_size(
        rect.min + Vec2::new(4.0, 34.0),
        Vec2::new(14.0, height - 44.0),
    );
    let steps = 48;
    for k in 0..steps {
        let t0 = k as f32 / steps as f32;
        let seg = Rect::from_min_max(
            Pos2::new(
                bar.min.x,
                bar.max.y - (t0 + 1.0 / steps as f32) * bar.height(),
            ),
            Pos2::new(bar.max.x, bar.max.y - t0 * bar.height()),
        );
        painter.rect_filled(seg, 0.0, rgb(map.at(t0 as f64 + 0.5 / steps as f64)));
    }
    let text = ui.visuals().text_color();
    let font = FontId::proportional(11.0);
    painter.text(
        Pos2::new(bar.max.x + 4.0, bar.min.y),
        Align2::LEFT_CENTER,
        format!("{:.1}", range.1),
        font.clone(),
        text,
    );
    painter.text(
        Pos2::new(bar.max.x + 4.0, bar.max.y),
        Align2::LEFT_CENTER,
        format!("{:.1}", range.0),
        font.clone(),
        text,
    );
    painter.text(
        Pos2::new(rect.min.x, rect.min.y + 6.0),
        Align2::LEFT_CENTER,
        title,
        font.clone(),
        text,
    );
    // A view that says the unit elsewhere (a long one would be cut here) gives none.
    if !unit.is_empty() {
        painter.text(
            Pos2::new(rect.min.x, rect.min.y + 20.0),
            Align2::LEFT_CENTER,
            format!("({unit})"),
            font,
            text,
        );
    }
}
