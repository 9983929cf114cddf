//! The supervised OIESGP experts (DS, GS) as models that leave their session: trained on
//! every grasp of a session in the protocol's order, saved with the experts' whole state,
//! applied to another session, and taught further on a new session (the second paper's
//! premise: objects are learned incrementally, over time; a class the model has not seen
//! gets a new expert).
//!
//! Sequences are min-max normalised per feature; the model keeps its training session's
//! range, and a new session is read on that range (`none`), on its own (`session`) or on
//! its first grasps' (`first:K`). Teaching a model further reads the new session on the
//! model's range, so that the experts keep one scale.

use std::time::Instant;

use ndarray::{Array2, s};
use serde::{Deserialize, Serialize};

use super::inputs::SequenceInputs;
use super::{Calibration, Model, ModelError, ModelFile, Provenance, SelectionScore, SessionRef};
use crate::catalogue::MethodId;
use crate::experiments::feature_choice::FeatureChoice;
use crate::experiments::labels::session_labels;
use crate::experiments::recognition::{
    RecognitionParams, RecognitionResult, SupervisedLearner, choose_auto_features, prefix_len,
    protocol_order,
};
use crate::experiments::result::SizeReason;
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::learners::{Ds, DsParams, Gs, GsParams, SequenceClassifier};
use crate::rng::Rng;
use crate::session::Session;

/// The experts of a supervised learner with their whole state.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(tag = "learner", content = "state", rename_all = "snake_case")]
pub enum Experts {
    Ds(Ds),
    Gs(Gs),
}

impl PartialEq for Experts {
    /// Equal when their saved states are: the learners hold caches that rebuild on load.
    fn eq(&self, other: &Self) -> bool {
        serde_json::to_string(self).ok() == serde_json::to_string(other).ok()
    }
}

impl Experts {
    fn learner(&mut self) -> &mut dyn SequenceClassifier {
        match self {
            Experts::Ds(l) => l,
            Experts::Gs(l) => l,
        }
    }

