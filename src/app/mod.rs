//! The egui workbench. One room per view (`views/`), each a form and tiles; the app owns
//! the open sessions, the results, the selection and the command queue; rooms read them
//! and push commands, applied between frames. Nothing here blocks: files load and analyses
//! run on worker threads.

pub mod browser;
pub mod figure_view;
pub mod files;
pub mod heatmap;
pub mod import;
pub mod loader;
pub mod models;
pub mod notify;
pub mod replay;
pub mod results;
pub mod selection;
pub mod views;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::mpsc::{Receiver, channel};
use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::experiments::result::AnalysisKind;
use browser::{Browser, BrowserAction};
use files::{FilePicker, Picked, Purpose};
use loader::{LoadedSession, Loader, Source};
use replay::Replay;
use results::Analyses;
use selection::{Command, ModelSpec, Selection};
use views::{Cx, Layout, Pane, Rooms};

const STORAGE_KEY: &str = "tactile-workbench";
const MAX_RECENT: usize = 10;

pub use crate::cli::View;

impl View {
    pub const ALL: [View; 7] = [
        View::Replay,
        View::Stability,
        View::Recognition,
        View::Clustering,
        View::Baselines,
        View::SpeedAccuracy,
        View::Robustness,
    ];

    pub fn title(self) -> &'static str {
        match self {
            View::Replay => "Replay",
            View::Stability => "Grasp stability",
            View::Recognition => "Recognition",
            View::Clustering => "Clustering",
            View::Baselines => "Baselines",
            View::SpeedAccuracy => "Speed vs accuracy",
            View::Robustness => "Where methods fail",
        }
    }

    /// The analysis this view shows, if it shows one.
    pub fn kind(self) -> Option<AnalysisKind> {
        match self {
            View::Stability => Some(AnalysisKind::Stability),
            View::Recognition => Some(AnalysisKind::Recognition),
            View::Clustering => Some(AnalysisKind::Clustering),
            View::Baselines => Some(AnalysisKind::Baselines),
            View::Robustness => Some(AnalysisKind::Robustness),
            View::Replay | View::SpeedAccuracy => None,
        }
    }

    fn of(kind: AnalysisKind) -> View {
        match kind {
            AnalysisKind::Baselines => View::Baselines,
            AnalysisKind::Recognition => View::Recognition,
            AnalysisKind::Clustering => View::Clustering,
            AnalysisKind::Stability => View::Stability,
            AnalysisKind::Robustness => View::Robustness,
        }
    }
}

/// The file in the data folder that keeps the open project between runs.
pub const KEPT_RESULTS: &str = "results.json";

/// What persists between runs.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Persisted {
    pub sources: Vec<Source>,
    pub view: View,
    pub dark: bool,
    pub recent: Vec<PathBuf>,
    pub browser: Browser,
    /// The focused grasp: (session, grasp).
    pub selected: Option<(usize, usize)>,
    pub replay: Replay,
    /// Each view's tiles, by view title.
    #[serde(default)]
    pub layouts: BTreeMap<String, Layout>,
    #[serde(default = "yes")]
    pub form_open: bool,
    /// Each view's form settings.
    #[serde(default)]
    pub forms: views::Forms,
    /// The folder the file picker last opened from or saved to.
    #[serde(default)]
    pub last_folder: Option<PathBuf>,
    /// Run times measured on this machine, which correct the expected times.
    #[serde(default)]
    pub timings: crate::jobs::estimate::Timings,
}

fn yes() -> bool {
    true
}

impl Default for Persisted {
    fn default() -> Self {
        Persisted {
            sources: Vec::new(),
            view: View::default(),
            dark: true,
            recent: Vec::new(),
            browser: Browser::default(),
            selected: None,
            replay: Replay::default(),
            layouts: BTreeMap::new(),
            form_open: true,
            forms: views::Forms::default(),
            last_folder: None,
            timings: Default::default(),
        }
    }
}

