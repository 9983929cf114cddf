//! Clustering and its scores (the second paper, Sec. VII-A, Table IV): sequential
//! k-means and a self-organising map on per-grasp features, and the external scores
//! purity / ARI / NMI against true labels (the baselines' protocol: `experiments::baselines`).

pub mod kmeans;
pub mod order_agreement;
pub mod scores;
pub mod som;

use ndarray::{ArrayView1, ArrayView2};

/// The baselines as their series and scores name them (a learner's result is compared
/// with them, and shows their numbers apart from its own).
pub const KMEANS_NAME: &str = "sequential k-means";
pub const SOM_NAME: &str = "SOM";
pub const BASELINE_NAMES: [&str; 2] = [KMEANS_NAME, SOM_NAME];

pub use kmeans::{SequentialKMeans, SequentialKMeansParams};
pub use scores::{
    ClusterScores, adjusted_rand_index, mutual_info, normalized_mutual_info, purity, scores,
};
pub use som::{Schedule, SelfOrganisingMap, SomParams};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ClusterError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("invalid data: {0}")]
    InvalidData(String),
}

impl From<crate::features::FeatureError> for ClusterError {
    fn from(e: crate::features::FeatureError) -> Self {
        match e {
            crate::features::FeatureError::InvalidData(m) => ClusterError::InvalidData(m),
        }
    }
}

impl ClusterError {
    fn invalid(name: &'static str, reason: impl Into<String>) -> Self {
        ClusterError::InvalidParameter {
            name,
            reason: reason.into(),
        }
    }
}

/// Samples to cluster must exist and be finite.
fn check_data(data: ArrayView2<f64>) -> Result<(), ClusterError> {
    Ok(crate::features::normalise::check_data(data)?)
}

/// Samples to assign must be finite and have the model's width.
fn check_width(data: ArrayView2<f64>, width: usize) -> Result<(), ClusterError> {
    Ok(crate::features::normalise::check_width(data, width)?)
}

/// Row of `rows` nearest to `x` in squared Euclidean distance (ties to the lower index).
fn nearest_row(rows: ArrayView2<f64>, x: ArrayView1<f64>) -> usize {
    let mut best = (0, f64::INFINITY);
    for (j, r) in rows.rows().into_iter().enumerate() {
        let d: f64 = r.iter().zip(x).map(|(a, b)| (a - b) * (a - b)).sum();
        if d < best.1 {
            best = (j, d);
        }
    }
    best.0
}
