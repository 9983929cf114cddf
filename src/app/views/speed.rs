//! Speed against accuracy: every trained model's training time, or its prediction time per
//! step or sample (log axis), against its headline score, with the Pareto front; and the
//! active session's frontiers by model size, computed from the form, with the recommended
//! size marked. Clicking a trained model opens its view; clicking a size on a frontier opens
//! that model's result, or trains it.

use super::tiles::Pane;
use super::{Cx, Estimate, Room, Run, estimate_text};
use crate::app::View;
use crate::app::figure_view::{self, Selection as FigureSelection};
use crate::app::results::Analyses;
use crate::app::results::{FRONTIER_JOB, JobOutput, experiment_error, recognition_ready};
use crate::app::selection::{Command, ModelSpec};
use crate::catalogue::{MethodId, Task};
use crate::experiments::frontier::report::frontier_figures;
use crate::experiments::frontier::{
    CostAxis, Frontier, FrontierItem, FrontierParams, SweepKnob, frontier_items,
    item_cost as frontier_item_cost, size_knobs,
};
use crate::experiments::result::{self, TimeAxis, date_text};
use crate::features::FeatureSet;
use crate::figures::{self, Rgb, Series, SeriesStyle};
use crate::session::Session;
use std::sync::Arc;

/// What the frontier form sweeps: a method, its knobs' values as typed, and repetitions.
#[derive(Clone, Debug)]
pub struct FrontierForm {
    pub method: MethodId,
    pub features: FeatureSet,
    /// Fewer than the CLI's 10, so the view answers in minutes.
    pub reps: usize,
    /// Each method's values of each size knob, as typed (by method key and knob name); a
    /// knob not typed in sweeps its method's default values.
    pub knobs: std::collections::BTreeMap<(&'static str, &'static str), String>,
}

fn list_text(v: &[f64]) -> String {
    v.iter().map(f64::to_string).collect::<Vec<_>>().join(", ")
}

impl Default for FrontierForm {
    fn default() -> Self {
        FrontierForm {
            method: MethodId::Ds,
            features: FeatureSet::ALL,
            reps: 3,
            knobs: Default::default(),
        }
    }
}

/// "2, 5, 10" as numbers (counts for a whole knob); the error names the knob.
fn parse_list(text: &str, knob: &SweepKnob) -> Result<Vec<f64>, String> {
    let number = |t: &str| {
        if knob.whole {
            t.parse::<usize>().map(|v| v as f64).ok()
        } else {
            t.parse::<f64>().ok()
        }
    };
    let field = knob.name;
    let v: Option<Vec<f64>> = text
        .split([',', ' '])
        .filter(|t| !t.is_empty())
        .map(number)
        .collect();
    match v {
        Some(v) if !v.is_empty() => Ok(v),
        Some(_) => Err(format!("{field}: give at least one value")),
        None => Err(format!("{field}: `{text}` is not a list of numbers")),
    }
}

impl FrontierForm {
    /// The frontier's parameters, or what is wrong with the form.
    pub fn params(&self) -> Result<FrontierParams, String> {
        let mut p = FrontierParams::for_method(self.method);
        p.reps = self.reps;
        if self.method.uses_features() {
            p.features = self.features;
        }
        let lists = (size_knobs(self.method).iter())
            .map(|k| match self.knobs.get(&(self.method.key(), k.name)) {
                Some(typed) => parse_list(typed, k),
                None => Ok(k.values.clone()),
            })
            .collect::<Result<Vec<_>, _>>()?;
        p.set_size_knobs(&lists).map_err(|e| e.to_string())?;
        p.validate().map_err(|e| e.to_string())?;
        Ok(p)
    }

    fn ready(&self, s: &Session) -> bool {
        match self.method.task() {
            Task::Stability => s.label_sets.iter().any(|l| l.classes.len() == 2),
            Task::Recognition | Task::Clustering => recognition_ready(s),
        }
    }

