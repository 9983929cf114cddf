//! The stream's latest frame as heatmaps in the sensors' layouts, and its last seconds as
//! traces.

use egui::{Color32, Vec2};
use egui_plot::{Line, Plot, PlotPoints};

use super::LiveRoom;
use crate::app::figure_view;
use crate::app::heatmap::{colour_bar, sensor_heatmap};
use crate::figures::{ColorMap, Scale};

/// Points a trace line draws at most, whatever the stream's rate: about one per pixel of
/// a tile (more only cost frame time).
const TRACE_POINTS: usize = 600;

impl LiveRoom {
    pub(super) fn touch_ui(&mut self, ui: &mut egui::Ui) {
        let Some(c) = &self.connected else {
            ui.label("No stream.");
            return;
        };
        let sensors = c.sensors.clone();
        let latest = self.shown(|s| s.latest.clone()).flatten();
        let Some(frame) = latest else {
            ui.label("Waiting for the first frame…");
            return;
        };
        let pressures: Vec<Vec<f64>> = sensors
            .iter()
            .zip(&frame.taxels)
            .map(|(s, raw)| {
                raw.iter()
                    .enumerate()
                    .map(|(i, &v)| s.transform.apply(i, v))
                    .collect()
            })
            .collect();
        // The colours' range widens with what the stream has shown, so a frame's colours
        // compare with the earlier ones'.
        let (lo, hi) = pressures
            .iter()
            .flatten()
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &v| {
                (a.min(v), b.max(v))
            });
        let span = match (self.connected.as_mut(), lo.is_finite()) {
            (Some(c), true) => {
                let s = c.span.get_or_insert((lo, hi));
                *s = (s.0.min(lo), s.1.max(hi));
                *s
            }
            _ => (0.0, 1.0),
        };
        let range = if span.1 > span.0 {
            span
        } else {
            (span.0, span.0 + 1.0)
        };
        let unit = sensors.first().map(|s| s.unit.clone()).unwrap_or_default();
        // The unit in a line of its own (it wraps), not in the colour bar's narrow column.
        ui.small(format!(
            "Pressure ({unit}), coloured over the range the stream has shown"
        ));
        let (cell, cols) = heatmap_cells(sensors.len(), ui.available_size());
        ui.horizontal_top(|ui| {
            ui.vertical(|ui| {
                for row in sensors.chunks(cols).zip(pressures.chunks(cols)) {
                    ui.horizontal_top(|ui| {
                        for (sensor, p) in row.0.iter().zip(row.1) {
                            ui.vertical(|ui| {
                                ui.label(&sensor.name);
                                sensor_heatmap(ui, sensor, p, range, ColorMap::Viridis, cell);
                            });
                        }
                    });
                }
            });
            let rows = sensors.len().div_ceil(cols).max(1) as f32;
            colour_bar(
                ui,
                range,
                ColorMap::Viridis,
                "pressure",
                "",
                rows * (cell.y + HEATMAP_LABEL) - 4.0,
            );
        });
    }

    pub(super) fn traces_ui(&self, ui: &mut egui::Ui) {
        let Some(c) = &self.connected else {
            ui.label("No stream.");
            return;
        };
        let names: Vec<String> = c.sensors.iter().map(|s| s.name.clone()).collect();
        // Seconds before the latest frame, per sensor: at most TRACE_POINTS of the trace's
        // points (a 1 kHz stream holds ten thousand in ten seconds), copied under the lock.
        let lines = self
            .shown(|s| {
                let last = s.trace.back().map_or(0, |(t, _)| *t);
                let every = s.trace.len().div_ceil(TRACE_POINTS).max(1);
                let mut lines = vec![Vec::with_capacity(TRACE_POINTS); names.len()];
                for (t, totals) in s.trace.iter().step_by(every) {
                    let x = -(last.saturating_sub(*t) as f64) / 1e9;
                    for (line, v) in lines.iter_mut().zip(totals) {
                        line.push([x, *v]);
                    }
                }
                lines
            })
            .unwrap_or_default();
        ui.small("Total reading per sensor over the last seconds (s before the latest frame)");
        // The legend a row of names above the plot, as the replay's traces have it: inside,
        // it would cover the newest readings.
        let ctx = ui.ctx().clone();
        let color = |j: usize| figure_view::series_rgb(&ctx, None, j);
        let entries: Vec<(String, Color32)> = (names.iter().enumerate())
            .map(|(j, name)| (name.clone(), color(j)))
            .collect();
        figure_view::legend_row(ui, &entries);
        // Ticks as every chart's: at least three distinct labels on each axis.
        Plot::new("live-traces")
            .allow_scroll(false)
            .x_grid_spacer(figure_view::tick_spacer(
                Scale::Linear,
                70.0,
                figure_view::X_EDGE,
                figure_view::x_label_room(ui),
            ))
            .y_grid_spacer(figure_view::tick_spacer(
                Scale::Linear,
                36.0,
                figure_view::Y_EDGE,
                figure_view::y_label_room(ui),
            ))
            .show(ui, |p| {
                for (j, (name, pts)) in names.iter().zip(lines).enumerate() {
                    p.line(Line::new(name.clone(), PlotPoints::new(pts)).color(color(j)));
                }
            });
    }
}

/// Room for a sensor's name above its heatmap, and for the colour bar beside them.
const HEATMAP_LABEL: f32 = 26.0;
const COLOUR_BAR: f32 = 130.0;

/// The heatmaps' cell size and columns in `avail`: the rows (of `n` sensors) that give
/// the largest cells, each cell 1.3 times as tall as wide.
fn heatmap_cells(n: usize, avail: Vec2) -> (Vec2, usize) {
    let n = n.max(1);
    let (width, cols) = (1..=n)
        .map(|rows| {
            let cols = n.div_ceil(rows);
            let w = (avail.x - COLOUR_BAR) / cols as f32 - 10.0;
            let h = avail.y / rows as f32 - HEATMAP_LABEL;
            (w.min(h / 1.3), cols)
        })
        .fold(
            (f32::NEG_INFINITY, n),
            |best, c| if c.0 > best.0 { c } else { best },
        );
    let width = width.clamp(30.0, 320.0);
    (Vec2::new(width, width * 1.3), cols)
}
