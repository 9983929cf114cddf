//! Heatmaps and image grids, painted cell by cell with a colour bar and hover values. Both
//! take the whole body they are given: the cells grow with it, and the labels follow the
//! export's rules (`figures::legibility`): every row and column named when the names fit,
//! else every k-th, all of them on hover.

use std::sync::Arc;

use egui::Galley;

use super::*;
use crate::figures::legibility::{decimals_for, thin_categories, tick_count, value_text};

/// The smallest pixel of an image grid's images, in points.
const MIN_IMAGE_CELL: f32 = 1.0;
/// The smallest square cell; below it, cells stretch to fill the body.
const MIN_SQUARE: f32 = 8.0;
/// The thinnest stretched cell: a body less than half a point per row runs past its edge.
const MIN_STRIP: f32 = 0.5;
/// Room between the parts of a matrix (labels, cells, colour bar).
const GAP: f32 = 4.0;

fn label_font() -> FontId {
    FontId::proportional(11.0)
}

/// The height of a line of `font`.
fn line_height(ui: &egui::Ui, font: &FontId) -> f32 {
    (ui.painter())
        .layout_no_wrap("0".into(), font.clone(), Color32::WHITE)
        .size()
        .y
}

/// `text` laid out on one line, cut with an ellipsis to at most `max_w`.
fn fitted(ui: &egui::Ui, text: &str, font: &FontId, max_w: f32) -> Arc<Galley> {
    let color = ui.visuals().text_color();
    let text = fit_text(ui, text, font, max_w);
    ui.painter().layout_no_wrap(text, font.clone(), color)
}

/// A text shape of `galley` at `pos`, turned to read bottom to top when `rotated` (then
/// `pos` is where its bottom-left corner lands).
fn text_shape(galley: Arc<Galley>, pos: Pos2, rotated: bool, color: Color32) -> egui::Shape {
    if rotated {
        egui::epaint::TextShape::new(pos, galley, color)
            .with_angle(-std::f32::consts::FRAC_PI_2)
            .into()
    } else {
        egui::epaint::TextShape::new(pos, galley, color).into()
    }
}

