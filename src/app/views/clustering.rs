//! Clustering (second paper): DU or GU over a novelty-threshold sweep; scores and clusters
//! against the threshold, NMI against effective clusters, and the true classes against the
//! clusters at the threshold the marker selects, as tiles.

use super::pane::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text, run_button};
use crate::app::View;
use crate::app::loader::LoadedSession;
use crate::app::results::Analyses;
use crate::app::results::{JobOutput, experiment_error, recognition_ready};
use crate::catalogue::Task;
use crate::experiments::clustering::report::clustering_report;
use crate::experiments::clustering::{ClusteringParams, UnsupervisedLearner, run_clustering};
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::AnalysisKind;
use crate::jobs::JobError;
use crate::session::Session;
use crate::sweep::Experiment;
use std::sync::Arc;

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

    /// The parameters the form runs with.
    pub fn params(&self) -> ClusteringParams {
        ClusteringParams {
            learner: self.learner,
            reps: self.reps,
            seed: self.seed,
            thresholds: self.threshold_list(),
            gu_min_grasps: self.gu_min_grasps,
            ..Default::default()
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

/// Seconds per observed step per threshold and order on 2 cores, for the suggested sweeps:
/// the geometric mean of the recognition sample and iCub (DU 9.0 and 17.8 s, GU 6.3 and
/// 11.4 s for two orders; `benches/estimates.rs`). DU's experts read the session's pair
/// table; an order is learned once for all thresholds until they part.
fn seconds_per_step(learner: UnsupervisedLearner) -> f64 {
    match learner {
        UnsupervisedLearner::Du => 0.000139,
        UnsupervisedLearner::Gu => 0.00007,
    }
}

impl ClusteringForm {
    /// What a run on `session` is expected to cost (DU and GU are timed apart: they cost
    /// differently).
    pub fn estimate(&self, session: &Session) -> Estimate {
        let steps = session.total_frames();
        Estimate {
            timing: format!("clustering {:?}", self.learner),
            modelled: seconds_per_step(self.learner)
                * steps as f64
                * self.reps as f64
                * self.threshold_list().len() as f64,
        }
    }
}

#[derive(Default)]
pub struct ClusteringRoom {
    pub form: ClusteringForm,
}

impl Room for ClusteringRoom {
    fn view(&self) -> View {
        View::Clustering
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        let f = Pane::Figure;
        vec![
            vec![f(FigureId::ScoresVsThreshold), f(FigureId::NmiVsEffective)],
            vec![f(FigureId::ClustersVsThreshold), f(FigureId::ScoresAt10)],
            vec![Pane::Detail(FigureId::ScoresVsThreshold), Pane::Scores],
            vec![Pane::Replay],
        ]
    }

    fn run_text(&self, s: &LoadedSession, analyses: &Analyses) -> Option<String> {
        if !recognition_ready(&s.session) {
            return None;
        }
        let f = &self.form;
        let n = f.threshold_list().len();
        Some(format!(
            "Run: {} over {n} novelty threshold{} from {} to {}, {} order{} of {} grasps; {}.",
            format!("{:?}", f.learner).to_uppercase(),
            if n == 1 { "" } else { "s" },
            f.thresholds[0],
            f.thresholds[1],
            f.reps,
            if f.reps == 1 { "" } else { "s" },
            s.session.grasps.len(),
            estimate_text(&f.estimate(&s.session), analyses)
        ))
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Clustering");
        ui.label("Online OIESGP experts without labels (DU, GU)");
        let f = &mut self.form;
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
        ui.horizontal(|ui| {
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
        if run_button(
            ui,
            cx,
            AnalysisKind::Clustering,
            recognition_ready,
            "(needs an object-recognition session: encoders and `object` labels)",
        ) {
            self.start(cx);
        }
        super::models::section(ui, cx, |m| m.task() == Task::Clustering);
    }

    fn sweep(&self, cx: &Cx) -> Option<Result<Experiment, String>> {
        cx.session()?;
        Some(Ok(Experiment::Clustering(self.form.params())))
    }

    fn run(&self, session: &Arc<Session>, _analyses: &Analyses) -> Option<Run> {
        if !recognition_ready(session) {
            return None;
        }
        let f = self.form.clone();
        let session = session.clone();
        Some(Run {
            kind: Some(AnalysisKind::Clustering),
            title: format!("Clustering on {}", session.meta.name),
            estimate: self.form.estimate(&session),
            work: Box::new(move |p| {
                let r = run_clustering(&session, &f.params(), p).map_err(experiment_error)?;
                let result = Box::new(clustering_report(&session.meta.name, &r));
                // Learned at the threshold chosen without labels (when the run chose one),
                // the experts leave the session as a model file.
                let models = crate::models::cluster_file_of_run(&session, &r)
                    .map_err(JobError::failed)?
                    .into_iter()
                    .collect();
                Ok(JobOutput::Trained { result, models })
            }),
        })
    }
}