    /// What the frontier on `session` is expected to cost; None when the form or the
    /// session cannot run it.
    pub fn estimate(&self, session: &Session) -> Option<Estimate> {
        if !self.ready(session) {
            return None;
        }
        let p = self.params().ok()?;
        // The session's size once, not per item (this runs every frame the form shows).
        let (grasps, steps) = (session.grasps.len() as f64, session.total_frames() as f64);
        let modelled = frontier_items(&p)
            .iter()
            .map(|item| item_seconds(item, &p, grasps, steps))
            .sum();
        Some(Estimate {
            timing: format!("frontier {}", p.method.key()),
            modelled,
        })
    }

    fn ui(&mut self, ui: &mut egui::Ui) {
        egui::ComboBox::from_label("Frontier method")
            .selected_text(self.method.title())
            .show_ui(ui, |ui| {
                for m in crate::experiments::frontier::methods() {
                    ui.selectable_value(&mut self.method, m, m.title());
                }
            });
        if self.method.uses_features() {
            egui::ComboBox::from_label("Frontier features")
                .selected_text(self.features.name())
                .show_ui(ui, |ui| {
                    for f in FeatureSet::OFFERED {
                        ui.selectable_value(&mut self.features, f, f.name());
                    }
                });
        }
        for k in size_knobs(self.method) {
            let text = self
                .knobs
                .entry((self.method.key(), k.name))
                .or_insert_with(|| list_text(&k.values));
            text_field(ui, &k.label, text);
        }
        ui.add(
            egui::DragValue::new(&mut self.reps)
                .range(2..=50)
                .prefix("frontier repetitions "),
        );
    }
}

/// Seconds one item of a frontier takes on a session of `grasps` grasps and `steps` frames
/// on 2 cores (`benches/estimates.rs` measured the constants; see docs/estimates.md).
fn item_seconds(item: &FrontierItem, p: &FrontierParams, grasps: f64, steps: f64) -> f64 {
    let relative = frontier_item_cost(item);
    match *item {
        // A repetition of the supervised protocol at the paper's capacity (cost 100) takes
        // about a repetition of Recognition.
        FrontierItem::Recognition { .. } => FRONTIER_STEP * steps * relative / 100.0,
        // A dictionary is coded and cross-validated at every γ and repetition; its SVMs
        // grow about with the square of the grasps.
        FrontierItem::Dictionary { .. } => {
            FRONTIER_GRASP2_BASIS * grasps * grasps * relative * (p.gamma.len() * p.reps) as f64
        }
        FrontierItem::Threshold { .. } | FrontierItem::Classifier { .. } => FRONTIER_STEP * steps,
        FrontierItem::Clusters { .. } | FrontierItem::Svm { .. } => {
            FRONTIER_GRASP2_BASIS * grasps * grasps * relative
        }
    }
}

/// DS's frontier on the recognition sample and iCub; sparse coding's on the
/// grasp-stability sample and BTS3 (geometric means, `benches/estimates.rs`). The other
/// methods' items are modelled on these.
const FRONTIER_STEP: f64 = 0.000081;
const FRONTIER_GRASP2_BASIS: f64 = 6.6e-10;

/// A labelled one-line field.
fn text_field(ui: &mut egui::Ui, label: &str, text: &mut String) {
    let label = ui.label(label);
    ui.text_edit_singleline(text).labelled_by(label.id);
}

#[derive(Default)]
pub struct SpeedRoom {
    /// The time on the charts' x axis.
    pub time_axis: TimeAxis,
    pub frontier: FrontierForm,
    /// The score and session the chart of every trained model shows (None: the active
    /// session's first).
    pub kind: Option<result::ScoreKind>,
}

impl Room for SpeedRoom {
    fn view(&self) -> View {
        View::SpeedAccuracy
    }

    fn default_groups(&self) -> Vec<Vec<Pane>> {
        vec![vec![Pane::Frontier], vec![Pane::SpeedChart, Pane::Models]]
    }

