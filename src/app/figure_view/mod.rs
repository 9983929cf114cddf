//! Draws a `figures::Figure` on screen: the same figure data the SVG/PNG export renders,
//! so what a researcher inspects is what ends up in the paper. Charts and bars go through
//! egui_plot (hover values, zoom); heatmaps and image grids are painted cell by cell with a
//! colour bar and hover values.

mod axes;
mod bars;
mod chart;
mod grid;

use egui::{Color32, FontId, Pos2, Rect, Sense, Stroke, Vec2};
use egui_plot::{
    AxisHints, Bar, BarChart, ColorConflictHandling, Corner, FilledArea, GridInput, GridMark,
    HLine, HoverPosition, Legend, Line, MarkerShape, Plot, PlotPoint, PlotPoints, Points, VLine,
};

use super::heatmap::rgb;
use crate::figures::{
    self, ColorMap, ColorScale, ErrorDisplay, Figure, FigureKind, Orientation, Rgb, Scale,
    SeriesStyle, series_color,
};
pub(crate) use axes::{X_EDGE, Y_EDGE, tick_spacer, x_label_room, y_label_room};
use bars::show_bars;
pub(crate) use chart::legend_row;
use chart::show_chart;
pub use chart::{linked_x_range, marker_position, shown_x_range};
use grid::{show_heatmap, show_image_grid};

/// The colour of series `i` on screen: its own colour, else the palette's, as the export
/// draws them, except that black (drawn on white paper) would vanish on a dark background
/// and takes the theme's text colour there.
pub(crate) fn series_rgb(ctx: &egui::Context, color: Option<Rgb>, i: usize) -> Color32 {
    let c = color.unwrap_or_else(|| series_color(i));
    let visuals = &ctx.global_style().visuals;
    let near_black = u16::from(c.0) + u16::from(c.1) + u16::from(c.2) < 0x60;
    match visuals.dark_mode && near_black {
        true => visuals.strong_text_color(),
        false => rgb(c),
    }
}

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

/// The smallest plot (or matrix, or grid of images) that still reads, in points: when a
/// tile is short, the subtitle and then the legend fold away before the body gets less.
const MIN_BODY: f32 = 150.0;

/// Where a chart's legend goes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum LegendPlace {
    /// No legend: one series, hidden by the user, or folded for want of room.
    None,
    /// Inside the plot, in the corner where it covers no point.
    InPlot(Corner),
    /// A row of names above the plot, this tall.
    Row(f32),
}

/// The legend's entries: one per series (a front joins its owner's) and named reference
/// line of a chart; one per group of a bar chart with several.
fn legend_entries(ctx: &egui::Context, figure: &Figure) -> Vec<(String, Color32)> {
    match &figure.kind {
        FigureKind::Chart(c) if c.series.len() > 1 => chart::legend_entries(ctx, c),
        FigureKind::Bars(b) if b.groups.len() > 1 => (b.groups.iter().enumerate())
            .map(|(i, g)| (g.name.clone(), series_rgb(ctx, g.color, i)))
            .collect(),
        _ => Vec::new(),
    }
}

/// How tall a row of legend entries is when wrapped into `width`.
pub(crate) fn legend_row_height(ui: &egui::Ui, entries: &[(String, Color32)], width: f32) -> f32 {
    let font = egui::TextStyle::Body.resolve(ui.style());
    let gap = ui.spacing().item_spacing;
    let (mut rows, mut x) = (1, 0.0);
    for (name, _) in entries {
        let w = (ui.painter())
            .layout_no_wrap(format!("— {name}"), font.clone(), Color32::WHITE)
            .size()
            .x
            .min(width);
        if x > 0.0 && x + w > width {
            rows += 1;
            x = 0.0;
        }
        x += w + gap.x;
    }
    rows as f32 * (ui.text_style_height(&egui::TextStyle::Body) + gap.y)
}

/// Title (cut to one line, whole on hover), subtitle when there is room (else on the
/// title's hover) and, for figures with a legend, a button that hides or shows it. Returns
/// where the legend goes, given the `height` of the whole figure.
fn header(ui: &mut egui::Ui, id: &str, figure: &Figure, height: f32) -> LegendPlace {
    let entries = legend_entries(ui.ctx(), figure);
    let key = egui::Id::unique(("figure-legend-hidden", id));
    let mut hidden = ui.ctx().data(|d| d.get_temp::<bool>(key)).unwrap_or(false);
    let line = ui.text_style_height(&egui::TextStyle::Body) + ui.spacing().item_spacing.y;
    let width = ui.available_width();
    let body = height - line;
    // A legend taller than a third of the plot, or one that would cover data in every
    // corner: a row above the plot instead.
    let wanted = match &figure.kind {
        _ if entries.is_empty() || hidden => LegendPlace::None,
        FigureKind::Chart(c) if entries.len() as f32 * 18.0 <= (body - 40.0) / 3.0 => {
            match chart::legend_corner(ui, c, &entries, Vec2::new(width, body)) {
                (corner, 0) => LegendPlace::InPlot(corner),
                _ => LegendPlace::Row(legend_row_height(ui, &entries, width)),
            }
        }
        _ => LegendPlace::Row(legend_row_height(ui, &entries, width)),
    };
    let legend_h = match wanted {
        LegendPlace::Row(h) => h,
        _ => 0.0,
    };
    let subtitle = figure.subtitle.as_deref().filter(|s| !s.is_empty());
    let show_subtitle = subtitle.is_some() && body - line - legend_h >= MIN_BODY;
    let legend = match wanted {
        LegendPlace::Row(h) if body - h < MIN_BODY => LegendPlace::None,
        other => other,
    };
    ui.horizontal(|ui| {
        if !entries.is_empty() {
            let text = if legend == LegendPlace::None {
                "show legend"
            } else {
                "hide legend"
            };
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                if ui.small_button(text).clicked() {
                    hidden = legend != LegendPlace::None;
                    ui.ctx().data_mut(|d| d.insert_temp(key, hidden));
                }
                title(ui, figure, show_subtitle);
            });
        } else {
            title(ui, figure, show_subtitle);
        }
    });
    if let Some(sub) = subtitle.filter(|_| show_subtitle) {
        ui.add(egui::Label::new(egui::RichText::new(sub).weak()).truncate());
    }
    legend
}

