//! Grasp replay: a timeline (play / pause / step / speed), the frame's pressures as
//! heatmaps in each sensor's layout, and encoder and per-finger feature traces with a
//! cursor at the current frame.

use egui::{ComboBox, Vec2};
use egui_plot::{Line, Plot, PlotPoints, VLine};

use super::figure_view::{
    self, Selection, X_EDGE, Y_EDGE, legend_row, legend_row_height, series_rgb, tick_spacer,
    x_label_room, y_label_room,
};
use crate::figures::{Axis, AxisTitle, BarGroup, Figure, Scale};

use super::heatmap::{colour_bar, taxel_picker};
use super::loader::LoadedSession;
use super::results::ReplayTrace;
use crate::experiments::recognition::{GraspTrace, SupervisedLearner};
use crate::features::FingerStats;
use crate::figures::ColorMap;
use crate::session::{Grasp, Session};

/// Over what the heatmaps' colours are scaled.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ColourRange {
    /// The whole session: colours mean the same in every grasp.
    Session,
    /// This grasp: its contact pattern shows even when its pressures stay low (a session's
    /// range is set by its hardest grasp and leaves the others dim).
    #[default]
    Grasp,
    /// This frame alone.
    Frame,
}

impl ColourRange {
    pub const ALL: [ColourRange; 3] =
        [ColourRange::Session, ColourRange::Grasp, ColourRange::Frame];

    pub fn text(self) -> &'static str {
        match self {
            ColourRange::Session => "session",
            ColourRange::Grasp => "grasp",
            ColourRange::Frame => "frame",
        }
    }
}

/// Every sensor's values at `frame`: pressures, or their change since the grasp's first frame.
fn frame_values(session: &Session, g: &Grasp, frame: usize, change: bool) -> Vec<Vec<f64>> {
    (0..session.sensors.len())
        .map(|k| {
            let p = session.frame_pressures(&g.frames[frame], k);
            if change {
                let first = session.frame_pressures(&g.frames[0], k);
                p.iter().zip(&first).map(|(a, b)| a - b).collect()
            } else {
                p
            }
        })
        .collect()
}

fn span(values: impl Iterator<Item = f64>) -> (f64, f64) {
    let (lo, hi) = values
        .filter(|v| v.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
            (lo.min(v), hi.max(v))
        });
    if lo.is_finite() && hi > lo {
        (lo, hi)
    } else if lo.is_finite() {
        (lo - 0.5, lo + 0.5)
    } else {
        (0.0, 1.0)
    }
}

pub const SPEEDS: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Replay {
    pub frame: usize,
    pub playing: bool,
    pub speed: f32,
    /// Which per-finger statistic the feature trace shows (index into FingerStats::NAMES).
    pub stat: usize,
    /// The learner whose class distribution is drawn beside the heatmaps.
    #[serde(default = "default_learner")]
    pub learner: SupervisedLearner,
    /// Over what the colours are scaled.
    #[serde(default)]
    pub colours: ColourRange,
    /// Show each frame's change since the grasp's first frame instead of its pressures.
    #[serde(default)]
    pub change: bool,
    #[serde(skip)]
    carry: f64,
}

impl Default for Replay {
    fn default() -> Self {
        Replay {
            frame: 0,
            playing: false,
            speed: 1.0,
            stat: 0,
            learner: default_learner(),
            colours: ColourRange::default(),
            change: false,
            carry: 0.0,
        }
    }
}

fn default_learner() -> SupervisedLearner {
    SupervisedLearner::Ds
}

/// What the replay asks the app to do.
pub enum ReplayAction {
    None,
    /// Compute the recognition trace of this grasp with this learner.
    Trace(SupervisedLearner),
    /// A taxel was clicked: compare it.
    PickTaxel {
        sensor: usize,
        taxel: usize,
    },
}

impl Replay {
    /// Back to the first frame, stopped (a replay from the start).
    pub fn reset(&mut self) {
        self.open_at(0);
    }

    /// Stopped at `frame`: a newly focused grasp opens at its key frame, where the touch is.
    pub fn open_at(&mut self, frame: usize) {
        self.frame = frame;
        self.playing = false;
        self.carry = 0.0;
    }

    /// Go to the frame nearest time `t` (seconds) among `times`, stopped.
    pub fn seek(&mut self, t: f64, times: &[f64]) {
        let nearest =
            (0..times.len()).min_by(|&a, &b| (times[a] - t).abs().total_cmp(&(times[b] - t).abs()));
        if let Some(k) = nearest {
            self.open_at(k);
        }
    }