    fn view(&self) -> &dyn SequenceClassifier {
        match self {
            Experts::Ds(l) => l,
            Experts::Gs(l) => l,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SequenceModel {
    pub experts: Experts,
    #[serde(flatten)]
    pub inputs: SequenceInputs,
    pub label_set: String,
    /// The class of each expert.
    pub classes: Vec<String>,
    /// Seed of the training order.
    pub seed: u64,
    /// Grasps taught, over every session the model learned from.
    pub grasps_taught: usize,
}

/// How a supervised model is fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct SequenceFitOptions {
    pub method: MethodId,
    pub features: FeatureSet,
    pub label_set: String,
    pub seed: u64,
    pub ds: DsParams,
    pub gs: GsParams,
}

/// The classes of `session` under `label_set` and every grasp's class index.
pub(super) fn labels(
    session: &Session,
    label_set: &str,
) -> Result<(Vec<usize>, Vec<String>), ModelError> {
    session_labels(session, label_set).map_err(ModelError::Labels)
}

/// Teach `model` every grasp of `session` in the protocol's order (one grasp per class
/// first, then stratified random rounds), reading it on the model's range. A class the
/// model has not seen gets a new expert.
fn teach(model: &mut SequenceModel, session: &Session) -> Result<(), ModelError> {
    let feats = model.inputs.read(session, None)?;
    let (labels, classes) = labels(session, &model.label_set)?;
    // The model's expert for each class the session's grasps have, new ones added (a
    // class a label set names but no grasp has gets no expert: it would never be taught).
    let mut expert = vec![usize::MAX; classes.len()];
    for (c, name) in classes.iter().enumerate() {
        if !labels.contains(&c) {
            continue;
        }
        expert[c] = match model.classes.iter().position(|m| m == name) {
            Some(e) => e,
            None => {
                let e = model.experts.learner().add_class()?;
                model.classes.push(name.clone());
                e
            }
        };
    }
    let mut rng = Rng::stream(model.seed, model.grasps_taught as u64);
    let (teach, order) = protocol_order(&labels, classes.len(), &mut rng);
    for g in teach.into_iter().chain(order) {
        let learner = model.experts.learner();
        learner.train_sequence(feats.sequences[g].view(), expert[labels[g]]);
    }
    model.grasps_taught += session.grasps.len();
    Ok(())
}

/// Fit DS or GS on every grasp of `session`.
pub fn fit_sequences(
    session: &Session,
    opts: &SequenceFitOptions,
) -> Result<(SequenceModel, f64), ModelError> {
    let t0 = Instant::now();
    let inputs = SequenceInputs::fit(session, opts.features)?;
    let dim = inputs.feature_names.len();
    let experts = match opts.method {
        MethodId::Ds => Experts::Ds(Ds::new(dim, &opts.ds)?),
        MethodId::Gs => Experts::Gs(Gs::new(dim, &opts.gs)?),
        other @ (MethodId::SparseSvm
        | MethodId::RawSvm
        | MethodId::Du
        | MethodId::Gu
        | MethodId::KMeans
        | MethodId::Som
        | MethodId::RbfSvm
        | MethodId::Classifier(_)) => {
            return Err(ModelError::Param(format!(
                "{} is not a supervised sequence method (ds, gs)",
                other.key()
            )));
        }
    };
    let mut model = SequenceModel {
        experts,
        inputs,
        label_set: opts.label_set.clone(),
        classes: Vec::new(),
        seed: opts.seed,
        grasps_taught: 0,
    };
    teach(&mut model, session)?;
    Ok((model, t0.elapsed().as_secs_f64()))
}

/// `opts` with `auto` features replaced by the family the experts' cross validation on
/// `session` chooses (`experiments::feature_choice`), and that choice; or as they are.
pub fn choose_sequence_features(
    session: &Session,
    opts: &SequenceFitOptions,
    progress: &Progress,
) -> Result<(SequenceFitOptions, Option<FeatureChoice>), ModelError> {
    let learner = SupervisedLearner::of(opts.method).ok_or_else(|| {
        ModelError::Param(format!(
            "{} is not a supervised sequence method (ds, gs)",
            opts.method.key()
        ))
    })?;
    let params = RecognitionParams {
        learner,
        features: opts.features,
        label_set: opts.label_set.clone(),
        seed: opts.seed,
        ds: opts.ds.clone(),
        gs: opts.gs.clone(),
        ..RecognitionParams::default()
    };
    let (params, choice) = choose_auto_features(session, &params, progress)?;
    let opts = SequenceFitOptions {
        features: params.features,
        ..opts.clone()
    };
    Ok((opts, choice))
}

/// The model a `recognition` run leaves: DS or GS fitted on every grasp of `session` with
/// the run's settings, selected by the run's online-protocol accuracies.
pub fn sequence_file_of_run(
    session: &Session,
    run: &RecognitionResult,
) -> Result<ModelFile, ModelError> {
    let params = &run.params;
    let method = params.learner.method();
    let opts = SequenceFitOptions {
        method,
        features: params.features,
        label_set: params.label_set.clone(),
        seed: params.seed,
        ds: params.ds.clone(),
        gs: params.gs.clone(),
    };
    let (model, secs) = fit_sequences(session, &opts)?;
    let mut file = sequence_file(model, session, secs, params.size_reason, None);
    file.provenance.feature_choice = run.feature_choice.clone();
    let protocol = format!("online protocol, {} orders", params.reps);
    file.provenance.selection = SelectionScore::under(
        &protocol,
        &[
            ("accuracy", run.summary.all.mean),
            ("accuracy, final 20 %", run.summary.final_20.mean),
        ],
    );
    Ok(file)
}

/// Teach a saved model further on a new session.
pub fn continue_sequences(
    model: &SequenceModel,
    session: &Session,
) -> Result<(SequenceModel, f64), ModelError> {
    let t0 = Instant::now();
    let mut next = model.clone();
    teach(&mut next, session)?;
    Ok((next, t0.elapsed().as_secs_f64()))
}

/// One grasp as the experts see it: the class distribution after every step.
pub struct SequencePrediction {
    pub distributions: Array2<f64>,
    /// The decision from the whole grasp and from its first ⌈f·T⌉ steps for each
    /// fraction of `early`.
    pub class: usize,
    pub early: Vec<usize>,
}

pub const EARLY_FRACTIONS: [f64; 10] = [0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9, 1.0];

impl SequenceModel {
    pub fn method(&self) -> MethodId {
        match self.experts {
            Experts::Ds(_) => MethodId::Ds,
            Experts::Gs(_) => MethodId::Gs,
        }
    }

    /// Every grasp's prediction (the model is not changed: each grasp is predicted by a
    /// copy of the experts as saved).
    pub fn predict(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<SequencePrediction>, ModelError> {
        let feats = self.inputs.read(session, Some(calibration))?;
        let mut experts = self.experts.clone();
        Ok(feats
            .sequences
            .iter()
            .map(|seq| {
                let learner = experts.learner();
                let dist = learner.predict_sequence(seq.view());
                let t = dist.nrows();
                let early = EARLY_FRACTIONS
                    .iter()
                    .map(|&f| learner.decide(dist.slice(s![..prefix_len(f, t), ..])))
                    .collect();
                SequencePrediction {
                    class: learner.decide(dist.view()),
                    distributions: dist,
                    early,
                }
            })
            .collect())
    }

    pub fn validate(&self) -> Result<(), ModelError> {
        let l = self.experts.view();
        self.inputs.validate(l.dim())?;
        if l.n_classes() != self.classes.len() {
            return Err(ModelError::field(
                "model.classes",
                format!(
                    "{} classes for {} experts",
                    self.classes.len(),
                    l.n_classes()
                ),
            ));
        }
        Ok(())
    }
}

/// The model file of a supervised model trained (or taught further) on `session`;
/// `previous`: the provenance of the model it continued.
pub fn sequence_file(
    model: SequenceModel,
    session: &Session,
    secs: f64,
    size_reason: SizeReason,
    previous: Option<&Provenance>,
) -> ModelFile {
    let gp = match &model.experts {
        Experts::Ds(l) => l.params().gp.clone(),
        Experts::Gs(l) => l.params().gp.clone(),
    };
    let mut parameters = vec![
        ("features".to_string(), model.inputs.features.to_string()),
        ("target".to_string(), model.label_set.clone()),
        ("order seed".to_string(), model.seed.to_string()),
        (
            "adaptation".to_string(),
            if gp.adaptation.is_some() { "on" } else { "off" }.to_string(),
        ),
        ("grasps taught".to_string(), model.grasps_taught.to_string()),
    ];
    if let Some(p) = previous {
        parameters.push((
            "continued from".to_string(),
            format!("{} [{}]", p.summary(), p.session.hash),
        ));
    }
    let provenance = Provenance {
        method: model.method(),
        parameters,
        size: vec![("capacity".into(), gp.capacity), ("tau".into(), gp.tau)],
        size_reason,
        session: SessionRef::of(session),
        features: model.inputs.describe(),
        normalisation: "each feature min-max scaled over every frame of the training session \
                        (a new session: see its calibration; teaching further keeps this range)"
            .into(),
        label_set: model.label_set.clone(),
        classes: model.classes.clone(),
        trained_at: Provenance::now(),
        train_seconds: secs,
        selection: Vec::new(),
        // Taught further, the inputs stay the ones the first session chose.
        feature_choice: previous.and_then(|p| p.feature_choice.clone()),
    };
    ModelFile::new(provenance, Model::Sequences(model))
}
