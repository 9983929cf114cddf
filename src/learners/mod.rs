//! Online learners over OIESGP experts (DS, GS, DU, GU) and their novelty scores.

pub mod ds;
pub mod du;
pub mod evt;
pub mod gs;
pub mod gu;

use ndarray::{Array2, ArrayView2};

pub use ds::{Ds, DsParams};
pub use du::{Assignment, Du, DuParams, du_novelty};
pub use gs::{Gs, GsParams};
pub use gu::{EvtDraws, Gu, GuAggregate, GuNoise, GuParams};

use crate::gp::{GpError, Sogp};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LearnerError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error(transparent)]
    Gp(#[from] GpError),
}

impl LearnerError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> LearnerError {
        LearnerError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}

/// One expert per class over sequences of feature vectors (rows of a T × D matrix).
pub trait SequenceClassifier: Send {
    fn dim(&self) -> usize;
    fn n_classes(&self) -> usize;
    /// Add an (untrained) expert; returns its class index.
    fn add_class(&mut self) -> Result<usize, LearnerError>;
    fn models(&self) -> &[Sogp];
    /// The class distribution after every step of the sequence (T × C).
    fn predict_sequence(&mut self, seq: ArrayView2<f64>) -> Array2<f64>;
    fn train_sequence(&mut self, seq: ArrayView2<f64>, class: usize);
    /// The sequence methods one observation at a time (what a step costs): a new sequence
    /// starts, ...
    fn start_sequence(&mut self);
    /// ... the class distribution after observing `o` (as a row of `predict_sequence`)
    /// into `dist`, ...
    fn predict_step(&mut self, o: &[f64], dist: &mut [f64]);
    /// ... or a training step on `o` of class `class` (as in `train_sequence`).
    fn train_step(&mut self, o: &[f64], class: usize);
    /// The class of a sequence (or of its first steps) from its per-step distributions.
    fn decide(&self, dist: ArrayView2<f64>) -> usize;
}

/// The steps of a standard-layout sequence as one slice (empty when its width is not
/// `dim`, so that a mismatched sequence is never read out of step).
fn steps<'a>(seq: &'a ndarray::CowArray<'_, f64, ndarray::Ix2>, dim: usize) -> &'a [f64] {
    if seq.ncols() != dim {
        return &[];
    }
    seq.as_slice().unwrap_or_default()
}

fn argmax(v: impl Iterator<Item = f64>) -> usize {
    let mut best = (0, f64::NEG_INFINITY);
    for (i, x) in v.enumerate() {
        if x > best.1 {
            best = (i, x);
        }
    }
    best.0
}

/// Argmax of the per-step distributions averaged over the steps.
pub fn argmax_of_mean(dist: ArrayView2<f64>) -> usize {
    argmax(dist.columns().into_iter().map(|c| c.sum()))
}

/// Argmax of the last step's distribution.
pub fn argmax_of_last(dist: ArrayView2<f64>) -> usize {
    match dist.nrows() {
        0 => 0,
        t => argmax(dist.row(t - 1).iter().copied()),
    }
}

/// Lengthscales of every expert (class × input dimension).
pub fn lengthscales(learner: &dyn SequenceClassifier) -> Array2<f64> {
    let models = learner.models();
    let d = learner.dim();
    Array2::from_shape_fn((models.len(), d), |(c, j)| {
        models[c].kernel_params().lengthscales[j]
    })
}

#[cfg(test)]
mod tests {
    use ndarray::array;

    use super::*;

    /// A tie goes to the first class, so that a decision does not depend on how many
    /// classes tie after it (an untrained learner's uniform distribution decides class 0).
    #[test]
    fn a_tie_goes_to_the_first_class() {
        let uniform = array![[0.25, 0.25, 0.25, 0.25], [0.25, 0.25, 0.25, 0.25]];
        assert_eq!(argmax_of_mean(uniform.view()), 0);
        assert_eq!(argmax_of_last(uniform.view()), 0);
        let tied = array![[0.1, 0.45, 0.45]];
        assert_eq!(argmax_of_mean(tied.view()), 1);
        assert_eq!(argmax_of_last(tied.view()), 1);
    }
}
