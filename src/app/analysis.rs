//! The analysis views: a form to run each method on the active session as a background
//! job, the results kept per session, their scores and figures, export, and the chart of
//! speed against accuracy over every result.

use std::path::PathBuf;

use egui::{ProgressBar, RichText};

use super::figure_view::{self, Selection};
use super::loader::LoadedSession;
use crate::cluster::baselines::{BaselinesParams, run_baselines};
use crate::cluster::grasp_features::session_features;
use crate::experiments::ExperimentError;
use crate::experiments::baselines_report::baselines_report;
use crate::experiments::clustering::{ClusteringParams, UnsupervisedLearner, run_clustering};
use crate::experiments::recognition::{
    GraspTrace, RecognitionParams, SupervisedLearner, grasp_trace, run_recognition,
};
use crate::experiments::recognition_report::{
    accuracy_comparison, clustering_report, comparison_figures, recognition_report,
};
use crate::experiments::report::{self, AnalysisKind, AnalysisResult, TimeAxis, date_text};
use crate::experiments::stability::{
    Config, DataOptions, GridSpec, StabilityData, StabilityError, StabilityOptions,
};
use crate::experiments::stability_report::stability_report;
use crate::features::sequence::FeatureSet;
use crate::figures::{self, Format, RenderOptions};
use crate::jobs::{Job, JobError, Outcome};

/// A job and what it is for.
pub struct RunningJob {
    pub kind: Option<AnalysisKind>,
    pub title: String,
    pub job: Job<JobOutput>,
}

pub enum JobOutput {
    Result(Box<AnalysisResult>),
    Message(String),
    Project(report::Project),
    Trace(Box<ReplayTrace>),
}

/// The class distribution at every step of one grasp, for the replay view.
pub struct ReplayTrace {
    pub session: String,
    pub grasp: usize,
    pub learner: SupervisedLearner,
    pub trace: GraspTrace,
}

/// Export settings shared by every view.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ExportSettings {
    pub dir: PathBuf,
    pub width: u32,
    pub height: u32,
    pub dpi: f64,
}

impl Default for ExportSettings {
    fn default() -> Self {
        ExportSettings {
            dir: PathBuf::from("figures-export"),
            width: 960,
            height: 640,
            dpi: 96.0,
        }
    }
}

impl ExportSettings {
    fn options(&self) -> RenderOptions {
        RenderOptions {
            width: self.width,
            height: self.height,
            dpi: self.dpi,
        }
    }

    /// The folder, size and DPI form shown above each view's figures.
    fn ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let caption = ui.label("Export folder");
            let mut dir = self.dir.display().to_string();
            if ui
                .text_edit_singleline(&mut dir)
                .labelled_by(caption.id)
                .changed()
            {
                self.dir = PathBuf::from(dir);
            }
            ui.add(
                egui::DragValue::new(&mut self.width)
                    .range(200..=6000)
                    .prefix("width "),
            );
            ui.add(
                egui::DragValue::new(&mut self.height)
                    .range(150..=6000)
                    .prefix("height "),
            );
            ui.add(
                egui::DragValue::new(&mut self.dpi)
                    .range(48.0..=600.0)
                    .prefix("DPI "),
            );
        });
    }

    /// Write `figure` as SVG, PNG and CSV named `name`; returns the message to show.
    fn write(&self, figure: &figures::Figure, name: &str) -> String {
        let opts = self.options();
        let mut written = Vec::new();
        let result = std::fs::create_dir_all(&self.dir)
            .map_err(|e| format!("{}: {e}", self.dir.display()))
            .and_then(|_| {
                for f in [Format::Svg, Format::Png, Format::Csv] {
                    let path = self.dir.join(format!("{name}.{}", f.extension()));
                    figures::write_figure(figure, &path, &opts).map_err(|e| e.to_string())?;
                    written.push(path.display().to_string());
                }
                Ok(())
            });
        match result {
            Ok(()) => format!("exported {}", written.join(", ")),
            Err(e) => format!("export failed: {e}"),
        }
    }
}