    fn form_ui(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        ui.heading("Speed against accuracy");
        ui.label("Time axis:");
        ui.selectable_value(&mut self.time_axis, TimeAxis::Training, "training time");
        ui.selectable_value(
            &mut self.time_axis,
            TimeAxis::Prediction,
            "prediction time per step or sample",
        );
        ui.separator();
        ui.strong("Frontier by model size");
        ui.label(
            "Sweep a method's size on the active session; the cheapest size within one \
             standard error of the best becomes the size its view trains by default.",
        );
        self.frontier.ui(ui);
        let Some(s) = cx.session() else { return };
        let problem = if !self.frontier.ready(&s.session) {
            Some(match self.frontier.method.task() {
                Task::Stability => "(needs a session with a two-class outcome)".into(),
                Task::Recognition | Task::Clustering => {
                    "(needs an object-recognition session: encoders and `object` labels)".into()
                }
            })
        } else {
            self.frontier.params().err()
        };
        if let Some(p) = &problem {
            ui.label(egui::RichText::new(p).color(ui.visuals().warn_fg_color));
        }
        let running = cx.analyses.frontier_running();
        if let Some(e) = self.frontier.estimate(&s.session) {
            ui.label(format!(
                "Expected to take {}.",
                estimate_text(&e, cx.analyses)
            ));
        }
        if ui
            .add_enabled(
                problem.is_none() && !running,
                egui::Button::new("Compute frontier"),
            )
            .clicked()
        {
            self.start(cx);
        }
    }

    /// The frontier the form sweeps.
    fn run(&self, session: &Arc<Session>, _analyses: &Analyses) -> Option<Run> {
        let params = self.frontier.params().ok()?;
        let estimate = self.frontier.estimate(session)?;
        let session = session.clone();
        Some(Run {
            kind: None,
            title: format!(
                "{FRONTIER_JOB}{} on {}",
                params.method.title(),
                session.meta.name
            ),
            estimate,
            work: Box::new(move |p| {
                let f = crate::experiments::frontier::run_frontier(&session, &params, p)
                    .map_err(experiment_error)?;
                Ok(JobOutput::Frontier(Box::new(f)))
            }),
        })
    }

    fn pane_ui(&mut self, ui: &mut egui::Ui, pane: &Pane, cx: &mut Cx) -> bool {
        match pane {
            Pane::SpeedChart => self.chart(ui, cx),
            Pane::Models => models(ui, cx),
            Pane::Frontier => self.frontier_pane(ui, cx),
            _ => return false,
        }
        true
    }
}

/// What a point of the frontier chart stands for.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Charted {
    /// Frontier `f`, size `k`.
    Size(usize, usize),
    /// A trained model: index into the results.
    Model(usize),
}

/// Each marker series of the frontier chart, in `frontier_figures`' order: every frontier's
/// sizes, then the recommended sizes (one per frontier), the paper defaults that are not
/// recommended, and the trained models added here.
fn charted(chart: &figures::Chart, frontiers: &[Frontier], models: &[usize]) -> Vec<Vec<Charted>> {
    let paper: Vec<usize> = (0..frontiers.len())
        .filter(|&i| {
            let f = &frontiers[i];
            f.paper_default.is_some_and(|d| d != f.recommended)
        })
        .collect();
    chart
        .series
        .iter()
        .map(|s| {
            if let Some(i) = frontiers.iter().position(|f| f.short_label() == s.name) {
                (0..frontiers[i].points.len())
                    .map(|k| Charted::Size(i, k))
                    .collect()
            } else if s.name == "recommended" {
                (0..frontiers.len())
                    .map(|i| Charted::Size(i, frontiers[i].recommended))
                    .collect()
            } else if s.name == "paper default" {
                paper
                    .iter()
                    .filter_map(|&i| Some(Charted::Size(i, frontiers[i].paper_default?)))
                    .collect()
            } else if s.name == TRAINED {
                models.iter().map(|&r| Charted::Model(r)).collect()
            } else {
                Vec::new()
            }
        })
        .collect()
}

