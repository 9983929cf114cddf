//! Object recognition (second paper): DS or GS OIESGP experts on all, tactile or encoder
//! features; accuracy as trials progress, the confusion matrix, early classification and
//! lengthscale relevance as tiles, with every model of the session compared on one chart.

use super::pane::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text, run_button};
use crate::app::View;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::loader::LoadedSession;
use crate::app::results::{Analyses, JobOutput, experiment_error, sequences_ready};
use crate::catalogue::{MethodId, Task};
use crate::experiments::figure_id::FigureId;
use crate::experiments::recognition::report::{accuracy_comparison, recognition_report};
use crate::experiments::recognition::{RecognitionParams, SupervisedLearner, run_recognition};
use crate::experiments::result::features_text;
use crate::experiments::result::{AnalysisKind, SizeReason};
use crate::features::sequence::FeatureSet;
use crate::jobs::JobError;
use crate::session::Session;
use crate::sweep::Experiment;
use std::sync::Arc;

/// Supervised recognition form: a few repetitions by default so the view answers quickly;
/// the CLI runs the paper's 50.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RecognitionForm {
    pub learner: SupervisedLearner,
    pub features: FeatureSet,
    pub reps: usize,
    pub noise_variance: f64,
    pub seed: u64,
    /// The experts' budget and kernel lags: automatic (the session's frontier
    /// recommendation, else the paper's 50 and 15) until the user sets them.
    pub capacity: usize,
    pub tau: usize,
    pub user_size: bool,
}

impl Default for RecognitionForm {
    fn default() -> Self {
        RecognitionForm {
            learner: SupervisedLearner::Ds,
            features: FeatureSet::AUTO,
            reps: 3,
            noise_variance: 0.0,
            seed: 0,
            capacity: paper_size().0,
            tau: paper_size().1,
            user_size: false,
        }
    }
}

/// The paper's capacity and tau (the learners' defaults).
fn paper_size() -> (usize, usize) {
    let gp = RecognitionParams::default().ds.gp;
    (gp.capacity, gp.tau)
}

impl RecognitionForm {
    fn method(&self) -> MethodId {
        self.learner.method()
    }

    /// The size the form runs with and why: the user's, else the recommendation of the
    /// frontier of this learner and feature set on the session, else the paper's. A size
    /// equal to the recommended or the paper's is called so, whoever set it.
    pub fn size(&self, analyses: &Analyses, session: &str) -> (usize, usize, SizeReason) {
        let recommended = analyses
            .frontier(session, self.method(), self.features)
            .and_then(|f| {
                let p = &f.points[f.recommended];
                Some((p.knob("capacity")? as usize, p.knob("tau")? as usize))
            });
        let size = match (self.user_size, recommended) {
            (true, _) => (self.capacity, self.tau),
            (false, Some(r)) => r,
            (false, None) => paper_size(),
        };
        let reason = SizeReason::of(&size, recommended.as_ref(), &paper_size());
        (size.0, size.1, reason)
    }
}

/// Seconds per repetition per observed step (every grasp's frames, trained and predicted)
/// at the paper's size, DS and GS: the geometric mean of the recognition sample and iCub
/// (`benches/estimates.rs`; docs/estimates.md has the table).
fn seconds_per_step(learner: SupervisedLearner) -> f64 {
    match learner {
        SupervisedLearner::Ds => 0.000117,
        SupervisedLearner::Gs => 0.0000386,
    }
}

/// What choosing the inputs costs, in repetitions of the protocol (none unless `auto`).
fn auto_repetitions(features: FeatureSet) -> f64 {
    match features.is_auto() {
        true => crate::experiments::recognition::AUTO_REPETITIONS,
        false => 0.0,
    }
}

impl RecognitionForm {
    /// The parameters the form runs with on `session`.
    pub fn params(&self, analyses: &Analyses, session: &str) -> RecognitionParams {
        let (capacity, tau, size_reason) = self.size(analyses, session);
        let mut p = RecognitionParams {
            learner: self.learner,
            features: self.features,
            reps: self.reps,
            seed: self.seed,
            taxel_noise_variance: self.noise_variance,
            size_reason,
            ..Default::default()
        };
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = capacity;
            gp.tau = tau;
        }
        p
    }

    /// What a run on `session` is expected to cost (DS and GS are timed apart: they cost
    /// differently).
    pub fn estimate(&self, session: &Session, _analyses: &Analyses) -> Estimate {
        let steps = session.total_frames();
        Estimate {
            timing: format!("recognition {:?}", self.learner),
            modelled: seconds_per_step(self.learner)
                * steps as f64
                * (self.reps as f64 + auto_repetitions(self.features)),
        }
    }
}

#[derive(Default)]
pub struct RecognitionRoom {
    pub form: RecognitionForm,
}

impl Room for RecognitionRoom {
    fn view(&self) -> View {
        View::Recognition
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        let f = Pane::Figure;
        vec![
            vec![f(FigureId::AccuracyByTrials), Pane::Comparison],
            vec![f(FigureId::Confusion), Pane::Scores],
            vec![f(FigureId::EarlyClassification), f(FigureId::Lengthscales)],
            vec![Pane::Replay],
        ]
    }