pub struct WorkbenchApp {
    pub sessions: Vec<LoadedSession>,
    /// The selected grasps and the focused one (the one the replay shows).
    pub selection: Selection,
    /// Changes asked for while drawing, applied between frames.
    pub commands: Vec<Command>,
    pub browser: Browser,
    pub replay: Replay,
    pub view: View,
    pub dark: bool,
    pub recent: Vec<PathBuf>,
    pub analyses: Analyses,
    pub rooms: Rooms,
    pub layouts: BTreeMap<String, Layout>,
    /// The form side panel is open.
    pub form_open: bool,
    loader: Loader,
    /// Sources in the order they were asked for, so sessions list in a stable order.
    requested: Vec<Source>,
    /// The system file dialog, while it is open (on its own thread).
    dialog: Option<(Purpose, Receiver<Vec<PathBuf>>)>,
    /// The in-app file picker, while it is open.
    pub picker: Option<FilePicker>,
    /// The folder the file picker last opened from or saved to.
    last_folder: Option<PathBuf>,
    /// Recordings (ROS 2 bags, long-format CSVs) waiting for their import spec.
    pub import: import::ImportDialog,
    pub cluster: views::cluster::ClusterForm,
    /// The selection to restore once the persisted sessions have loaded.
    restore: Option<(usize, usize)>,
    /// After a project opens: once its sessions have loaded, show the open view's results,
    /// or else those of this session.
    focus_pending: Option<Option<String>>,
}

impl WorkbenchApp {
    /// A workbench opening `files`, or else the sessions of the last run, or else the
    /// bundled sample sessions.
    pub fn new(ctx: &egui::Context, persisted: Option<Persisted>, files: Vec<PathBuf>) -> Self {
        let p = persisted.unwrap_or_default();
        let mut app = WorkbenchApp {
            sessions: Vec::new(),
            selection: Selection::default(),
            commands: Vec::new(),
            browser: p.browser.clone(),
            replay: p.replay.clone(),
            view: p.view,
            dark: p.dark,
            recent: p.recent.clone(),
            analyses: Analyses::default(),
            rooms: Rooms::with_forms(p.forms.clone()),
            layouts: p.layouts.clone(),
            form_open: p.form_open,
            loader: Loader::default(),
            requested: Vec::new(),
            dialog: None,
            picker: None,
            last_folder: p.last_folder.clone(),
            import: import::ImportDialog::default(),
            cluster: views::cluster::ClusterForm::default(),
            restore: None,
            focus_pending: None,
        };
        app.analyses.timings = p.timings.clone();
        ctx.set_theme(if app.dark {
            egui::Theme::Dark
        } else {
            egui::Theme::Light
        });
        if !files.is_empty() {
            for f in files {
                app.open_path(f, ctx);
            }
        } else if !p.sources.is_empty() {
            app.restore = p.selected;
            for s in p.sources {
                app.open(s, ctx);
            }
        } else {
            app.open_samples(ctx);
        }
        app
    }

    pub fn open_samples(&mut self, ctx: &egui::Context) {
        for (name, _) in loader::BUNDLED {
            self.open(Source::Bundled(name.to_string()), ctx);
        }
    }

    /// Open a session file, or a project file (which reopens its sessions); a recording
    /// that needs an import spec waits in the import dialog.
    pub fn open_path(&mut self, path: PathBuf, ctx: &egui::Context) {
        if crate::project::is_project(&path) {
            self.analyses.open_project(ctx, path);
        } else if crate::session::needs_spec(&path) {
            self.import.push(path);
        } else {
            self.open(Source::File(path), ctx);
        }
    }

    /// Make the session of the result `kind`'s view shows the active one.
    fn focus_results(&mut self, kind: AnalysisKind) {
        let name = self.analyses.shown_result(kind).map(|r| r.session.clone());
        self.focus_session(name.as_deref());
    }

    fn focus_session(&mut self, name: Option<&str>) {
        if let Some(i) = self
            .sessions
            .iter()
            .position(|s| Some(s.session.meta.name.as_str()) == name)
        {
            self.browser.active = i;
        }
    }

    pub fn open(&mut self, source: Source, ctx: &egui::Context) {
        if self.sessions.iter().any(|s| s.source == source) {
            return;
        }
        if let Source::File(p) = &source {
            self.recent.retain(|r| r != p);
            self.recent.insert(0, p.clone());
            self.recent.truncate(MAX_RECENT);
        }
        if !self.requested.contains(&source) {
            self.requested.push(source.clone());
        }
        self.loader.request(source, ctx);
    }

    pub fn is_loading(&self) -> bool {
        !self.loader.pending.is_empty()
    }

    pub fn persisted(&self) -> Persisted {
        Persisted {
            sources: self.sessions.iter().map(|s| s.source.clone()).collect(),
            view: self.view,
            dark: self.dark,
            recent: self.recent.clone(),
            browser: self.browser.clone(),
            selected: self.selection.focus,
            replay: self.replay.clone(),
            layouts: self.layouts.clone(),
            form_open: self.form_open,
            forms: self.rooms.forms(),
            last_folder: self.last_folder.clone(),
            timings: self.analyses.timings.clone(),
        }
    }