const TRAINED: &str = "trained models";

impl SpeedRoom {
    fn chart(&mut self, ui: &mut egui::Ui, cx: &mut Cx) {
        let axis = self.time_axis;
        let results = &cx.analyses.results;
        let kinds = result::score_kinds(results, axis);
        let active = cx.session().map(|s| s.session.meta.name.clone());
        let shown = (self.kind.clone())
            .filter(|k| kinds.contains(k))
            .or_else(|| {
                kinds
                    .iter()
                    .find(|k| Some(&k.session) == active.as_ref())
                    .cloned()
            })
            .or_else(|| kinds.first().cloned());
        let Some(mut kind) = shown else {
            if axis == TimeAxis::Prediction && !results.is_empty() {
                ui.label("None of the results times its predictions (the OIESGP learners do).");
            } else {
                ui.label("Train a model in any analysis view: every result appears here.");
            }
            return;
        };
        // One score of one session a chart: accuracies and success rates are not one axis.
        ui.horizontal(|ui| {
            let caption = ui.label("Score");
            // Cut to the tile's width, so that a long name never widens the chart.
            let width = (ui.available_width() - 30.0).max(80.0);
            egui::ComboBox::from_id_salt("speed-kind")
                .width(width)
                .truncate()
                .selected_text(kind.text())
                .show_ui(ui, |ui| {
                    for k in &kinds {
                        ui.selectable_value(&mut kind, k.clone(), k.text());
                    }
                })
                .response
                .labelled_by(caption.id);
        });
        self.kind = Some(kind.clone());
        let Some(chart) = result::speed_accuracy_of(results, axis, &kind) else {
            return;
        };
        let file = match axis {
            TimeAxis::Training => "speed-against-accuracy",
            TimeAxis::Prediction => "prediction-speed-against-accuracy",
        };
        if ui
            .small_button("Export")
            .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
            .clicked()
        {
            let file = format!(
                "{file}-{}-{}",
                result::slug(&kind.session),
                result::slug(&kind.score)
            );
            cx.analyses.export_figure(&chart.figure, &file);
        }
        let height = (ui.available_height() - 40.0).max(160.0);
        let act = figure_view::show(
            ui,
            "speed-accuracy",
            &chart.figure,
            height,
            FigureSelection::None,
        );
        // Clicking a model's point opens its view, like its button.
        if let Some((series, k)) = act.clicked_point
            && let Some(&i) = chart.sources.get(series).and_then(|s| s.get(k))
        {
            cx.commands.push(Command::OpenResult(i));
        }
    }