    pub fn step(&mut self, delta: isize, n_frames: usize) {
        let last = n_frames.saturating_sub(1) as isize;
        self.frame = (self.frame as isize + delta).clamp(0, last) as usize;
        self.carry = 0.0;
    }

    pub fn toggle(&mut self, n_frames: usize) {
        if !self.playing && self.frame + 1 >= n_frames {
            // Playing from the last frame starts again at the beginning.
            self.frame = 0;
        }
        self.playing = !self.playing;
        self.carry = 0.0;
    }

    /// Advance by `dt` seconds of wall time at `rate` frames per second.
    /// Returns true while still playing (the UI keeps repainting).
    pub fn advance(&mut self, dt: f64, rate: f64, n_frames: usize) -> bool {
        if !self.playing || n_frames == 0 {
            return false;
        }
        self.carry += dt * rate * self.speed as f64;
        while self.carry >= 1.0 {
            self.carry -= 1.0;
            if self.frame + 1 >= n_frames {
                self.playing = false;
                self.carry = 0.0;
                return false;
            }
            self.frame += 1;
        }
        true
    }

    pub fn ui(
        &mut self,
        ui: &mut egui::Ui,
        s: &LoadedSession,
        grasp: usize,
        trace: Option<&ReplayTrace>,
    ) -> ReplayAction {
        let mut action = ReplayAction::None;
        let session = &s.session;
        let Some(g) = session.grasps.get(grasp) else {
            ui.label("Select a grasp in the browser.");
            return action;
        };
        let n = g.frames.len();
        self.frame = self.frame.min(n - 1);
        let label = g
            .labels
            .first()
            .and_then(|&l| {
                session
                    .label_sets
                    .first()
                    .and_then(|set| set.classes.get(l))
            })
            .cloned()
            .unwrap_or_default();
        ui.heading(format!(
            "{}{} · {label}",
            g.object,
            g.trial.map(|t| format!(" #{t}")).unwrap_or_default()
        ));
        self.controls(ui, g);
        ui.separator();
        if let Some((sensor, taxel)) = self.heatmaps(ui, s, g) {
            action = ReplayAction::PickTaxel { sensor, taxel };
        }
        let trace = trace.filter(|t| {
            t.session == session.meta.name && t.grasp == grasp && t.learner == self.learner
        });
        if let Some(t) = trace {
            class_distribution(ui, &t.trace, self.frame, 200.0);
        }
        if session.label_set("object").is_some() && !session.encoders.is_empty() {
            let row = self.recognition_row(ui);
            if !matches!(row, ReplayAction::None) {
                action = row;
            }
        }
        ui.separator();
        if let Some(t) = self.traces(ui, session, g) {
            let times: Vec<f64> = g.frames.iter().map(|fr| fr.t).collect();
            self.seek(t, &times);
        }
        action
    }

    /// Step, play, speed and the frame slider, with the frame's number and time.
    fn controls(&mut self, ui: &mut egui::Ui, g: &Grasp) {
        let n = g.frames.len();
        ui.horizontal_wrapped(|ui| {
            if ui
                .button("Step back")
                .on_hover_text("Left arrow key")
                .clicked()
            {
                self.step(-1, n);
            }
            let play = if self.playing { "Pause" } else { "Play" };
            if ui.button(play).on_hover_text("Space bar").clicked() {
                self.toggle(n);
            }
            if ui
                .button("Step forward")
                .on_hover_text("Right arrow key")
                .clicked()
            {
                self.step(1, n);
            }
            ComboBox::from_label("Speed")
                .selected_text(format!("{}×", self.speed))
                .show_ui(ui, |ui| {
                    for sp in SPEEDS {
                        ui.selectable_value(&mut self.speed, sp, format!("{sp}×"));
                    }
                });
            // A slider does not wrap by itself: a row of its own when the rest of this one
            // is too short for it (and its value and name), so that it stays in the tile.
            // (In a wrapping row `available_width` is a whole row's: the rest is measured.)
            if ui.max_rect().right() - ui.cursor().min.x < ui.spacing().slider_width + 110.0 {
                ui.end_row();
            }
            // Numbered from 1, as everywhere the frame is shown.
            let mut frame = self.frame + 1;
            if ui
                .add(egui::Slider::new(&mut frame, 1..=n).text("frame"))
                .changed()
            {
                self.open_at(frame - 1);
            }
        });
        let f = &g.frames[self.frame];
        let key = if self.frame == g.key_frame {
            " · key frame (full contact)"
        } else {
            ""
        };
        ui.label(format!(
            "Frame {} / {n} · t = {:.2} s{key}",
            self.frame + 1,
            f.t
        ));
    }