    /// Keep the results (the open project) in `dir` from now on, written after each finished
    /// job, and reopen those kept there by an earlier run.
    pub fn keep_results_in(&mut self, ctx: &egui::Context, dir: PathBuf) {
        let path = dir.join(KEPT_RESULTS);
        if path.is_file() {
            self.analyses.restore_results(ctx, path.clone());
        }
        self.analyses.keep = Some(path);
        self.analyses.keep_models_in(ctx, &dir);
    }

    fn close(&mut self, i: usize) {
        let source = self.sessions.remove(i).source;
        self.requested.retain(|s| s != &source);
        self.selection.session_closed(i);
        self.browser.active = self
            .browser
            .active
            .min(self.sessions.len().saturating_sub(1));
    }

    /// Focus (and replay) one grasp.
    /// A newly focused grasp opens at its key frame (full contact), where the touch shows.
    pub fn select(&mut self, session: usize, grasp: usize) {
        if self.selection.focus != Some((session, grasp)) {
            let key = self
                .sessions
                .get(session)
                .and_then(|s| s.session.grasps.get(grasp))
                .map_or(0, |g| g.key_frame.min(g.frames.len().saturating_sub(1)));
            self.replay.open_at(key);
        }
        self.selection.focus = Some((session, grasp));
    }

    /// The selection belongs to the active session and to the results shown: see
    /// [`Selection::scope`]. The focused grasp (the one every replay plays) follows the
    /// active session too: its first grasp when the focus was in another.
    fn scope_selection(&mut self) {
        if self.is_loading() {
            return;
        }
        self.browser.active = self
            .browser
            .active
            .min(self.sessions.len().saturating_sub(1));
        let active = self.browser.active;
        let name = self
            .sessions
            .get(active)
            .map(|s| s.session.meta.name.as_str());
        let analyses = &self.analyses;
        self.selection.scope(active, |i| {
            let (Some(r), Some(name)) = (analyses.results.get(i), name) else {
                return false;
            };
            analyses.shown_index(r.kind, name) == Some(i)
        });
        let focus_elsewhere = self.selection.focus.is_some_and(|(s, _)| s != active);
        if focus_elsewhere
            && self
                .sessions
                .get(active)
                .is_some_and(|s| !s.session.grasps.is_empty())
        {
            self.select(active, 0);
        }
    }

    /// Start `view`'s run, as its form stands, on the active session.
    pub fn start(&mut self, ctx: &egui::Context, view: View) {
        let (room, mut cx, ..) = self.parts(ctx, view);
        room.start(&mut cx);
    }

    /// `view`'s room, what it may read and ask for, and the layouts and form switch beside
    /// them (disjoint borrows of the app).
    fn parts(
        &mut self,
        ctx: &egui::Context,
        view: View,
    ) -> (
        &mut dyn views::Room,
        Cx<'_>,
        &mut BTreeMap<String, Layout>,
        &mut bool,
    ) {
        let cx = Cx {
            ctx: ctx.clone(),
            sessions: &self.sessions,
            active: self.browser.active,
            analyses: &mut self.analyses,
            selection: &self.selection,
            commands: &mut self.commands,
            replay: &mut self.replay,
            cluster: &mut self.cluster,
        };
        (
            self.rooms.get(view),
            cx,
            &mut self.layouts,
            &mut self.form_open,
        )
    }

    /// Apply the commands the views pushed while drawing.
    pub fn apply_commands(&mut self, ctx: &egui::Context) {
        for c in std::mem::take(&mut self.commands) {
            match c {
                Command::SelectGrasps {
                    session,
                    grasps,
                    origin,
                    result,
                } => {
                    if let Some(&first) = grasps.first() {
                        self.select(session, first);
                    }
                    self.selection.session = Some(session);
                    self.selection.grasps = grasps;
                    self.selection.origin = origin;
                    self.selection.result = result;
                    self.browser.active = session;
                }
                Command::Focus { session, grasp } => self.select(session, grasp),
                Command::FocusBasis { result, basis } => {
                    self.selection.basis = Some((result, basis))
                }
                Command::Strength {
                    result,
                    figure,
                    strength,
                } => self.selection.strength = Some((result, figure, strength)),
                Command::ClearSelection => {
                    self.selection.clear_set();
                    self.browser.only_selection = false;
                }
                Command::OpenResult(i) => {
                    if let Some(kind) = self.analyses.results.get(i).map(|r| r.kind) {
                        self.analyses.shown.insert(kind, i);
                        self.view = View::of(kind);
                        self.focus_results(kind);
                    }
                }
                Command::Open(v) => self.view = v,
                Command::TrainModel(spec) => self.train_model(spec, ctx),
                Command::SaveModel(i) => self.open_picker(Purpose::SaveModel(i)),
                Command::LoadModel => self.open_picker(Purpose::LoadModel),
                Command::SaveSelection => self.open_picker(Purpose::SaveSelection),
            }
        }
    }

