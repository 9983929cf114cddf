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
    /// A named part of the parameters that its method refuses.
    #[error("invalid parameter `{name}`: {source}")]
    Parameter {
        name: &'static str,
        #[source]
        source: crate::error::MethodError,
    },
    /// A named part of the parameters that the RBF SVM refuses.
    #[error("invalid parameter `{name}`: {source}")]
    KernelSvmParameter {
        name: &'static str,
        #[source]
        source: crate::svm::kernel_svm::KernelSvmError,
    },
    /// A method's name that names none (`--methods`).
    #[error("invalid parameter `{name}`: {source}")]
    UnknownMethod {
        name: &'static str,
        #[source]
        source: crate::catalogue::UnknownMethod,
    },
    #[error("invalid data: {0}")]
    Data(String),
    /// The RBF SVM's error on the data it was given.
    #[error("{0}")]
    KernelSvm(#[from] crate::svm::kernel_svm::KernelSvmError),
    /// Data that does not take the shape the protocol gives it.
    #[error("invalid data: {0}")]
    Shape(#[from] ndarray::ShapeError),
    /// A part of the experiment (`what` names it) that failed.
    #[error("{what}: {source}")]
    Within {
        what: String,
        #[source]
        source: crate::error::Kept<ExperimentError>,
    },
    #[error("{0}")]
    Features(#[from] SequenceError),
    /// The Table I features or their normalisation.
    #[error("{0}")]
    FeatureTable(#[from] crate::features::FeatureError),
    #[error("{0}")]
    Learner(#[from] LearnerError),
    #[error("{0}")]
    Cluster(#[from] crate::cluster::ClusterError),
    /// A registered method's error (its parameters are `InvalidParameter`, a cancel is
    /// `Cancelled`).
    #[error("{0}")]
    Classifier(#[source] crate::catalogue::ClassifierError),
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
