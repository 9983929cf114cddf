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

use super::{Calibration, Model, ModelError, ModelFile, Provenance, SessionRef};
use crate::catalogue::MethodId;
use crate::experiments::labels::session_labels;
use crate::experiments::recognition::{prefix_len, protocol_order};
use crate::experiments::result::SizeReason;
use crate::features::{
    FeatureSequences, FeatureSet, SequenceParams, SequenceRange, feature_sequences_in,
};
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
    /// The families the columns hold (resolved on the training session).
    pub features: FeatureSet,
    pub feature_names: Vec<String>,
    /// The training session's range of each feature.
    pub min: Vec<f64>,
    pub max: Vec<f64>,
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
    session_labels(session, label_set).map_err(|e| ModelError::Mismatch(e.to_string()))
}

pub(super) fn sequences(
    session: &Session,
    features: FeatureSet,
    range: SequenceRange,
) -> Result<FeatureSequences, ModelError> {
    feature_sequences_in(
        session,
        &SequenceParams {
            features,
            taxel_noise_variance: 0.0,
            seed: 0,
        },
        range,
    )
    .map_err(|e| ModelError::Mismatch(e.to_string()))
}

/// Teach `model` every grasp of `session` in the protocol's order (one grasp per class
/// first, then stratified random rounds), reading it on the model's range. A class the
/// model has not seen gets a new expert.
fn teach(model: &mut SequenceModel, session: &Session) -> Result<(), ModelError> {
    let feats = sequences(
        session,
        model.features,
        SequenceRange::Given {
            min: &model.min,
            max: &model.max,
        },
    )?;
    if feats.names != model.feature_names {
        return Err(ModelError::Mismatch(format!(
            "the model reads {} features ({}); the session gives {} ({})",
            model.feature_names.len(),
            model.features,
            feats.names.len(),
            feats.families
        )));
    }
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
    let feats = sequences(session, opts.features, SequenceRange::Session)?;
    let dim = feats.dim();
    let experts = match opts.method {
        MethodId::Ds => Experts::Ds(Ds::new(dim, &opts.ds)?),
        MethodId::Gs => Experts::Gs(Gs::new(dim, &opts.gs)?),
        other => {
            return Err(ModelError::Param(format!(
                "{} is not a supervised sequence method (ds, gs)",
                other.key()
            )));
        }
    };
    let mut model = SequenceModel {
        experts,
        features: feats.families,
        feature_names: feats.names,
        min: feats.min,
        max: feats.max,
        label_set: opts.label_set.clone(),
        classes: Vec::new(),
        seed: opts.seed,
        grasps_taught: 0,
    };
    teach(&mut model, session)?;
    Ok((model, t0.elapsed().as_secs_f64()))
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
        let range = match calibration.grasps(session.grasps.len())? {
            None => SequenceRange::Given {
                min: &self.min,
                max: &self.max,
            },
            Some(r) => SequenceRange::Grasps(r),
        };
        let feats = sequences(session, self.features, range)?;
        if feats.names != self.feature_names {
            return Err(ModelError::Mismatch(format!(
                "the model reads features {}; the session gives {}",
                self.feature_names.join(", "),
                feats.names.join(", ")
            )));
        }
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
        let n = self.feature_names.len();
        if n == 0 || self.min.len() != n || self.max.len() != n {
            return Err(ModelError::field(
                "model.min",
                format!(
                    "{} minima and {} maxima for {n} features",
                    self.min.len(),
                    self.max.len()
                ),
            ));
        }
        if self.min.iter().chain(&self.max).any(|v| !v.is_finite()) {
            return Err(ModelError::field("model.min", "ranges must be finite"));
        }
        let l = self.experts.view();
        if l.dim() != n {
            return Err(ModelError::field(
                "model.experts",
                format!("experts of {} inputs for {n} features", l.dim()),
            ));
        }
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
        ("features".to_string(), model.features.to_string()),
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
        features: format!(
            "{} per step: {}",
            model.feature_names.len(),
            model.feature_names.join(", ")
        ),
        normalisation: "each feature min-max scaled over every frame of the training session \
                        (a new session: see its calibration; teaching further keeps this range)"
            .into(),
        label_set: model.label_set.clone(),
        classes: model.classes.clone(),
        trained_at: Provenance::now(),
        train_seconds: secs,
        selection: Vec::new(),
    };
    ModelFile::new(provenance, Model::Sequences(model))
}