    /// Open the active session's result of the model `spec`, or set the form of its view to
    /// that size and train it there.
    fn train_model(&mut self, spec: ModelSpec, ctx: &egui::Context) {
        let Some(session) = self.sessions.get(self.browser.active) else {
            return;
        };
        let name = session.session.meta.name.clone();
        let (kind, view) = match &spec {
            ModelSpec::Recognition { .. } => (AnalysisKind::Recognition, View::Recognition),
            ModelSpec::Stability(_) => (AnalysisKind::Stability, View::Stability),
            ModelSpec::Clustering { .. } => (AnalysisKind::Clustering, View::Clustering),
            ModelSpec::Baselines { .. } => (AnalysisKind::Baselines, View::Baselines),
        };
        let same = |r: &crate::experiments::result::AnalysisResult| {
            let of = |key: &str| r.parameters.get(key).map(String::as_str);
            let sized = || r.model_size.as_ref().map(|m| m.knobs.as_str()) == Some(&spec.knobs());
            r.kind == kind
                && r.session == name
                && r.held_out.is_none()
                && r.methods.contains(&spec.method())
                && match &spec {
                    ModelSpec::Recognition { features, .. } => {
                        sized()
                            && of("features")
                                == Some(&crate::experiments::result::features_text(*features))
                    }
                    ModelSpec::Stability(_) => sized(),
                    ModelSpec::Clustering { threshold, .. } => {
                        r.details.iter().any(|d| d.at(*threshold).is_some())
                    }
                    ModelSpec::Baselines { k: Some(k) } => of("k") == Some(&k.to_string()),
                    ModelSpec::Baselines { k: None } => true,
                }
        };
        if let Some(i) = self.analyses.results.iter().rposition(same) {
            if let ModelSpec::Clustering { threshold, .. } = spec {
                // The clustering charts' markers go to the threshold clicked.
                for d in &self.analyses.results[i].details {
                    if let Some(k) = d.at(threshold) {
                        self.analyses.selected.insert((i, d.figure.clone()), k);
                    }
                }
            }
            self.commands.push(Command::OpenResult(i));
            return;
        }
        match spec {
            ModelSpec::Recognition {
                learner,
                features,
                capacity,
                tau,
            } => {
                let f = &mut self.rooms.recognition.form;
                (f.learner, f.features) = (learner, features);
                (f.capacity, f.tau, f.user_size) = (capacity, tau, true);
            }
            ModelSpec::Stability(c) => {
                let f = &mut self.rooms.stability.form;
                f.grid = false;
                (f.num_bases, f.beta, f.gamma) = (c.num_bases, c.beta, c.gamma);
                f.user_size = true;
            }
            ModelSpec::Clustering { learner, threshold } => {
                let f = &mut self.rooms.clustering.form;
                f.learner = learner;
                f.thresholds = [threshold, threshold, f.thresholds[2]];
            }
            ModelSpec::Baselines { k } => {
                let f = &mut self.rooms.baselines.form;
                match k {
                    Some(k) => f.k = k,
                    None => f.with_svm = true,
                }
            }
        }
        self.view = view;
        let (room, mut cx, _, _) = self.parts(ctx, view);
        if !cx.analyses.is_running(kind) {
            room.start(&mut cx);
        }
    }

    /// Replay the focused grasp: play it, in the open view's replay tile if it has one,
    /// else in the replay view.
    fn replay_focused(&mut self) {
        let Some((n, _)) = self.replay_frames() else {
            return;
        };
        let key = views::layout_key(self.view);
        match self.layouts.get_mut(&key) {
            Some(l) if l.tree.tiles.find_pane(&Pane::Replay).is_some() => {
                l.activate(&Pane::Replay);
            }
            _ => self.view = View::Replay,
        }
        self.replay.reset();
        self.replay.toggle(n);
    }

    /// Frames of the grasp being replayed.
    fn replay_frames(&self) -> Option<(usize, f64)> {
        let (s, g) = self.selection.focus?;
        let ls = self.sessions.get(s)?;
        let grasp = ls.session.grasps.get(g)?;
        let rate = ls.session.meta.frame_rate_hz.unwrap_or(10.0);
        Some((grasp.frames.len(), rate))
    }

