//! Applying the commands the views push while drawing, between frames.

use super::files::Purpose;
use super::selection::{Command, ModelSpec};
use super::{View, WorkbenchApp};
use crate::experiments::result::AnalysisKind;

impl WorkbenchApp {
    /// Apply the commands the views pushed while drawing.
    pub fn apply_commands(&mut self, ctx: &egui::Context) {
        for c in std::mem::take(&mut self.commands) {
            match c {
                Command::SelectGrasps {
                    session,
                    grasps,
                    origin,
                    result,
                } => {
                    if let Some(&first) = grasps.first() {
                        self.select(session, first);
                    }
                    self.selection.session = Some(session);
                    self.selection.grasps = grasps;
                    self.selection.origin = origin;
                    self.selection.result = result;
                    self.browser.active = session;
                }
                Command::Focus { session, grasp } => self.select(session, grasp),
                Command::FocusBasis { result, basis } => {
                    self.selection.basis = Some((result, basis))
                }
                Command::Strength {
                    result,
                    figure,
                    strength,
                } => self.selection.strength = Some((result, figure, strength)),
                Command::ClearSelection => {
                    self.selection.clear_set();
                    self.browser.only_selection = false;
                }
                Command::OpenResult(i) => {
                    if let Some(kind) = self.analyses.results.get(i).map(|r| r.kind) {
                        self.analyses.shown.insert(kind, i);
                        if let Some(view) = View::showing(kind) {
                            self.view = view;
                        }
                        self.focus_results(kind);
                    }
                }
                Command::Open(v) => self.view = v,
                Command::TrainModel(spec) => self.train_model(spec, ctx),
                Command::SaveModel(i) => self.open_picker(Purpose::SaveModel(i)),
                Command::LoadModel => self.open_picker(Purpose::LoadModel),
                Command::SaveSelection => self.open_picker(Purpose::SaveSelection),
                Command::CompareSignal(signal) => self.rooms.compare.form.signal = signal,
            }
        }
    }

    /// Open the active session's result of the model `spec`, or set the form of its view to
    /// that size and train it there.
    fn train_model(&mut self, spec: ModelSpec, ctx: &egui::Context) {
        let Some(session) = self.sessions.get(self.browser.active) else {
            return;
        };
        let name = session.session.meta.name.clone();
        let (kind, view) = match &spec {
            ModelSpec::Recognition { .. } => (AnalysisKind::Recognition, View::Recognition),
            ModelSpec::Stability(_) => (AnalysisKind::Stability, View::Stability),
            ModelSpec::Clustering { .. } => (AnalysisKind::Clustering, View::Clustering),
            ModelSpec::Baselines { .. } => (AnalysisKind::Baselines, View::Baselines),
        };
        let same = |r: &crate::experiments::result::AnalysisResult| {
            let of = |key: &str| r.parameters.get(key).map(String::as_str);
            let sized = || r.model_size.as_ref().map(|m| m.knobs.as_str()) == Some(&spec.knobs());
            r.kind == kind
                && r.session == name
                && r.held_out.is_none()
                && r.methods.contains(&spec.method())
                && match &spec {
                    ModelSpec::Recognition { features, .. } => {
                        sized()
                            && of("features")
                                == Some(&crate::experiments::result::features_text(*features))
                    }
                    ModelSpec::Stability(_) => sized(),
                    ModelSpec::Clustering { threshold, .. } => {
                        r.details.iter().any(|d| d.at(*threshold).is_some())
                    }
                    ModelSpec::Baselines { k: Some(k) } => of("k") == Some(&k.to_string()),
                    ModelSpec::Baselines { k: None } => true,
                }
        };
        if let Some(i) = self.analyses.results.iter().rposition(same) {
            if let ModelSpec::Clustering { threshold, .. } = spec {
                // The clustering charts' markers go to the threshold clicked.
                for d in &self.analyses.results[i].details {
                    if let Some(k) = d.at(threshold) {
                        self.analyses.selected.insert((i, d.figure), k);
                    }
                }
            }
            self.commands.push(Command::OpenResult(i));
            return;
        }
        match spec {
            ModelSpec::Recognition {
                learner,
                features,
                capacity,
                tau,
            } => {
                let f = &mut self.rooms.recognition.form;
                (f.learner, f.features) = (learner, features);
                (f.capacity, f.tau, f.user_size) = (capacity, tau, true);
            }
            ModelSpec::Stability(c) => {
                let f = &mut self.rooms.stability.form;
                f.grid = false;
                (f.num_bases, f.beta, f.gamma) = (c.num_bases, c.beta, c.gamma);
                f.user_size = true;
            }
            ModelSpec::Clustering { learner, threshold } => {
                let f = &mut self.rooms.clustering.form;
                f.learner = learner;
                f.thresholds = [threshold, threshold, f.thresholds[2]];
            }
            ModelSpec::Baselines { k } => {
                let f = &mut self.rooms.baselines.form;
                match k {
                    Some(k) => f.k = k,
                    None => f.with_svm = true,
                }
            }
        }
        self.view = view;
        let (room, mut cx, _, _) = self.parts(ctx, view);
        if !cx.analyses.is_running(kind) {
            room.start(&mut cx);
        }
    }
}