pub(super) fn show_heatmap(
    ui: &mut egui::Ui,
    id: &str,
    h: &figures::Heatmap,
    size: Vec2,
    selection: Selection,
    interaction: &mut Interaction,
) {
    let values: Vec<f64> = h.values.iter().flatten().copied().collect();
    let limits = h.colors.resolve(values.iter().copied());
    let rows = h.values.len().max(1);
    let cols = h.values.first().map_or(0, Vec::len).max(1);
    let font = label_font();
    let line = line_height(ui, &font) + 2.0;
    let text = ui.visuals().text_color();
    let bar_w = colour_bar_width(ui, &h.colors, limits);
    // Row names take at most a quarter of the width; column names stand when they fit
    // their cells, else they are turned, at most a quarter of the height tall.
    let row_w = (h.rows.iter())
        .map(|r| fitted(ui, r, &font, size.x * 0.25).size().x)
        .fold(0.0f32, f32::max);
    let col_w = (h.columns.iter())
        .map(|c| fitted(ui, c, &font, size.y * 0.25).size().x)
        .fold(0.0f32, f32::max);
    // Square cells while they stay at least MIN_SQUARE; a matrix of more rows or columns
    // than that holds (a strip of two hundred grasps × time) stretches its cells to fill
    // the body instead, as an image would, rather than running past it.
    let cell_for = |col_h: f32| {
        let w = size.x - line - row_w - bar_w - 3.0 * GAP;
        // Half a line above the cells, for the first row's name and the bar's top tick.
        let ht = size.y - col_h - 1.5 * line - 2.0 * GAP;
        let fill = Vec2::new(w / cols as f32, ht / rows as f32).max(Vec2::ZERO);
        if fill.min_elem() >= MIN_SQUARE {
            Vec2::splat(fill.min_elem())
        } else {
            fill.max(Vec2::splat(MIN_STRIP))
        }
    };
    let mut cell = cell_for(line);
    let rotated = col_w + GAP > cell.x;
    if rotated {
        cell = cell_for(col_w);
    }
    let col_h = if rotated { col_w } else { line };
    let row_thin = thin_categories(rows, cell.y as f64, line as f64);
    let col_thin = thin_categories(
        cols,
        cell.x as f64,
        if rotated { line } else { col_w + GAP } as f64,
    );
    let (rect, response) = ui.allocate_exact_size(size, Sense::hover());
    let painter = ui.painter_at(rect);
    let origin = rect.min + Vec2::new(line + row_w + GAP, line / 2.0);
    let grid = Rect::from_min_size(origin, cell * Vec2::new(cols as f32, rows as f32));
    let decimals = decimals_for(&values);
    let annotations: Vec<Option<Arc<Galley>>> = (values.iter())
        .map(|v| {
            (h.annotate && v.is_finite()).then(|| {
                ui.painter()
                    .layout_no_wrap(value_text(*v, decimals), font.clone(), text)
            })
        })
        .collect();
    // Values are written in the cells only when every one fits.
    let annotate = annotations
        .iter()
        .flatten()
        .all(|g| g.size().x + GAP <= cell.x && g.size().y <= cell.y);
    let mut hover = None;
    for (r, row) in h.values.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            let cr = Rect::from_min_size(origin + Vec2::new(c as f32, r as f32) * cell, cell);
            let fill = if v.is_finite() {
                rgb(h.colors.map.color(v, limits))
            } else {
                Color32::from_gray(90)
            };
            painter.rect_filled(cr, 0.0, fill);
            if let Selection::Cell(chosen) = selection {
                // Each cell is a button of its own, so it can be found by name.
                let cell_response = ui.interact(cr, ui.scope_id().with((id, r, c)), Sense::click());
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
                if cell_response.hovered() {
                    hover = Some((r, c, v, cell_response.clone()));
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
            if annotate && let Some(g) = &annotations[r * cols + c] {
                let t = h.colors.map.color(v, limits);
                let lum = 0.299 * t.0 as f32 + 0.587 * t.1 as f32 + 0.114 * t.2 as f32;
                let tc = if lum > 140.0 {
                    Color32::BLACK
                } else {
                    Color32::WHITE
                };
                painter.galley(cr.center() - g.size() / 2.0, g.clone(), tc);
            }
            if hover.is_none() && response.hover_pos().is_some_and(|p| cr.contains(p)) {
                hover = Some((r, c, v, response.clone()));
            }
        }
    }
    // Row names right-aligned against the cells, column names under them.
    let row_font = FontId::new(font.size * row_thin.scale as f32, font.family.clone());
    for (r, name) in h
        .rows
        .iter()
        .enumerate()
        .filter(|(r, _)| row_thin.shows(*r))
    {
        let g = fitted(ui, name, &row_font, row_w);
        let y = origin.y + (r as f32 + 0.5) * cell.y - g.size().y / 2.0;
        painter.galley(Pos2::new(origin.x - GAP - g.size().x, y), g, text);
    }
    let col_font = FontId::new(font.size * col_thin.scale as f32, font.family.clone());
    for (c, name) in (h.columns.iter().enumerate()).filter(|(c, _)| col_thin.shows(*c)) {
        // Standing names have their cell's width; turned ones the height below the grid.
        let g = fitted(ui, name, &col_font, if rotated { col_h } else { cell.x });
        let centre = origin.x + (c as f32 + 0.5) * cell.x;
        let top = grid.bottom() + GAP;
        let size = g.size();
        let pos = if rotated {
            Pos2::new(centre - size.y / 2.0, top + size.x)
        } else {
            Pos2::new(centre - size.x / 2.0, top)
        };
        painter.add(text_shape(g, pos, rotated, text));
    }
    let x_title = fitted(ui, &h.x.text(), &font, size.x - line);
    let at = Pos2::new(
        (grid.center().x - x_title.size().x / 2.0).max(rect.left() + line),
        grid.bottom() + GAP + col_h + GAP,
    );
    painter.galley(at, x_title, text);
    let y_title = fitted(ui, &h.y.text(), &font, grid.height().max(line));
    let at = Pos2::new(rect.left(), grid.center().y + y_title.size().x / 2.0);
    painter.add(text_shape(y_title, at, true, text));
    let bar = Rect::from_min_size(
        Pos2::new(grid.right() + 2.0 * GAP, grid.top()),
        Vec2::new(bar_w, grid.height().max(4.0 * line)),
    );
    colour_bar(ui, &painter, bar, &h.colors, limits);
    if let Some((r, c, v, response)) = hover {
        let value = if v.is_finite() {
            value_text(v, decimals.max(1))
        } else {
            "n/a".into()
        };
        response.on_hover_text_at_pointer(format!(
            "{}: {}\n{}: {}\n{}: {value}",
            h.y.title,
            h.rows.get(r).map_or("", String::as_str),
            h.x.title,
            h.columns.get(c).map_or("", String::as_str),
            h.colors.title,
        ));
    }
}