    fn run_text(&self, s: &LoadedSession, analyses: &Analyses) -> Option<String> {
        if !sequences_ready(&s.session) {
            return None;
        }
        let f = &self.form;
        let (capacity, tau, reason) = f.size(analyses, &s.session.meta.name);
        Some(format!(
            "Run: {} on {}, capacity {capacity}, tau {tau} ({}), {} repetition{} over {} grasps; {}.",
            format!("{:?}", f.learner).to_uppercase(),
            features_text(f.features),
            reason.text(),
            f.reps,
            if f.reps == 1 { "" } else { "s" },
            s.session.grasps.len(),
            estimate_text(&f.estimate(&s.session, analyses), analyses)
        ))
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Object recognition");
        ui.label("Online OIESGP experts (DS, GS)");
        let f = &mut self.form;
        egui::ComboBox::from_label("Learner")
            .selected_text(format!("{:?}", f.learner).to_uppercase())
            .show_ui(ui, |ui| {
                ui.selectable_value(&mut f.learner, SupervisedLearner::Ds, "DS (discriminative)");
                ui.selectable_value(&mut f.learner, SupervisedLearner::Gs, "GS (generative)");
            });
        // auto (chosen by cross validation on the session), the paper's three sets and the
        // per-taxel families; the count is on this session.
        let session = cx.session().map(|s| &s.session);
        egui::ComboBox::from_label("Features")
            .selected_text(features_text(f.features))
            .show_ui(ui, |ui| {
                for set in std::iter::once(FeatureSet::AUTO).chain(FeatureSet::OFFERED) {
                    let dim = session
                        .and_then(|s| set.dim(s))
                        .map(|d| format!(" ({d})"))
                        .unwrap_or_default();
                    ui.selectable_value(&mut f.features, set, features_text(set) + &dim);
                }
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
        if let Some(s) = cx.session() {
            let (capacity, tau, reason) = f.size(cx.analyses, &s.session.meta.name);
            (f.capacity, f.tau) = (capacity, tau);
            ui.label(format!("Model size ({}):", reason.text()));
            ui.horizontal(|ui| {
                let c = ui.add(
                    egui::DragValue::new(&mut f.capacity)
                        .range(1..=500)
                        .prefix("capacity "),
                );
                let t = ui.add(
                    egui::DragValue::new(&mut f.tau)
                        .range(1..=100)
                        .prefix("tau "),
                );
                if c.changed() || t.changed() {
                    f.user_size = true;
                }
            });
            if f.user_size
                && ui
                    .small_button("Automatic size")
                    .on_hover_text(
                        "The session's frontier recommendation for this learner and these \
                         features (Speed vs accuracy view), else the paper's 50 and 15",
                    )
                    .clicked()
            {
                f.user_size = false;
            }
        }
        if run_button(
            ui,
            cx,
            AnalysisKind::Recognition,
            sequences_ready,
            "(needs an object-recognition session: `object` labels and tactile sensors)",
        ) {
            self.start(cx);
        }
        super::models::section(ui, cx, |m| m.task() == Task::Recognition);
    }

    fn sweep(&self, cx: &Cx) -> Option<Result<Experiment, String>> {
        let s = cx.session()?;
        Some(if sequences_ready(&s.session) {
            Ok(Experiment::Recognition(
                self.form.params(cx.analyses, &s.session.meta.name),
            ))
        } else {
            Err("This session has no objects or no tactile sensors.".into())
        })
    }

    fn run(&self, session: &Arc<Session>, analyses: &Analyses) -> Option<Run> {
        if !sequences_ready(session) {
            return None;
        }
        let params = self.form.params(analyses, &session.meta.name);
        let session = session.clone();
        Some(Run {
            kind: Some(AnalysisKind::Recognition),
            title: format!("Recognition on {}", session.meta.name),
            estimate: self.form.estimate(&session, analyses),
            work: Box::new(move |p| {
                let r = run_recognition(&session, &params, p).map_err(experiment_error)?;
                // The experts trained on every grasp leave the session as a model file.
                let model =
                    crate::models::sequence_file_of_run(&session, &r).map_err(JobError::failed)?;
                Ok(JobOutput::Trained {
                    result: Box::new(recognition_report(&session.meta.name, &r)),
                    models: vec![model],
                })
            }),
        })
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, pane: &Pane, cx: &mut Cx) -> bool {
        if *pane != Pane::Comparison {
            return false;
        }
        let Some(s) = cx.session() else { return true };
        // Fig. 6 across every model trained on this session (and the offline SVM).
        match accuracy_comparison(&cx.analyses.results, &s.session.meta.name) {
            Some(fig) => {
                if ui
                    .small_button("Export")
                    .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
                    .clicked()
                {
                    cx.analyses.export_figure(&fig, "accuracy-compared");
                }
                let height = (ui.available_height() - 40.0).max(120.0);
                figure_view::show(ui, "accuracy-compared", &fig, height, FigureSelection::None);
            }
            None => {
                ui.label(
                    "Train a model: every recognition model of this session is compared here.",
                );
            }
        }
        true
    }
}
