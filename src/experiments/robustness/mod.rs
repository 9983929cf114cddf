//! Where the methods fail: sweep one perturbation at a time over a list of strengths and
//! record each method's score (mean and sd over seeded repetitions) against strength, with
//! the break point where the mean first falls below `fraction` × the clean score.
//!
//! Families and scores:
//! - grasp stability: sparse coding + linear SVM at one fixed configuration, and the linear
//!   SVM on the raw key-frame values; score = pooled weighted success rate of a stratified
//!   k-fold (the first paper's protocol, [`crate::experiments::stability`]). The scaling and the
//!   dictionary are learned without labels on the clean session, as the paper does.
//! - object recognition: DS and GS under the second paper's supervised protocol
//!   ([`crate::experiments::recognition`]); score = "final 20 %" accuracy.
//!
//! Where a perturbation acts (see [`Perturbation::scope`]): noise is on every grasp (the
//! sensor is noisy while learning too; the pipeline is refitted on the noisy session, as
//! the paper's Fig. 8 does). Dead taxels, a dead sensor, drift, gain, truncation and
//! missing frames hit only the grasps a model is tested on, after it learned on clean ones:
//! a fault or a new sensor after training. Those test grasps are scaled with the clean
//! session's scaling (a deployed model cannot refit it). Class imbalance, few examples and
//! new objects change which grasps are learned from.
//!
//! Every (strength, repetition) is one rayon task; repetition r uses the same folds, order
//! and perturbation seed at every strength (streams of `seed`), so the curves compare like
//! with like and the numbers do not depend on the thread count.

use std::str::FromStr;
use std::time::Instant;

use ndarray::Array2;
use serde::{Deserialize, Serialize};

use crate::catalogue::MethodId;
use crate::cluster::kmeans::SequentialKMeansParams;
use crate::cluster::scores::scores;
use crate::experiments::ExperimentError;
use crate::experiments::classifier::train_test;
use crate::experiments::clustering::{
    ClusteringParams, UnsupervisedLearner, every_gu_cluster, one_run, som_setup,
};
use crate::experiments::labels::session_labels;
use crate::experiments::parallel::compute_items;
use crate::experiments::recognition::{SupervisedLearner, new_learner, protocol_order};
use crate::experiments::result::MeanSd;
use crate::experiments::stability::{
    Config, DataOptions, PipelineSettings, StabilityData, StabilityError, concatenated_codes,
};
use crate::features::{
    FeatureSequences, FeatureSet, KeyFramePatches, PatchScaling, SequenceParams, feature_sequences,
};
use crate::features::{Normalisation, Normaliser, table_one::session_features};
use crate::jobs::Progress;
use crate::learners::{DsParams, GsParams, GuAggregate, GuParams};
use crate::perturb::{PerturbError, PerturbParams, PerturbationKind, Stuck, perturb};
use crate::rng::Rng;
use crate::session::Session;
use crate::sparse::{Dictionary, DictionaryParams};
use crate::svm::kernel_svm::{KernelSvmParams, stratified_folds};
use crate::svm::{Confusion, LinearSvmParams, gather, stratified_k_fold};

mod method;
mod params;
mod perturbations;
mod recognition_tasks;
mod registered;
mod registry;
pub mod report;
mod run;
mod stability_tasks;
mod supervised;
mod table_one;
mod unsupervised;

use method::*;
pub use params::*;
pub use perturbations::*;
use recognition_tasks::*;
use registry::robustness_method;
pub use run::*;
use stability_tasks::*;

impl From<PerturbError> for ExperimentError {
    fn from(e: PerturbError) -> Self {
        match e {
            PerturbError::InvalidParameter { name, reason } => {
                ExperimentError::InvalidParameter { name, reason }
            }
            PerturbError::Data(d) => ExperimentError::Data(d),
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Family {
    Stability,
    Recognition,
}

impl FromStr for Family {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "stability" => Ok(Family::Stability),
            "recognition" => Ok(Family::Recognition),
            other => Err(ExperimentError::param(
                "family",
                format!("`{other}` is not stability or recognition"),
            )),
        }
    }
}

impl Family {
    /// The methods a sweep of this family runs unless told otherwise.
    pub fn methods(self) -> Vec<MethodId> {
        MethodId::all()
            .filter(|&m| Family::of(m) == self && m.info().robustness_default)
            .collect()
    }

    pub fn score_name(self) -> &'static str {
        match self {
            Family::Stability => "weighted success rate",
            Family::Recognition => "accuracy (final 20%) or NMI",
        }
    }
}

