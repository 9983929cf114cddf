//! Baselines: sequential k-means, a SOM and an RBF SVM on the per-grasp Table I features.

use super::pane::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text, run_button};
use crate::app::View;
use crate::app::loader::LoadedSession;
use crate::app::results::Analyses;
use crate::app::results::{JobOutput, recognition_ready};
use crate::catalogue::Input;
use crate::experiments::baselines::baselines_report;
use crate::experiments::baselines::{BaselinesParams, run_baselines};
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::AnalysisKind;
use crate::features::table_one::session_features;
use crate::jobs::JobError;
use crate::session::Session;
use std::sync::Arc;

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

/// Seconds per order (k-means and SOM) and per repeat of the SVM's 5-fold grid, per grasp,
/// on 2 cores: the defaults took 2.6 s on the recognition sample and 2.9 s on iCub (200
/// grasps each; `benches/estimates.rs`), the SVM's grid most of it.
const SECONDS_PER_ORDER_GRASP: f64 = 0.00009;
const SECONDS_PER_SVM_REPEAT_GRASP: f64 = 0.0064;

impl BaselinesForm {
    /// What a run on `session` is expected to cost (timed apart with and without the RBF
    /// SVM's grid).
    pub fn estimate(&self, session: &Session) -> Estimate {
        let g = session.grasps.len() as f64;
        let svm = if self.with_svm { 2.0 } else { 0.0 };
        Estimate {
            timing: format!("baselines{}", if self.with_svm { " with SVM" } else { "" }),
            modelled: SECONDS_PER_ORDER_GRASP * g * self.orders as f64
                + SECONDS_PER_SVM_REPEAT_GRASP * g * svm,
        }
    }
}

#[derive(Default)]
pub struct BaselinesRoom {
    pub form: BaselinesForm,
}

impl Room for BaselinesRoom {
    fn view(&self) -> View {
        View::Baselines
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        let f = Pane::Figure;
        vec![
            vec![f(FigureId::NmiVsClusters)],
            vec![f(FigureId::Scores), Pane::Scores],
            vec![f(FigureId::SvmGrid)],
        ]
    }

    fn run_text(&self, s: &LoadedSession, analyses: &Analyses) -> Option<String> {
        if !recognition_ready(&s.session) {
            return None;
        }
        let f = &self.form;
        Some(format!(
            "Run: k-means and a SOM with k = {} over {} orders{} on {} grasps; {}.",
            f.k,
            f.orders,
            if f.with_svm {
                ", and an RBF SVM (5-fold, twice)"
            } else {
                ""
            },
            s.session.grasps.len(),
            estimate_text(&f.estimate(&s.session), analyses)
        ))
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Baselines");
        ui.label("Sequential k-means, SOM and RBF SVM on the Table I features");
        let f = &mut self.form;
        ui.add(
            egui::DragValue::new(&mut f.orders)
                .range(1..=200)
                .prefix("orders "),
        );
        ui.add(egui::DragValue::new(&mut f.k).range(2..=40).prefix("k "));
        ui.add(egui::DragValue::new(&mut f.seed).prefix("seed "));
        ui.checkbox(&mut f.with_svm, "RBF SVM (5-fold)");
        if run_button(
            ui,
            cx,
            AnalysisKind::Baselines,
            recognition_ready,
            "(needs an object-recognition session: encoders and `object` labels)",
        ) {
            self.start(cx);
        }
        super::models::section(ui, cx, |m| m.input() == Input::TableOne);
    }

    fn run(&self, session: &Arc<Session>, _analyses: &Analyses) -> Option<Run> {
        if !recognition_ready(session) {
            return None;
        }
        let form = self.form.clone();
        let session = session.clone();
        Some(Run {
            kind: Some(AnalysisKind::Baselines),
            title: format!("Baselines on {}", session.meta.name),
            estimate: self.form.estimate(&session),
            work: Box::new(move |p| {
                let t0 = std::time::Instant::now();
                let set = session
                    .label_set("object")
                    .ok_or_else(|| JobError::failed("no `object` labels"))?;
                let truth = session.labels_of(set);
                let features = session_features(&session).map_err(JobError::failed)?;
                let (rows, cols) = crate::experiments::baselines::grid_for(form.k);
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
                let r =
                    run_baselines(features.view(), &truth, &params, p).map_err(|e| match e {
                        crate::experiments::baselines::BaselinesError::Cancelled(_) => {
                            JobError::Cancelled
                        }
                        other => JobError::failed(other),
                    })?;
                let result = Box::new(baselines_report(
                    &session.meta.name,
                    &r,
                    t0.elapsed().as_secs_f64(),
                ));
                // Each baseline fitted on every grasp leaves the session as a model file.
                let models = crate::models::table_one_files_of_run(&session, "object", &r)
                    .map_err(JobError::failed)?;
                Ok(JobOutput::Trained { result, models })
            }),
        })
    }
}
