//! What the workbench keeps between runs: the window's state in eframe's storage, and the
//! results (the open project) in the data folder.

use std::collections::BTreeMap;
use std::path::PathBuf;

use serde::{Deserialize, Serialize};

use super::browser::Browser;
use super::loader::Source;
use super::replay::Replay;
use super::views::{self, Layout};
use super::{View, WorkbenchApp};

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
    /// The export folder and size.
    #[serde(default)]
    pub export: super::results::ExportSettings,
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
            export: Default::default(),
        }
    }
}

impl WorkbenchApp {
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
            export: self.analyses.export.clone(),
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
}