    /// The active session's frontiers on the chosen time axis, with the session's trained
    /// models of the same methods (on the prediction axis, where their times are per step
    /// or grasp like the frontier's); hovering a size gives its details, clicking it opens
    /// or trains it.
    fn frontier_pane(&self, ui: &mut egui::Ui, cx: &mut Cx) {
        let Some(s) = cx.session() else { return };
        let name = s.session.meta.name.clone();
        let frontiers: Vec<Frontier> = cx
            .analyses
            .frontiers
            .iter()
            .filter(|f| f.session == name)
            .cloned()
            .collect();
        if frontiers.is_empty() {
            ui.label(format!(
                "No frontier for «{name}» yet: choose a method in the form and Compute \
                 frontier to chart its score against its time by model size."
            ));
            return;
        }
        let (cost, file) = match self.time_axis {
            TimeAxis::Training => (CostAxis::Training, "frontier-training"),
            TimeAxis::Prediction => (CostAxis::Prediction, "frontier-prediction"),
        };
        let Some((_, mut fig)) = frontier_figures(&frontiers)
            .into_iter()
            .find(|(n, _)| n == file)
        else {
            return;
        };
        let mut models = Vec::new();
        if cost == CostAxis::Prediction
            && let figures::FigureKind::Chart(c) = &mut fig.kind
        {
            let (mut x, mut y, mut labels) = (Vec::new(), Vec::new(), Vec::new());
            for (i, r) in cx.analyses.results.iter().enumerate() {
                if r.session != name || r.model_size.is_none() {
                    continue;
                }
                if let (Some(t), Some((_, score))) = (r.predict_seconds_per_sample, &r.headline) {
                    models.push(i);
                    x.push(t * 1e6);
                    y.push(*score);
                    labels.push(String::new());
                }
            }
            if !models.is_empty() {
                c.series.push(
                    Series::new(TRAINED, x, y)
                        .style(SeriesStyle::Markers)
                        .labels(labels)
                        .color(Rgb(0xd0, 0x30, 0x30)),
                );
            }
        }
        if ui
            .small_button("Export")
            .on_hover_text("SVG, PDF, PNG and CSV into the export folder")
            .clicked()
        {
            let export = format!("{file}-{}", result::slug(&name));
            cx.analyses.export_figure(&fig, &export);
        }
        let height = (ui.available_height() - 110.0).max(160.0);
        let act = figure_view::show(ui, "frontier", &fig, height, FigureSelection::None);
        let figures::FigureKind::Chart(chart) = &fig.kind else {
            return;
        };
        let map = charted(chart, &frontiers, &models);
        let at = |hit: Option<(usize, usize)>| hit.and_then(|(s, k)| map.get(s)?.get(k).copied());
        match at(act.hovered_point) {
            Some(Charted::Size(i, k)) => {
                let f = &frontiers[i];
                let p = &f.points[k];
                let click = match ModelSpec::of_point(&f.params, &f.points[k]) {
                    Some(ModelSpec::Baselines { k: None }) => {
                        "click to open or run the Baselines, whose SVM searches this grid"
                    }
                    Some(_) => "click to open or train",
                    None => "",
                };
                ui.label(format!(
                    "{}: {} · {} {:.3} ± {:.3} · training {:.1} µs, prediction {:.1} µs per {} · {click}",
                    f.short_label(),
                    p.detail,
                    f.score_name,
                    p.score,
                    p.score_se,
                    p.train_us,
                    p.predict_us,
                    f.unit
                ));
            }
            Some(Charted::Model(r)) => {
                let r = &cx.analyses.results[r];
                let size = r.model_size.as_ref().map(|m| m.text()).unwrap_or_default();
                ui.label(format!(
                    "{} · {size} · {} · click to open",
                    r.label,
                    date_text(r.created)
                ));
            }
            None => {
                for f in &frontiers {
                    let p = &f.points[f.recommended];
                    ui.label(format!(
                        "Recommended {} ({:.3} ± {:.3}, {:.1} µs per {} to predict)",
                        p.detail, p.score, p.score_se, p.predict_us, f.unit
                    ));
                }
            }
        }
        match at(act.clicked_point) {
            Some(Charted::Size(i, k)) => {
                if let Some(spec) =
                    ModelSpec::of_point(&frontiers[i].params, &frontiers[i].points[k])
                {
                    cx.commands.push(Command::TrainModel(spec));
                }
            }
            Some(Charted::Model(r)) => cx.commands.push(Command::OpenResult(r)),
            None => {}
        }
    }
}

/// Every result with a headline score, as a button that opens its view.
fn models(ui: &mut egui::Ui, cx: &mut Cx) {
    ui.label("Open a model's views:");
    egui::ScrollArea::vertical().show(ui, |ui| {
        for (i, r) in cx.analyses.results.iter().enumerate() {
            if r.headline.is_some() {
                let size = r
                    .model_size
                    .as_ref()
                    .map(|m| format!(" · {}", m.text()))
                    .unwrap_or_default();
                if ui
                    .button(format!("{} · {}{size}", r.label, r.session))
                    .on_hover_text(date_text(r.created))
                    .clicked()
                {
                    cx.commands.push(Command::OpenResult(i));
                }
            }
        }
    });
}
