//! The results every view reads: the analyses run as background jobs, the results they
//! leave (per session), which one each view shows, export settings and notifications.

mod export;
mod kept;

pub use export::{ExportSettings, PendingExport};

use std::path::PathBuf;

use egui::ProgressBar;

use super::loader::LoadedSession;
use super::models::{KEPT_MODELS, Models};
use super::notify::Notifications;
use crate::catalogue::MethodId;
use crate::experiments::ExperimentError;
use crate::experiments::figure_id::FigureId;
use crate::experiments::frontier::Frontier;
use crate::experiments::frontier::report::frontier_figures;
use crate::experiments::recognition::report::comparison_figures;
use crate::experiments::recognition::{
    GraspTrace, RecognitionParams, SupervisedLearner, grasp_trace,
};
use crate::experiments::result::{self, AnalysisKind, AnalysisResult, date_text};
use crate::features::FeatureSet;
use crate::figures::{self, Format, RenderOptions};
use crate::jobs::estimate::Timings;
use crate::jobs::{Job, JobError, Outcome};
use crate::models::{self, Calibration, ModelFile};
use crate::session::Session;

/// How a frontier job's title starts (one frontier runs at a time).
pub const FRONTIER_JOB: &str = "Frontier of ";

/// A job and what it is for.
pub struct RunningJob {
    pub kind: Option<AnalysisKind>,
    pub title: String,
    pub job: Job<JobOutput>,
    /// The kind of run for the timings and the seconds its model expected (a run that
    /// finishes corrects the expectation of the next).
    pub timing: Option<(String, f64)>,
    /// Keeping results and models in the data folder: no bar in the jobs strip (a failure
    /// still shows as a notification).
    pub bookkeeping: bool,
}

pub enum JobOutput {
    Result(Box<AnalysisResult>),
    Frontier(Box<Frontier>),
    Message(String),
    /// A project, its sessions narrowed to those it may open, and why the others may not.
    Project(crate::project::Project, Vec<String>),
    /// The results kept by an earlier run, back.
    Restored(crate::project::Project),
    /// The results were written to the data folder.
    Kept,
    Trace(Box<ReplayTrace>),
    /// A result and the models it trained (for the Models list).
    Trained {
        result: Box<AnalysisResult>,
        models: Vec<ModelFile>,
    },
    /// A model of the list on another session: shown at once.
    HeldOut(Box<AnalysisResult>),
    /// A model file read from disk for the list.
    ModelLoaded(Box<ModelFile>),
    /// The models kept by an earlier run, and the files of their folder that could not be
    /// read.
    ModelsRestored(Vec<(PathBuf, ModelFile)>, Vec<String>),
}

/// The class distribution at every step of one grasp, for the replay view.
pub struct ReplayTrace {
    pub session: String,
    pub grasp: usize,
    pub learner: SupervisedLearner,
    pub trace: GraspTrace,
}

pub(super) fn experiment_error(e: ExperimentError) -> JobError {
    match e {
        ExperimentError::Cancelled => JobError::Cancelled,
        other => JobError::failed(other),
    }
}

/// An object-recognition session: encoders, sequences and `object` labels.
pub(super) fn recognition_ready(s: &Session) -> bool {
    s.label_set("object").is_some() && !s.encoders.is_empty()
}

/// DS and GS need `object` labels and the paper's features: `all` is the moments alone on
/// a session without encoders.
pub(super) fn sequences_ready(s: &Session) -> bool {
    s.label_set("object").is_some() && FeatureSet::ALL.dim(s).is_some()
}

