//! The views, one room each: a form in a collapsible side panel, and the shown result's
//! figures laid out as tiles (`egui_tiles`) that the user can drag, split, tab, maximise and
//! reset. Rooms read the shared selection and push commands; they never change another view.

pub mod baselines;
pub mod card;
pub mod clustering;
pub mod compare;
pub mod live;
pub mod models;
pub mod pane;
pub mod panes;
pub mod recognition;
pub mod replay;
pub mod robustness;
pub mod slurm;
pub mod speed;
pub mod stability;
pub mod tiles;

use super::View;
use super::loader::LoadedSession;
use super::replay::Replay;
use super::results::{Analyses, JobOutput};
use super::selection::{Command, Selection};
use crate::experiments::result::AnalysisKind;
pub use crate::jobs::estimate::Estimate;
use crate::jobs::{JobError, Progress};
use crate::session::Session;
pub use pane::Pane;
use std::sync::Arc;
pub use tiles::Layout;

/// What a room may read and ask for while it draws.
pub struct Cx<'a> {
    pub ctx: egui::Context,
    pub sessions: &'a [LoadedSession],
    /// The session the browser has active.
    pub active: usize,
    pub analyses: &'a mut Analyses,
    pub selection: &'a Selection,
    pub commands: &'a mut Vec<Command>,
    pub replay: &'a mut Replay,
    /// The settings of "Run on a cluster…", shared by the views.
    pub slurm: &'a mut slurm::SlurmForm,
}

impl Cx<'_> {
    pub fn session(&self) -> Option<&LoadedSession> {
        self.sessions.get(self.active)
    }

    /// Run `work` as a background job of analysis `kind`.
    pub fn spawn(
        &mut self,
        kind: AnalysisKind,
        title: String,
        work: impl FnOnce(
            &crate::jobs::Progress,
        ) -> Result<super::results::JobOutput, crate::jobs::JobError>
        + Send
        + 'static,
    ) {
        let ctx = self.ctx.clone();
        self.analyses.spawn(&ctx, Some(kind), title, work);
    }

    /// Start a form's run as a background job whose time left starts from its estimate.
    pub fn spawn_run(&mut self, run: Run) {
        let ctx = self.ctx.clone();
        self.analyses
            .spawn_timed(&ctx, run.kind, run.title, run.estimate, run.work);
    }

    /// The result of `kind` shown for the active session (index into the results).
    pub fn shown(&self, kind: AnalysisKind) -> Option<usize> {
        let name = &self.session()?.session.meta.name;
        self.analyses.shown_index(kind, name)
    }
}

/// One view of the workbench.
pub trait Room {
    fn view(&self) -> View;

    /// The analysis whose results the room lays out as tiles, if any.
    fn kind(&self) -> Option<AnalysisKind> {
        self.view().kind()
    }

    /// The default layout: groups of tabs, one grid cell each.
    fn default_groups(&self) -> Vec<Vec<Pane>>;

    /// The form (parameters and Run) in the side panel; nothing for rooms without one.
    fn form_ui(&mut self, _ui: &mut egui::Ui, _cx: &mut Cx) {}

    /// What Run does with the form as it is (with the model size it trains, which a frontier
    /// among `analyses` may recommend), with the time it is expected to take on `session`;
    /// None when the session cannot run it.
    fn run_text(&self, _session: &LoadedSession, _analyses: &Analyses) -> Option<String> {
        None
    }

    /// The form's run on `session` as it stands (with the model size it trains, which a
    /// frontier among `analyses` may recommend); None when the session cannot run it.
    fn run(&self, _session: &Arc<Session>, _analyses: &Analyses) -> Option<Run> {
        None
    }

    /// Start the form's run on the active session (a background job).
    fn start(&mut self, cx: &mut Cx) {
        if let Some(run) = cx.session().and_then(|s| self.run(&s.session, cx.analyses)) {
            cx.spawn_run(run);
        }
    }

