//! The live view: a robot's stream as it arrives (File > Connect to a live stream…). The
//! engine (`live::Running`) reads the socket, cuts grasps, records them and runs the model
//! on its own thread; this room only reads its snapshot, a short lock per tile, and sends
//! it commands by hand through a bounded queue, so the window never waits on the stream.
//!
//! Tiles: the latest frame as heatmaps in the sensors' layouts; the traces of the last
//! seconds; the model at work (the open grasp's class distribution step by step, the
//! decision and when it settled; the last grasp's verdict); the connection's status with
//! pause, cutting and teaching by hand. Without a spec the form lists the server's
//! channels and proposes one to edit and save.

use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::time::Duration;

use egui::{Color32, Sense, Vec2};
use egui_plot::{Line, Plot, PlotPoints};
use serde::{Deserialize, Serialize};

use super::pane::{LivePane, Pane};
use super::{Cx, Room};
use crate::app::View;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::heatmap::{colour_bar, sensor_heatmap};
use crate::figures::{ColorMap, Scale};
use crate::live::client::{State, lock};
use crate::live::discover::{self, Found};
use crate::live::model::Verdict;
use crate::live::{LiveOptions, Running, Snapshot};
use crate::session::{ImportSpec, LabelSet, Sensor};

/// The connection as the form holds it (it persists between runs).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct LiveForm {
    pub url: String,
    pub spec: String,
    /// A model file to run on each grasp (empty: none), and whether labelled grasps
    /// teach it.
    pub model: String,
    pub teach: bool,
    /// A session file to record the grasps to (empty: no recording).
    pub record: String,
    pub by_hand: bool,
    /// The span of the traces (s).
    pub trace_seconds: f64,
}

impl Default for LiveForm {
    fn default() -> Self {
        LiveForm {
            url: "ws://127.0.0.1:8765".into(),
            spec: String::new(),
            model: String::new(),
            teach: false,
            record: String::new(),
            by_hand: false,
            trace_seconds: 10.0,
        }
    }
}

/// Points a trace line draws at most, whatever the stream's rate: about one per pixel of
/// a tile (more only cost frame time).
const TRACE_POINTS: usize = 600;

/// A stream the view is connected to.
struct Connected {
    running: Running,
    url: String,
    sensors: Vec<Sensor>,
    /// The recorded label sets (teaching by hand chooses a class of each) and the objects
    /// offered (the spec's, else the model's classes).
    label_sets: Vec<LabelSet>,
    objects: Vec<String>,
    /// The colour range seen so far (pressures), widened as frames arrive.
    span: Option<(f64, f64)>,
}

#[derive(Default)]
pub struct LiveRoom {
    pub form: LiveForm,
    connected: Option<Connected>,
    /// The display frozen by Pause (the engine and the recording go on).
    frozen: Option<Snapshot>,
    /// Why the last connect was refused (the spec or model did not read).
    error: Option<String>,
    /// Teaching by hand: the object and each label set's class chosen.
    object: String,
    labels: Vec<usize>,
    /// A grasp started by hand and not yet ended.
    open_by_hand: bool,
    /// Listing a server's channels (no spec): the answer arrives from a thread.
    discovering: Option<Receiver<Result<Vec<Found>, String>>>,
    found: Vec<Found>,
    found_error: Option<String>,
    /// The spec proposed from `found`, as the user edits it, and where to save it.
    proposed: String,
    left_out: Vec<String>,
    save_to: String,
    saved: Option<Result<String, String>>,
    /// The frame whose keys were read (the keys act once per frame).
    keys_frame: Option<u64>,
}

fn path_or_none(text: &str) -> Option<PathBuf> {
    let t = text.trim();
    (!t.is_empty()).then(|| PathBuf::from(t))
}

impl LiveRoom {
    /// Whether a stream is connected (or being connected).
    pub fn is_connected(&self) -> bool {
        self.connected.is_some()
    }

