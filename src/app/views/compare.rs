//! The Compare view: any signal of the active session for many grasps on one timeline. The
//! form holds the searchable signal tree (and a clickable taxel map of the focused frame),
//! the event grasps are aligned at, the groups and their spread; the tiles show the
//! selection's grasps overlaid, one band (or, for single frames, one distribution) per
//! group, and a grasps × time heatmap. The engine (`crate::compare`) computes them on a
//! worker thread; the replay's frame cursor is drawn on every time plot, and a click seeks
//! or focuses.

use std::sync::Arc;
use std::sync::mpsc::{Receiver, channel};

use egui::RichText;
use serde::{Deserialize, Serialize};

use super::pane::Pane;
use super::{Cx, Room};
use crate::app::View;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::selection::Command;
use crate::compare::{
    self, ComparePlot, Comparison, Event, Groups, ModelReading, Request, Signal, Spread,
    StepOutputs, grasp_name,
};
use crate::experiments::result::{AnalysisKind, AnalysisResult};
use crate::figures::{ColorMap, Figure, FigureKind};
use crate::models::Model;
use crate::session::Session;

/// What grasps are grouped by.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Grouping {
    /// The classes of the session's label set of this name (the first when absent).
    #[default]
    FirstLabelSet,
    LabelSet(String),
    Object,
    /// Right or wrong by the chosen model.
    CorrectWrong,
    /// The cells of the chosen model's confusion map.
    ConfusionCells,
    /// The chosen clustering model's clusters.
    Clusters,
    /// A clustering result's clusters at its chosen threshold (the result by its creation
    /// time and label, as a pinned tile names it).
    ResultClusters {
        created: u64,
        label: String,
    },
}

impl Grouping {
    fn text(&self, session: &Session) -> String {
        match self {
            Grouping::FirstLabelSet => match session.label_sets.first() {
                Some(l) => format!("label: {} (the first)", l.name),
                None => "all grasps (no labels)".into(),
            },
            Grouping::LabelSet(name) => format!("label: {name}"),
            Grouping::Object => "object".into(),
            Grouping::CorrectWrong => "correct vs wrong (model)".into(),
            Grouping::ConfusionCells => "confusion cells (model)".into(),
            Grouping::Clusters => "clusters (model)".into(),
            Grouping::ResultClusters { label, .. } => format!("clusters of {label}"),
        }
    }

    /// A clustering result's clusters, read where the results are (the window's thread);
    /// None for every other grouping.
    fn of_result(&self, results: &[AnalysisResult], grasps: usize) -> Option<Groups> {
        let Grouping::ResultClusters { created, label } = self else {
            return None;
        };
        (results.iter())
            .find(|r| r.created == *created && &r.label == label)
            .and_then(|r| Groups::by_result_clusters(r, grasps))
    }

    fn groups(&self, session: &Session, reading: Option<&ModelReading>) -> Groups {
        let labels = |set: Option<usize>| match set {
            Some(set) => Groups::by_label_set(session, set),
            None => Groups::all(session),
        };
        match (self, reading) {
            (Grouping::FirstLabelSet, _) => labels((!session.label_sets.is_empty()).then_some(0)),
            (Grouping::LabelSet(name), _) => labels(session.label_set(name)),
            (Grouping::Object, _) => Groups::by_object(session),
            (Grouping::CorrectWrong, Some(r)) => {
                let mut g = Groups::correct_vs_wrong(&r.truth, &r.predicted);
                g.title = format!("correct vs wrong ({})", r.model);
                g
            }
            (Grouping::ConfusionCells, Some(r)) => {
                Groups::confusion_cells(&r.classes, &r.truth, &r.predicted)
            }
            (
                Grouping::Clusters,
                Some(ModelReading {
                    clusters: Some(c), ..
                }),
            ) => c.clone(),
            // A model's groups without a model read yet (or of another kind of model):
            // everything in one.
            // (A result's clusters are read beforehand, by `of_result`; here the result is
            // gone.)
            (
                Grouping::CorrectWrong
                | Grouping::ConfusionCells
                | Grouping::Clusters
                | Grouping::ResultClusters { .. },
                _,
            ) => Groups::all(session),
        }
    }
}

/// The form's choices, kept between runs.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct CompareForm {
    pub signal: Signal,
    pub event: Event,
    pub spread: Spread,
    pub grouping: Grouping,
}

