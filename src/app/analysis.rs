//! The analysis views: a form to run each method on the active session as a background
//! job, the results kept per session, their scores and figures, export, and the chart of
//! speed against accuracy over every result.

use std::path::PathBuf;

use egui::{ProgressBar, RichText};

use super::figure_view;
use super::loader::LoadedSession;
use crate::cluster::baselines::{BaselinesParams, run_baselines};
use crate::cluster::grasp_features::session_features;
use crate::experiments::baselines_report::baselines_report;
use crate::experiments::report::{self, AnalysisKind, AnalysisResult, date_text};
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

#[derive(Default)]
pub struct Analyses {
    pub results: Vec<AnalysisResult>,
    pub jobs: Vec<RunningJob>,
    /// The result shown in each analysis view (index into `results`).
    pub shown: std::collections::HashMap<AnalysisKind, usize>,
    pub export: ExportSettings,
    pub baselines: BaselinesForm,
    /// Messages of finished jobs (errors and exports), newest last.
    pub messages: Vec<String>,
    /// A view the user asked to open from the speed-against-accuracy chart.
    pub open_request: Option<AnalysisKind>,
}

impl Analyses {
    pub fn busy(&self) -> bool {
        !self.jobs.is_empty()
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
                Some(Outcome::Done(JobOutput::Project(p))) => {
                    self.messages.push(format!(
                        "opened a project with {} results (sessions: {})",
                        p.results.len(),
                        p.sessions.join(", ")
                    ));
                    self.results.extend(p.results);
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
                        .desired_width(260.0)
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
        if let Some(f) = report::speed_accuracy(&self.results) {
            set_all.entries.push(figures::FigureEntry {
                name: "speed-against-accuracy".into(),
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
            let index = figures::export_all(
                &set_all,
                &dir,
                &[Format::Svg, Format::Png, Format::Csv],
                &opts,
            )
            .map_err(JobError::failed)?;
            Ok(JobOutput::Message(format!(
                "exported {} figures to {}",
                index.entries.len(),
                dir.display()
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

    fn export_one(&mut self, figure: &figures::Figure, name: &str) {
        let opts = self.export.options();
        let mut written = Vec::new();
        let result = std::fs::create_dir_all(&self.export.dir)
            .map_err(|e| format!("{}: {e}", self.export.dir.display()))
            .and_then(|_| {
                for f in [Format::Svg, Format::Png, Format::Csv] {
                    let path = self.export.dir.join(format!("{name}.{}", f.extension()));
                    figures::write_figure(figure, &path, &opts).map_err(|e| e.to_string())?;
                    written.push(path.display().to_string());
                }
                Ok(())
            });
        self.messages.push(match result {
            Ok(()) => format!("exported {}", written.join(", ")),
            Err(e) => format!("export failed: {e}"),
        });
    }

    fn export_settings_ui(&mut self, ui: &mut egui::Ui) {
        ui.horizontal(|ui| {
            let caption = ui.label("Export folder");
            let mut dir = self.export.dir.display().to_string();
            if ui
                .text_edit_singleline(&mut dir)
                .labelled_by(caption.id)
                .changed()
            {
                self.export.dir = PathBuf::from(dir);
            }
            ui.add(
                egui::DragValue::new(&mut self.export.width)
                    .range(200..=6000)
                    .prefix("width "),
            );
            ui.add(
                egui::DragValue::new(&mut self.export.height)
                    .range(150..=6000)
                    .prefix("height "),
            );
            ui.add(
                egui::DragValue::new(&mut self.export.dpi)
                    .range(48.0..=600.0)
                    .prefix("DPI "),
            );
        });
    }

    fn results_ui(&mut self, ui: &mut egui::Ui, kind: AnalysisKind, session: &str) {
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
        let r = self.results[shown].clone();
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
        self.export_settings_ui(ui);
        for (name, fig) in &r.figures {
            ui.separator();
            if ui
                .button(format!("Export {name} (SVG, PNG, CSV)"))
                .clicked()
            {
                let file = format!("{}-{name}", r.label.replace([' ', ',', '='], "_"));
                self.export_one(fig, &file);
            }
            figure_view::show(ui, &format!("{shown}-{name}"), fig, 300.0);
        }
    }

    pub fn baselines_ui(&mut self, ui: &mut egui::Ui, s: &LoadedSession, ctx: &egui::Context) {
        ui.heading("Baselines: sequential k-means, SOM and RBF SVM on the Table I features");
        let running = self
            .jobs
            .iter()
            .any(|j| j.kind == Some(AnalysisKind::Baselines));
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

    pub fn speed_accuracy_ui(&mut self, ui: &mut egui::Ui) {
        ui.heading("Speed against accuracy");
        match report::speed_accuracy(&self.results) {
            Some(fig) => {
                self.export_settings_ui(ui);
                if ui
                    .button("Export speed-against-accuracy (SVG, PNG, CSV)")
                    .clicked()
                {
                    self.export_one(&fig, "speed-against-accuracy");
                }
                figure_view::show(ui, "speed-accuracy", &fig, 420.0);
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
            None => {
                ui.label("Train a model in any analysis view: every result appears here.");
            }
        }
    }
}