#[derive(Default)]
pub struct Analyses {
    pub results: Vec<AnalysisResult>,
    pub jobs: Vec<RunningJob>,
    /// The result shown in each analysis view (index into `results`).
    pub shown: std::collections::HashMap<AnalysisKind, usize>,
    /// The detail item selected through a figure: (result index, figure name) -> item.
    pub selected: std::collections::HashMap<(usize, FigureId), usize>,
    /// The heatmap cell last clicked in a figure: (result index, figure name, detail item)
    /// -> [row, column].
    pub cells: std::collections::HashMap<(usize, FigureId, Option<usize>), [usize; 2]>,
    pub export: ExportSettings,
    /// What finished, failed or was exported (toasts and the log).
    pub notes: Notifications,
    /// Speed–accuracy frontiers, at most one per session, method and feature set.
    pub frontiers: Vec<Frontier>,
    /// The last recognition trace computed for the replay.
    pub trace: Option<ReplayTrace>,
    /// Projects that just opened: the sessions each names (for the app to reopen) and the
    /// session of its first result.
    pub opened_projects: Vec<(Vec<String>, Option<String>)>,
    /// Measured corrections of the expected run times on this machine.
    pub timings: Timings,
    /// The file in the data folder that keeps the results between runs (none: not kept).
    pub keep: Option<PathBuf>,
    /// The results changed since they were last kept.
    keep_pending: bool,
    /// Every model trained here or loaded, kept beside the results.
    pub models: Models,
    /// A result to show at once (a held-out result just computed): the app opens it.
    pub reveal: Option<usize>,
    /// An export waiting for the user to confirm its folder (the first export asks).
    pub pending_export: Option<PendingExport>,
}

/// The title of the job that keeps the results in the data folder.
const KEEP_JOB: &str = "Keeping the results";

impl Analyses {
    pub fn busy(&self) -> bool {
        !self.jobs.is_empty()
    }

    /// A job the jobs strip shows is running (bookkeeping has no bar).
    pub fn shows_jobs(&self) -> bool {
        self.jobs.iter().any(|j| !j.bookkeeping)
    }

    /// A job of this analysis is running (one at a time per analysis).
    pub fn is_running(&self, kind: AnalysisKind) -> bool {
        self.jobs.iter().any(|j| j.kind == Some(kind))
    }

    /// Collect finished jobs. Returns true when something changed.
    pub fn poll(&mut self) -> bool {
        let mut changed = false;
        let mut i = 0;
        while i < self.jobs.len() {
            if self.jobs[i].job.is_running() {
                i += 1;
                continue;
            }
            let mut rj = self.jobs.remove(i);
            changed = true;
            let outcome = rj.job.take();
            if let (Some(Outcome::Done(_)), Some((kind, modelled))) = (&outcome, &rj.timing) {
                self.timings
                    .record(kind, *modelled, rj.job.progress.elapsed_secs());
            }
            match outcome {
                Some(Outcome::Done(JobOutput::Result(r))) => self.add_result(*r),
                Some(Outcome::Done(JobOutput::Trained { result, models })) => {
                    for m in models {
                        self.models.add_trained(m, result.created, &result.label);
                    }
                    self.add_result(*result);
                }
                Some(Outcome::Done(JobOutput::HeldOut(r))) => {
                    let score = r
                        .scores
                        .first()
                        .map(|(n, v)| format!(": {n} {v:.3}"))
                        .unwrap_or_default();
                    self.notes
                        .info(format!("{} on {}{score}", r.label, r.session));
                    self.add_result(*r);
                    self.reveal = Some(self.results.len() - 1);
                }
                Some(Outcome::Done(JobOutput::ModelLoaded(m))) => {
                    let summary = m.provenance.summary();
                    if self.models.add(*m) {
                        self.notes.info(format!("model loaded: {summary}"));
                    } else {
                        self.notes.info(format!("already in the list: {summary}"));
                    }
                }
                Some(Outcome::Done(JobOutput::ModelsRestored(ok, bad))) => {
                    for (path, file) in ok {
                        self.models.add_kept(file, path);
                    }
                    for e in bad {
                        self.notes
                            .error(format!("a kept model could not be read: {e}"));
                    }
                }
                Some(Outcome::Done(JobOutput::Kept)) => {}
                Some(Outcome::Done(JobOutput::Restored(p))) => {
                    // Appended: indices held by the views stay valid; a frontier computed
                    // meanwhile is newer than the kept one.
                    let n = p.results.len();
                    self.results.extend(p.results);
                    for f in p.frontiers {
                        let same = |g: &Frontier| {
                            g.session == f.session
                                && g.params.method == f.params.method
                                && g.params.features == f.params.features
                        };
                        if !self.frontiers.iter().any(same) {
                            self.frontiers.push(f);
                        }
                    }
                    if n > 0 {
                        self.notes.info(format!(
                            "{n} result{} of the last run reopened",
                            if n == 1 { "" } else { "s" }
                        ));
                    }
                }
                Some(Outcome::Done(JobOutput::Frontier(f))) => {
                    let rec = &f.points[f.recommended];
                    self.notes.info(format!(
                        "{} on {}: recommended {} (score {:.3} ± {:.3})",
                        f.label(),
                        f.session,
                        rec.detail,
                        rec.score,
                        rec.score_se
                    ));
                    self.add_frontier(*f);
                    self.keep_pending = true;
                }
                Some(Outcome::Done(JobOutput::Message(m))) => self.notes.info(m),
                Some(Outcome::Done(JobOutput::Trace(t))) => self.trace = Some(*t),
                Some(Outcome::Done(JobOutput::Project(p, refused))) => {
                    let n = p.results.len();
                    let models = p.models.len();
                    self.notes.info(format!(
                        "opened a project with {n} result{} and {models} model{}; it opens the \
                         sessions {}",
                        if n == 1 { "" } else { "s" },
                        if models == 1 { "" } else { "s" },
                        p.sessions.join(", ")
                    ));
                    for why in refused {
                        self.notes.error(format!("{}: {why}", rj.title));
                    }
                    let first = p.results.first().map(|r| r.session.clone());
                    self.results.extend(p.results);
                    for f in p.frontiers {
                        self.add_frontier(f);
                    }
                    for m in p.models {
                        self.models.add(m);
                    }
                    self.opened_projects.push((p.sessions, first));
                    self.keep_pending = true;
                }
                Some(Outcome::Cancelled) => self.notes.info(format!("{}: cancelled", rj.title)),
                Some(Outcome::Failed(e)) => self.notes.error(format!("{} failed: {e}", rj.title)),
                None => {}
            }
        }
        changed
    }