    /// Per-frame work that draws nothing: finished loads, dialogs, dropped files, playback.
    pub fn tick(&mut self, ctx: &egui::Context) {
        for (source, result) in self.loader.poll() {
            match result {
                Ok(loaded) => {
                    let rank = |s: &Source| {
                        self.requested
                            .iter()
                            .position(|r| r == s)
                            .unwrap_or(usize::MAX)
                    };
                    let at = self
                        .sessions
                        .partition_point(|x| rank(&x.source) < rank(&source));
                    self.sessions.insert(at, loaded);
                }
                Err(e) => {
                    self.requested.retain(|s| s != &source);
                    if let Source::File(p) = &source {
                        self.recent.retain(|r| r != p);
                    }
                    self.analyses.notes.error(e);
                }
            }
        }
        if !self.is_loading()
            && let Some((s, g)) = self.restore.take()
            && self
                .sessions
                .get(s)
                .is_some_and(|x| g < x.session.grasps.len())
        {
            self.select(s, g);
        }
        // A first start shows something: the first grasp of the first session.
        if !self.is_loading()
            && self.restore.is_none()
            && self.selection.focus.is_none()
            && self
                .sessions
                .first()
                .is_some_and(|s| !s.session.grasps.is_empty())
        {
            self.select(0, 0);
        }
        if let Some((purpose, rx)) = &self.dialog
            && let Ok(paths) = rx.try_recv()
        {
            let purpose = *purpose;
            self.dialog = None;
            if paths.is_empty() {
                // Cancelled, or no dialog on this machine: the in-app picker stays.
                if let Some(p) = &mut self.picker {
                    p.system_gave_nothing = true;
                }
            } else {
                self.picker = None;
                self.picked(purpose, paths, ctx);
            }
        }
        self.apply_commands(ctx);
        if self.analyses.poll() {
            ctx.request_repaint();
        }
        if let Some(i) = self.analyses.reveal.take() {
            self.commands.push(Command::OpenResult(i));
            self.apply_commands(ctx);
        }
        self.analyses.keep_models(ctx);
        self.scope_selection();
        let sessions = self.sessions.iter().map(|s| s.source.label()).collect();
        self.analyses.keep_if_changed(ctx, sessions);
        let now = ctx.input(|i| i.time);
        if self.analyses.notes.tick(now) {
            ctx.request_repaint_after(std::time::Duration::from_millis(100));
        }
        for (sessions, first) in std::mem::take(&mut self.analyses.opened_projects) {
            for label in sessions {
                self.open(Source::from_label(&label), ctx);
            }
            self.focus_pending.get_or_insert(first);
        }
        if !self.is_loading()
            && let Some(first) = self.focus_pending.take()
        {
            match self.view.kind() {
                Some(kind) => self.focus_results(kind),
                None => self.focus_session(first.as_deref()),
            }
        }
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        for p in dropped {
            self.open_path(p, ctx);
        }
        if let Some((n, rate)) = self.replay_frames() {
            let (space, left, right, dt) = ctx.input(|i| {
                (
                    i.key_pressed(egui::Key::Space),
                    i.key_pressed(egui::Key::ArrowLeft),
                    i.key_pressed(egui::Key::ArrowRight),
                    i.stable_dt as f64,
                )
            });
            let typing = ctx.text_edit_focused();
            if !typing && ctx.input(|i| i.key_pressed(egui::Key::Enter)) {
                self.replay_focused();
            }
            let (n, rate) = self.replay_frames().unwrap_or((n, rate));
            if !typing {
                if space {
                    self.replay.toggle(n);
                }
                if left {
                    self.replay.step(-1, n);
                }
                if right {
                    self.replay.step(1, n);
                }
            }
            if self.replay.advance(dt.min(0.1), rate, n) {
                ctx.request_repaint();
            }
        }
    }

