//! Experiments: the papers' protocols as engine functions returning plain, serialisable
//! results (for the CLI, the views and the figures), and what they leave behind.

pub mod baselines;
pub mod classifier;
pub mod clustering;
pub mod experiment;
pub mod feature_choice;
pub mod figure_id;
pub mod frontier;
pub mod labels;
pub mod links;
pub mod parallel;
pub mod recognition;
pub mod result;
pub mod robustness;
pub mod stability;

use crate::features::sequence::SequenceError;
use crate::jobs::Cancelled;
use crate::learners::LearnerError;

/// Why an experiment failed: its own parameters or data, a cancel, or a lower layer's error
/// (kept as the source).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExperimentError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("invalid data: {0}")]
    Data(String),
    #[error("{0}")]
    Features(#[from] SequenceError),
    /// The Table I features or their normalisation.
    #[error("{0}")]
    FeatureTable(#[from] crate::features::FeatureError),
    #[error("{0}")]
    Learner(#[from] LearnerError),
    /// The stability pipeline (its patches, sparse coder or SVM); a cancel is
    /// [`ExperimentError::Cancelled`].
    #[error("{0}")]
    Stability(#[source] stability::StabilityError),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for ExperimentError {
    fn from(_: Cancelled) -> Self {
        ExperimentError::Cancelled
    }
}

impl From<stability::StabilityError> for ExperimentError {
    fn from(e: stability::StabilityError) -> Self {
        if e.is_cancelled() {
            ExperimentError::Cancelled
        } else {
            ExperimentError::Stability(e)
        }
    }
}

impl ExperimentError {
    pub(crate) fn param(name: &'static str, reason: impl Into<String>) -> ExperimentError {
        ExperimentError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}