    fn add_result(&mut self, r: AnalysisResult) {
        let kind = r.kind;
        self.results.push(r);
        self.shown.insert(kind, self.results.len() - 1);
        self.keep_pending = true;
    }

    /// Keep `f`, replacing the frontier of the same session, method and features.
    pub fn add_frontier(&mut self, f: Frontier) {
        let same = |g: &Frontier| {
            g.session == f.session
                && g.params.method == f.params.method
                && g.params.features == f.params.features
        };
        match self.frontiers.iter().position(same) {
            Some(i) => self.frontiers[i] = f,
            None => self.frontiers.push(f),
        }
    }

    /// The frontier of `method` with `features` on `session` (for `auto`, one whose
    /// features `auto` chose).
    pub fn frontier(
        &self,
        session: &str,
        method: MethodId,
        features: FeatureSet,
    ) -> Option<&Frontier> {
        self.frontiers.iter().find(|f| {
            f.session == session
                && f.params.method == method
                && (method == MethodId::SparseSvm
                    || match features.is_auto() {
                        true => f.feature_choice.is_some(),
                        false => f.params.features == features,
                    })
        })
    }

    /// A frontier is being computed.
    pub fn frontier_running(&self) -> bool {
        self.jobs.iter().any(|j| j.title.starts_with(FRONTIER_JOB))
    }

    pub fn spawn(
        &mut self,
        ctx: &egui::Context,
        kind: Option<AnalysisKind>,
        title: String,
        work: impl FnOnce(&crate::jobs::Progress) -> Result<JobOutput, JobError> + Send + 'static,
    ) {
        let c = ctx.clone();
        let job = Job::spawn(title.clone(), move || c.request_repaint(), work);
        self.jobs.push(RunningJob {
            kind,
            title,
            job,
            timing: None,
            bookkeeping: false,
        });
    }

    /// Spawn a job that keeps something in the data folder, out of the jobs strip.
    pub fn spawn_bookkeeping(
        &mut self,
        ctx: &egui::Context,
        title: String,
        work: impl FnOnce(&crate::jobs::Progress) -> Result<JobOutput, JobError> + Send + 'static,
    ) {
        self.spawn(ctx, None, title, work);
        if let Some(rj) = self.jobs.last_mut() {
            rj.bookkeeping = true;
        }
    }

