//! A registered method ([`crate::catalogue::Classifier`]) as a model that leaves its
//! session: fitted on every grasp of a session, saved with the state the method gives, and
//! applied to another session read on the model's range (or the new session's own, per
//! its calibration). Nothing here names a method: the registry's trait does the work.

use std::time::Instant;

use ndarray::ArrayView2;
use serde::{Deserialize, Serialize};

use super::inputs::SequenceInputs;
use super::{Calibration, Model, ModelError, ModelFile, Provenance, SessionRef};
use crate::catalogue::{Classifier, ClassifierError, Fitted, MethodId, Training};
use crate::experiments::classifier::ClassifierScorer;
use crate::experiments::feature_choice::{AUTO_FOLDS, FeatureChoice, choose_features};
use crate::experiments::result::SizeReason;
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::session::Session;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClassifierModel {
    pub method: MethodId,
    /// One value per size knob of the method.
    pub size: Vec<f64>,
    /// What the method saved of itself.
    pub state: serde_json::Value,
    #[serde(flatten)]
    pub inputs: SequenceInputs,
    pub label_set: String,
    pub classes: Vec<String>,
    pub seed: u64,
}

/// How a registered method is fitted.
#[derive(Clone, Debug, PartialEq)]
pub struct ClassifierFitOptions {
    pub method: MethodId,
    /// None: the method's own families.
    pub features: Option<FeatureSet>,
    /// None: the method's default size.
    pub size: Option<Vec<f64>>,
    pub label_set: String,
    pub seed: u64,
}

fn method_of(id: MethodId) -> Result<&'static dyn Classifier, ModelError> {
    id.classifier().ok_or_else(|| {
        ModelError::Param(format!(
            "{} is not a registered method (those are fitted by their own protocol)",
            id.key()
        ))
    })
}

fn model_err(e: ClassifierError) -> ModelError {
    match e {
        ClassifierError::State(reason) => ModelError::field("model.state", reason),
        ClassifierError::Data(d) => ModelError::Mismatch(d),
        e @ ClassifierError::StateJson(_) => ModelError::MethodCheck {
            field: "model.state",
            source: e,
        },
        other => ModelError::Classifier(other),
    }
}

/// `opts` with `auto` features replaced by the family the method's own cross validation on
/// `session` chooses at its size (`experiments::feature_choice`), and that choice; or as
/// they are.
pub fn choose_classifier_features(
    session: &Session,
    opts: &ClassifierFitOptions,
    progress: &Progress,
) -> Result<(ClassifierFitOptions, Option<FeatureChoice>), ModelError> {
    if opts.features != Some(FeatureSet::AUTO) {
        return Ok((opts.clone(), None));
    }
    let method = method_of(opts.method)?;
    let size = opts.size.clone().unwrap_or_else(|| method.default_size());
    let choice = choose_features(
        session,
        &ClassifierScorer {
            method,
            size: &size,
        },
        &opts.label_set,
        AUTO_FOLDS,
        opts.seed,
        progress,
    )?;
    let opts = ClassifierFitOptions {
        features: Some(choice.chosen),
        ..opts.clone()
    };
    Ok((opts, Some(choice)))
}

/// Fit a registered method on every grasp of `session`.
pub fn fit_classifier(
    session: &Session,
    opts: &ClassifierFitOptions,
    progress: &Progress,
) -> Result<(ClassifierModel, f64), ModelError> {
    let t0 = Instant::now();
    let method = method_of(opts.method)?;
    let size = opts.size.clone().unwrap_or_else(|| method.default_size());
    let inputs = SequenceInputs::fit(session, opts.features.unwrap_or(method.features()))?;
    let feats = inputs.read(session, None)?;
    let (labels, classes) = super::recognition::labels(session, &opts.label_set)?;
    let x: Vec<ArrayView2<f64>> = feats.sequences.iter().map(|s| s.view()).collect();
    let fitted = method
        .fit(
            &size,
            &Training {
                sequences: &x,
                labels: &labels,
                n_classes: classes.len(),
                seed: opts.seed,
            },
            progress,
        )
        .map_err(model_err)?;
    let model = ClassifierModel {
        method: opts.method,
        size,
        state: fitted.state(),
        inputs,
        label_set: opts.label_set.clone(),
        classes,
        seed: opts.seed,
    };
    Ok((model, t0.elapsed().as_secs_f64()))
}

impl ClassifierModel {
    fn fitted(&self) -> Result<Box<dyn Fitted>, ModelError> {
        method_of(self.method)?.load(&self.state).map_err(model_err)
    }

    /// The class id of every grasp of `session`.
    pub fn assign(
        &self,
        session: &Session,
        calibration: Calibration,
    ) -> Result<Vec<usize>, ModelError> {
        let fitted = self.fitted()?;
        let feats = self.inputs.read(session, Some(calibration))?;
        Ok(feats
            .sequences
            .iter()
            .map(|s| fitted.predict(s.view()))
            .collect())
    }

    pub fn validate(&self) -> Result<(), ModelError> {
        let method = method_of(self.method).map_err(|e| ModelError::FieldCheck {
            field: "model.method",
            source: crate::error::Kept::new(e),
        })?;
        method
            .check(&self.size)
            .map_err(|source| ModelError::MethodCheck {
                field: "model.size",
                source,
            })?;
        let fitted = self.fitted()?;
        self.inputs.validate(fitted.dim())?;
        if fitted.n_classes() != self.classes.len() {
            return Err(ModelError::field(
                "model.classes",
                format!(
                    "{} class names for a model of {} classes",
                    self.classes.len(),
                    fitted.n_classes()
                ),
            ));
        }
        Ok(())
    }
}

/// The model file of a registered method fitted on `session`.
pub fn classifier_file(
    model: ClassifierModel,
    session: &Session,
    secs: f64,
    size_reason: SizeReason,
) -> ModelFile {
    let info = model.method.info();
    let named = info.size_knobs.iter().map(|k| k.name).zip(&model.size);
    // Whole-numbered knobs are sizes; the others (a penalty) are parameters.
    let size = named
        .clone()
        .filter(|(_, v)| v.fract() == 0.0 && **v >= 0.0)
        .map(|(k, v)| (k.to_string(), *v as usize))
        .collect();
    let mut parameters: Vec<(String, String)> = named
        .filter(|(_, v)| !(v.fract() == 0.0 && **v >= 0.0))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    parameters.push(("features".into(), model.inputs.features.to_string()));
    parameters.push(("target".into(), model.label_set.clone()));
    parameters.push(("seed".into(), model.seed.to_string()));
    let provenance = Provenance {
        method: model.method,
        parameters,
        size,
        size_reason,
        session: SessionRef::of(session),
        features: model.inputs.describe(),
        normalisation: "each feature min-max scaled over every frame of the training session \
                        (a new session: see its calibration)"
            .into(),
        label_set: model.label_set.clone(),
        classes: model.classes.clone(),
        trained_at: Provenance::now(),
        train_seconds: secs,
        selection: Vec::new(),
        feature_choice: None,
    };
    ModelFile::new(provenance, Model::Classifier(model))
}