/// The gradient's width in a colour bar.
const BAR: f32 = 12.0;

/// The width a colour bar takes: the gradient, its tick labels and its turned title.
fn colour_bar_width(ui: &egui::Ui, scale: &ColorScale, limits: (f64, f64)) -> f32 {
    let font = label_font();
    // Whatever its height, a bar takes 3 to 10 ticks: the widest label of any of them
    // (a step of 0.25 writes longer labels than one of 0.2).
    let widest = ((3..=10).flat_map(|n| figures::axis_ticks(limits.0, limits.1, Scale::Linear, n)))
        .map(|(_, t)| {
            (ui.painter())
                .layout_no_wrap(t.clone(), font.clone(), Color32::WHITE)
                .size()
                .x
        })
        .fold(0.0f32, f32::max);
    let title = if scale.text().is_empty() {
        0.0
    } else {
        line_height(ui, &font) + GAP
    };
    BAR + GAP + widest + GAP + title
}

/// A colour bar in `rect`: the gradient, the export's ticks (at least three, as many as
/// its height holds) and the scale's title turned along it.
fn colour_bar(
    ui: &egui::Ui,
    painter: &egui::Painter,
    rect: Rect,
    scale: &ColorScale,
    limits: (f64, f64),
) {
    let font = label_font();
    let text = ui.visuals().text_color();
    let line = line_height(ui, &font);
    let bar = Rect::from_min_size(rect.min, Vec2::new(BAR, rect.height()));
    // Slices a few points tall: a smooth gradient at any height.
    let steps = ((bar.height() / 3.0) as usize).max(16);
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
    let (lo, hi) = limits;
    let count = tick_count(bar.height() as f64, 2.5 * line as f64);
    let mut right = bar.right();
    for (v, label) in figures::axis_ticks(lo, hi, Scale::Linear, count) {
        let y = bar.bottom() - ((v - lo) / (hi - lo)) as f32 * bar.height();
        let g = ui.painter().layout_no_wrap(label, font.clone(), text);
        let top = y - g.size().y / 2.0;
        right = right.max(bar.right() + GAP + g.size().x);
        painter.galley(Pos2::new(bar.right() + GAP, top), g, text);
    }
    let title = scale.text();
    if !title.is_empty() {
        let g = fitted(ui, &title, &font, rect.height());
        let at = Pos2::new(right + GAP, rect.center().y + g.size().x / 2.0);
        painter.add(text_shape(g, at, true, text));
    }
}

/// How an image grid fills its body: images per row, cell size and whether captions show.
struct GridLayout {
    per_row: usize,
    cell: f32,
    captions: bool,
}

impl GridLayout {
    /// The arrangement with the largest cells: for each number of images a row, the cell
    /// that fits both the width (less the colour bar) and the height (with captions when
    /// every caption fits under its image).
    fn fit(ui: &egui::Ui, g: &figures::ImageGrid, area: Vec2, caption_h: f32) -> Self {
        let n = g.images.len().max(1);
        let (rows, cols) = g.images.first().map_or((1, 1), |im| {
            (
                im.values.len().max(1),
                im.values.first().map_or(1, Vec::len).max(1),
            )
        });
        let font = label_font();
        let widest_caption = (g.images.iter())
            .map(|im| {
                (ui.painter())
                    .layout_no_wrap(im.caption.clone(), font.clone(), Color32::WHITE)
                    .size()
                    .x
            })
            .fold(0.0f32, f32::max);
        let mut best = GridLayout {
            per_row: n,
            cell: 0.0,
            captions: false,
        };
        for per_row in 1..=n {
            let lines = n.div_ceil(per_row) as f32;
            for captions in [true, false] {
                let under = if captions { caption_h } else { 0.0 };
                let w = (area.x - GAP * per_row as f32) / (per_row * cols) as f32;
                let h = (area.y - lines * (GAP + under)) / (lines * rows as f32);
                let cell = w.min(h);
                let fits = !captions || widest_caption <= cell * cols as f32 + GAP;
                if fits && cell > best.cell {
                    best = GridLayout {
                        per_row,
                        cell,
                        captions,
                    };
                }
            }
        }
        best.cell = best.cell.max(MIN_IMAGE_CELL);
        best
    }
}