impl Default for CompareForm {
    fn default() -> Self {
        CompareForm {
            signal: Signal::HandTotal,
            event: Event::default(),
            spread: Spread::default(),
            grouping: Grouping::default(),
        }
    }
}

/// What a comparison was computed for: when any of it changes, it is computed again.
#[derive(Clone, Debug, PartialEq)]
struct Key {
    session: String,
    grasps: usize,
    form: CompareForm,
    overlaid: Vec<usize>,
    /// The model whose outputs and groups the comparison reads (index into the models).
    model: Option<usize>,
    /// Whether that model's reading had arrived.
    read: bool,
}

/// A model's reading of the active session, computed on a worker.
struct Reading {
    session: String,
    model: usize,
    result: Option<Result<Arc<ModelReading>, String>>,
    rx: Option<Receiver<Result<ModelReading, String>>>,
}

#[derive(Default)]
pub struct CompareRoom {
    pub form: CompareForm,
    /// The text the signal tree is searched by.
    pub search: String,
    /// The model whose per-step outputs are in the tree (index into the models list).
    pub model: Option<usize>,
    reading: Option<Reading>,
    /// The comparison on screen, and what it was computed for.
    pub shown: Option<Arc<Comparison>>,
    shown_key: Option<Key>,
    pending: Option<(Key, Receiver<Comparison>)>,
    /// The grasp of the point under the pointer, and in which plot.
    pointing: Option<(ComparePlot, usize)>,
    zoomed: Option<Zoomed>,
}

/// The heatmap's columns in the time plots' zoom.
struct Zoomed {
    /// The comparison's address: a new comparison is cropped anew.
    comparison: usize,
    range: (f64, f64),
    /// None: no column in the range.
    figure: Option<Arc<Figure>>,
}

/// The link group of the time plots' x axes (zoom one, and all follow).
fn time_link() -> egui::Id {
    egui::Id::unique("compare-time-axis")
}

impl Room for CompareRoom {
    fn view(&self) -> View {
        View::Compare
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![
            vec![Pane::Compare(ComparePlot::Groups)],
            vec![Pane::Compare(ComparePlot::Overlay)],
            vec![Pane::Compare(ComparePlot::Heatmap)],
            vec![Pane::Replay],
        ]
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        let Some(s) = cx.session() else {
            ui.label("Open a session first.");
            return;
        };
        let session = s.session.clone();
        self.poll(cx);
        self.choices_ui(ui, cx, &session);
        ui.separator();
        self.taxel_map_ui(ui, cx, &session);
        ui.separator();
        self.tree_ui(ui, &session);
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, pane: &Pane, cx: &mut Cx) -> bool {
        let Pane::Compare(plot) = pane else {
            return false;
        };
        self.poll(cx);
        self.plot_ui(ui, *plot, cx);
        true
    }

    fn hides(&self, pane: &Pane) -> bool {
        // Single frames have no time: their grasps × time would be one column.
        *pane == Pane::Compare(ComparePlot::Heatmap)
            && self.shown.as_ref().is_some_and(|c| c.single_frame)
    }
}

impl CompareRoom {
    /// Whether a comparison or a model's reading is being computed.
    pub fn computing(&self) -> bool {
        self.pending.is_some() || self.reading.as_ref().is_some_and(|r| r.rx.is_some())
    }

    /// The grasps × time heatmap as drawn while the time plots are zoomed (None when they
    /// are not, or no column lies in their range).
    pub fn heatmap_in_zoom(&self) -> Option<&Figure> {
        self.zoomed.as_ref()?.figure.as_deref()
    }

    /// The outputs of the chosen model, once read.
    fn outputs(&self) -> Option<Arc<ModelReading>> {
        match &self.reading {
            Some(Reading {
                result: Some(Ok(r)),
                model,
                ..
            }) if Some(*model) == self.model => Some(r.clone()),
            _ => None,
        }
    }