    /// Open, save or add what the user picked for `purpose`.
    fn picked(&mut self, purpose: Purpose, paths: Vec<PathBuf>, ctx: &egui::Context) {
        if let Some(p) = paths.first() {
            let folder = if p.is_dir() {
                Some(p.as_path())
            } else {
                p.parent()
            };
            self.last_folder = folder.map(std::path::Path::to_path_buf);
        }
        for p in paths {
            match purpose {
                Purpose::Sessions | Purpose::Folder => self.open_path(p, ctx),
                Purpose::OpenProject => self.analyses.open_project(ctx, p),
                Purpose::SaveProject => {
                    let sessions = self.sessions.iter().map(|s| s.source.label()).collect();
                    self.analyses.save_project(ctx, p, sessions);
                }
                Purpose::SaveModel(i) => self.analyses.save_model(ctx, i, p),
                Purpose::LoadModel => self.analyses.load_model(ctx, p),
                Purpose::SaveSelection => match self.selection.session {
                    Some(s) if !self.selection.grasps.is_empty() => {
                        let grasps = self.selection.grasps.clone();
                        if let Some(ls) = self.sessions.get(s) {
                            self.analyses.save_selection(ctx, ls, grasps, p);
                        }
                    }
                    _ => self.analyses.notes.error("no grasps are selected"),
                },
            }
        }
    }

    /// Open the in-app picker for `purpose` on its default location: the folder last used
    /// (for sessions, that of the most recent file), else the working folder.
    pub fn open_picker(&mut self, purpose: Purpose) {
        let recent = self
            .recent
            .first()
            .and_then(|p| p.parent())
            .map(|p| p.to_path_buf());
        let folder = match purpose {
            Purpose::Sessions | Purpose::Folder => recent.or_else(|| self.last_folder.clone()),
            _ => self.last_folder.clone().or(recent),
        }
        .filter(|d| d.is_dir())
        .or_else(|| std::env::current_dir().ok())
        .unwrap_or_else(|| PathBuf::from("."));
        let start = match purpose {
            Purpose::SaveProject => folder.join("project.json"),
            Purpose::SaveModel(i) => match self.analyses.models.list.get(i) {
                Some(m) => folder.join(models::file_name(&m.file)),
                None => folder.join("model.json"),
            },
            Purpose::SaveSelection => {
                let name = self
                    .selection
                    .session
                    .and_then(|s| self.sessions.get(s))
                    .map_or("session".into(), |s| {
                        crate::experiments::result::slug(&s.session.meta.name)
                    });
                folder.join(format!("{name}-selection.json"))
            }
            _ => folder,
        };
        self.picker = Some(FilePicker::new(purpose, start));
    }

    /// The system file dialog for `purpose`, on a thread of its own.
    fn open_dialog(&mut self, purpose: Purpose) {
        let (tx, rx) = channel();
        self.dialog = Some((purpose, rx));
        // The portal dialog blocks its thread; keep it off the UI thread.
        std::thread::spawn(move || {
            let dialog = rfd::FileDialog::new();
            let picked = match purpose {
                Purpose::Folder => dialog.pick_folder().map(|p| vec![p]),
                Purpose::Sessions => dialog
                    .add_filter(
                        "Sessions, datasets and recordings",
                        &["json", "csv", "mcap"],
                    )
                    .pick_files(),
                Purpose::OpenProject => dialog
                    .add_filter("Projects", &["json"])
                    .pick_file()
                    .map(|p| vec![p]),
                Purpose::SaveProject => dialog
                    .add_filter("Projects", &["json"])
                    .set_file_name("project.json")
                    .save_file()
                    .map(|p| vec![p]),
                Purpose::SaveModel(_) | Purpose::SaveSelection => dialog
                    .add_filter("JSON", &["json"])
                    .save_file()
                    .map(|p| vec![p]),
                Purpose::LoadModel => dialog
                    .add_filter("Models", &["json"])
                    .pick_file()
                    .map(|p| vec![p]),
            };
            let _ = tx.send(picked.unwrap_or_default());
        });
    }

    /// The in-app picker, when open.
    fn picker_ui(&mut self, ctx: &egui::Context) {
        let Some(picker) = &mut self.picker else {
            return;
        };
        let purpose = picker.purpose;
        match picker.show(ctx, &mut self.analyses.notes) {
            Picked::None => {}
            Picked::Cancel => self.picker = None,
            Picked::System => {
                picker.system_gave_nothing = false;
                self.open_dialog(purpose);
            }
            Picked::Paths(paths) => {
                self.picker = None;
                self.picked(purpose, paths, ctx);
            }
        }
    }

