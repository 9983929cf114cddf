//! Grasp stability (first paper): one dictionary size with β and γ, or a grid search with the
//! parsimonious choice; basis images, score against bases, usage differentials and confusion
//! maps as tiles.

use super::pane::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text, run_button};
use crate::app::View;
use crate::app::loader::LoadedSession;
use crate::app::results::Analyses;
use crate::app::results::JobOutput;
use crate::catalogue::{MethodId, Task};
use crate::experiments::figure_id::FigureId;
use crate::experiments::result::{AnalysisKind, SizeReason};
use crate::experiments::stability::report::stability_report;
use crate::experiments::stability::{
    Config, DataOptions, GridSpec, PipelineInputs, StabilityData, StabilityOptions,
};
use crate::features::FeatureSet;
use crate::jobs::JobError;
use crate::models::stability::StabilityFit;
use crate::session::Session;
use crate::sweep::{Experiment, StabilitySweep};
use std::sync::Arc;

/// Grasp-stability form: one configuration, or a grid search with the parsimony rule.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct StabilityForm {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
    pub grid: bool,
    /// Grid over num_bases: from, to, step.
    pub bases: [usize; 3],
    /// The single configuration's size is the user's; otherwise it is automatic (the
    /// session's sparse-coding frontier recommendation, else the paper's).
    pub user_size: bool,
    /// What the SVM reads (forms saved before the choice existed read codes).
    #[serde(default)]
    pub inputs: PipelineInputs,
}

impl Default for StabilityForm {
    fn default() -> Self {
        StabilityForm {
            num_bases: 29,
            beta: 1.0,
            gamma: 1.0,
            grid: false,
            bases: [5, 60, 5],
            user_size: false,
            inputs: PipelineInputs::Codes,
        }
    }
}

/// Seconds one configuration takes per grasp squared at 29 bases, on 2 cores (its SVMs'
/// training grows about with the square of the grasps): alone, with both cross
/// validations; in a grid, where a dictionary serves every γ and only 10-fold runs. The
/// dictionary's cost grows about linearly with the number of bases. Geometric means of the
/// grasp-stability sample (540 grasps) and BTS3 (1,276), `benches/estimates.rs`.
const SECONDS_PER_GRASP2_CONFIG: f64 = 1.9e-7;
const SECONDS_PER_GRASP2_GRID_CELL: f64 = 3.1e-8;

/// The kind of run whose measured times correct the model above.
const TIMING: &str = "stability";

impl StabilityForm {
    /// The single configuration the form runs with on `session` and why: the user's, else
    /// the recommendation of the session's sparse-coding frontier, else the paper's.
    /// A size equal to the recommended or the paper's is called so, whoever set it.
    pub fn size(&self, analyses: &Analyses, session: &str) -> (Config, SizeReason) {
        let paper = StabilityOptions::default().single;
        let recommended = analyses
            .frontier(session, MethodId::SparseSvm, FeatureSet::ALL)
            .and_then(|f| {
                let p = &f.points[f.recommended];
                Some(Config {
                    num_bases: p.knob("num_bases")? as usize,
                    beta: p.knob("beta")?,
                    gamma: p.knob("gamma")?,
                })
            });
        let size = match (self.user_size, recommended) {
            (true, _) => Config {
                num_bases: self.num_bases,
                beta: self.beta,
                gamma: self.gamma,
            },
            (false, Some(r)) => r,
            (false, None) => paper,
        };
        (size, SizeReason::of(&size, recommended.as_ref(), &paper))
    }

    /// The options the form runs with on `session`.
    pub fn options(&self, analyses: &Analyses, session: &str) -> StabilityOptions {
        let (single, reason) = self.size(analyses, session);
        let mut opts = StabilityOptions {
            single,
            grid: self.grid_spec(),
            size_reason: Some(reason).filter(|_| !self.grid),
            ..Default::default()
        };
        opts.settings.inputs = self.inputs;
        opts
    }

    fn grid_spec(&self) -> Option<GridSpec> {
        let [from, to, step] = self.bases;
        self.grid.then(|| GridSpec {
            num_bases: (from..=to.max(from)).step_by(step.max(1)).collect(),
            beta: vec![0.5, 1.0, 2.0],
            gamma: vec![0.5, 1.0, 2.0],
        })
    }

    /// What a run on a session of `grasps` grasps is expected to cost.
    pub fn estimate(&self, grasps: usize) -> Estimate {
        Estimate {
            timing: TIMING.into(),
            modelled: self.expected_seconds(grasps),
        }
    }

    fn expected_seconds(&self, grasps: usize) -> f64 {
        let g2 = (grasps * grasps) as f64;
        let bases = |k: usize| (k as f64 / 29.0).max(0.2);
        match self.grid_spec() {
            Some(g) => {
                SECONDS_PER_GRASP2_GRID_CELL
                    * g2
                    * g.num_bases.iter().map(|&k| bases(k)).sum::<f64>()
                    * 9.0
            }
            None => SECONDS_PER_GRASP2_CONFIG * g2 * bases(self.num_bases),
        }
    }
}

/// The pipeline predicts a two-class outcome (success / failure).
fn ready(s: &Session) -> bool {
    s.label_sets.iter().any(|l| l.classes.len() == 2)
}

#[derive(Default)]
pub struct StabilityRoom {
    pub form: StabilityForm,
}