    /// Collect what the workers finished, and start what the form now asks for.
    fn poll(&mut self, cx: &mut Cx) {
        let Some(s) = cx.session() else { return };
        let session = s.session.clone();
        let name = session.meta.name.clone();
        if let Some(r) = &mut self.reading
            && let Some(rx) = &r.rx
            && let Ok(done) = rx.try_recv()
        {
            r.result = Some(done.map(Arc::new));
            r.rx = None;
        }
        // A model of another session, or gone from the list, is dropped.
        if self
            .model
            .is_some_and(|m| session_model(cx, m, &name).is_none())
        {
            self.model = None;
        }
        let wanted = self.model.map(|m| (name.clone(), m));
        let have = (self.reading.as_ref()).map(|r| (r.session.clone(), r.model));
        if wanted != have {
            self.reading = wanted.map(|(session_name, m)| self.read_model(cx, m, session_name));
        }
        if let Some((_, rx)) = &self.pending
            && let Ok(c) = rx.try_recv()
        {
            let (key, _) = self.pending.take().expect("pending");
            self.shown = Some(Arc::new(c));
            self.shown_key = Some(key);
        }
        let reading = self.outputs();
        let key = Key {
            session: name,
            grasps: session.grasps.len(),
            form: self.form.clone(),
            overlaid: overlaid(cx, &session),
            model: self.model,
            read: reading.is_some(),
        };
        let current = (self.pending.as_ref().map(|p| &p.0)).or(self.shown_key.as_ref());
        if current != Some(&key) {
            self.start(cx, key, session, reading);
        }
    }

    /// Compute the comparison of `key` on a worker (the window never waits for it).
    fn start(
        &mut self,
        cx: &Cx,
        key: Key,
        session: Arc<Session>,
        reading: Option<Arc<ModelReading>>,
    ) {
        let (tx, rx) = channel();
        let ctx = cx.ctx.clone();
        let k = key.clone();
        let of_result = (k.form.grouping).of_result(&cx.analyses.results, session.grasps.len());
        std::thread::spawn(move || {
            let groups =
                of_result.unwrap_or_else(|| k.form.grouping.groups(&session, reading.as_deref()));
            let outputs: &[StepOutputs] = reading.as_ref().map_or(&[], |r| &r.outputs);
            let request = Request {
                signal: k.form.signal,
                event: k.form.event,
                spread: k.form.spread,
                overlaid: k.overlaid.clone(),
                groups,
                seed: 1,
            };
            let _ = tx.send(compare::compare(&session, outputs, &request));
            ctx.request_repaint();
        });
        self.pending = Some((key, rx));
    }

    /// Read model `m`'s per-step outputs of the active session on a worker.
    fn read_model(&self, cx: &Cx, m: usize, session_name: String) -> Reading {
        let (tx, rx) = channel();
        let ctx = cx.ctx.clone();
        let session = cx.session().map(|s| s.session.clone());
        // The outputs are named by the method alone ("DS · true class probability").
        let model = session_model(cx, m, &session_name).map(|_| {
            let file = &cx.analyses.models.list[m].file;
            (file.provenance.method.title().to_string(), file.clone())
        });
        if let (Some(session), Some((title, file))) = (session, model) {
            std::thread::spawn(move || {
                let r = compare::read_model(&title, &file, &session);
                let _ = tx.send(r.map_err(|e| e.to_string()));
                ctx.request_repaint();
            });
        }
        Reading {
            session: session_name,
            model: m,
            result: None,
            rx: Some(rx),
        }
    }