    fn menu(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                if ui.button("Open sessions…").clicked() {
                    self.open_picker(Purpose::Sessions);
                }
                if ui
                    .button("Open folder (iCub dataset or ROS 2 bag)…")
                    .clicked()
                {
                    self.open_picker(Purpose::Folder);
                }
                ui.separator();
                if ui.button("Open project…").clicked() {
                    self.open_picker(Purpose::OpenProject);
                }
                if ui.button("Save project…").clicked() {
                    self.open_picker(Purpose::SaveProject);
                }
                if ui.button("Export all figures").clicked() {
                    self.analyses.export_all(ui.ctx());
                }
                ui.separator();
                if ui.button("Open sample sessions").clicked() {
                    self.open_samples(ui.ctx());
                }
                ui.menu_button("Recent", |ui| {
                    if self.recent.is_empty() {
                        ui.label("(none)");
                    }
                    for p in self.recent.clone() {
                        if ui.button(p.display().to_string()).clicked() {
                            self.open(Source::File(p), ui.ctx());
                        }
                    }
                });
            });
            ui.menu_button("View", |ui| {
                for v in View::ALL {
                    ui.selectable_value(&mut self.view, v, v.title());
                }
                ui.separator();
                ui.checkbox(&mut self.form_open, "Form panel");
                if ui.button("Notification log").clicked() {
                    self.analyses.notes.log_open = true;
                }
                ui.separator();
                if ui.checkbox(&mut self.dark, "Dark theme").changed() {
                    ui.ctx().set_theme(if self.dark {
                        egui::Theme::Dark
                    } else {
                        egui::Theme::Light
                    });
                }
            });
            ui.separator();
            for v in View::ALL {
                ui.selectable_value(&mut self.view, v, v.title());
            }
            if self.is_loading() {
                ui.spinner();
                ui.label("loading…");
            }
        });
    }

    /// Draw the whole workbench into `ui`.
    pub fn show(&mut self, ui: &mut egui::Ui) {
        egui::Panel::top("menu").show(ui, |ui| self.menu(ui));
        if self.analyses.busy() {
            egui::Panel::bottom("jobs").show(ui, |ui| self.analyses.jobs_ui(ui));
        }
        // Side panels keep to a share of the window, whatever a section opened in them
        // holds, so the tiles keep their room at 1000 × 700 too.
        let width = ui.available_width();
        egui::Panel::left("browser")
            .resizable(true)
            .default_size(300.0_f32.min(width * 0.26))
            .max_size((width * 0.3).max(200.0))
            .show(ui, |ui| {
                match self.browser.ui(ui, &self.sessions, &self.selection) {
                    BrowserAction::Select(g) => {
                        let session = self.browser.active;
                        self.commands.push(Command::Focus { session, grasp: g });
                    }
                    BrowserAction::Replay(g) => {
                        self.select(self.browser.active, g);
                        self.replay_focused();
                    }
                    BrowserAction::Close(i) => self.close(i),
                    BrowserAction::None => {}
                }
            });
        let ctx = ui.ctx().clone();
        let view = self.view;
        let (room, mut cx, layouts, form_open) = self.parts(&ctx, view);
        if view != View::Replay && *form_open {
            egui::Panel::right("form")
                .resizable(true)
                .default_size(250.0_f32.min(width * 0.22))
                .max_size((width * 0.3).max(200.0))
                .show(ui, |ui| {
                    egui::ScrollArea::vertical().show(ui, |ui| {
                        room.form_ui(ui, &mut cx);
                        views::cluster::ui(ui, room, &mut cx);
                        ui.separator();
                        ui.collapsing("Export settings", |ui| cx.analyses.export.ui(ui));
                    });
                });
        }
        egui::CentralPanel::default_margins().show(ui, |ui| {
            if view != View::Replay {
                ui.horizontal(|ui| {
                    ui.strong(view.title());
                    ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                        let (text, hint) = if *form_open {
                            ("Hide form", "More room for the tiles")
                        } else {
                            ("Show form", "Parameters and Run")
                        };
                        if ui.small_button(text).on_hover_text(hint).clicked() {
                            *form_open = !*form_open;
                        }
                    });
                });
            }
            views::central_ui(ui, room, layouts, &mut cx);
        });
        let now = ctx.input(|i| i.time);
        views::models::evaluate_window(&ctx, &mut cx);
        cx.analyses.notes.ui(&ctx, now);
        if let Some(source) = self.import.show(&ctx) {
            self.open(source, &ctx);
        }
        self.picker_ui(&ctx);
    }
}

/// A measurement the window makes of itself, then quits.
#[derive(Clone, Copy, Debug)]
pub enum Measure {
    /// The time from the process start to the first frame and to the sessions shown.
    Startup(Instant),
    /// Per-frame UI time (layout and tessellation, not GPU painting) of the grasp-stability
    /// view for `seconds` while a 108-cell grid search runs on the grasp-stability sample.
    Frames { seconds: f64 },
}