    /// One heatmap per sensor at the current frame, beside a colour bar.
    /// The frame's heatmaps; the taxel clicked, as (sensor, taxel).
    fn heatmaps(
        &mut self,
        ui: &mut egui::Ui,
        s: &LoadedSession,
        g: &Grasp,
    ) -> Option<(usize, usize)> {
        let session = &s.session;
        let n = g.frames.len();
        let unit = session
            .sensors
            .first()
            .map(|x| match x.transform {
                crate::session::ValueTransform::Identity => x.unit.clone(),
                _ => "reading below rest".into(),
            })
            .unwrap_or_default();
        ui.horizontal_wrapped(|ui| {
            ComboBox::from_label("Colour range")
                .selected_text(self.colours.text())
                .show_ui(ui, |ui| {
                    for c in ColourRange::ALL {
                        ui.selectable_value(&mut self.colours, c, c.text());
                    }
                });
            ui.checkbox(&mut self.change, "Change since the first frame");
        });
        let values = frame_values(session, g, self.frame, self.change);
        let range = match (self.colours, self.change) {
            (ColourRange::Session, false) => s.pressure_range,
            (ColourRange::Session, true) => {
                let m = s.pressure_range.1 - s.pressure_range.0;
                (-m, m)
            }
            (ColourRange::Grasp, _) => span((0..n).flat_map(|f| {
                frame_values(session, g, f, self.change)
                    .into_iter()
                    .flatten()
            })),
            (ColourRange::Frame, _) => span(values.iter().flatten().copied()),
        };
        // A change is signed: diverging colours centred on no change.
        let (map, range) = if self.change {
            let m = range.0.abs().max(range.1.abs()).max(1e-9);
            (ColorMap::Diverging, (-m, m))
        } else {
            (ColorMap::Viridis, range)
        };
        // The heatmaps grow with the tile: one column per sensor, beside a colour bar.
        let sensors = session.sensors.len().max(1) as f32;
        // The tile's width (its clip), not a row's overflow from above.
        let room = ui
            .available_width()
            .min(ui.clip_rect().right() - ui.cursor().min.x);
        let width = ((room - 140.0) / sensors - 8.0).clamp(40.0, 420.0);
        let height = (width * 1.3).min((ui.available_height() * 0.45).max(120.0));
        let cell = Vec2::new(width, height);
        let title = format!(
            "{} ({} range)",
            if self.change { "change" } else { "pressure" },
            self.colours.text()
        );
        let mut picked = None;
        ui.horizontal_wrapped(|ui| {
            for (k, sensor) in session.sensors.iter().enumerate() {
                ui.vertical(|ui| {
                    // A column no wider than its heatmap, so that the row wraps inside the
                    // tile rather than running past its edge (the name whole on hover).
                    ui.set_max_width(width);
                    let name = format!("{} ({} taxels)", sensor.name, sensor.layout.taxel_count());
                    ui.add(egui::Label::new(name).truncate());
                    // A click on a taxel plots it in the Compare view.
                    if let Some(t) = taxel_picker(ui, sensor, &values[k], range, map, cell) {
                        picked = Some((k, t));
                    }
                });
            }
            colour_bar(ui, range, map, &title, &unit, cell.y + 20.0);
        });
        picked
    }

    /// The learner choice and the button that asks for its recognition trace.
    fn recognition_row(&mut self, ui: &mut egui::Ui) -> ReplayAction {
        let mut action = ReplayAction::None;
        ui.horizontal_wrapped(|ui| {
            ComboBox::from_label("Recognition learner")
                .selected_text(format!("{:?}", self.learner).to_uppercase())
                .show_ui(ui, |ui| {
                    ui.selectable_value(&mut self.learner, SupervisedLearner::Ds, "DS");
                    ui.selectable_value(&mut self.learner, SupervisedLearner::Gs, "GS");
                });
            // Its words wrap in a narrow tile rather than run past the edge.
            let button = egui::Button::new("Show the recognition as the hand closes")
                .wrap_mode(egui::TextWrapMode::Wrap);
            if ui
                .add(button)
                .on_hover_text(
                    "Teach the learner every other grasp, then classify this one step by step",
                )
                .clicked()
            {
                action = ReplayAction::Trace(self.learner);
            }
        });
        action
    }

