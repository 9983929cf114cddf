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

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ExperimentError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("invalid data: {0}")]
    Data(String),
    #[error(transparent)]
    Features(#[from] SequenceError),
    #[error(transparent)]
    Learner(#[from] LearnerError),
    #[error("cancelled")]
    Cancelled,
}

impl From<Cancelled> for ExperimentError {
    fn from(_: Cancelled) -> Self {
        ExperimentError::Cancelled
    }
}

impl From<crate::sparse::SparseError> for ExperimentError {
    fn from(e: crate::sparse::SparseError) -> Self {
        stability::StabilityError::from(e).into()
    }
}

impl From<crate::svm::SvmError> for ExperimentError {
    fn from(e: crate::svm::SvmError) -> Self {
        stability::StabilityError::from(e).into()
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

impl From<crate::features::FeatureError> for ExperimentError {
    fn from(e: crate::features::FeatureError) -> Self {
        ExperimentError::Data(e.to_string())
    }
}