    /// The form's run on the active session as a sweep a cluster can shard: None for rooms
    /// whose runs do not shard, an error saying why when the form as it is cannot be sharded.
    fn sweep(&self, _cx: &Cx) -> Option<Result<crate::sweep::Experiment, String>> {
        None
    }

    /// Draw a pane this room owns (not a result's figure). Returns false for panes it
    /// does not know.
    fn pane_ui(&mut self, _ui: &mut egui::Ui, _pane: &Pane, _cx: &mut Cx) -> bool {
        false
    }

    /// A pane the room has nothing to show in now: its tile folds away (and comes back
    /// when it has).
    fn hides(&self, _pane: &Pane) -> bool {
        false
    }
}

/// Every view in one place, a line each: the field of [`Rooms`] that owns its room and the
/// room's type, the view, its title, the analysis whose results it shows, and for a room
/// with a form, the form's field (it persists between runs under the room's field name).
/// A view missing here is a compile error (the matches below are exhaustive).
macro_rules! views {
    ($( $field:ident: $room:ty => $view:ident, $title:literal, $kind:expr $(, $form:ident)?; )*) => {
        /// Every room, each owning its form state.
        #[derive(Default)]
        pub struct Rooms {
            $( pub $field: $room, )*
        }

        impl Rooms {
            /// The rooms with their forms as they were left (a form that no longer reads
            /// starts from its defaults).
            pub fn with_forms(forms: &Forms) -> Rooms {
                let mut rooms = Rooms::default();
                $($(
                    if let Some(f) = forms
                        .get(stringify!($field))
                        .and_then(|v| serde_json::from_value(v.clone()).ok())
                    {
                        rooms.$field.$form = f;
                    }
                )?)*
                rooms
            }

            pub fn forms(&self) -> Forms {
                let mut forms = Forms::new();
                $($(
                    if let Ok(v) = serde_json::to_value(&self.$field.$form) {
                        forms.insert(stringify!($field).to_string(), v);
                    }
                )?)*
                forms
            }

            pub fn get(&mut self, view: View) -> &mut dyn Room {
                match view {
                    $( View::$view => &mut self.$field, )*
                }
            }
        }

        impl View {
            pub fn title(self) -> &'static str {
                match self {
                    $( View::$view => $title, )*
                }
            }

            /// The analysis this view shows, if it shows one.
            pub fn kind(self) -> Option<AnalysisKind> {
                match self {
                    $( View::$view => $kind, )*
                }
            }
        }
    };
}

views! {
    replay: replay::ReplayRoom => Replay, "Replay", None;
    stability: stability::StabilityRoom => Stability, "Grasp stability", Some(AnalysisKind::Stability), form;
    recognition: recognition::RecognitionRoom => Recognition, "Recognition", Some(AnalysisKind::Recognition), form;
    clustering: clustering::ClusteringRoom => Clustering, "Clustering", Some(AnalysisKind::Clustering), form;
    baselines: baselines::BaselinesRoom => Baselines, "Baselines", Some(AnalysisKind::Baselines), form;
    speed: speed::SpeedRoom => SpeedAccuracy, "Speed vs accuracy", None;
    robustness: robustness::RobustnessRoom => Robustness, "Where methods fail", Some(AnalysisKind::Robustness), form;
    live: live::LiveRoom => Live, "Live", None, form;
    compare: compare::CompareRoom => Compare, "Compare", None, form;
}

/// A run as a form starts it: the job's title and analysis, what it is expected to cost,
/// and the work (on a worker thread). The window and `benches/estimates.rs` start the same.
pub struct Run {
    pub kind: Option<AnalysisKind>,
    pub title: String,
    pub estimate: Estimate,
    pub work: Work,
}

/// The work of a run.
pub type Work = Box<dyn FnOnce(&Progress) -> Result<JobOutput, JobError> + Send>;

/// "about 20 s": what a form says `estimate` will take on this machine.
pub fn estimate_text(estimate: &Estimate, analyses: &Analyses) -> String {
    duration_text(estimate.expected(&analyses.timings))
}

/// Each room's form settings as they persist between runs, by the room's field name.
pub type Forms = std::collections::BTreeMap<String, serde_json::Value>;