pub(super) fn show_image_grid(
    ui: &mut egui::Ui,
    g: &figures::ImageGrid,
    size: Vec2,
    selection: Selection,
    interaction: &mut Interaction,
) {
    let values: Vec<f64> = g
        .images
        .iter()
        .flat_map(|i| i.values.iter().flatten().copied())
        .collect();
    let limits = g.colors.resolve(values.iter().copied());
    let font = label_font();
    let caption_h = line_height(ui, &font) + 2.0;
    let bar_w = colour_bar_width(ui, &g.colors, limits);
    let images_area = Vec2::new(size.x - bar_w - 2.0 * GAP, size.y);
    let layout = GridLayout::fit(ui, g, images_area, caption_h);
    let (rect, _) = ui.allocate_exact_size(size, Sense::hover());
    let painter = ui.painter_at(rect);
    let text = ui.visuals().text_color();
    let mut bottom = rect.top();
    let mut right = rect.left();
    for (i, img) in g.images.iter().enumerate() {
        let rows = img.values.len();
        let cols = img.values.first().map_or(0, Vec::len);
        let image = Vec2::new(layout.cell * cols as f32, layout.cell * rows as f32);
        let under = if layout.captions { caption_h } else { 0.0 };
        let (line, k) = (i / layout.per_row, i % layout.per_row);
        let min = rect.min
            + Vec2::new(
                k as f32 * (image.x + GAP),
                line as f32 * (image.y + under + GAP),
            );
        let area = Rect::from_min_size(min, image);
        bottom = bottom.max(area.bottom());
        right = right.max(area.right());
        let state = match selection {
            Selection::Image(sel) => Some(sel == Some(i)),
            _ => None,
        };
        if image_cell(ui, &painter, area, i, img, g.colors.map, limits, state) {
            interaction.clicked_image = Some(i);
        }
        if layout.captions && !img.caption.is_empty() {
            let c = fitted(ui, &img.caption, &font, image.x + GAP);
            let at = Pos2::new(area.center().x - c.size().x / 2.0, area.bottom() + 1.0);
            painter.galley(at, c, text);
        }
    }
    // Half a line above and below the bar for its end ticks' labels.
    let line = line_height(ui, &font);
    let bar_h = (bottom - rect.top()).max(100.0).min(rect.height() - line);
    let bar = Rect::from_min_size(
        Pos2::new(right + 2.0 * GAP, rect.top() + line / 2.0),
        Vec2::new(bar_w, bar_h),
    );
    colour_bar(ui, &painter, bar, &g.colors, limits);
}

/// One image of a grid at `area`; `selected` is None when images are not clickable, else
/// whether this one is the selected one. Returns whether it was clicked.
#[allow(clippy::too_many_arguments)]
fn image_cell(
    ui: &egui::Ui,
    painter: &egui::Painter,
    area: Rect,
    i: usize,
    img: &figures::GridImage,
    map: ColorMap,
    limits: (f64, f64),
    selected: Option<bool>,
) -> bool {
    let cols = img.values.first().map_or(0, Vec::len).max(1);
    let cell = area.width() / cols as f32;
    let sense = if selected.is_some() {
        Sense::click()
    } else {
        Sense::hover()
    };
    let response = ui.interact(area, ui.scope_id().with(("grid-image", i)), sense);
    if selected.is_some() {
        let caption = img.caption.clone();
        response.widget_info(|| {
            egui::WidgetInfo::labeled(egui::Role::Button, true, format!("show {caption}"))
        });
    }
    let mut hover = None;
    for (r, row) in img.values.iter().enumerate() {
        for (c, &v) in row.iter().enumerate() {
            let cr = Rect::from_min_size(
                area.min + Vec2::new(c as f32 * cell, r as f32 * cell),
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
            area,
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
        let decimals = decimals_for(&[limits.0, limits.1]).max(1);
        response.on_hover_text_at_pointer(format!("{}: {}", img.caption, value_text(v, decimals)));
    }
    clicked
}