    fn choices_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx, session: &Session) {
        let reading = self.outputs();
        let outputs: &[StepOutputs] = reading.as_ref().map_or(&[], |r| &r.outputs);
        let (name, unit) = self.form.signal.name(session, outputs);
        ui.label(RichText::new(format!("Signal: {name}")).strong())
            .on_hover_text(if unit.is_empty() {
                "no unit".into()
            } else {
                unit
            });
        let caption = ui.label("Align at");
        egui::ComboBox::from_id_salt("compare-event")
            .selected_text(self.form.event.text())
            .show_ui(ui, |ui| {
                for e in Event::ALL {
                    ui.selectable_value(&mut self.form.event, e, e.text());
                }
            })
            .response
            .labelled_by(caption.id);
        let caption = ui.label("Groups");
        let mut choices: Vec<Grouping> = Vec::new();
        choices.extend((session.label_sets.iter()).map(|l| Grouping::LabelSet(l.name.clone())));
        choices.push(Grouping::Object);
        if reading.as_ref().is_some_and(|r| !r.classes.is_empty()) {
            choices.extend([Grouping::CorrectWrong, Grouping::ConfusionCells]);
        }
        if reading.as_ref().is_some_and(|r| r.clusters.is_some()) {
            choices.push(Grouping::Clusters);
        }
        // The clustering results of this session (not held-out ones: their grasps are
        // another session's).
        choices.extend(
            (cx.analyses.results.iter())
                .filter(|r| {
                    r.kind == AnalysisKind::Clustering
                        && r.session == session.meta.name
                        && r.held_out.is_none()
                        && Groups::by_result_clusters(r, session.grasps.len()).is_some()
                })
                .map(|r| Grouping::ResultClusters {
                    created: r.created,
                    label: r.label.clone(),
                }),
        );
        egui::ComboBox::from_id_salt("compare-groups")
            .selected_text(self.form.grouping.text(session))
            .show_ui(ui, |ui| {
                for g in choices {
                    let text = g.text(session);
                    ui.selectable_value(&mut self.form.grouping, g, text);
                }
            })
            .response
            .labelled_by(caption.id);
        let caption = ui.label("Spread");
        egui::ComboBox::from_id_salt("compare-spread")
            .selected_text(self.form.spread.text())
            .show_ui(ui, |ui| {
                for sp in Spread::ALL {
                    ui.selectable_value(&mut self.form.spread, sp, sp.text());
                }
            })
            .response
            .labelled_by(caption.id);
        let name = session.meta.name.clone();
        let models: Vec<(usize, String)> = (0..cx.analyses.models.list.len())
            .filter_map(|m| session_model(cx, m, &name).map(|t| (m, t)))
            .collect();
        let caption = ui.label("Model outputs");
        let chosen = self
            .model
            .and_then(|m| models.iter().find(|(k, _)| *k == m))
            .map_or("none".to_string(), |(_, t)| t.clone());
        egui::ComboBox::from_id_salt("compare-model")
            .selected_text(chosen)
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut self.model, None, "none");
                for (m, title) in &models {
                    ui.selectable_value(&mut self.model, Some(*m), title);
                }
            })
            .response
            .labelled_by(caption.id)
            .on_hover_text(
                "A model of this session: a recognition model's (DS, GS) class probabilities \
                 after every step, or a stability model's SVM decision value, join the \
                 signals, and its decisions the groups; a clustering model's (DU, GU) \
                 clusters join the groups",
            );
        if models.is_empty() {
            ui.weak("No model of this session yet (run an analysis).");
        }
        match &self.reading {
            Some(Reading { rx: Some(_), .. }) => {
                ui.horizontal(|ui| {
                    ui.spinner();
                    ui.label("reading the model's outputs…");
                });
            }
            Some(Reading {
                result: Some(Err(e)),
                ..
            }) => {
                ui.colored_label(ui.visuals().error_fg_color, e);
            }
            _ => {}
        }
    }

    /// The focused grasp's frame on each sensor's layout: a click picks that taxel.
    fn taxel_map_ui(&mut self, ui: &mut egui::Ui, cx: &Cx, session: &Session) {
        let Some((_, g)) = cx.selection.focus.filter(|&(s, _)| s == cx.active) else {
            return;
        };
        let Some(grasp) = session.grasps.get(g) else {
            return;
        };
        let Some(frame) = grasp
            .frames
            .get(cx.replay.frame.min(grasp.frames.len() - 1))
        else {
            return;
        };
        ui.label("Pick a taxel (the replay's frame):");
        let pressures: Vec<Vec<f64>> = (0..session.sensors.len())
            .map(|k| session.frame_pressures(frame, k))
            .collect();
        // Coloured over the frame's own range, so that its contact shows.
        let (lo, hi) = (pressures.iter().flatten().filter(|v| v.is_finite()))
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
                (lo.min(v), hi.max(v))
            });
        let range = if hi > lo { (lo, hi) } else { (0.0, 1.0) };
        ui.horizontal_wrapped(|ui| {
            for (k, (sensor, p)) in session.sensors.iter().zip(&pressures).enumerate() {
                let picked = crate::app::heatmap::taxel_picker(
                    ui,
                    sensor,
                    p,
                    range,
                    ColorMap::Viridis,
                    egui::Vec2::new(56.0, 56.0),
                );
                if let Some(taxel) = picked {
                    self.form.signal = Signal::Taxel { sensor: k, taxel };
                }
            }
        });
    }

    /// The signal tree, searched: a click on a leaf plots it.
    fn tree_ui(&mut self, ui: &mut egui::Ui, session: &Session) {
        let caption = ui.label("Signals");
        ui.add(
            egui::TextEdit::singleline(&mut self.search)
                .hint_text("search: taxel 3, joint, total…"),
        )
        .labelled_by(caption.id);
        let reading = self.outputs();
        let outputs: &[StepOutputs] = reading.as_ref().map_or(&[], |r| &r.outputs);
        let tree = compare::signal::tree(session, outputs);
        let shown = compare::signal::search(&tree, &self.search);
        if shown.is_empty() {
            ui.weak("No signal matches.");
        }
        let searching = !self.search.trim().is_empty();
        for branch in shown {
            egui::CollapsingHeader::new(&branch.name)
                .id_salt(("compare-branch", &branch.name))
                .open(searching.then_some(true))
                .show(ui, |ui| {
                    for (name, signal) in &branch.leaves {
                        let on = self.form.signal == *signal;
                        // Click to plot it, or drag it onto a plot.
                        let leaf = (ui.selectable_label(on, name)).interact(egui::Sense::drag());
                        leaf.dnd_set_drag_payload(*signal);
                        if leaf.clicked() {
                            self.form.signal = *signal;
                        }
                    }
                });
        }
    }

    fn plot_ui(&mut self, ui: &mut egui::Ui, plot: ComparePlot, cx: &mut Cx) {
        // A signal dragged from the tree and dropped anywhere on the tile is plotted.
        let area = ui.max_rect();
        let zone = ui.interact(
            area,
            ui.make_persistent_id(("compare-drop", plot.key())),
            egui::Sense::hover(),
        );
        if zone.dnd_hover_payload::<Signal>().is_some() {
            let stroke = ui.visuals().selection.stroke;
            (ui.painter()).rect_stroke(area, 4.0, stroke, egui::StrokeKind::Inside);
        }
        if let Some(signal) = zone.dnd_release_payload::<Signal>() {
            self.form.signal = *signal;
        }
        let Some(s) = cx.session() else {
            ui.label("Open a session first.");
            return;
        };
        let session = s.session.clone();
        let Some(c) = self.shown.clone() else {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label("Computing…");
            });
            return;
        };
        let figure = c.figure(plot);
        let time_plot = !c.single_frame && plot != ComparePlot::Heatmap;
        let cursor = time_plot
            .then(|| cursor_time(cx, &session, self.form.event))
            .flatten();
        let mut export = false;
        let mut pointing = None;
        ui.horizontal(|ui| {
            export = ui
                .small_button("Export")
                .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
                .clicked();
            if self.pending.is_some() {
                ui.spinner();
            }
            // The grasp under the pointer in the last frame (strips name groups only).
            if let Some((_, g)) = self.pointing.filter(|(p, _)| *p == plot) {
                ui.label(grasp_name(&session, g));
            }
        });
        let id = format!("compare-{}", plot.key());
        let selection = match (plot, time_plot) {
            (ComparePlot::Heatmap, _) => FigureSelection::Cell(None),
            (_, true) => FigureSelection::Marker(cursor.unwrap_or(f64::NAN)),
            (_, false) => FigureSelection::None,
        };
        let height = ui.available_height();
        let link = (!c.single_frame).then(time_link);
        let zoomed = match plot {
            ComparePlot::Heatmap => {
                let range = link.and_then(|l| figure_view::linked_x_range(ui.ctx(), l));
                match range {
                    Some(range) => Some(self.zoomed_heatmap(&c, range)),
                    None => {
                        self.zoomed = None;
                        None
                    }
                }
            }
            _ => None,
        };
        let done = match &zoomed {
            Some(Some(window)) => figure_view::show(ui, &id, window, height, selection),
            Some(None) => {
                ui.label("No frame in the time plots' zoom (double-click one to show all).");
                return;
            }
            None if time_plot => figure_view::show_linked(ui, &id, figure, height, selection, link),
            None => figure_view::show(ui, &id, figure, height, selection),
        };
        let points = match plot {
            ComparePlot::Overlay => &c.overlay_grasps,
            _ => &c.group_grasps,
        };
        let grasp_of = |(series, k): (usize, usize)| {
            let p = points.get(series)?;
            p.get(k).or(p.first()).copied()
        };
        if let Some(g) = done.hovered_point.and_then(grasp_of) {
            pointing = Some(g);
        }
        if let Some(g) = done.clicked_point.and_then(grasp_of) {
            cx.commands.push(Command::Focus {
                session: cx.active,
                grasp: g,
            });
        }
        if let Some(x) = done.marker_x {
            // A click on a trace focuses its grasp; elsewhere it seeks the replay.
            let near = (plot == ComparePlot::Overlay)
                .then(|| nearest_trace(ui.ctx(), &id, figure, &c.overlay_grasps))
                .flatten();
            match near {
                Some(g) => cx.commands.push(Command::Focus {
                    session: cx.active,
                    grasp: g,
                }),
                None => seek(cx, &session, self.form.event, x),
            }
        }
        if let Some([row, _]) = done.clicked_cell
            && let Some(&g) = c.heatmap_rows.get(row)
        {
            cx.commands.push(Command::Focus {
                session: cx.active,
                grasp: g,
            });
        }
        if pointing.is_some() || self.pointing.is_some_and(|(p, _)| p == plot) {
            self.pointing = pointing.map(|g| (plot, g));
        }
        if export {
            cx.analyses.export_figure(figure, plot.key());
        }
    }

    /// The heatmap's columns within `range` of aligned time, built once per comparison and
    /// range.
    fn zoomed_heatmap(&mut self, c: &Arc<Comparison>, range: (f64, f64)) -> Option<Arc<Figure>> {
        let at = Arc::as_ptr(c) as usize;
        match &self.zoomed {
            Some(z) if z.comparison == at && z.range == range => z.figure.clone(),
            _ => {
                let f = compare::time_window(&c.heatmap, &c.heatmap_times, range.0, range.1)
                    .map(Arc::new);
                self.zoomed = Some(Zoomed {
                    comparison: at,
                    range,
                    figure: f.clone(),
                });
                f
            }
        }
    }
}

