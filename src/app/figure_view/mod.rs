//! Draws a `figures::Figure` on screen: the same figure data the SVG/PNG export renders,
//! so what a researcher inspects is what ends up in the paper. Charts and bars go through
//! egui_plot (hover values, zoom); heatmaps and image grids are painted cell by cell with a
//! colour bar and hover values.

mod axes;
mod bars;
mod chart;
mod grid;

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Vec2};
use egui_plot::{
    AxisHints, Bar, BarChart, ColorConflictHandling, Corner, FilledArea, GridInput, GridMark,
    HLine, HoverPosition, Legend, Line, MarkerShape, Plot, PlotPoint, PlotPoints, Points, VLine,
};

use super::heatmap::rgb;
use crate::figures::{
    self, ColorMap, ColorScale, ErrorDisplay, Figure, FigureKind, Orientation, Rgb, Scale,
    SeriesStyle, series_color,
};
pub(crate) use axes::tick_spacer;
use bars::show_bars;
pub(crate) use chart::legend_row;
pub use chart::marker_position;
use chart::show_chart;
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