/// The title on one line, cut with an ellipsis when long; the whole title, and the subtitle
/// when it is not shown, on hover.
fn title(ui: &mut egui::Ui, figure: &Figure, subtitle_shown: bool) {
    let r = ui.add(
        egui::Label::new(egui::RichText::new(&figure.title).strong())
            .truncate()
            .show_tooltip_when_elided(false),
    );
    let mut hover = figure.title.clone();
    if let Some(sub) = figure.subtitle.as_deref().filter(|_| !subtitle_shown) {
        hover = format!("{hover}\n{sub}");
    }
    if hover != figure.title || r.rect.width() + 1.0 < ui.available_width() {
        r.on_hover_text(hover);
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

/// Draw `figure` in the available width, `height` points tall (at most what is left):
/// header, legend and body all inside that rectangle, nothing scrolled or cut.
pub fn show(
    ui: &mut egui::Ui,
    id: &str,
    figure: &Figure,
    height: f32,
    selection: Selection,
) -> Interaction {
    show_linked(ui, id, figure, height, selection, None)
}

/// [`show`], a chart's x axis linked to every plot shown with the same `link`: zoom or pan
/// one and the others follow ([`linked_x_range`] tells where they went).
pub fn show_linked(
    ui: &mut egui::Ui,
    id: &str,
    figure: &Figure,
    height: f32,
    selection: Selection,
    link: Option<egui::Id>,
) -> Interaction {
    let height = height.min(ui.available_height()).max(0.0);
    // Within what is visible too: a wide widget above (a slider, a row of buttons) can
    // widen the tile's ui past its clip, and the figure would run out of its tile.
    let width = (ui.available_width())
        .min(ui.clip_rect().right() - ui.cursor().min.x)
        .max(0.0);
    let rect = Rect::from_min_size(ui.cursor().min, Vec2::new(width, height));
    let mut interaction = Interaction::default();
    let builder = egui::UiBuilder::new()
        .max_rect(rect)
        .layout(egui::Layout::top_down(egui::Align::Min));
    ui.scope_builder(builder, |ui| {
        ui.shrink_clip_rect(rect);
        let legend = header(ui, id, figure, height);
        if let LegendPlace::Row(_) = legend {
            let entries = legend_entries(ui.ctx(), figure);
            legend_row(ui, &entries);
        }
        let body = Vec2::new(ui.available_width(), ui.available_height().max(0.0));
        match &figure.kind {
            FigureKind::Chart(chart) => {
                show_chart(
                    ui,
                    id,
                    chart,
                    body,
                    selection,
                    match legend {
                        LegendPlace::InPlot(corner) => Some(corner),
                        _ => None,
                    },
                    link,
                    &mut interaction,
                );
            }
            FigureKind::Bars(bars) => show_bars(ui, id, bars, body),
            FigureKind::Heatmap(h) => show_heatmap(ui, id, h, body, selection, &mut interaction),
            FigureKind::ImageGrid(g) => show_image_grid(ui, g, body, selection, &mut interaction),
        }
    });
    ui.advance_cursor_after_rect(rect);
    interaction
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

/// `text` cut with an ellipsis to at most `max_w` points wide in `font` (whole when it fits).
fn fit_text(ui: &egui::Ui, text: &str, font: &FontId, max_w: f32) -> String {
    let width = |t: &str| {
        (ui.painter())
            .layout_no_wrap(t.to_string(), font.clone(), Color32::WHITE)
            .size()
            .x
    };
    if width(text) <= max_w {
        return text.to_string();
    }
    (1..text.chars().count())
        .rev()
        .map(|k| abbreviated(text, k))
        .find(|t| width(t) <= max_w)
        .unwrap_or_else(|| "…".into())
}

/// A category name cut to `max` characters (the full name is in the bar's tooltip).
fn abbreviated(name: &str, max: usize) -> String {
    if name.chars().count() <= max {
        name.to_string()
    } else {
        name.chars().take(max.saturating_sub(1)).collect::<String>() + "…"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_palettes_black_reads_on_a_dark_background() {
        let ctx = egui::Context::default();
        let black = Rgb(0, 0, 0);
        assert_eq!(series_color(6), black, "the palette's seventh colour");
        ctx.set_visuals(egui::Visuals::dark());
        let panel = egui::Visuals::dark().extreme_bg_color;
        let light = |c: Color32| u16::from(c.r()) + u16::from(c.g()) + u16::from(c.b());
        // The palette's black series and a series given black are both bright against the
        // dark panel behind the plot.
        for c in [series_rgb(&ctx, None, 6), series_rgb(&ctx, Some(black), 0)] {
            assert!(light(c) > light(panel) + 300, "{c:?}");
        }
        // Every other colour, and black on a light background, is the export's.
        assert_eq!(series_rgb(&ctx, None, 0), rgb(series_color(0)));
        ctx.set_visuals(egui::Visuals::light());
        assert_eq!(series_rgb(&ctx, None, 6), Color32::BLACK);
        assert_eq!(series_rgb(&ctx, Some(black), 0), Color32::BLACK);
    }
}