    /// Connect as the form says: the spec is read here (a short file), the model and the
    /// socket on the engine's thread.
    pub fn connect(&mut self) {
        self.disconnect();
        self.error = None;
        let Some(spec_path) = path_or_none(&self.form.spec) else {
            self.error =
                Some("choose a spec file (or list the server's channels to propose one)".into());
            return;
        };
        let spec = match ImportSpec::load(&spec_path) {
            Ok(s) => s,
            Err(e) => {
                self.error = Some(e.to_string());
                return;
            }
        };
        let label_sets: Vec<LabelSet> = spec.recorded_label_sets().into_iter().cloned().collect();
        let objects = spec
            .label_sets
            .iter()
            .find(|l| l.name == crate::session::spec::OBJECT)
            .map(|l| l.classes.clone())
            .unwrap_or_default();
        self.labels = vec![0; label_sets.len()];
        self.object = objects.first().cloned().unwrap_or_default();
        self.open_by_hand = false;
        let opts = LiveOptions {
            url: self.form.url.trim().to_string(),
            spec: spec.clone(),
            by_hand: self.form.by_hand,
            model: path_or_none(&self.form.model).map(|m| (m, self.form.teach)),
            record: path_or_none(&self.form.record),
            trace_seconds: self.form.trace_seconds.clamp(1.0, 600.0),
        };
        self.connected = Some(Connected {
            running: Running::start(opts),
            url: self.form.url.trim().to_string(),
            sensors: spec.sensors.iter().map(|s| s.sensor.clone()).collect(),
            label_sets,
            objects,
            span: None,
        });
    }

    /// Close the stream (the engine completes the recording on its own thread).
    pub fn disconnect(&mut self) {
        if let Some(c) = self.connected.take() {
            c.running.stop();
        }
        self.frozen = None;
    }

    /// The connected engine's snapshot.
    pub fn snapshot(&self) -> Option<std::sync::Arc<std::sync::Mutex<Snapshot>>> {
        self.connected.as_ref().map(|c| c.running.snapshot.clone())
    }

    pub fn paused(&self) -> bool {
        self.frozen.is_some()
    }

    /// Pause freezes what is shown; the engine and the recording go on.
    pub fn toggle_pause(&mut self) {
        self.frozen = match (&self.frozen, &self.connected) {
            (Some(_), _) | (None, None) => None,
            (None, Some(c)) => Some(lock(&c.running.snapshot).clone()),
        };
    }

    /// Draw `f` over the shown snapshot: the frozen one, else the live one under its lock
    /// (held only while the tile draws).
    fn shown<R>(&self, f: impl FnOnce(&Snapshot) -> R) -> Option<R> {
        if let Some(s) = &self.frozen {
            return Some(f(s));
        }
        let c = self.connected.as_ref()?;
        let guard = lock(&c.running.snapshot);
        Some(f(&guard))
    }

    /// A command by hand to the engine (its refusal shows in the status).
    fn command(&mut self, text: String) {
        if let Some(c) = &self.connected
            && !c.running.command(&text)
        {
            self.error = Some("the engine is busy: the command was not taken".into());
        }
    }

    fn labels_text(&self, c: &Connected) -> String {
        c.label_sets
            .iter()
            .zip(&self.labels)
            .map(|(s, &k)| s.classes.get(k).cloned().unwrap_or_default())
            .collect::<Vec<_>>()
            .join(",")
    }

    /// Cut by hand: start a grasp of the chosen object, or end the open one with the
    /// chosen labels (the key `G` does the same).
    pub fn cut_by_hand(&mut self) {
        let Some(c) = &self.connected else { return };
        let text = if self.open_by_hand {
            format!("end:{}", self.labels_text(c))
        } else {
            format!("start:{}", self.object.trim())
        };
        self.open_by_hand = !self.open_by_hand;
        self.command(text);
    }