    /// The encoder and per-finger traces with the current frame's cursor; the time a click
    /// or drag on either points at. Their plots share what the tile has left after their
    /// titles and legends, each at least [`MIN_TRACE_PLOT`] tall: in a shorter tile the
    /// replay's column scrolls to them rather than squeezing them flat.
    fn traces(&mut self, ui: &mut egui::Ui, session: &Session, g: &Grasp) -> Option<f64> {
        let t_now = g.frames[self.frame].t;
        if g.frames.len() == 1 {
            // One frame has no time axis: its values, a bar per finger.
            self.finger_feature(ui);
            let figure = finger_values_figure(session, g, self.stat);
            let height = ui.available_height().max(MIN_TRACE_PLOT);
            figure_view::show(ui, "finger_values", &figure, height, Selection::None);
            return None;
        }
        let joints = (!session.encoders.is_empty()).then(|| Trace {
            id: "encoder_trace",
            label: "Joint encoders trace",
            y_title: "angle (degrees)".into(),
            lines: (session.encoders.iter().enumerate())
                .map(|(j, name)| {
                    let pts = g.frames.iter().map(|fr| [fr.t, fr.encoders[j]]).collect();
                    (name.clone(), pts)
                })
                .collect(),
        });
        let fingers = Trace {
            id: "finger_trace",
            label: "Per-finger feature trace",
            y_title: format!("{} of pressure", FingerStats::NAMES[self.stat]),
            lines: (session.sensors.iter().enumerate())
                .map(|(k, sensor)| {
                    let pts = (g.frames.iter())
                        .map(|fr| {
                            let stats = FingerStats::of(&session.frame_pressures(fr, k));
                            [fr.t, stats.to_array()[self.stat]]
                        })
                        .collect();
                    (sensor.name.clone(), pts)
                })
                .collect(),
        };
        // Each trace's title (or feature picker) row and legend, then the plots' share.
        let row = ui.spacing().interact_size.y + ui.spacing().item_spacing.y;
        let width = ui.available_width();
        let chrome: f32 = (joints.iter().chain([&fingers]))
            .map(|t| row + t.legend_height(ui, width))
            .sum();
        let plots = if joints.is_some() { 2.0 } else { 1.0 };
        let plot = ((ui.available_height() - chrome) / plots).max(MIN_TRACE_PLOT);
        let mut seek_to = None;
        if let Some(joints) = joints {
            ui.label("Joint encoders");
            seek_to = joints.show(ui, t_now, Some(plot));
        }
        self.finger_feature(ui);
        seek_to.or(fingers.show(ui, t_now, None))
    }

    /// The per-finger statistic the finger trace shows.
    fn finger_feature(&mut self, ui: &mut egui::Ui) {
        ComboBox::from_label("Per-finger feature")
            .selected_text(FingerStats::NAMES[self.stat])
            .show_ui(ui, |ui| {
                for (i, name) in FingerStats::NAMES.iter().enumerate() {
                    ui.selectable_value(&mut self.stat, i, *name);
                }
            });
    }
}

/// The least height a trace's plot is drawn at: three ticks on its y axis and the time
/// axis's labels and title below them.
const MIN_TRACE_PLOT: f32 = 110.0;

/// A trace of a grasp over time: one line per joint or finger, its legend a row of names
/// above the plot (in the lines' colours) so that it never covers the lines or the cursor.
struct Trace {
    id: &'static str,
    /// The plot's name for assistive technology.
    label: &'static str,
    y_title: String,
    lines: Vec<(String, Vec<[f64; 2]>)>,
}

impl Trace {
    /// How tall its legend's row of names is in `width`.
    fn legend_height(&self, ui: &egui::Ui, width: f32) -> f32 {
        let names: Vec<(String, egui::Color32)> = (self.lines.iter())
            .map(|(name, _)| (name.clone(), egui::Color32::WHITE))
            .collect();
        legend_row_height(ui, &names, width)
    }