    /// Spawn a run whose cost model expects `estimate`: its time left starts from the
    /// expectation measured on this machine, and its time, once done, corrects the next.
    pub fn spawn_timed(
        &mut self,
        ctx: &egui::Context,
        kind: Option<AnalysisKind>,
        title: String,
        estimate: crate::jobs::estimate::Estimate,
        work: impl FnOnce(&crate::jobs::Progress) -> Result<JobOutput, JobError> + Send + 'static,
    ) {
        self.spawn(ctx, kind, title, work);
        if let Some(rj) = self.jobs.last_mut() {
            rj.job
                .progress
                .set_expected(self.timings.expected(&estimate.timing, estimate.modelled));
            rj.timing = Some((estimate.timing, estimate.modelled));
        }
    }

    /// The jobs strip: what runs, how far, time left, Cancel.
    pub fn jobs_ui(&mut self, ui: &mut egui::Ui) {
        for rj in self.jobs.iter_mut().filter(|j| !j.bookkeeping) {
            ui.horizontal(|ui| {
                ui.label(&rj.title);
                let p = &rj.job.progress;
                let eta = match p.eta_secs() {
                    Some(s) if s < 1.0 => ", finishing".to_string(),
                    Some(s) if s < 90.0 => format!(", about {s:.0} s left"),
                    Some(s) => format!(", about {:.0} min left", s / 60.0),
                    None => String::new(),
                };
                ui.add(
                    ProgressBar::new(p.fraction() as f32)
                        .desired_width(480.0)
                        .show_percentage()
                        .text(format!("{}{eta}", p.message())),
                );
                if ui.button("Cancel").clicked() {
                    rj.job.cancel();
                }
            });
        }
    }

    /// The result of `kind` shown for session `session`: the chosen one if it is of that
    /// session, else the session's newest.
    pub fn shown_index(&self, kind: AnalysisKind, session: &str) -> Option<usize> {
        let of = |i: usize| {
            self.results
                .get(i)
                .is_some_and(|r| r.kind == kind && r.session == session)
        };
        self.shown
            .get(&kind)
            .copied()
            .filter(|&i| of(i))
            .or_else(|| (0..self.results.len()).rev().find(|&i| of(i)))
    }

    /// The results of `kind` on session `session`.
    pub fn of_session(&self, kind: AnalysisKind, session: &str) -> Vec<usize> {
        (0..self.results.len())
            .filter(|&i| self.results[i].kind == kind && self.results[i].session == session)
            .collect()
    }

    /// The result `kind`'s view shows (the chosen one, else the newest).
    pub fn shown_result(&self, kind: AnalysisKind) -> Option<&AnalysisResult> {
        self.shown
            .get(&kind)
            .and_then(|&i| self.results.get(i))
            .filter(|r| r.kind == kind)
            .or_else(|| self.results.iter().rev().find(|r| r.kind == kind))
    }

    /// Teach a learner every other grasp, then record its class distribution at each step
    /// of `grasp` (in the background).
    pub fn request_trace(
        &mut self,
        ctx: &egui::Context,
        s: &LoadedSession,
        grasp: usize,
        learner: SupervisedLearner,
    ) {
        if self
            .jobs
            .iter()
            .any(|j| j.title.starts_with("Recognition trace"))
        {
            return;
        }
        let session = s.session.clone();
        self.spawn(
            ctx,
            None,
            format!("Recognition trace of grasp {}", grasp + 1),
            move |p| {
                p.set(0.1, "teaching the other grasps");
                let params = RecognitionParams {
                    learner,
                    reps: 1,
                    ..Default::default()
                };
                let trace = grasp_trace(&session, &params, grasp).map_err(experiment_error)?;
                Ok(JobOutput::Trace(Box::new(ReplayTrace {
                    session: session.meta.name.clone(),
                    grasp,
                    learner,
                    trace,
                })))
            },
        );
    }
}