/// The form's Run button: enabled while no `kind` job runs and the active session can run it
/// (`ready`); otherwise `needs` says what the session lacks. Returns whether it was clicked.
pub fn run_button(
    ui: &mut egui::Ui,
    cx: &Cx,
    kind: AnalysisKind,
    ready: impl Fn(&Session) -> bool,
    needs: &str,
) -> bool {
    let Some(s) = cx.session() else { return false };
    let ok = ready(&s.session);
    if !ok {
        ui.label(needs);
    }
    let running = cx.analyses.is_running(kind);
    ui.add_enabled(!running && ok, egui::Button::new("Run"))
        .clicked()
}

/// Show a number compactly (scores to 3 decimals, large values without decimals).
pub fn number(v: f64) -> String {
    if !v.is_finite() {
        "n/a".into()
    } else if v.abs() >= 1000.0 {
        format!("{v:.0}")
    } else if v.abs() >= 10.0 {
        format!("{v:.1}")
    } else {
        format!("{v:.3}")
    }
}

/// A duration in words for the expected time of a run.
pub fn duration_text(seconds: f64) -> String {
    if seconds < 1.0 {
        "under a second".into()
    } else if seconds < 90.0 {
        format!("about {seconds:.0} s")
    } else {
        format!("about {:.0} min", seconds / 60.0)
    }
}

/// The key a room's layout persists under.
pub fn layout_key(view: View) -> String {
    view.title().to_string()
}

/// The key of the layout a room shows `result` in: a held-out result has figures of its
/// own, so its tiles are laid out and kept apart.
pub fn result_layout_key(
    view: View,
    result: &crate::experiments::result::AnalysisResult,
) -> String {
    match result.held_out {
        Some(_) => format!("{} (held out)", layout_key(view)),
        None => layout_key(view),
    }
}

/// A room's central area: for an analysis room, the card and the shown result's tiles, or
/// the room's default run when the active session has no result yet (nothing runs until
/// asked); for the other rooms, their tiles.
pub fn central_ui(
    ui: &mut egui::Ui,
    room: &mut dyn Room,
    layouts: &mut std::collections::BTreeMap<String, Layout>,
    cx: &mut Cx,
) {
    let key = layout_key(room.view());
    let Some(kind) = room.kind() else {
        card::selection_line(ui, cx);
        let layout = layouts
            .entry(key.clone())
            .or_insert_with(|| Layout::build(&key, room.default_groups(), None, None));
        tiles::show(ui, layout, room, cx);
        return;
    };
    let Some(session) = cx.session() else {
        ui.label("Open a session first (File > Open, or drop a file on the window).");
        return;
    };
    let Some(i) = cx.shown(kind) else {
        let name = session.session.meta.name.clone();
        let text = room.run_text(session, cx.analyses);
        let running = cx.analyses.is_running(kind);
        ui.add_space(24.0);
        ui.vertical_centered(|ui| {
            ui.heading(format!(
                "No results yet for «{name}»: {}",
                kind.title().to_lowercase()
            ));
            match &text {
                Some(t) => {
                    ui.label(t);
                    ui.add_space(6.0);
                    if ui
                        .add_enabled(!running, egui::Button::new("Start this run"))
                        .on_hover_text("Or change the parameters in the form on the right first")
                        .clicked()
                    {
                        room.start(cx);
                    }
                }
                None => {
                    ui.label("This session cannot run this analysis (the form says why).");
                }
            }
        });
        return;
    };
    let mut reset = false;
    card::card(ui, cx, i, &mut reset);
    ui.separator();
    let result = &cx.analyses.results[i];
    let key = result_layout_key(room.view(), result);
    let layout = layouts
        .entry(key.clone())
        .or_insert_with(|| Layout::build(&key, room.default_groups(), Some(result), Some(i)));
    if reset || (!layout.edited && layout.built_for != Some(i)) {
        *layout = Layout::build(&key, room.default_groups(), Some(result), Some(i));
    }
    tiles::show(ui, layout, room, cx);
}
