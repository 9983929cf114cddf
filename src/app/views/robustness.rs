//! "Where methods fail": sweep one perturbation at a time on the open session and chart each
//! method's score against its strength, with the break points marked. The family follows the
//! session: grasp stability for a session with a two-class outcome, object recognition for one
//! with objects and encoders.

use crate::app::results::Analyses;
use crate::catalogue::MethodId;
use egui::RichText;

use super::pane::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text};
use crate::app::View;
use crate::app::loader::LoadedSession;
use crate::app::results::{JobOutput, experiment_error, recognition_ready};
use crate::experiments::result::AnalysisKind;
use crate::experiments::robustness::report::robustness_report;
use crate::experiments::robustness::{
    Family, Perturbation, RobustnessParams, Sweep, run_robustness,
};
use crate::session::Session;
use crate::sweep::Experiment;
use std::sync::Arc;

/// The form: which methods and perturbations, with few repetitions by default so the view
/// answers in minutes; the CLI runs the full sweeps.
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct RobustnessForm {
    pub methods: Vec<MethodId>,
    pub perturbations: Vec<Perturbation>,
    pub reps: usize,
    /// The break point is where the score falls below this share of the clean score.
    pub fraction: f64,
    pub seed: u64,
}

impl Default for RobustnessForm {
    fn default() -> Self {
        RobustnessForm {
            // The catalogue's defaults (DU and GU on request: each of their clusters is a
            // GP to score every step against).
            methods: MethodId::all()
                .filter(|m| m.info().robustness_default)
                .collect(),
            perturbations: vec![
                Perturbation::Noise,
                Perturbation::DeadTaxels,
                Perturbation::Gain,
            ],
            reps: 2,
            fraction: 0.9,
            seed: 0,
        }
    }
}

impl RobustnessForm {
    /// The experiment's parameters for `family`: the chosen methods and perturbations of that
    /// family, each perturbation at its default strengths.
    pub fn params(&self, family: Family) -> RobustnessParams {
        RobustnessParams {
            methods: methods_of(family)
                .filter(|m| self.methods.contains(m))
                .collect(),
            sweeps: self
                .perturbations
                .iter()
                .filter(|p| applies(**p, family))
                .map(|&p| Sweep {
                    perturbation: p,
                    strengths: p.default_strengths(family),
                })
                .collect(),
            reps: self.reps,
            fraction: self.fraction,
            seed: self.seed,
            ..RobustnessParams::defaults(family)
        }
    }
}

/// Every method of `family`, in the experiment's order.
fn methods_of(family: Family) -> impl Iterator<Item = MethodId> {
    MethodId::all().filter(move |m| Family::of(*m) == family)
}

/// Never-seen objects are a perturbation of the grasp-stability protocol only: in object
/// recognition each object is its own class.
fn applies(p: Perturbation, family: Family) -> bool {
    family == Family::Stability || p != Perturbation::NewObjects
}

/// The family a session supports, if any.
fn family_of(s: &Session) -> Option<Family> {
    if recognition_ready(s) {
        Some(Family::Recognition)
    } else if s
        .label_sets
        .iter()
        .any(|l| l.classes.len() == 2 && l.name == "outcome")
    {
        Some(Family::Stability)
    } else {
        None
    }
}

/// Seconds per method, perturbation strength and repetition on 2 cores: per grasp squared
/// for the stability family (its SVMs' training grows about so: 3.9 s on the 540-grasp
/// sample, 13.7 s on BTS3's 1,276), per grasp for the recognition family's online learners
/// (the geometric means of the sample sessions and BTS3 or iCub, `benches/estimates.rs`).
fn seconds_per_cell(family: Family, grasps: usize) -> f64 {
    let g = grasps as f64;
    match family {
        Family::Stability => 1.21e-7 * g * g,
        Family::Recognition => 0.000287 * g,
    }
}

impl RobustnessForm {
    /// What a run of `family` on `session` is expected to cost (the families are timed
    /// apart: their methods cost differently).
    pub fn estimate(&self, family: Family, session: &Session) -> Estimate {
        let p = self.params(family);
        let strengths: usize = p.sweeps.iter().map(|s| s.strengths.len() + 1).sum();
        Estimate {
            timing: format!("robustness {family:?}"),
            modelled: seconds_per_cell(family, session.grasps.len())
                * (p.methods.len() * strengths * p.reps) as f64,
        }
    }
}