impl Family {
    /// The family a method's robustness curves belong to.
    pub fn of(method: MethodId) -> Family {
        robustness_method(method).family()
    }
}

/// A method named by `--methods`, with the parameter's name in the error.
pub fn parse_method(s: &str) -> Result<MethodId, ExperimentError> {
    s.parse().map_err(|source| ExperimentError::UnknownMethod {
        name: "methods",
        source,
    })
}

/// One strength of a curve.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SweepPoint {
    pub strength: f64,
    /// Mean and population sd over the repetitions.
    pub score: MeanSd,
    /// Mean score over the clean score (None when the clean score is 0).
    pub relative: Option<f64>,
    /// The score of every repetition.
    pub scores: Vec<f64>,
}

/// One method under one perturbation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Curve {
    pub method: MethodId,
    pub perturbation: Perturbation,
    pub scope: Scope,
    /// Why the perturbation does not apply (then `points` is empty).
    pub not_applicable: Option<String>,
    pub points: Vec<SweepPoint>,
    /// The strength at which the mean score falls below `fraction` × clean, interpolated
    /// linearly; None = it holds through the sweep.
    pub break_point: Option<f64>,
    /// Seconds of work spent on this curve: the time of its tasks summed over threads, a
    /// task's time shared equally by the methods it ran.
    pub task_seconds: f64,
}

/// A method's score without perturbation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CleanScore {
    pub method: MethodId,
    pub score: MeanSd,
    pub scores: Vec<f64>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessResult {
    pub params: RobustnessParams,
    pub session: String,
    pub score_name: String,
    pub clean: Vec<CleanScore>,
    pub curves: Vec<Curve>,
    /// Seconds spent preparing (features, the clean dictionary).
    pub setup_seconds: f64,
    pub wall_seconds: f64,
    pub threads: usize,
}

impl RobustnessResult {
    pub fn curve(&self, method: MethodId, perturbation: Perturbation) -> Option<&Curve> {
        self.curves
            .iter()
            .find(|c| c.method == method && c.perturbation == perturbation)
    }

    pub fn clean_score(&self, method: MethodId) -> Option<f64> {
        self.clean
            .iter()
            .find(|c| c.method == method)
            .map(|c| c.score.mean)
    }
}

/// The first strength, in sweep order, at which `points` (strength, mean score) fall below
/// `fraction · clean`, linearly interpolated from the point before it. The sweep starts
/// from (`neutral`, `clean`) when the perturbation has a neutral strength; when the first
/// point already falls below and there is nothing before it, the break is that point.
pub fn break_point(
    neutral: Option<f64>,
    clean: f64,
    points: &[(f64, f64)],
    fraction: f64,
) -> Option<f64> {
    let bar = fraction * clean;
    let mut prev: Option<(f64, f64)> = neutral.map(|n| (n, clean));
    for &(s, m) in points {
        if m < bar {
            return Some(match prev {
                Some((s0, m0)) if m0 > m && m0 >= bar => s0 + (m0 - bar) / (m0 - m) * (s - s0),
                _ => s,
            });
        }
        prev = Some((s, m));
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn imbalance_keeps_the_asked_share_of_failures() {
        let labels: Vec<bool> = (0..100).map(|i| i % 2 == 0).collect();
        let train: Vec<usize> = (0..100).collect();
        let kept = imbalance_train(&train, &labels, 0.05, &mut Rng::new(1));
        let f = kept.iter().filter(|&&i| labels[i]).count();
        assert_eq!(kept.len() - f, 50);
        // 0.05 / 0.95 · 50 = 2.6 → 3 failures.
        assert_eq!(f, 3);
    }

    #[test]
    fn few_examples_caps_every_class() {
        let classes: Vec<usize> = (0..60).map(|i| i % 3).collect();
        let train: Vec<usize> = (0..60).collect();
        let kept = few_train(&train, &classes, 4, &mut Rng::new(2));
        for c in 0..3 {
            assert_eq!(kept.iter().filter(|&&i| classes[i] == c).count(), 4);
        }
    }

    #[test]
    fn training_kept_few_examples_counts_the_taught_grasp() {
        let labels: Vec<usize> = (0..30).map(|i| i % 3).collect();
        let part: Vec<usize> = (0..30).collect();
        let keep = training_kept(
            Some((Perturbation::FewExamples, 3.0)),
            &labels,
            3,
            &part,
            true,
            &mut Rng::new(0),
        );
        assert_eq!(keep.iter().filter(|k| **k).count(), 6);
    }
}
