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
//!
//! Here the form, the connection and the status tile; `touch` the heatmaps and traces,
//! `model_at_work` the model's tile, `discovery` the spec proposed from the server.

mod discovery;
mod model_at_work;
mod touch;

use std::path::PathBuf;
use std::sync::mpsc::Receiver;
use std::time::Duration;

use serde::{Deserialize, Serialize};

use super::pane::{LivePane, Pane};
use super::{Cx, Room};
use crate::app::View;
use crate::live::client::{State, lock};
use crate::live::discover::Found;
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