#[derive(Default)]
pub struct RobustnessRoom {
    pub form: RobustnessForm,
}

impl Room for RobustnessRoom {
    fn view(&self) -> View {
        View::Robustness
    }

    /// One perturbation per figure: the first three in cells of their own, the rest and the
    /// numbers in tabs of the fourth.
    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![vec![Pane::Scores]]
    }

    fn run_text(&self, s: &LoadedSession, analyses: &Analyses) -> Option<String> {
        let family = family_of(&s.session)?;
        let p = self.form.params(family);
        p.validate().ok()?;
        Some(format!(
            "Run: {} method{} under {} perturbation{}, {} repetition{} on {} grasps; {}.",
            p.methods.len(),
            if p.methods.len() == 1 { "" } else { "s" },
            p.sweeps.len(),
            if p.sweeps.len() == 1 { "" } else { "s" },
            p.reps,
            if p.reps == 1 { "" } else { "s" },
            s.session.grasps.len(),
            estimate_text(&self.form.estimate(family, &s.session), analyses)
        ))
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Where methods fail");
        ui.label("Score against perturbation strength");
        let Some(s) = cx.session() else { return };
        let family = family_of(&s.session);
        let form = &mut self.form;
        ui.label("Methods:");
        for m in family.into_iter().flat_map(methods_of) {
            member_checkbox(ui, &mut form.methods, m, m.title());
        }
        ui.label("Perturbations:");
        for p in Perturbation::ALL {
            if family.is_some_and(|f| !applies(p, f)) {
                continue;
            }
            member_checkbox(ui, &mut form.perturbations, p, p.key());
        }
        ui.add(
            egui::DragValue::new(&mut form.reps)
                .range(1..=50)
                .prefix("repetitions "),
        );
        ui.add(
            egui::DragValue::new(&mut form.fraction)
                .range(0.05..=1.0)
                .speed(0.01)
                .prefix("break below ")
                .suffix(" × clean score"),
        );
        ui.add(egui::DragValue::new(&mut form.seed).prefix("seed "));
        let Some(family) = family else {
            ui.label(
                "This session has neither a two-class outcome (grasp stability) nor objects \
                 with encoders (object recognition).",
            );
            return;
        };
        let problem = self.form.params(family).validate().err();
        if let Some(e) = &problem {
            ui.label(RichText::new(e.to_string()).color(ui.visuals().warn_fg_color));
        }
        let running = cx.analyses.is_running(AnalysisKind::Robustness);
        if ui
            .add_enabled(!running && problem.is_none(), egui::Button::new("Run"))
            .clicked()
        {
            self.start(cx);
        }
    }

    fn sweep(&self, cx: &Cx) -> Option<Result<Experiment, String>> {
        let s = cx.session()?;
        let Some(family) = family_of(&s.session) else {
            return Some(Err(
                "This session has no family of methods to perturb.".into()
            ));
        };
        let params = self.form.params(family);
        Some(
            params
                .validate()
                .map(|()| Experiment::Robustness(params))
                .map_err(|e| e.to_string()),
        )
    }

    fn run(&self, session: &Arc<Session>, _analyses: &Analyses) -> Option<Run> {
        let family = family_of(session)?;
        let params = self.form.params(family);
        let session = session.clone();
        Some(Run {
            kind: Some(AnalysisKind::Robustness),
            title: format!("Robustness sweep on {}", session.meta.name),
            estimate: self.form.estimate(family, &session),
            work: Box::new(move |p| {
                let r = run_robustness(&session, &params, p).map_err(experiment_error)?;
                Ok(JobOutput::Result(Box::new(robustness_report(
                    &session.meta.name,
                    &r,
                ))))
            }),
        })
    }
}

/// A checkbox for whether `item` is in `list`; ticking it appends the item, unticking
/// removes it.
fn member_checkbox<T: PartialEq + Copy>(ui: &mut egui::Ui, list: &mut Vec<T>, item: T, text: &str) {
    let mut on = list.contains(&item);
    if ui.checkbox(&mut on, text).changed() {
        list.retain(|x| *x != item);
        if on {
            list.push(item);
        }
    }
}