/// The grasps overlaid: the selection's, when it is of the active session, else them all.
fn overlaid(cx: &Cx, session: &Session) -> Vec<usize> {
    let sel = cx.selection;
    if sel.session == Some(cx.active) && !sel.grasps.is_empty() {
        sel.grasps.clone()
    } else {
        (0..session.grasps.len()).collect()
    }
}

/// Model `m` of the models list when the Compare view reads it (DS, GS; sparse-svm,
/// raw-svm; DU, GU) and the session named `session` has its label set: its title ("DS,
/// trained on …").
fn session_model(cx: &Cx, m: usize, session: &str) -> Option<String> {
    let kept = cx.analyses.models.list.get(m)?;
    let label_set = match &kept.file.model {
        Model::Sequences(model) => &model.label_set,
        Model::Stability(model) => &model.label_set,
        Model::Clusters(model) => &model.label_set,
        Model::TableOne(_) | Model::Classifier(_) => return None,
    };
    let s = cx
        .sessions
        .iter()
        .find(|s| s.session.meta.name == session)?;
    s.session.label_set(label_set)?;
    let p = &kept.file.provenance;
    Some(format!(
        "{}, trained on {}",
        p.method.title(),
        p.session.name
    ))
}

/// The replay's frame as aligned time of the focused grasp (None when the focus is not in
/// the active session).
fn cursor_time(cx: &Cx, session: &Session, event: Event) -> Option<f64> {
    let (_, g) = cx.selection.focus.filter(|&(s, _)| s == cx.active)?;
    event.times(session, g).get(cx.replay.frame).copied()
}

/// Seek the replay of the focused grasp to aligned time `x`.
fn seek(cx: &mut Cx, session: &Session, event: Event, x: f64) {
    if let Some((_, g)) = cx.selection.focus.filter(|&(s, _)| s == cx.active) {
        let times = event.times(session, g);
        cx.replay.seek(x, &times);
    }
}

/// The overlaid grasp whose trace passes nearest the pointer (within a few points), from
/// where the chart drew its points in this frame.
fn nearest_trace(
    ctx: &egui::Context,
    id: &str,
    figure: &crate::figures::Figure,
    grasps: &compare::PointGrasps,
) -> Option<usize> {
    let FigureKind::Chart(chart) = &figure.kind else {
        return None;
    };
    let pointer = ctx.pointer_interact_pos()?;
    let mut best: Option<(f32, usize)> = None;
    for (i, s) in chart.series.iter().enumerate() {
        for k in 0..s.x.len() {
            if let Some(p) = figure_view::marker_position(ctx, id, chart, i, k) {
                let d = p.distance(pointer);
                if d <= 6.0 && best.is_none_or(|(b, _)| d < b) {
                    best = Some((d, i));
                }
            }
        }
    }
    best.and_then(|(_, i)| grasps.get(i)?.first().copied())
}