    fn discover(&mut self, ctx: &egui::Context) {
        let (tx, rx) = channel();
        let url = self.form.url.trim().to_string();
        let ctx = ctx.clone();
        std::thread::spawn(move || {
            let _ = tx
                .send(discover::discover(&url, Duration::from_secs(3)).map_err(|e| e.to_string()));
            ctx.request_repaint();
        });
        self.discovering = Some(rx);
        self.found_error = None;
    }

    fn poll_discovery(&mut self) {
        let Some(rx) = &self.discovering else { return };
        let Ok(answer) = rx.try_recv() else { return };
        self.discovering = None;
        match answer {
            Ok(found) => {
                let (spec, left_out) = discover::propose("live stream", &found);
                self.proposed = serde_json::to_string_pretty(&spec).unwrap_or_default();
                self.left_out = left_out;
                self.found = found;
            }
            Err(e) => self.found_error = Some(e),
        }
    }

    /// Save the edited proposal atomically, once it reads as a spec; the form then uses it.
    fn save_proposal(&mut self) {
        let Some(path) = path_or_none(&self.save_to) else {
            self.saved = Some(Err("give a file to save the spec to".into()));
            return;
        };
        let outcome = ImportSpec::from_str(&self.proposed, &path)
            .map_err(|e| e.to_string())
            .and_then(|_| {
                crate::fsutil::write_atomic(&path, self.proposed.as_bytes())
                    .map_err(|e| format!("{}: {e}", path.display()))
            });
        self.saved = Some(match outcome {
            Ok(()) => {
                self.form.spec = path.display().to_string();
                Ok(format!("saved {}", path.display()))
            }
            Err(e) => Err(e),
        });
    }

    fn form_fields(&mut self, ui: &mut egui::Ui) {
        let field = |ui: &mut egui::Ui, label: &str, text: &mut String, hint: &str| {
            let l = ui.label(label);
            ui.add(
                egui::TextEdit::singleline(text)
                    .hint_text(hint)
                    .desired_width(f32::INFINITY),
            )
            .labelled_by(l.id);
        };
        field(ui, "Server", &mut self.form.url, "ws://HOST:PORT");
        field(
            ui,
            "Spec file",
            &mut self.form.spec,
            "a .spec.json (docs/live.md)",
        );
        field(
            ui,
            "Model file (optional)",
            &mut self.form.model,
            "a model from `fit`",
        );
        ui.add_enabled(
            !self.form.model.trim().is_empty(),
            egui::Checkbox::new(&mut self.form.teach, "Teach it with each labelled grasp"),
        );
        field(
            ui,
            "Record to (optional)",
            &mut self.form.record,
            "a session file; each grasp is journalled as it ends",
        );
        ui.checkbox(&mut self.form.by_hand, "Cut grasps by hand");
        ui.add(
            egui::Slider::new(&mut self.form.trace_seconds, 2.0..=60.0)
                .text("trace span (s)")
                .integer(),
        );
    }