impl Room for StabilityRoom {
    fn view(&self) -> View {
        View::Stability
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        let f = Pane::Figure;
        vec![
            vec![
                f(FigureId::BasesRaw),
                f(FigureId::BasesFiltered),
                f(FigureId::Reconstruction),
            ],
            vec![
                f(FigureId::ScoreVsBases),
                f(FigureId::BetaGamma),
                f(FigureId::CoefficientDifferential),
                Pane::Scores,
            ],
            vec![
                f(FigureId::UsageDifferential),
                Pane::Grasp,
                Pane::Detail(FigureId::BasesRaw),
                f(FigureId::BasisUsage),
            ],
            vec![
                f(FigureId::ConfusionKfold),
                f(FigureId::ConfusionObjects),
                Pane::Replay,
            ],
        ]
    }

    fn run_text(&self, s: &LoadedSession, analyses: &Analyses) -> Option<String> {
        if !ready(&s.session) {
            return None;
        }
        let f = &self.form;
        let what = match f.grid_spec() {
            Some(g) => format!(
                "a grid search over {} dictionary sizes × β × γ ({} cells) with the parsimonious choice",
                g.num_bases.len(),
                g.num_bases.len() * 9
            ),
            None => {
                let (c, reason) = f.size(analyses, &s.session.meta.name);
                format!(
                    "{} bases, β = {}, γ = {} ({}), with 10-fold and leave-objects-out validation",
                    c.num_bases,
                    c.beta,
                    c.gamma,
                    reason.text()
                )
            }
        };
        Some(format!(
            "Run: sparse coding + linear SVM on {} grasps, {what}; {}.",
            s.session.grasps.len(),
            estimate_text(&f.estimate(s.session.grasps.len()), analyses)
        ))
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Grasp stability");
        ui.label("Sparse coding of tactile images and a linear SVM");
        let f = &mut self.form;
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
        } else if let Some(s) = cx.session() {
            let (c, reason) = f.size(cx.analyses, &s.session.meta.name);
            (f.num_bases, f.beta, f.gamma) = (c.num_bases, c.beta, c.gamma);
            ui.label(format!("Model size ({}):", reason.text()));
            let changed = [
                ui.add(
                    egui::DragValue::new(&mut f.num_bases)
                        .range(1..=200)
                        .prefix("num_bases "),
                ),
                ui.add(
                    egui::DragValue::new(&mut f.beta)
                        .range(1e-4..=1e4)
                        .speed(0.05)
                        .prefix("β "),
                ),
                ui.add(
                    egui::DragValue::new(&mut f.gamma)
                        .range(1e-4..=1e4)
                        .speed(0.05)
                        .prefix("γ "),
                ),
            ]
            .iter()
            .any(|r| r.changed());
            if changed {
                f.user_size = true;
            }
            if f.user_size
                && ui
                    .small_button("Automatic size")
                    .on_hover_text(
                        "The session's sparse-coding frontier recommendation (Speed vs \
                         accuracy view), else the paper's 29 bases with β = γ = 1",
                    )
                    .clicked()
            {
                f.user_size = false;
            }
        }
        let mut values = f.inputs == PipelineInputs::CodesAndRaw;
        if ui
            .checkbox(&mut values, "SVM reads the values beside the codes")
            .on_hover_text(
                "codes+raw: each grasp's codes followed by its scaled key-frame values. \
                 On the BioTac sets it scores higher within the training sessions and on new \
                 objects recorded later (docs/held-out.md); the paper reads codes only.",
            )
            .changed()
        {
            f.inputs = match values {
                true => PipelineInputs::CodesAndRaw,
                false => PipelineInputs::Codes,
            };
        }
        ui.small("Pressures are z-scored per taxel over the session; β and γ use the 0.5·|x − Da|² + λ·|a|₁ convention.");
        if run_button(
            ui,
            cx,
            AnalysisKind::Stability,
            ready,
            "(needs a session with a two-class outcome label, e.g. success / failure)",
        ) {
            self.start(cx);
        }
        super::models::section(ui, cx, |m| m.task() == Task::Stability);
    }

    fn sweep(&self, cx: &Cx) -> Option<Result<Experiment, String>> {
        let s = cx.session()?;
        Some(if !ready(&s.session) {
            Err("This session has no two-class outcome.".into())
        } else if !self.form.grid {
            Err("A cluster shards a grid search: tick Grid search.".into())
        } else {
            Ok(Experiment::Stability(StabilitySweep {
                data: DataOptions::default(),
                options: self.form.options(cx.analyses, &s.session.meta.name),
            }))
        })
    }

    fn run(&self, session: &Arc<Session>, analyses: &Analyses) -> Option<Run> {
        if !ready(session) {
            return None;
        }
        let options = self.form.options(analyses, &session.meta.name);
        let session = session.clone();
        Some(Run {
            kind: Some(AnalysisKind::Stability),
            title: format!("Grasp stability on {}", session.meta.name),
            estimate: self.form.estimate(session.grasps.len()),
            work: Box::new(move |p| {
                let data = StabilityData::from_session(&session, &DataOptions::default())
                    .map_err(JobError::failed)?;
                let r =
                    crate::experiments::stability::run(&data, &options, p).map_err(|e| match e
                        .is_cancelled()
                    {
                        true => JobError::Cancelled,
                        false => JobError::failed(e),
                    })?;
                // The recommended model leaves the session as a model file (Models list).
                let model = StabilityFit::from_report(&session, &data, &options, &r)
                    .into_file(&session, &data);
                Ok(JobOutput::Trained {
                    result: Box::new(stability_report(&r)),
                    models: vec![model],
                })
            }),
        })
    }
}
