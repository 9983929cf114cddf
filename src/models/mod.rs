//! Models that leave their session: a method of the catalogue fitted on one recording,
//! saved as a versioned JSON file with its provenance, and applied to another recording —
//! evaluated against its labels, or predicting without them — under a stated calibration
//! of the new recording's sensors.
//!
//! - [`file`]: the model file (format, version, provenance, the model) and its checks;
//! - [`calibration`]: which per-taxel statistics stand for a new recording;
//! - [`stability`]: the grasp-stability classifiers (sparse coding + linear SVM, the raw
//!   linear SVM): fitting, the session checks, decision values;
//! - [`inputs`]: what the sequence models read, and how a session is read on their range;
//! - [`recognition`]: the supervised OIESGP experts (DS, GS): fitting, teaching further on a
//!   new session, per-step predictions;
//! - [`clustering`]: the unsupervised OIESGP experts (DU, GU): learning, learning further,
//!   assigning a new session's grasps to clusters;
//! - [`table_one`]: the offline baselines on the Table I features (k-means, SOM, RBF SVM);
//! - [`classifier`]: any registered method, through its trait;
//! - [`held_out`]: scores, predictions and figures on a session the model did not train on.

pub mod calibration;
pub mod classifier;
pub mod clustering;
pub mod file;
pub mod held_out;
pub mod held_out_report;
pub mod inputs;
pub mod recognition;
pub mod stability;
pub mod table_one;
#[cfg(test)]
mod tests;

pub use calibration::Calibration;
pub use classifier::{
    ClassifierFitOptions, ClassifierModel, choose_classifier_features, classifier_file,
    fit_classifier,
};
pub use clustering::{
    ClusterFitOptions, ClusterModel, choose_cluster_features, cluster_file, cluster_file_of_run,
    continue_clusters, fit_clusters,
};
pub use file::{
    FORMAT, Model, ModelFile, Provenance, SelectionScore, SessionRef, VERSION, load, save,
};
pub use held_out::{GraspPrediction, HeldOutResult, HeldOutScores, evaluate, predict};
pub use held_out_report::held_out_report;
pub use recognition::{
    SequenceFitOptions, SequenceModel, choose_sequence_features, continue_sequences, fit_sequences,
    sequence_file, sequence_file_of_run,
};
pub use stability::{SensorShape, SparseCodes, StabilityClassifier, fit_stability};
pub use table_one::{
    TableOneFitOptions, TableOneModel, fit_table_one, table_one_file, table_one_files_of_run,
};

use crate::experiments::stability::StabilityError;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ModelError {
    /// A model file that cannot be read or is not a model file.
    #[error("{path}: {message}")]
    File { path: String, message: String },
    /// A field of a model file that is present but wrong.
    #[error("model field `{field}`: {reason}")]
    Field { field: String, reason: String },
    /// A session that the model cannot read (other sensors, taxels, classes).
    #[error("the session does not fit the model: {0}")]
    Mismatch(String),
    #[error("{0}")]
    Param(String),
    /// A prediction that came out infinite or NaN: never reported as a class.
    #[error("{0}")]
    NotFinite(String),
    #[error("{0}")]
    Stability(#[from] StabilityError),
    #[error("{0}")]
    Learner(#[from] crate::learners::LearnerError),
    #[error("{0}")]
    Experiment(#[from] crate::experiments::ExperimentError),
}

impl ModelError {
    pub(crate) fn field(field: impl Into<String>, reason: impl Into<String>) -> ModelError {
        ModelError::Field {
            field: field.into(),
            reason: reason.into(),
        }
    }
}