/// Baselines form: few orders by default so the view answers in seconds.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct BaselinesForm {
    pub orders: usize,
    pub k: usize,
    pub seed: u64,
    pub with_svm: bool,
}

impl Default for BaselinesForm {
    fn default() -> Self {
        BaselinesForm {
            orders: 10,
            k: 10,
            seed: 0,
            with_svm: true,
        }
    }
}

/// Supervised recognition form: a few repetitions by default so the view answers quickly;
/// the CLI runs the paper's 50.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RecognitionForm {
    pub learner: SupervisedLearner,
    pub features: FeatureSet,
    pub reps: usize,
    pub noise_variance: f64,
    pub seed: u64,
}

impl Default for RecognitionForm {
    fn default() -> Self {
        RecognitionForm {
            learner: SupervisedLearner::Ds,
            features: FeatureSet::All,
            reps: 3,
            noise_variance: 0.0,
            seed: 0,
        }
    }
}

/// Grasp-stability form: one configuration, or a grid search with the parsimony rule.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StabilityForm {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
    pub grid: bool,
    /// Grid over num_bases: from, to, step.
    pub bases: [usize; 3],
}

impl Default for StabilityForm {
    fn default() -> Self {
        StabilityForm {
            num_bases: 29,
            beta: 1.0,
            gamma: 1.0,
            grid: false,
            bases: [5, 60, 5],
        }
    }
}

/// Unsupervised clustering form.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ClusteringForm {
    pub learner: UnsupervisedLearner,
    pub reps: usize,
    pub seed: u64,
    /// Novelty thresholds swept: from, to, step (the paper: 0.1 to 0.95).
    pub thresholds: [f64; 3],
    /// GU: clusters trained on fewer grasps take no part in the re-assignment.
    #[serde(default = "gu_min_grasps")]
    pub gu_min_grasps: usize,
}

fn gu_min_grasps() -> usize {
    crate::learners::GuParams::default().min_grasps
}

impl Default for ClusteringForm {
    fn default() -> Self {
        ClusteringForm {
            learner: UnsupervisedLearner::Du,
            reps: 2,
            seed: 0,
            thresholds: ClusteringForm::suggested_thresholds(UnsupervisedLearner::Du),
            gu_min_grasps: gu_min_grasps(),
        }
    }
}

impl ClusteringForm {
    /// The sweep offered for `learner`: the paper's 0.1 to 0.95 for DU; for GU 0.02 to 0.25
    /// in steps of 0.01, where its cluster count changes (above 0.3 it keeps 1–3 clusters
    /// on the iCub data).
    pub fn suggested_thresholds(learner: UnsupervisedLearner) -> [f64; 3] {
        match learner {
            UnsupervisedLearner::Du => [0.1, 0.95, 0.05],
            UnsupervisedLearner::Gu => [0.02, 0.25, 0.01],
        }
    }

    pub fn threshold_list(&self) -> Vec<f64> {
        let [from, to, step] = self.thresholds;
        if step.is_nan() || step <= 0.0 || to < from {
            return vec![from];
        }
        let n = ((to - from) / step + 1e-9).floor() as usize;
        (0..=n)
            .map(|i| ((from + i as f64 * step) * 1e6).round() / 1e6)
            .collect()
    }
}

pub(super) fn experiment_error(e: ExperimentError) -> JobError {
    match e {
        ExperimentError::Cancelled => JobError::Cancelled,
        other => JobError::failed(other),
    }
}

/// An object-recognition session: encoders, sequences and `object` labels.
pub(super) fn recognition_ready(s: &LoadedSession) -> bool {
    s.session.label_set("object").is_some() && !s.session.encoders.is_empty()
}