    /// Draw it with the current frame's cursor at `t_now`, its plot `height` tall or, with
    /// none, down to the tile's bottom edge (at least [`MIN_TRACE_PLOT`]); the time a click
    /// or drag points at.
    fn show(self, ui: &mut egui::Ui, t_now: f64, height: Option<f32>) -> Option<f64> {
        let ctx = ui.ctx().clone();
        let color = |j: usize| series_rgb(&ctx, None, j);
        let entries: Vec<(String, egui::Color32)> = (self.lines.iter().enumerate())
            .map(|(j, (name, _))| (name.clone(), color(j)))
            .collect();
        legend_row(ui, &entries);
        let height = height.unwrap_or_else(|| ui.available_height().max(MIN_TRACE_PLOT));
        let cursor = ui.visuals().selection.bg_fill;
        let shown = Plot::new(self.id)
            .allow_scroll(false)
            .allow_drag(false)
            .height(height)
            .x_axis_label("time (s)")
            .y_axis_label(self.y_title)
            .x_grid_spacer(tick_spacer(Scale::Linear, 70.0, X_EDGE, x_label_room(ui)))
            .y_grid_spacer(tick_spacer(Scale::Linear, 36.0, Y_EDGE, y_label_room(ui)))
            .show(ui, |plot| {
                for (j, (name, pts)) in self.lines.into_iter().enumerate() {
                    plot.line(Line::new(name, PlotPoints::new(pts)).color(color(j)));
                }
                plot.vline(VLine::new("current frame", t_now).color(cursor).width(2.0));
            });
        trace_seek(&shown, self.label)
    }
}

/// The time a click or a drag on a trace points at (the trace is named `label` for
/// assistive technology); the cursor follows it.
fn trace_seek<R>(shown: &egui_plot::PlotResponse<R>, label: &str) -> Option<f64> {
    let r = &shown.response;
    r.widget_info(|| egui::WidgetInfo::labeled(egui::Role::Image, true, label));
    if !(r.clicked() || r.dragged()) {
        return None;
    }
    let pos = r.interact_pointer_pos()?;
    Some(shown.transform.value_from_position(pos).x)
}

/// The learner's class distribution at step `step` of a grasp of class `true_class`, as
/// a figure: the same bars, rules and hover as every figure of the workbench.
pub fn class_distribution_figure(
    classes: &[String],
    p: &[f64],
    true_class: usize,
    step: usize,
) -> Figure {
    let best = (0..p.len()).max_by(|&a, &b| p[a].total_cmp(&p[b]));
    let name = |c: Option<usize>| c.and_then(|c| classes.get(c)).map_or("?", String::as_str);
    Figure::bars(
        format!(
            "Class distribution at step {} (true: {}; now: {})",
            step + 1,
            name(Some(true_class)),
            name(best)
        ),
        AxisTitle::new("class", ""),
        Axis::new("probability", "").including(0.0, 1.0),
        classes.to_vec(),
        vec![BarGroup::new("p(class | observations)", p.to_vec())],
    )
}

/// A single-frame grasp's per-finger feature `stat`: a bar per sensor.
pub fn finger_values_figure(session: &Session, g: &Grasp, stat: usize) -> Figure {
    let name = FingerStats::NAMES[stat];
    let values = (0..session.sensors.len())
        .map(|k| {
            let fr = &g.frames[0];
            FingerStats::of(&session.frame_pressures(fr, k)).to_array()[stat]
        })
        .collect();
    Figure::bars(
        format!("Per-finger {name} of pressure (the grasp's only frame)"),
        AxisTitle::new("sensor", ""),
        Axis::new(format!("{name} of pressure"), ""),
        session.sensors.iter().map(|x| x.name.clone()).collect(),
        vec![BarGroup::new(name, values)],
    )
}

/// The learner's class distribution at the current step, in a row of its own under the
/// heatmaps (never wider than the page).
fn class_distribution(ui: &mut egui::Ui, t: &GraspTrace, frame: usize, height: f32) {
    let step = frame.min(t.distribution.len().saturating_sub(1));
    let p = t.distribution.get(step).cloned().unwrap_or_default();
    let figure = class_distribution_figure(&t.classes, &p, t.true_class, step);
    let width = ui.available_width().min(520.0);
    ui.allocate_ui(Vec2::new(width, height), |ui| {
        figure_view::show(ui, "class_distribution", &figure, height, Selection::None);
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn playback_advances_at_rate_and_stops_at_the_end() {
        let mut r = Replay::default();
        r.toggle(5);
        assert!(r.playing);
        assert!(r.advance(0.25, 10.0, 5)); // 2.5 frames
        assert_eq!(r.frame, 2);
        r.speed = 2.0;
        assert!(!r.advance(1.0, 10.0, 5));
        assert_eq!(r.frame, 4);
        assert!(!r.playing);
        r.step(-10, 5);
        assert_eq!(r.frame, 0);
        r.step(3, 5);
        assert_eq!(r.frame, 3);
    }
}
