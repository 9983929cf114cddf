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
pub use held_out::{
    GraspPrediction, HeldOutResult, HeldOutScores, check_readable, evaluate, predict,
};
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

/// Why a model could not be read, written, fitted or applied. A lower layer's error is kept
/// as the source: the file's I/O or JSON error, the field check that failed, the session's
/// features, labels or shapes that do not fit, the stability pipeline, a learner, an
/// experiment or a registered method.
#[derive(Debug, thiserror::Error)]
pub enum ModelError {
    /// A model file that is not a model file (its format or version).
    #[error("{path}: {message}")]
    File { path: String, message: String },
    /// A model file that cannot be opened, read or written.
    #[error("{path}: {source}")]
    Io {
        path: String,
        #[source]
        source: std::io::Error,
    },
    /// A model file whose JSON does not read; `what` says so ("not JSON: ") where the head
    /// is read.
    #[error("{path}: {what}{source}")]
    Json {
        path: String,
        what: &'static str,
        #[source]
        source: serde_json::Error,
    },
    /// A model file that parses but whose fields do not check.
    #[error("{path}: {source}")]
    Invalid {
        path: String,
        #[source]
        source: crate::error::Kept<ModelError>,
    },
    /// A field of a model file that is present but wrong.
    #[error("model field `{field}`: {reason}")]
    Field { field: String, reason: String },
    /// A field of a model file that a method's own check refuses.
    #[error("model field `{field}`: {source}")]
    FieldCheck {
        field: &'static str,
        #[source]
        source: crate::error::Kept<ModelError>,
    },
    /// A model file's method state or size that its method refuses.
    #[error("model field `{field}`: {source}")]
    MethodCheck {
        field: &'static str,
        #[source]
        source: crate::catalogue::ClassifierError,
    },
    /// A session that the model cannot read (other sensors, taxels, classes).
    #[error("the session does not fit the model: {0}")]
    Mismatch(String),
    /// The session's feature sequences on the model's range.
    #[error("the session does not fit the model: {0}")]
    Sequences(#[source] crate::features::sequence::SequenceError),
    /// The one-grasp session a live model builds from the frames of an open grasp.
    #[error("the session does not fit the model: {0}")]
    Template(#[source] crate::error::Kept<crate::session::SessionError>),
    /// The session's labels under the model's label set.
    #[error("the session does not fit the model: {0}")]
    Labels(#[source] crate::experiments::ExperimentError),
    /// The session's Table I features or their normalisation.
    #[error("the session does not fit the model: {0}")]
    Features(#[source] crate::features::FeatureError),
    /// The session's images in the model's sensor shape.
    #[error("the session does not fit the model: {0}")]
    Shape(#[source] ndarray::ShapeError),
    /// The RBF SVM of a Table I model on the session's features.
    #[error("the session does not fit the model: {0}")]
    KernelSvm(#[source] crate::svm::kernel_svm::KernelSvmError),
    /// k-means or the SOM of a Table I model on the session's features.
    #[error("the session does not fit the model: {0}")]
    Cluster(#[source] crate::cluster::ClusterError),
    /// Fitting a Table I model (k-means, the SOM, the RBF SVM and its grid).
    #[error("{0}")]
    Baselines(#[source] crate::experiments::baselines::BaselinesError),
    /// A registered method's error that is not the session's (its parameters, or a cancel).
    #[error("{0}")]
    Classifier(#[source] crate::catalogue::ClassifierError),
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