#[derive(Default)]
pub struct Analyses {
    pub results: Vec<AnalysisResult>,
    pub jobs: Vec<RunningJob>,
    /// The result shown in each analysis view (index into `results`).
    pub shown: std::collections::HashMap<AnalysisKind, usize>,
    /// The detail item selected through a figure: (result index, figure name) -> item.
    pub selected: std::collections::HashMap<(usize, String), usize>,
    pub export: ExportSettings,
    pub baselines: BaselinesForm,
    pub recognition: RecognitionForm,
    pub clustering: ClusteringForm,
    pub stability: StabilityForm,
    pub robustness: super::robustness::RobustnessForm,
    /// Messages of finished jobs (errors and exports), newest last.
    pub messages: Vec<String>,
    /// The time on the speed-against-accuracy chart's x axis.
    pub time_axis: TimeAxis,
    /// A view the user asked to open from the speed-against-accuracy chart.
    pub open_request: Option<AnalysisKind>,
    /// The last recognition trace computed for the replay.
    pub trace: Option<ReplayTrace>,
    /// Projects that just opened: the sessions each names (for the app to reopen) and the
    /// session of its first result.
    pub opened_projects: Vec<(Vec<String>, Option<String>)>,
}

impl Analyses {
    pub fn busy(&self) -> bool {
        !self.jobs.is_empty()
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
            match rj.job.take() {
                Some(Outcome::Done(JobOutput::Result(r))) => {
                    let kind = r.kind;
                    self.results.push(*r);
                    self.shown.insert(kind, self.results.len() - 1);
                }
                Some(Outcome::Done(JobOutput::Message(m))) => self.messages.push(m),
                Some(Outcome::Done(JobOutput::Trace(t))) => self.trace = Some(*t),
                Some(Outcome::Done(JobOutput::Project(p))) => {
                    let n = p.results.len();
                    self.messages.push(format!(
                        "opened a project with {n} result{} (sessions: {})",
                        if n == 1 { "" } else { "s" },
                        p.sessions.join(", ")
                    ));
                    let first = p.results.first().map(|r| r.session.clone());
                    self.results.extend(p.results);
                    self.opened_projects.push((p.sessions, first));
                }
                Some(Outcome::Cancelled) => self.messages.push(format!("{}: cancelled", rj.title)),
                Some(Outcome::Failed(e)) => self.messages.push(format!("{} failed: {e}", rj.title)),
                None => {}
            }
        }
        changed
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
        self.jobs.push(RunningJob { kind, title, job });
    }

    /// The jobs panel: what runs, how far, time left, Cancel.
    pub fn jobs_ui(&mut self, ui: &mut egui::Ui) {
        for rj in &mut self.jobs {
            ui.horizontal(|ui| {
                ui.label(&rj.title);
                let p = &rj.job.progress;
                let eta = p
                    .eta_secs()
                    .map(|s| format!(", about {s:.0} s left"))
                    .unwrap_or_default();
                ui.add(
                    ProgressBar::new(p.fraction() as f32)
                        .desired_width(560.0)
                        .show_percentage()
                        .text(format!("{}{eta}", p.message())),
                );
                if ui.button("Cancel").clicked() {
                    rj.job.cancel();
                }
            });
        }
        let mut dismiss = None;
        for (i, m) in self.messages.iter().enumerate() {
            ui.horizontal(|ui| {
                let color = if m.contains("failed") {
                    ui.visuals().error_fg_color
                } else {
                    ui.visuals().text_color()
                };
                ui.colored_label(color, m);
                if ui.small_button("Dismiss").clicked() {
                    dismiss = Some(i);
                }
            });
        }
        if let Some(i) = dismiss {
            self.messages.remove(i);
        }
    }

    /// Export every figure of every result in the background.
    pub fn export_all(&mut self, ctx: &egui::Context) {
        let set = report::figure_set(&self.results);
        let mut set_all = set;
        let extra = report::speed_accuracy_figures(&self.results)
            .into_iter()
            .chain(comparison_figures(&self.results));
        for (name, f) in extra {
            set_all.entries.push(figures::FigureEntry {
                name,
                figure: f,
                parameters: Default::default(),
                session: "all".into(),
                date: date_text(report::now_unix()),
            });
        }
        let dir = self.export.dir.clone();
        let opts = self.export.options();
        self.spawn(ctx, None, "Export all figures".into(), move |p| {
            p.set(0.0, format!("writing {} figures", set_all.entries.len()));
            let t0 = std::time::Instant::now();
            let index = figures::export_all(
                &set_all,
                &dir,
                &[Format::Svg, Format::Png, Format::Csv],
                &opts,
            )
            .map_err(JobError::failed)?;
            Ok(JobOutput::Message(format!(
                "exported {} figures to {} in {:.2} s",
                index.entries.len(),
                dir.display(),
                t0.elapsed().as_secs_f64()
            )))
        });
    }

    /// Save the results and the sessions they came from as a project file (in the background).
    pub fn save_project(&mut self, ctx: &egui::Context, path: PathBuf, sessions: Vec<String>) {
        let project = report::Project::new(sessions, self.results.clone());
        self.spawn(
            ctx,
            None,
            format!("Save project {}", path.display()),
            move |_| {
                project.save(&path).map_err(JobError::failed)?;
                Ok(JobOutput::Message(format!(
                    "project saved to {}",
                    path.display()
                )))
            },
        );
    }

    /// Add the results of a saved project (read in the background).
    pub fn open_project(&mut self, ctx: &egui::Context, path: PathBuf) {
        self.spawn(
            ctx,
            None,
            format!("Open project {}", path.display()),
            move |_| {
                let project = report::Project::load(&path).map_err(JobError::failed)?;
                Ok(JobOutput::Project(project))
            },
        );
    }

    /// The result `kind`'s view shows (the chosen one, else the newest).
    pub fn shown_result(&self, kind: AnalysisKind) -> Option<&AnalysisResult> {
        self.shown
            .get(&kind)
            .and_then(|&i| self.results.get(i))
            .filter(|r| r.kind == kind)
            .or_else(|| self.results.iter().rev().find(|r| r.kind == kind))
    }

    pub(super) fn results_ui(&mut self, ui: &mut egui::Ui, kind: AnalysisKind, session: &str) {
        let mine: Vec<usize> = (0..self.results.len())
            .filter(|&i| self.results[i].kind == kind && self.results[i].session == session)
            .collect();
        if mine.is_empty() {
            ui.label("No results yet for this session: set the parameters and press Run.");
            return;
        }
        let shown = self
            .shown
            .get(&kind)
            .copied()
            .filter(|i| mine.contains(i))
            .unwrap_or(mine[mine.len() - 1]);
        ui.horizontal_wrapped(|ui| {
            ui.label("Results:");
            for &i in &mine {
                let r = &self.results[i];
                let text = format!("{} ({})", r.label, date_text(r.created));
                if ui.selectable_label(i == shown, text).clicked() {
                    self.shown.insert(kind, i);
                }
            }
        });
        // Borrow the result (it holds every figure): nothing is copied per frame.
        let r = &self.results[shown];
        egui::Grid::new(("scores", kind as u8))
            .striped(true)
            .show(ui, |ui| {
                for (name, v) in &r.scores {
                    ui.label(name);
                    ui.label(RichText::new(format!("{v:.4}")).strong());
                    ui.end_row();
                }
                ui.label("training time");
                ui.label(format!("{:.2} s", r.train_seconds));
                ui.end_row();
                for (k, v) in &r.parameters {
                    ui.label(k);
                    ui.label(v);
                    ui.end_row();
                }
            });
        self.export.ui(ui);
        let mut message = None;
        for (name, fig) in &r.figures {
            ui.separator();
            let file = format!("{}-{name}", r.label.replace([' ', ',', '='], "_"));
            if ui
                .button(format!("Export {name} (SVG, PNG, CSV)"))
                .clicked()
            {
                message = Some(self.export.write(fig, &file));
            }
            let id = format!("{shown}-{name}");
            let Some(details) = r.details_of(name).filter(|d| !d.items.is_empty()) else {
                figure_view::show(ui, &id, fig, 300.0, Selection::None);
                continue;
            };
            let key = (shown, name.clone());
            let chart = matches!(fig.kind, figures::FigureKind::Chart(_));
            let mut sel = self.selected.get(&key).copied();
            if chart {
                // A chart always carries its marker; a slider moves it too.
                let mut i = sel.unwrap_or(0).min(details.items.len() - 1);
                let keys: Vec<f64> = details.items.iter().map(|x| x.0).collect();
                ui.add(
                    egui::Slider::new(&mut i, 0..=details.items.len() - 1)
                        .text(&details.selector)
                        .custom_formatter(move |v, _| format!("{}", keys[v as usize]))
                        .custom_parser(|_| None),
                );
                sel = Some(i);
            }
            let selection = match (chart, sel) {
                (true, Some(i)) => Selection::Marker(details.items[i].0),
                _ => Selection::Image(sel),
            };
            let act = figure_view::show(ui, &id, fig, 300.0, selection);
            if let Some(x) = act.marker_x {
                sel = details.nearest(x);
            }
            if act.clicked_image.is_some() {
                sel = act.clicked_image;
            }
            match sel.and_then(|i| details.items.get(i)) {
                Some((_, detail)) => {
                    ui.group(|ui| {
                        if ui
                            .button(format!("Export this {} (SVG, PNG, CSV)", details.selector))
                            .clicked()
                        {
                            let file = format!(
                                "{file}-{}",
                                detail.title.replace([' ', ',', ':', '='], "_")
                            );
                            message = Some(self.export.write(detail, &file));
                        }
                        figure_view::show(
                            ui,
                            &format!("{id}-detail"),
                            detail,
                            220.0,
                            Selection::None,
                        );
                    });
                }
                None => {
                    ui.label(format!("Click a {} to see it in detail.", details.selector));
                }
            }
            if let Some(i) = sel {
                self.selected.insert(key, i);
            }
        }
        self.messages.extend(message);
    }

    pub fn baselines_ui(&mut self, ui: &mut egui::Ui, s: &LoadedSession, ctx: &egui::Context) {
        ui.heading("Baselines: sequential k-means, SOM and RBF SVM on the Table I features");
        let running = self.is_running(AnalysisKind::Baselines);
        ui.horizontal(|ui| {
            ui.add(
                egui::DragValue::new(&mut self.baselines.orders)
                    .range(1..=200)
                    .prefix("orders "),
            );
            ui.add(
                egui::DragValue::new(&mut self.baselines.k)
                    .range(2..=40)
                    .prefix("k "),
            );
            ui.add(egui::DragValue::new(&mut self.baselines.seed).prefix("seed "));
            ui.checkbox(&mut self.baselines.with_svm, "RBF SVM (5-fold)");
            let can_run = s.session.label_sets.iter().any(|l| l.name == "object")
                && !s.session.encoders.is_empty();
            if ui
                .add_enabled(!running && can_run, egui::Button::new("Run"))
                .clicked()
            {
                let form = self.baselines.clone();
                let session = s.session.clone();
                self.spawn(
                    ctx,
                    Some(AnalysisKind::Baselines),
                    format!("Baselines on {}", session.meta.name),
                    move |p| {
                        let t0 = std::time::Instant::now();
                        let set = session
                            .label_set("object")
                            .ok_or_else(|| JobError::failed("no `object` labels"))?;
                        let truth = session.labels_of(set);
                        let features = session_features(&session).map_err(JobError::failed)?;
                        let (rows, cols) = crate::cluster::baselines::grid_for(form.k);
                        let mut params = BaselinesParams {
                            orders: form.orders,
                            seed: form.seed,
                            k: form.k,
                            ..Default::default()
                        };
                        params.som.rows = rows;
                        params.som.cols = cols;
                        // Two repeats of 5-fold keep the view responsive; the CLI runs the full 10.
                        params.cv_repeats = if form.with_svm { 2 } else { 0 };
                        let r = run_baselines(features.view(), &truth, &params, p).map_err(
                            |e| match e {
                                crate::cluster::baselines::BaselinesError::Cancelled(_) => {
                                    JobError::Cancelled
                                }
                                other => JobError::failed(other),
                            },
                        )?;
                        Ok(JobOutput::Result(Box::new(baselines_report(
                            &session.meta.name,
                            &r,
                            t0.elapsed().as_secs_f64(),
                        ))))
                    },
                );
            }
            if !can_run {
                ui.label("(needs an object-recognition session: encoders and `object` labels)");
            }
        });
        ui.separator();
        self.results_ui(ui, AnalysisKind::Baselines, &s.session.meta.name);
    }

    pub fn stability_ui(&mut self, ui: &mut egui::Ui, s: &LoadedSession, ctx: &egui::Context) {
        ui.heading("Grasp stability: sparse coding of tactile images and a linear SVM");
        let running = self.is_running(AnalysisKind::Stability);
        let f = &mut self.stability;
        ui.horizontal(|ui| {
            ui.checkbox(&mut f.grid, "Grid search (β and γ over 0.5, 1, 2)");
            if f.grid {
                ui.add(
                    egui::DragValue::new(&mut f.bases[0])
                        .range(1..=200)
                        .prefix("bases from "),
                );
                ui.add(
                    egui::DragValue::new(&mut f.bases[1])
                        .range(1..=200)
                        .prefix("to "),
                );
                ui.add(
                    egui::DragValue::new(&mut f.bases[2])
                        .range(1..=50)
                        .prefix("step "),
                );
            } else {
                ui.add(
                    egui::DragValue::new(&mut f.num_bases)
                        .range(1..=200)
                        .prefix("num_bases "),
                );
                ui.add(
                    egui::DragValue::new(&mut f.beta)
                        .range(1e-4..=1e4)
                        .speed(0.05)
                        .prefix("β "),
                );
                ui.add(
                    egui::DragValue::new(&mut f.gamma)
                        .range(1e-4..=1e4)
                        .speed(0.05)
                        .prefix("γ "),
                );
            }
        });
        ui.label("Pressures are z-scored per taxel over the session; β and γ use the 0.5·|x − Da|² + λ·|a|₁ convention.");
        // The pipeline predicts a two-class outcome (success / failure).
        let ready = s.session.label_sets.iter().any(|l| l.classes.len() == 2);
        if !ready {
            ui.label("(needs a session with a two-class outcome label, e.g. success / failure)");
        }
        if ui
            .add_enabled(!running && ready, egui::Button::new("Run"))
            .clicked()
        {
            self.start_stability(ctx, s);
        }
        ui.separator();
        self.results_ui(ui, AnalysisKind::Stability, &s.session.meta.name);
    }

    /// Run the stability form's pipeline on `s` in the background.
    pub fn start_stability(&mut self, ctx: &egui::Context, s: &LoadedSession) {
        let f = self.stability.clone();
        let session = s.session.clone();
        self.spawn(
            ctx,
            Some(AnalysisKind::Stability),
            format!("Grasp stability on {}", session.meta.name),
            move |p| {
                let data = StabilityData::from_session(&session, &DataOptions::default())
                    .map_err(JobError::failed)?;
                let mut opts = StabilityOptions {
                    single: Config {
                        num_bases: f.num_bases,
                        beta: f.beta,
                        gamma: f.gamma,
                    },
                    ..Default::default()
                };
                if f.grid {
                    let [from, to, step] = f.bases;
                    opts.grid = Some(GridSpec {
                        num_bases: (from..=to.max(from)).step_by(step.max(1)).collect(),
                        beta: vec![0.5, 1.0, 2.0],
                        gamma: vec![0.5, 1.0, 2.0],
                    });
                }
                let r =
                    crate::experiments::stability::run(&data, &opts, p).map_err(|e| match e {
                        StabilityError::Cancelled => JobError::Cancelled,
                        other => JobError::failed(other),
                    })?;
                Ok(JobOutput::Result(Box::new(stability_report(&r))))
            },
        );
    }

    pub fn recognition_ui(&mut self, ui: &mut egui::Ui, s: &LoadedSession, ctx: &egui::Context) {
        ui.heading("Object recognition: online OIESGP experts (DS, GS)");
        let running = self.is_running(AnalysisKind::Recognition);
        let f = &mut self.recognition;
        ui.horizontal(|ui| {
            egui::ComboBox::from_label("Learner")
                .selected_text(format!("{:?}", f.learner).to_uppercase())
                .show_ui(ui, |ui| {
                    ui.selectable_value(
                        &mut f.learner,
                        SupervisedLearner::Ds,
                        "DS (discriminative)",
                    );
                    ui.selectable_value(&mut f.learner, SupervisedLearner::Gs, "GS (generative)");
                });
            egui::ComboBox::from_label("Features")
                .selected_text(crate::experiments::recognition_report::features_text(
                    f.features,
                ))
                .show_ui(ui, |ui| {
                    ui.selectable_value(&mut f.features, FeatureSet::All, "all features (34)");
                    ui.selectable_value(
                        &mut f.features,
                        FeatureSet::Tactile,
                        "tactile features (25)",
                    );
                    ui.selectable_value(
                        &mut f.features,
                        FeatureSet::Encoder,
                        "encoder features (9)",
                    );
                });
            ui.add(
                egui::DragValue::new(&mut f.reps)
                    .range(1..=50)
                    .prefix("repetitions "),
            );
            egui::ComboBox::from_label("Taxel noise σ²")
                .selected_text(format!("{}", f.noise_variance))
                .show_ui(ui, |ui| {
                    for v in [0.0, 100.0, 1000.0] {
                        ui.selectable_value(&mut f.noise_variance, v, format!("{v}"));
                    }
                });
            ui.add(egui::DragValue::new(&mut f.seed).prefix("seed "));
        });
        let ready = recognition_ready(s);
        if !ready {
            ui.label("(needs an object-recognition session: encoders and `object` labels)");
        }
        if ui
            .add_enabled(!running && ready, egui::Button::new("Run"))
            .clicked()
        {
            let f = self.recognition.clone();
            let session = s.session.clone();
            self.spawn(
                ctx,
                Some(AnalysisKind::Recognition),
                format!("Recognition on {}", session.meta.name),
                move |p| {
                    let params = RecognitionParams {
                        learner: f.learner,
                        features: f.features,
                        reps: f.reps,
                        seed: f.seed,
                        taxel_noise_variance: f.noise_variance,
                        ..Default::default()
                    };
                    let r = run_recognition(&session, &params, p).map_err(experiment_error)?;
                    Ok(JobOutput::Result(Box::new(recognition_report(
                        &session.meta.name,
                        &r,
                    ))))
                },
            );
        }
        ui.separator();
        // Fig. 6 across every model trained on this session (and the offline SVM).
        if let Some(fig) = accuracy_comparison(&self.results, &s.session.meta.name) {
            if ui.button("Export the comparison (SVG, PNG, CSV)").clicked() {
                let m = self.export.write(&fig, "accuracy-compared");
                self.messages.push(m);
            }
            figure_view::show(ui, "accuracy-compared", &fig, 300.0, Selection::None);
            ui.separator();
        }
        self.results_ui(ui, AnalysisKind::Recognition, &s.session.meta.name);
    }

    pub fn clustering_ui(&mut self, ui: &mut egui::Ui, s: &LoadedSession, ctx: &egui::Context) {
        ui.heading("Clustering: online OIESGP experts without labels (DU, GU)");
        let running = self.is_running(AnalysisKind::Clustering);
        let f = &mut self.clustering;
        ui.horizontal(|ui| {
            let before = f.learner;
            egui::ComboBox::from_label("Learner")
                .selected_text(format!("{:?}", f.learner).to_uppercase())
                .show_ui(ui, |ui| {
                    ui.selectable_value(
                        &mut f.learner,
                        UnsupervisedLearner::Du,
                        "DU (discriminative)",
                    );
                    ui.selectable_value(
                        &mut f.learner,
                        UnsupervisedLearner::Gu,
                        "GU (generative, EVT novelty)",
                    );
                });
            if f.learner != before {
                f.thresholds = ClusteringForm::suggested_thresholds(f.learner);
            }
            if f.learner == UnsupervisedLearner::Gu {
                ui.add(
                    egui::DragValue::new(&mut f.gu_min_grasps)
                        .range(1..=20)
                        .prefix("grasps to keep a cluster: "),
                )
                .on_hover_text(
                    "A cluster takes part in the final re-assignment once its expert has \
                     been trained on this many grasps (1 keeps every cluster created)",
                );
            }
            ui.add(
                egui::DragValue::new(&mut f.reps)
                    .range(1..=50)
                    .prefix("repetitions "),
            );
            ui.add(egui::DragValue::new(&mut f.seed).prefix("seed "));
            ui.label("thresholds");
            ui.add(
                egui::DragValue::new(&mut f.thresholds[0])
                    .range(0.01..=0.99)
                    .speed(0.01)
                    .prefix("from "),
            );
            ui.add(
                egui::DragValue::new(&mut f.thresholds[1])
                    .range(0.01..=0.99)
                    .speed(0.01)
                    .prefix("to "),
            );
            ui.add(
                egui::DragValue::new(&mut f.thresholds[2])
                    .range(0.01..=0.5)
                    .speed(0.01)
                    .prefix("step "),
            );
        });
        let ready = recognition_ready(s);
        if ui
            .add_enabled(!running && ready, egui::Button::new("Run"))
            .clicked()
        {
            let f = self.clustering.clone();
            let session = s.session.clone();
            self.spawn(
                ctx,
                Some(AnalysisKind::Clustering),
                format!("Clustering on {}", session.meta.name),
                move |p| {
                    let params = ClusteringParams {
                        learner: f.learner,
                        reps: f.reps,
                        seed: f.seed,
                        thresholds: f.threshold_list(),
                        gu_min_grasps: f.gu_min_grasps,
                        ..Default::default()
                    };
                    let r = run_clustering(&session, &params, p).map_err(experiment_error)?;
                    Ok(JobOutput::Result(Box::new(clustering_report(
                        &session.meta.name,
                        &r,
                    ))))
                },
            );
        }
        ui.separator();
        self.results_ui(ui, AnalysisKind::Clustering, &s.session.meta.name);
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

    pub fn speed_accuracy_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Speed against accuracy");
        ui.horizontal(|ui| {
            ui.label("Time axis:");
            ui.selectable_value(&mut self.time_axis, TimeAxis::Training, "training time");
            ui.selectable_value(
                &mut self.time_axis,
                TimeAxis::Prediction,
                "prediction time per step or sample",
            );
        });
        let axis = self.time_axis;
        match report::speed_accuracy(&self.results, axis) {
            Some(fig) => {
                self.export.ui(ui);
                let file = match axis {
                    TimeAxis::Training => "speed-against-accuracy",
                    TimeAxis::Prediction => "prediction-speed-against-accuracy",
                };
                if ui
                    .button(format!("Export {file} (SVG, PNG, CSV)"))
                    .clicked()
                {
                    let m = self.export.write(&fig, file);
                    self.messages.push(m);
                }
                let act = figure_view::show(ui, "speed-accuracy", &fig, 420.0, Selection::None);
                // Clicking a model's point opens its view, like its button below.
                let sources = report::speed_accuracy_sources(&self.results, axis);
                if let Some((series, k)) = act.clicked_point
                    && let figures::FigureKind::Chart(c) = &fig.kind
                    && c.series
                        .get(series)
                        .is_some_and(|s| s.name == "trained models")
                    && let Some(&i) = sources.get(k)
                {
                    self.shown.insert(self.results[i].kind, i);
                    self.open_request = Some(self.results[i].kind);
                }
                ui.label("Open a model's views:");
                ui.horizontal_wrapped(|ui| {
                    for i in 0..self.results.len() {
                        let r = &self.results[i];
                        if r.headline.is_some()
                            && ui.button(format!("{} · {}", r.label, r.session)).clicked()
                        {
                            self.shown.insert(r.kind, i);
                            self.open_request = Some(r.kind);
                        }
                    }
                });
            }
            None if axis == TimeAxis::Prediction && !self.results.is_empty() => {
                ui.label("None of the results times its predictions (the OIESGP learners do).");
            }
            None => {
                ui.label("Train a model in any analysis view: every result appears here.");
            }
        }
    }
}