    fn discovery_ui(&mut self, ui: &mut egui::Ui) {
        ui.label("No spec? List what the server advertises and start from a proposed spec.");
        if ui
            .add_enabled(
                self.discovering.is_none(),
                egui::Button::new("List channels"),
            )
            .clicked()
        {
            self.discover(ui.ctx());
        }
        if self.discovering.is_some() {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("listening to the server…");
            });
        }
        if let Some(e) = &self.found_error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        if self.found.is_empty() {
            return;
        }
        ui.label(format!("{} channels advertised:", self.found.len()));
        for f in &self.found {
            ui.small(f.line());
        }
        for l in &self.left_out {
            ui.small(format!("left out: {l}"));
        }
        let l = ui.label("Proposed spec (edit it: units, ranges, label sets):");
        // A long spec scrolls in a box of its own, so Save stays in reach.
        egui::ScrollArea::vertical()
            .id_salt("proposed-spec")
            .max_height(260.0)
            .show(ui, |ui| {
                ui.add(
                    egui::TextEdit::multiline(&mut self.proposed)
                        .code_editor()
                        .desired_rows(10)
                        .desired_width(f32::INFINITY),
                )
                .labelled_by(l.id);
            });
        ui.horizontal(|ui| {
            let l = ui.label("Save as");
            ui.add(egui::TextEdit::singleline(&mut self.save_to).hint_text("robot.spec.json"))
                .labelled_by(l.id);
        });
        if ui.button("Save spec").clicked() {
            self.save_proposal();
        }
        match &self.saved {
            Some(Ok(t)) => {
                ui.label(t);
            }
            Some(Err(e)) => {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            None => {}
        }
    }

    fn status_ui(&mut self, ui: &mut egui::Ui) {
        let Some(c) = &self.connected else {
            ui.label("Not connected: File > Connect to a live stream…, or the form's Connect.");
            if let Some(e) = &self.error {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            return;
        };
        let url = c.url.clone();
        let by_hand_cutting = self.shown(|s| s.cutting == "by hand").unwrap_or(false);
        let contact_cutting = self.shown(|s| s.cutting == "by contact").unwrap_or(false);
        let lines = self.shown(status_lines).unwrap_or_default();
        ui.strong(&url);
        for (text, warn) in lines {
            if warn {
                ui.colored_label(ui.visuals().warn_fg_color, text);
            } else {
                ui.label(text);
            }
        }
        if let Some(e) = &self.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        ui.horizontal(|ui| {
            let pause = if self.paused() { "Resume" } else { "Pause" };
            if ui
                .button(pause)
                .on_hover_text("Freeze the display; the recording goes on (key P)")
                .clicked()
            {
                self.toggle_pause();
            }
            if ui.button("Disconnect").clicked() {
                self.disconnect();
            }
        });
        if self.paused() {
            ui.colored_label(
                ui.visuals().warn_fg_color,
                "paused: the display is frozen, the stream is still recorded",
            );
        }
        if by_hand_cutting || contact_cutting {
            self.teach_ui(ui, by_hand_cutting);
        }
    }

    /// The object and labels of a grasp cut (or, under contact cutting, labelled) by hand.
    fn teach_ui(&mut self, ui: &mut egui::Ui, by_hand: bool) {
        let Some(c) = &self.connected else { return };
        let objects = c.objects.clone();
        let sets = c.label_sets.clone();
        ui.separator();
        ui.horizontal_wrapped(|ui| {
            let l = ui.label("Object");
            ui.add(egui::TextEdit::singleline(&mut self.object).desired_width(100.0))
                .labelled_by(l.id);
            if !objects.is_empty() {
                egui::ComboBox::from_label("known objects")
                    .selected_text("…")
                    .show_ui(ui, |ui| {
                        for o in &objects {
                            ui.selectable_value(&mut self.object, o.clone(), o);
                        }
                    });
            }
            for (k, set) in sets.iter().enumerate() {
                let chosen = self.labels.get(k).copied().unwrap_or(0);
                egui::ComboBox::from_label(&set.name)
                    .selected_text(set.classes.get(chosen).cloned().unwrap_or_default())
                    .show_ui(ui, |ui| {
                        for (i, class) in set.classes.iter().enumerate() {
                            if let Some(slot) = self.labels.get_mut(k) {
                                ui.selectable_value(slot, i, class);
                            }
                        }
                    });
            }
        });
        if by_hand {
            let text = if self.open_by_hand {
                "End grasp (G)"
            } else {
                "Start grasp (G)"
            };
            ui.horizontal(|ui| {
                if ui.button(text).clicked() {
                    self.cut_by_hand();
                }
                if ui
                    .add_enabled(self.open_by_hand, egui::Button::new("Key frame (K)"))
                    .clicked()
                {
                    self.command("key".into());
                }
            });
        } else if ui
            .button("Label the next grasp")
            .on_hover_text("Grasps are cut by contact: the next one gets these labels")
            .clicked()
        {
            let labels = self.labels_text(c);
            let text = format!("label:{}:{labels}", self.object.trim());
            self.command(text);
        }
    }

    fn touch_ui(&mut self, ui: &mut egui::Ui) {
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

    fn traces_ui(&self, ui: &mut egui::Ui) {
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

    fn model_ui(&self, ui: &mut egui::Ui) {
        // Under the lock: the verdicts' last steps and charts, not every step of them.
        let Some(view) = self.shown(|s| {
            (
                s.open_verdict.as_ref().map(Shown::of),
                s.last_verdict.as_ref().map(Shown::of),
                s.early_error.clone(),
                s.in_progress,
                s.recent.iter().rev().take(4).cloned().collect::<Vec<_>>(),
            )
        }) else {
            ui.label("No stream.");
            return;
        };
        let (open, last, early_error, in_progress, recent) = view;
        // The latest grasps' lines stay in sight below the chart where it has its minimum.
        let reserve = if recent.is_empty() {
            0.0
        } else {
            (recent.len() as f32 + 1.0) * 15.0 + 12.0
        };
        if let Some(e) = early_error {
            ui.colored_label(ui.visuals().warn_fg_color, format!("model: {e}"));
        }
        match (&open, &last) {
            (Some(v), _) => {
                ui.strong(format!("Grasp in progress: {in_progress} frames"));
                verdict_ui(ui, v, true, reserve);
            }
            (None, Some(v)) => {
                ui.strong("Last grasp");
                verdict_ui(ui, v, false, reserve);
            }
            (None, None) => {
                ui.label(if in_progress > 0 {
                    format!("Grasp in progress: {in_progress} frames")
                } else {
                    "Waiting for a grasp (choose a model file in the form to see it at work)."
                        .into()
                });
            }
        }
        // As many of the latest grasps as the chart leaves room for, the newest first.
        let line = ui.text_style_height(&egui::TextStyle::Small) + ui.spacing().item_spacing.y;
        let fit = ((ui.available_height() - 12.0) / line - 1.0)
            .floor()
            .max(0.0) as usize;
        if fit > 0 && !recent.is_empty() {
            ui.separator();
            ui.small("Latest grasps");
            for line in recent.into_iter().take(fit) {
                // The CLI's arrow is not in the window's font; one line each (a cut line
                // shows whole on hover).
                let line = line.replace('→', "->");
                ui.add(egui::Label::new(egui::RichText::new(line).small()).truncate());
            }
        }
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

/// The connection's status as lines, the ones that need attention marked.
fn status_lines(s: &Snapshot) -> Vec<(String, bool)> {
    let st = &s.status;
    let mut out = Vec::new();
    if let Some(f) = &s.failed {
        out.push((format!("could not start: {f}"), true));
    }
    out.push(match &st.state {
        State::Connecting => ("connecting…".into(), false),
        State::Connected {
            server,
            subprotocol,
        } => (format!("connected to `{server}` ({subprotocol})"), false),
        State::Reconnecting { attempt, error } => {
            (format!("reconnecting (attempt {attempt}): {error}"), true)
        }
        State::Stopped => ("stopped".into(), false),
    });
    out.push((
        format!(
            "{:.0} messages/s · latency {} · {} messages",
            s.rate_hz,
            s.latency_ms.map_or("n/a".into(), |l| format!("{l:.1} ms")),
            st.messages
        ),
        false,
    ));
    out.push((
        format!(
            "{} dropped (frames left out) · {} malformed · {} queue waits · {} reconnects",
            s.left_out, st.malformed, st.waits, st.reconnects
        ),
        st.malformed > 0 || s.left_out > 0,
    ));
    if let Some(m) = &st.last_malformed {
        out.push((format!("last malformed: {m}"), true));
    }
    for r in &st.refused {
        out.push((format!("refused {r}"), true));
    }
    out.push((
        format!(
            "cut {} · {} grasps · {} recorded · {} taps left out",
            s.cutting, s.grasps, s.recorded, s.taps
        ),
        false,
    ));
    if let Some(r) = &s.last_refused {
        out.push((format!("event refused: {r}"), true));
    }
    if let Some(r) = &s.last_command {
        out.push((format!("command refused: {r}"), true));
    }
    if let Some((level, text)) = &st.server_status {
        out.push((format!("server says: {text}"), *level > 0));
    }
    out
}

/// A verdict: the decision, when it settled, the latest step's distribution as bars and
/// every class's probability over the steps.
/// `reserve`: the height to leave below the chart.
/// What the model tile draws of a verdict: the verdict with its latest step only, how many
/// steps it has, and its chart.
struct Shown {
    verdict: Verdict,
    steps: usize,
    figure: Option<crate::figures::Figure>,
}

impl Shown {
    fn of(v: &Verdict) -> Shown {
        Shown {
            verdict: Verdict {
                method: v.method,
                predicted: v.predicted.clone(),
                decision: v.decision,
                classes: v.classes.clone(),
                steps: v.steps.last().cloned().into_iter().collect(),
                settled: v.settled,
                novelty: v.novelty,
                novelty_steps: v.novelty_steps.last().copied().into_iter().collect(),
            },
            steps: v.steps.len(),
            figure: v.figure(5),
        }
    }
}

/// The height the model's chart keeps before class bars and the latest grasps give way.
const CHART_MIN: f32 = 150.0;

/// The chart's height: what is left less the latest grasps' `reserve`, but never less
/// than [`CHART_MIN`] where the tile has that (the grasps' lines then give way).
fn chart_height(ui: &egui::Ui, reserve: f32) -> f32 {
    let avail = ui.available_height();
    (avail - reserve).max(CHART_MIN.min(avail))
}

fn verdict_ui(ui: &mut egui::Ui, shown: &Shown, open: bool, reserve: f32) {
    let v = &shown.verdict;
    let word = if open { "running decision" } else { "decided" };
    let mut head = format!("{}: {word} {}", v.method.key(), v.predicted);
    if v.decision.is_finite() {
        head += &format!(" ({:.3})", v.decision);
    }
    if let Some(s) = v.settled {
        head += &format!(" · settled at step {} of {}", s + 1, shown.steps);
    }
    if let Some((n, t)) = v.novelty {
        head += &format!(" · novelty {n:.3} (new cluster above {t:.3})");
    }
    ui.label(head);
    if v.steps.is_empty() {
        novelty_ui(ui, shown, open, reserve);
        return;
    }
    let Some(last) = v.steps.last() else { return };
    ui.small(format!("Class distribution at step {}", shown.steps));
    let text = ui.visuals().text_color();
    let accent = ui.visuals().selection.bg_fill;
    let width = ui.available_width().min(420.0);
    let mut order: Vec<usize> = (0..last.len()).collect();
    order.sort_by(|&a, &b| last[b].total_cmp(&last[a]));
    // The chart keeps a readable height: in a short tile, fewer class bars (the chart
    // names every class it draws).
    let bars = match shown.figure {
        Some(_) => ((ui.available_height() - reserve - CHART_MIN - 20.0) / 16.0).floor() as usize,
        None => 5,
    };
    for &k in order.iter().take(bars.clamp(1, 5)) {
        let (rect, _) = ui.allocate_exact_size(Vec2::new(width, 16.0), Sense::hover());
        let p = last[k].clamp(0.0, 1.0) as f32;
        let label_w = 110.0;
        let bar = egui::Rect::from_min_size(
            rect.min + Vec2::new(label_w, 2.0),
            Vec2::new((rect.width() - label_w - 50.0).max(0.0) * p, 12.0),
        );
        let painter = ui.painter_at(rect);
        let chosen = v.classes.get(k) == Some(&v.predicted);
        painter.rect_filled(bar, 2.0, if chosen { accent } else { Color32::GRAY });
        let name = v.classes.get(k).cloned().unwrap_or_default();
        painter.text(
            rect.left_center(),
            egui::Align2::LEFT_CENTER,
            name,
            egui::FontId::proportional(12.0),
            text,
        );
        painter.text(
            rect.right_center(),
            egui::Align2::RIGHT_CENTER,
            format!("{:.3}", last[k]),
            egui::FontId::proportional(12.0),
            text,
        );
    }
    // The top classes' probability at every step: how the decision formed (a figure of
    // the figure model, so its legend and axes follow the audited layout rules).
    if let Some(figure) = &shown.figure {
        let id = if open {
            "live-steps-open"
        } else {
            "live-steps-last"
        };
        figure_view::show(
            ui,
            id,
            figure,
            chart_height(ui, reserve),
            FigureSelection::None,
        );
    }
}

/// DU/GU: the cluster of the grasp so far and its novelty at every step, against the
/// threshold (the chart's reference line).
fn novelty_ui(ui: &mut egui::Ui, shown: &Shown, open: bool, reserve: f32) {
    let Some(s) = shown.verdict.novelty_steps.last() else {
        return;
    };
    let cluster = crate::models::clustering::cluster_name(s.cluster);
    ui.small(format!(
        "At step {}: novelty {:.3} of the grasp so far against {cluster}",
        s.step + 1,
        s.novelty
    ));
    if let Some(figure) = &shown.figure {
        let id = if open {
            "live-novelty-open"
        } else {
            "live-novelty-last"
        };
        figure_view::show(
            ui,
            id,
            figure,
            chart_height(ui, reserve),
            FigureSelection::None,
        );
    }
}

impl Room for LiveRoom {
    fn view(&self) -> View {
        View::Live
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![
            vec![Pane::Live(LivePane::Touch)],
            vec![Pane::Live(LivePane::Model)],
            vec![Pane::Live(LivePane::Traces)],
            vec![Pane::Live(LivePane::Status)],
        ]
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        self.poll_discovery();
        ui.heading("Live stream");
        self.form_fields(ui);
        ui.horizontal(|ui| {
            if ui.button("Connect").clicked() {
                self.connect();
            }
            if ui
                .add_enabled(self.is_connected(), egui::Button::new("Disconnect"))
                .clicked()
            {
                self.disconnect();
            }
        });
        if let Some(e) = &self.error {
            ui.colored_label(ui.visuals().error_fg_color, e);
        }
        ui.separator();
        self.discovery_ui(ui);
        self.keys(&cx.ctx);
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, pane: &Pane, cx: &mut Cx) -> bool {
        let Pane::Live(p) = pane else { return false };
        self.keys(&cx.ctx);
        match p {
            LivePane::Touch => self.touch_ui(ui),
            LivePane::Traces => self.traces_ui(ui),
            LivePane::Model => self.model_ui(ui),
            LivePane::Status => self.status_ui(ui),
        }
        // A live display redraws at a steady pace while the stream runs.
        if self.connected.is_some() && !self.paused() {
            cx.ctx.request_repaint_after(Duration::from_millis(33));
        }
        true
    }
}

impl LiveRoom {
    /// The keys (P pause, G cut by hand, K key frame), once per frame whichever tiles draw.
    fn keys(&mut self, ctx: &egui::Context) {
        let frame = ctx.cumulative_frame_nr();
        if self.keys_frame == Some(frame) || ctx.text_edit_focused() {
            return;
        }
        self.keys_frame = Some(frame);
        let (p, g, k) = ctx.input(|i| {
            (
                i.key_pressed(egui::Key::P),
                i.key_pressed(egui::Key::G),
                i.key_pressed(egui::Key::K),
            )
        });
        if p {
            self.toggle_pause();
        }
        let by_hand = self.shown(|s| s.cutting == "by hand").unwrap_or(false);
        if g && by_hand {
            self.cut_by_hand();
        }
        if k && by_hand && self.open_by_hand {
            self.command("key".into());
        }
    }
}
