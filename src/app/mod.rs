//! The egui workbench. One room per view (`views/`), each a form and tiles; the app owns
//! the open sessions, the results, the selection and the command queue; rooms read them
//! and push commands, applied between frames. Nothing here blocks: files load and analyses
//! run on worker threads.

pub mod browser;
mod commands;
pub mod figure_view;
pub mod files;
pub mod heatmap;
pub mod import;
pub mod loader;
pub mod models;
pub mod notify;
mod persisted;
mod picking;
pub mod replay;
pub mod results;
pub mod selection;
mod view;
pub mod views;
mod window;

use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::mpsc::Receiver;

use crate::experiments::result::AnalysisKind;
use browser::{Browser, BrowserAction};
use files::{FilePicker, Purpose};
use loader::{LoadedSession, Loader, Source};
use replay::Replay;
use results::Analyses;
use selection::{Command, Selection};
use views::{Cx, Layout, Pane, Rooms};

const STORAGE_KEY: &str = "tactile-workbench";
const MAX_RECENT: usize = 10;

pub use crate::cli::View;
pub use persisted::{KEPT_RESULTS, Persisted};
pub use window::{Measure, run};

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
    /// Sessions the user opened (not those restored at start): each becomes the active
    /// session when it has loaded.
    activate: Vec<Source>,
    /// The system file dialog, while it is open (on its own thread).
    dialog: Option<(Purpose, Receiver<Vec<PathBuf>>)>,
    /// The in-app file picker, while it is open.
    pub picker: Option<FilePicker>,
    /// The folder the file picker last opened from or saved to.
    last_folder: Option<PathBuf>,
    /// Recordings (ROS 2 bags, long-format CSVs) waiting for their import spec.
    pub import: import::ImportDialog,
    pub slurm: views::slurm::SlurmForm,
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
            rooms: Rooms::with_forms(&p.forms),
            layouts: p.layouts.clone(),
            form_open: p.form_open,
            loader: Loader::default(),
            requested: Vec::new(),
            activate: Vec::new(),
            dialog: None,
            picker: None,
            last_folder: p.last_folder.clone(),
            import: import::ImportDialog::default(),
            slurm: views::slurm::SlurmForm::default(),
            restore: None,
            focus_pending: None,
        };
        app.analyses.timings = p.timings.clone();
        app.analyses.export = p.export.clone();
        ctx.set_theme(if app.dark {
            egui::Theme::Dark
        } else {
            egui::Theme::Light
        });
        if !files.is_empty() {
            for f in files {
                app.open_path(f, ctx);
            }
            // The files a run starts with list in order; the first stays active.
            app.activate.clear();
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
            self.activate.push(Source::File(path.clone()));
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

    /// How the opening of the workbench ended, once nothing is loading or opening: the
    /// sessions shown, or the errors of what failed to open (a file that is not a session,
    /// a project of another version, a project's unreadable sessions). None while opening.
    pub fn startup_outcome(&self) -> Option<Result<(), String>> {
        if self.is_loading() || self.analyses.busy() || !self.analyses.opened_projects.is_empty() {
            return None;
        }
        let errors = self.analyses.notes.errors();
        Some(match (errors.is_empty(), self.sessions.is_empty()) {
            (false, _) => Err(errors.join("\n")),
            (true, true) => Err("no session was opened".into()),
            (true, false) => Ok(()),
        })
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
            slurm: &mut self.slurm,
        };
        (
            self.rooms.get(view),
            cx,
            &mut self.layouts,
            &mut self.form_open,
        )
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
                    let opened = self.activate.contains(&source);
                    self.activate.retain(|s| s != &source);
                    let text = format!(
                        "opened «{}»: {} grasps",
                        loaded.session.meta.name,
                        loaded.session.grasps.len()
                    );
                    self.sessions.insert(at, loaded);
                    if opened {
                        self.browser.active = at;
                        self.analyses.notes.info(text);
                    }
                }
                Err(e) => {
                    self.requested.retain(|s| s != &source);
                    self.activate.retain(|s| s != &source);
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
                if ui.button("Connect to a live stream…").clicked() {
                    (self.view, self.form_open) = (View::Live, true);
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
                            self.activate.push(Source::File(p.clone()));
                            self.open(Source::File(p), ui.ctx());
                        }
                    }
                });
            });
            ui.menu_button("View", |ui| {
                for &v in View::all() {
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
            for &v in View::all() {
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
        self.analyses.export_folder_ui(ui.ctx());
        if self.analyses.shows_jobs() {
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
                        views::slurm::ui(ui, room, &mut cx);
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