struct EframeApp {
    app: WorkbenchApp,
    measure: Option<Measure>,
    first_frame: Option<f64>,
    /// UI times (ms) of the frames drawn while the measured grid search ran.
    frame_ms: Vec<f64>,
    measuring_since: Option<Instant>,
}

impl EframeApp {
    /// `--measure-frames`: start the grid once the samples are in, time each frame.
    fn measure_frames(&mut self, ui: &egui::Ui, seconds: f64, ms: f64) {
        let ctx = ui.ctx().clone();
        match self.measuring_since {
            None if !self.app.is_loading() && !self.app.sessions.is_empty() => {
                let stability = self
                    .app
                    .sessions
                    .iter()
                    .position(|s| s.session.label_sets.iter().any(|l| l.classes.len() == 2));
                if let Some(i) = stability {
                    self.app.browser.active = i;
                    self.app.view = View::Stability;
                    self.app.rooms.stability.form.grid = true;
                    self.app.start(&ctx, View::Stability);
                    self.measuring_since = Some(Instant::now());
                }
            }
            Some(t0) => {
                let running = self.app.analyses.busy();
                if running {
                    self.frame_ms.push(ms);
                }
                if !running || t0.elapsed().as_secs_f64() > seconds {
                    let mut v = self.frame_ms.clone();
                    v.sort_by(f64::total_cmp);
                    let n = v.len().max(1);
                    let mean = v.iter().sum::<f64>() / n as f64;
                    let p95 = v.get(n * 95 / 100).copied().unwrap_or(0.0);
                    let max = v.last().copied().unwrap_or(0.0);
                    println!(
                        "{} frames during the grid search: UI time mean {mean:.2} ms, p95 {p95:.2} ms, max {max:.2} ms",
                        v.len()
                    );
                    self.app.analyses.jobs.iter().for_each(|j| j.job.cancel());
                    ctx.send_viewport_cmd(egui::ViewportCommand::Close);
                    self.measure = None;
                    return;
                }
            }
            None => {}
        }
        // Keep drawing, as an animation would, so frames are timed continuously.
        ctx.request_repaint();
    }
}

impl eframe::App for EframeApp {
    fn logic(&mut self, ctx: &egui::Context, _frame: &mut eframe::Frame) {
        self.app.tick(ctx);
    }

    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        let t = Instant::now();
        self.app.show(ui);
        let frame_ms = t.elapsed().as_secs_f64() * 1e3;
        match self.measure {
            Some(Measure::Startup(t0)) => {
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let first = *self.first_frame.get_or_insert(ms);
                if !self.app.is_loading() && !self.app.sessions.is_empty() {
                    println!("first frame: {first:.0} ms; sessions shown: {ms:.0} ms");
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                    // Report once: frames may still be drawn while the window closes.
                    self.measure = None;
                }
            }
            Some(Measure::Frames { seconds }) => self.measure_frames(ui, seconds, frame_ms),
            None => {}
        }
    }

    fn save(&mut self, storage: &mut dyn eframe::Storage) {
        if self.measure.is_none() && self.measuring_since.is_none() {
            eframe::set_value(storage, STORAGE_KEY, &self.app.persisted());
        }
    }
}

/// Open the workbench window; with `measure`, measure the window itself, print the result
/// and close.
pub fn run(
    files: Vec<PathBuf>,
    view: Option<View>,
    measure: Option<Measure>,
) -> anyhow::Result<()> {
    let options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title("Tactile Workbench")
            .with_inner_size([1400.0, 900.0])
            .with_drag_and_drop(true),
        ..Default::default()
    };
    eframe::run_native(
        "Tactile Workbench",
        options,
        Box::new(move |cc| {
            // A measurement always starts from the bundled samples.
            let persisted = cc
                .storage
                .filter(|_| measure.is_none())
                .and_then(|s| eframe::get_value::<Persisted>(s, STORAGE_KEY));
            let mut app = WorkbenchApp::new(&cc.egui_ctx, persisted, files);
            if let Some(v) = view {
                app.view = v;
            }
            // A measurement neither reads nor overwrites the results kept between runs.
            if measure.is_none()
                && let Some(dir) = eframe::storage_dir("Tactile Workbench")
            {
                app.keep_results_in(&cc.egui_ctx, dir);
            }
            Ok(Box::new(EframeApp {
                app,
                measure,
                first_frame: None,
                frame_ms: Vec::new(),
                measuring_since: None,
            }))
        }),
    )
    .map_err(|e| anyhow::anyhow!("could not open the window: {e}"))
}
