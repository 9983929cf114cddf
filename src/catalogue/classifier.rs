//! The method trait, in linfa's shape: parameters (a [`Size`]) are checked, fitted on a
//! session's grasps into a model, and the model predicts a grasp's class and saves its
//! state. What a method must answer follows scikit-learn's estimator contract: `fit` reads
//! only the training grasps and is deterministic for a seed; `predict` changes nothing;
//! a saved model loads back to the same predictions.
//!
//! The protocols build the inputs (per-step feature sequences of the method's families,
//! min-max scaled on the training grasps) and score the predictions; a method only learns
//! and predicts.

use ndarray::ArrayView2;

use super::MethodInfo;
use crate::features::FeatureSet;
use crate::jobs::{Cancelled, Progress};

/// A method's size: one value per size knob of its [`MethodInfo`], in their order.
pub type Size = Vec<f64>;

/// The grasps a method is fitted on.
pub struct Training<'a> {
    /// One sequence per grasp: steps × features.
    pub sequences: &'a [ArrayView2<'a, f64>],
    /// Each grasp's class, below `n_classes`.
    pub labels: &'a [usize],
    pub n_classes: usize,
    /// Every random choice of the fit follows from it.
    pub seed: u64,
}

impl Training<'_> {
    /// The features per step, once every grasp has a label below `n_classes` and all
    /// share one width of at least one feature.
    pub fn check(&self) -> Result<usize, ClassifierError> {
        let bad = |m: String| Err(ClassifierError::Data(m));
        if self.sequences.len() != self.labels.len() || self.sequences.is_empty() {
            return bad(format!(
                "{} grasps with {} labels",
                self.sequences.len(),
                self.labels.len()
            ));
        }
        if let Some(l) = self.labels.iter().find(|&&l| l >= self.n_classes) {
            return bad(format!("class {l} of {} classes", self.n_classes));
        }
        let dim = self.sequences[0].ncols();
        if dim == 0 || self.sequences.iter().any(|s| s.ncols() != dim) {
            return bad("every grasp needs the same features per step, at least one".into());
        }
        Ok(dim)
    }
}

/// A method that classifies whole grasps from their feature sequences.
pub trait Classifier: Sync {
    /// Key, title, task, score and size knobs.
    fn info(&self) -> &'static MethodInfo;
    /// The input families it reads unless told otherwise.
    fn features(&self) -> FeatureSet;
    /// The size a fit takes unless told otherwise.
    fn default_size(&self) -> Size;
    /// The sizes a frontier sweeps unless told otherwise.
    fn sizes(&self) -> Vec<Size>;
    /// A size it cannot fit at, said with the knob's name.
    fn check(&self, size: &[f64]) -> Result<(), ClassifierError>;
    /// Learn from `data` at `size` (checked first); `progress` reports and cancels.
    fn fit(
        &self,
        size: &[f64],
        data: &Training,
        progress: &Progress,
    ) -> Result<Box<dyn Fitted>, ClassifierError>;
    /// A fitted model back from the state it saved.
    fn load(&self, state: &serde_json::Value) -> Result<Box<dyn Fitted>, ClassifierError>;
}

/// A fitted method.
pub trait Fitted: Send + Sync {
    /// The class of one grasp (steps × features).
    fn predict(&self, sequence: ArrayView2<f64>) -> usize;
    /// Its whole state, as the model file keeps it.
    fn state(&self) -> serde_json::Value;
    /// The features per step it reads.
    fn dim(&self) -> usize;
    fn n_classes(&self) -> usize;
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClassifierError {
    #[error("invalid size knob `{knob}`: {reason}")]
    Param { knob: &'static str, reason: String },
    #[error("invalid data: {0}")]
    Data(String),
    /// Data that does not take the shape the method gives it.
    #[error("invalid data: {0}")]
    Shape(#[from] ndarray::ShapeError),
    /// A saved state that does not read back.
    #[error("saved state: {0}")]
    State(String),
    /// A saved state that is not the method's JSON (the parser's error kept).
    #[error("saved state: {0}")]
    StateJson(#[source] crate::error::Kept<serde_json::Error>),
    #[error("{0}")]
    Svm(#[from] crate::svm::SvmError),
    #[error("cancelled")]
    Cancelled,
}

impl ClassifierError {
    /// A saved state's JSON error.
    pub fn state_json(e: serde_json::Error) -> ClassifierError {
        ClassifierError::StateJson(crate::error::Kept::new(e))
    }
}

impl From<Cancelled> for ClassifierError {
    fn from(_: Cancelled) -> Self {
        ClassifierError::Cancelled
    }
}

impl ClassifierError {
    /// The size must hold one value per knob, each a whole number ≥ `min` where `whole`.
    pub fn check_knobs(
        info: &MethodInfo,
        size: &[f64],
        rules: &[(bool, f64)],
    ) -> Result<(), ClassifierError> {
        if size.len() != info.size_knobs.len() {
            return Err(ClassifierError::Param {
                knob: info.size_knobs.first().map_or("size", |k| k.name),
                reason: format!(
                    "{} values for {} knobs ({})",
                    size.len(),
                    info.size_knobs.len(),
                    info.size_knobs
                        .iter()
                        .map(|k| k.name)
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            });
        }
        for ((knob, &v), &(whole, min)) in info.size_knobs.iter().zip(size).zip(rules) {
            if !v.is_finite() || v < min || (whole && v.fract() != 0.0) {
                return Err(ClassifierError::Param {
                    knob: knob.name,
                    reason: format!(
                        "{v} is not {} ≥ {min}",
                        if whole { "a whole number" } else { "a number" }
                    ),
                });
            }
        }
        Ok(())
    }
}
