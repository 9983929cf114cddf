//! Where the methods fail: sweep one perturbation at a time over a list of strengths and
//! record each method's score (mean and sd over seeded repetitions) against strength, with
//! the break point where the mean first falls below `fraction` × the clean score.
//!
//! Families and scores:
//! - grasp stability: sparse coding + linear SVM at one fixed configuration, and the linear
//!   SVM on the raw key-frame values; score = pooled weighted success rate of a stratified
//!   k-fold (the first paper's protocol, [`super::stability`]). The scaling and the
//!   dictionary are learned without labels on the clean session, as the paper does.
//! - object recognition: DS and GS under the second paper's supervised protocol
//!   ([`super::recognition`]); score = "final 20 %" accuracy.
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
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use ndarray::Array2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::ExperimentError;
use super::clustering::{
    ClusteringParams, UnsupervisedLearner, every_gu_cluster, one_run, som_setup,
};
use super::recognition::{MeanSd, SupervisedLearner, new_learner, protocol_order, session_labels};
use super::stability::{
    Config, DataOptions, PipelineSettings, StabilityData, StabilityError, grasp_features,
};
use crate::cluster::ClusterError;
use crate::cluster::grasp_features::{Normalisation, Normaliser, session_features};
use crate::cluster::kmeans::SequentialKMeansParams;
use crate::cluster::scores::scores;
use crate::features::{
    FeatureSequences, FeatureSet, KeyFramePatches, PatchScaling, SequenceParams, feature_sequences,
};
use crate::jobs::Progress;
use crate::learners::{DsParams, GsParams, GuAggregate, GuParams};
use crate::perturb::{PerturbError, PerturbParams, PerturbationKind, Stuck, perturb};
use crate::rng::Rng;
use crate::session::Session;
use crate::sparse::{Dictionary, DictionaryParams};
use crate::svm::kernel_svm::{KernelSvmParams, stratified_folds};
use crate::svm::{Confusion, LinearSvmParams, gather, stratified_k_fold};

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

impl From<StabilityError> for ExperimentError {
    fn from(e: StabilityError) -> Self {
        match e {
            StabilityError::Cancelled => ExperimentError::Cancelled,
            StabilityError::Data(d) => ExperimentError::Data(d),
            e => ExperimentError::Data(e.to_string()),
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
    pub fn methods(self) -> Vec<Method> {
        match self {
            Family::Stability => vec![Method::SparseSvm, Method::RawSvm],
            // DU and GU run on request: at thresholds that give a useful partition they
            // grow tens of clusters, and every cluster is a GP to score each step against.
            Family::Recognition => vec![
                Method::Ds,
                Method::Gs,
                Method::KMeans,
                Method::Som,
                Method::RbfSvm,
            ],
        }
    }

    pub fn score_name(self) -> &'static str {
        match self {
            Family::Stability => "weighted success rate",
            Family::Recognition => "accuracy (final 20%) or NMI",
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Method {
    /// Sparse coding of the key-frame patches + linear SVM (first paper).
    SparseSvm,
    /// Linear SVM on the scaled raw key-frame values (the first paper's baseline).
    RawSvm,
    Ds,
    Gs,
    /// Online clustering at a fixed novelty threshold (second paper).
    Du,
    Gu,
    /// Sequential k-means and the SOM on the per-grasp Table I features.
    KMeans,
    Som,
    /// The offline RBF SVM on the Table I features (stratified k-fold).
    RbfSvm,
}

impl Method {
    pub const ALL: [Method; 9] = [
        Method::SparseSvm,
        Method::RawSvm,
        Method::Ds,
        Method::Gs,
        Method::Du,
        Method::Gu,
        Method::KMeans,
        Method::Som,
        Method::RbfSvm,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Method::SparseSvm => "sparse-svm",
            Method::RawSvm => "raw-svm",
            Method::Ds => "ds",
            Method::Gs => "gs",
            Method::Du => "du",
            Method::Gu => "gu",
            Method::KMeans => "kmeans",
            Method::Som => "som",
            Method::RbfSvm => "rbf-svm",
        }
    }

    pub fn title(self) -> &'static str {
        match self {
            Method::SparseSvm => "sparse coding + SVM",
            Method::RawSvm => "raw linear SVM",
            Method::Ds => "DS",
            Method::Gs => "GS",
            Method::Du => "DU",
            Method::Gu => "GU",
            Method::KMeans => "k-means",
            Method::Som => "SOM",
            Method::RbfSvm => "RBF SVM",
        }
    }

    pub fn family(self) -> Family {
        match self {
            Method::SparseSvm | Method::RawSvm => Family::Stability,
            _ => Family::Recognition,
        }
    }

    /// k-means, the SOM and the RBF SVM work on per-grasp features, not sequences.
    fn uses_table(self) -> bool {
        matches!(self, Method::KMeans | Method::Som | Method::RbfSvm)
    }

    /// The score this method is measured by.
    pub fn score_name(self) -> &'static str {
        match self {
            Method::SparseSvm | Method::RawSvm => "weighted success rate",
            Method::Ds | Method::Gs => "accuracy (final 20%)",
            Method::Du | Method::Gu | Method::KMeans | Method::Som => "NMI",
            Method::RbfSvm => "accuracy (k-fold)",
        }
    }
}

impl FromStr for Method {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Method::ALL
            .into_iter()
            .find(|m| m.key() == s)
            .ok_or_else(|| {
                ExperimentError::param(
                    "methods",
                    format!(
                        "`{s}` is not one of {}",
                        Method::ALL.map(|m| m.key()).join(", ")
                    ),
                )
            })
    }
}

/// One axis of the sweep.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Perturbation {
    /// Gaussian noise on the raw readings (variance, iCub 0–255 scale).
    Noise,
    /// A share of taxels stuck at zero pressure.
    DeadTaxels,
    /// A share of taxels stuck at full-scale pressure.
    SaturatedTaxels,
    /// Whole sensors (fingers) stuck at zero pressure (a count).
    DeadSensor,
    /// A linear offset over the session (share of full scale at the last grasp).
    Drift,
    /// Pressures multiplied by a factor (a new sensor).
    Gain,
    /// Share of each test grasp kept (its beginning).
    Truncation,
    /// Share of each test grasp's frames dropped at random.
    MissingFrames,
    /// Stability: failures' share of the training set; recognition: share of their
    /// training grasps kept by half the classes (the minority).
    Imbalance,
    /// Training grasps per class.
    FewExamples,
    /// Share of the objects held out (never seen in training).
    NewObjects,
}

/// Where a perturbation acts.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Scope {
    /// Every grasp, training and test.
    All,
    /// Only the grasps a model is tested on, after learning on clean ones.
    Test,
    /// Which grasps a model learns from (the data are clean).
    Training,
}

impl Perturbation {
    pub const ALL: [Perturbation; 11] = [
        Perturbation::Noise,
        Perturbation::DeadTaxels,
        Perturbation::SaturatedTaxels,
        Perturbation::DeadSensor,
        Perturbation::Drift,
        Perturbation::Gain,
        Perturbation::Truncation,
        Perturbation::MissingFrames,
        Perturbation::Imbalance,
        Perturbation::FewExamples,
        Perturbation::NewObjects,
    ];

    pub fn key(self) -> &'static str {
        match self {
            Perturbation::Noise => "noise",
            Perturbation::DeadTaxels => "dead-taxels",
            Perturbation::SaturatedTaxels => "saturated-taxels",
            Perturbation::DeadSensor => "dead-sensor",
            Perturbation::Drift => "drift",
            Perturbation::Gain => "gain",
            Perturbation::Truncation => "truncation",
            Perturbation::MissingFrames => "missing-frames",
            Perturbation::Imbalance => "imbalance",
            Perturbation::FewExamples => "few-examples",
            Perturbation::NewObjects => "new-objects",
        }
    }

    /// The session perturbation behind it (None for the protocol ones).
    pub fn session_kind(self) -> Option<PerturbationKind> {
        Some(match self {
            Perturbation::Noise => PerturbationKind::Noise,
            Perturbation::DeadTaxels => PerturbationKind::DeadTaxels { stuck: Stuck::Zero },
            Perturbation::SaturatedTaxels => PerturbationKind::DeadTaxels { stuck: Stuck::Max },
            Perturbation::DeadSensor => PerturbationKind::DeadSensor { stuck: Stuck::Zero },
            Perturbation::Drift => PerturbationKind::Drift,
            Perturbation::Gain => PerturbationKind::Gain,
            Perturbation::Truncation => PerturbationKind::Truncation,
            Perturbation::MissingFrames => PerturbationKind::MissingFrames,
            _ => return None,
        })
    }

    pub fn scope(self) -> Scope {
        match self {
            Perturbation::Noise => Scope::All,
            Perturbation::Imbalance | Perturbation::FewExamples | Perturbation::NewObjects => {
                Scope::Training
            }
            _ => Scope::Test,
        }
    }

    /// The strength at which nothing changes (None where the clean protocol is not a point
    /// of the sweep's axis).
    pub fn neutral(self) -> Option<f64> {
        self.session_kind().map(PerturbationKind::neutral)
    }

    /// Axis title and unit of the strength.
    pub fn strength_title(self, family: Family) -> (&'static str, &'static str) {
        if let Some(k) = self.session_kind() {
            return k.strength_title();
        }
        match (self, family) {
            (Perturbation::Imbalance, Family::Stability) => {
                ("failures' share of the training set", "fraction")
            }
            (Perturbation::Imbalance, Family::Recognition) => {
                ("training grasps kept by the minority classes", "fraction")
            }
            (Perturbation::FewExamples, _) => ("training grasps per class", "count"),
            _ => ("share of objects never seen in training", "fraction"),
        }
    }

    /// The default sweep, from mild to severe.
    pub fn default_strengths(self, family: Family) -> Vec<f64> {
        match (self, family) {
            (Perturbation::Noise, _) => {
                vec![25.0, 50.0, 100.0, 200.0, 400.0, 700.0, 1000.0, 1500.0]
            }
            (Perturbation::DeadTaxels | Perturbation::SaturatedTaxels, _) => {
                vec![0.05, 0.1, 0.2, 0.3, 0.5, 0.75]
            }
            (Perturbation::DeadSensor, _) => vec![1.0, 2.0],
            (Perturbation::Drift, _) => vec![0.01, 0.02, 0.05, 0.1, 0.2, 0.3],
            (Perturbation::Gain, _) => vec![1.1, 1.25, 1.5, 2.0, 3.0],
            (Perturbation::Truncation, _) => vec![0.9, 0.8, 0.6, 0.4, 0.2, 0.1],
            (Perturbation::MissingFrames, _) => vec![0.1, 0.2, 0.4, 0.6, 0.8],
            (Perturbation::Imbalance, Family::Stability) => vec![0.4, 0.3, 0.2, 0.1, 0.05],
            (Perturbation::Imbalance, Family::Recognition) => vec![0.5, 0.25, 0.1, 0.05],
            (Perturbation::FewExamples, Family::Stability) => {
                vec![200.0, 100.0, 50.0, 20.0, 10.0, 5.0, 2.0]
            }
            (Perturbation::FewExamples, Family::Recognition) => {
                vec![10.0, 5.0, 3.0, 2.0, 1.0]
            }
            (Perturbation::NewObjects, _) => vec![0.1, 0.2, 0.3, 0.5, 0.7, 0.9],
        }
    }

    /// Check one strength of a protocol perturbation (session ones are checked by
    /// [`PerturbParams::validate`]).
    fn check_protocol_strength(self, s: f64) -> Result<(), ExperimentError> {
        let bad = |why: &str| {
            Err(ExperimentError::param(
                "strengths",
                format!("{}: {why}, got {s}", self.key()),
            ))
        };
        match self {
            Perturbation::Imbalance if !(s > 0.0 && s <= 1.0) => bad("a share in (0, 1]"),
            Perturbation::FewExamples if !(s >= 1.0 && s.fract() == 0.0 && s.is_finite()) => {
                bad("a whole number of grasps ≥ 1")
            }
            Perturbation::NewObjects if !(s > 0.0 && s < 1.0) => bad("a share in (0, 1)"),
            _ => Ok(()),
        }
    }
}

impl FromStr for Perturbation {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Perturbation::ALL
            .into_iter()
            .find(|p| p.key() == s)
            .ok_or_else(|| {
                ExperimentError::param(
                    "perturbations",
                    format!(
                        "`{s}` is not one of {}",
                        Perturbation::ALL.map(|p| p.key()).join(", ")
                    ),
                )
            })
    }
}

/// One perturbation and its strengths (from mild to severe).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Sweep {
    pub perturbation: Perturbation,
    pub strengths: Vec<f64>,
}

/// The grasp-stability pipeline's fixed configuration.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct StabilitySetup {
    /// The default is BTS3's recommended (parsimonious) model of the `default` grid
    /// selected by 10-fold (docs/grasp-stability.md): K = 27, beta = gamma = 0.25.
    pub config: Config,
    /// Stratified folds of the protocol (the paper: 10).
    pub folds: usize,
    pub settings: PipelineSettings,
    pub data: DataOptions,
}

impl Default for StabilitySetup {
    fn default() -> Self {
        StabilitySetup {
            config: Config {
                num_bases: 27,
                beta: 0.25,
                gamma: 0.25,
            },
            folds: 10,
            settings: PipelineSettings::default(),
            data: DataOptions::default(),
        }
    }
}

/// The recognition family's settings: DS/GS as [`super::recognition::RecognitionParams`],
/// DU/GU as [`super::clustering::ClusteringParams`] at one threshold, and the baselines.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecognitionSetup {
    pub features: FeatureSet,
    pub test_fraction: f64,
    pub label_set: String,
    pub ds: DsParams,
    pub gs: GsParams,
    /// DU's and GU's novelty thresholds (defaults chosen on the sample iCub session, where
    /// they give the most informative partition of a 0.05–0.95 sweep: DU 0.2, 42
    /// effective clusters, NMI 0.39; GU 0.02, 11.4 effective clusters, NMI 0.83 over 5
    /// orders).
    pub du_threshold: f64,
    pub gu_threshold: f64,
    pub gu_aggregate: GuAggregate,
    /// GU's clusters take part in the re-assignment once trained on this many grasps
    /// (`GuParams::min_grasps`); files saved before it existed kept every cluster.
    #[serde(default = "every_gu_cluster")]
    pub gu_min_grasps: usize,
    /// Clusters / SOM units of k-means and the SOM (None: the number of classes).
    pub clusters: Option<usize>,
    /// The RBF SVM (the baselines' default C = 10, gamma = 0.01 on z-scored features).
    pub svm: KernelSvmParams,
    pub svm_folds: usize,
}

impl Default for RecognitionSetup {
    fn default() -> Self {
        RecognitionSetup {
            features: FeatureSet::All,
            test_fraction: 0.2,
            label_set: "object".into(),
            ds: DsParams::default(),
            gs: GsParams::default(),
            du_threshold: 0.2,
            gu_threshold: 0.02,
            gu_aggregate: GuAggregate::Mean,
            gu_min_grasps: GuParams::default().min_grasps,
            clusters: None,
            svm: KernelSvmParams::default(),
            svm_folds: 5,
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RobustnessParams {
    pub family: Family,
    pub methods: Vec<Method>,
    pub sweeps: Vec<Sweep>,
    /// Repetitions per strength (seeded folds / orders / perturbations).
    pub reps: usize,
    /// The break point is where the mean score falls below this share of the clean score.
    pub fraction: f64,
    pub seed: u64,
    /// Clamp perturbed readings to the sensor's raw range.
    pub saturate: bool,
    pub stability: StabilitySetup,
    pub recognition: RecognitionSetup,
}

impl RobustnessParams {
    /// Every method and perturbation of `family` with their default strengths.
    pub fn defaults(family: Family) -> Self {
        RobustnessParams {
            family,
            methods: family.methods(),
            sweeps: Perturbation::ALL
                .iter()
                .filter(|p| family == Family::Stability || **p != Perturbation::NewObjects)
                .map(|&p| Sweep {
                    perturbation: p,
                    strengths: p.default_strengths(family),
                })
                .collect(),
            reps: 5,
            fraction: 0.9,
            seed: 0,
            saturate: true,
            stability: StabilitySetup::default(),
            recognition: RecognitionSetup::default(),
        }
    }

    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.reps == 0 {
            return Err(ExperimentError::param("reps", "must be at least 1"));
        }
        if !(self.fraction > 0.0 && self.fraction <= 1.0) {
            return Err(ExperimentError::param(
                "fraction",
                format!("must lie in (0, 1], got {}", self.fraction),
            ));
        }
        if self.methods.is_empty() {
            return Err(ExperimentError::param(
                "methods",
                "name at least one method",
            ));
        }
        if let Some(m) = self.methods.iter().find(|m| m.family() != self.family) {
            return Err(ExperimentError::param(
                "methods",
                format!(
                    "{} does not belong to the {:?} family",
                    m.key(),
                    self.family
                ),
            ));
        }
        if self.sweeps.is_empty() {
            return Err(ExperimentError::param(
                "perturbations",
                "name at least one perturbation",
            ));
        }
        for sw in &self.sweeps {
            if sw.strengths.is_empty() {
                return Err(ExperimentError::param(
                    "strengths",
                    format!("{}: no strengths", sw.perturbation.key()),
                ));
            }
            for &s in &sw.strengths {
                match sw.perturbation.session_kind() {
                    Some(kind) => PerturbParams::new(kind, s, 0).validate()?,
                    None => sw.perturbation.check_protocol_strength(s)?,
                }
            }
        }
        let st = &self.stability;
        if st.folds < 2 {
            return Err(ExperimentError::param("folds", "must be at least 2"));
        }
        if st.config.num_bases == 0 {
            return Err(ExperimentError::param("num_bases", "must be at least 1"));
        }
        for (name, v) in [("beta", st.config.beta), ("gamma", st.config.gamma)] {
            if !(v > 0.0 && v.is_finite()) {
                return Err(ExperimentError::param(
                    name,
                    format!("must be finite and > 0, got {v}"),
                ));
            }
        }
        st.settings
            .svm
            .validate()
            .map_err(|e| ExperimentError::param("svm", e.to_string()))?;
        let rc = &self.recognition;
        if !(rc.test_fraction > 0.0 && rc.test_fraction < 1.0) {
            return Err(ExperimentError::param(
                "test_fraction",
                "must lie in (0, 1)",
            ));
        }
        rc.ds.validate()?;
        rc.gs.validate()?;
        for (name, t) in [
            ("du_threshold", rc.du_threshold),
            ("gu_threshold", rc.gu_threshold),
        ] {
            if !(0.0..=1.0).contains(&t) {
                return Err(ExperimentError::param(
                    name,
                    format!("must lie in [0, 1], got {t}"),
                ));
            }
        }
        if rc.gu_min_grasps == 0 {
            return Err(ExperimentError::param(
                "gu_min_grasps",
                "must be at least 1",
            ));
        }
        if rc.clusters == Some(0) {
            return Err(ExperimentError::param("clusters", "must be at least 1"));
        }
        if rc.svm_folds < 2 {
            return Err(ExperimentError::param("svm_folds", "must be at least 2"));
        }
        rc.svm
            .validate()
            .map_err(|e| ExperimentError::param("svm", e.to_string()))?;
        Ok(())
    }
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
    pub method: Method,
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
    pub method: Method,
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
    pub fn curve(&self, method: Method, perturbation: Perturbation) -> Option<&Curve> {
        self.curves
            .iter()
            .find(|c| c.method == method && c.perturbation == perturbation)
    }

    pub fn clean_score(&self, method: Method) -> Option<f64> {
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

// ---------------------------------------------------------------------------------------
// The run
// ---------------------------------------------------------------------------------------

/// What every task of a run shares, prepared once per run (or once per shard of a sweep).
pub struct Prepared {
    kind: PreparedKind,
}

enum PreparedKind {
    Stability(Box<StabilityPrep>),
    Recognition(Box<RecognitionPrep>),
}

struct StabilityPrep {
    data: StabilityData,
    dictionary: Dictionary,
    /// Clean grasp features of each method.
    sparse: Array2<f64>,
    raw: Array2<f64>,
}

struct RecognitionPrep {
    clean: FeatureSequences,
    labels: Vec<usize>,
    n_classes: usize,
    /// The clean per-grasp Table I features and their z-scoring (when a baseline runs).
    table: Option<(Array2<f64>, Normaliser)>,
}

/// A task: the clean protocol (`sweep` None) or one strength of one sweep (indices into
/// the parameters' sweeps and their strengths), one repetition. Its seeds follow from the
/// run's seed and `rep`, so any machine computes it alike.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Task {
    pub sweep: Option<usize>,
    pub strength: usize,
    pub rep: usize,
}

/// A task's score for each method (in the parameters' order) and its seconds.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct TaskScores {
    pub scores: Vec<f64>,
    pub seconds: f64,
}

/// Stream indices: the folds / order of repetition r use stream r; these offsets keep the
/// other random choices of the same repetition independent of them.
const PERTURB_STREAM: u64 = 1 << 40;
const PROTOCOL_STREAM: u64 = 2 << 40;
const CLUSTER_STREAM: u64 = 3 << 40;
const SVM_STREAM: u64 = 4 << 40;

fn cluster_err(e: ClusterError) -> ExperimentError {
    ExperimentError::Data(e.to_string())
}

/// The run's tasks, in order: the clean protocol's repetitions, then every applicable
/// sweep's strengths and repetitions. Checks the parameters against the session first.
pub fn robustness_tasks(
    session: &Session,
    params: &RobustnessParams,
) -> Result<Vec<Task>, ExperimentError> {
    params.validate()?;
    if let Some(sw) = params
        .sweeps
        .iter()
        .find(|sw| sw.perturbation == Perturbation::DeadSensor)
        && let Some(&s) = sw
            .strengths
            .iter()
            .find(|&&s| s as usize > session.sensors.len())
    {
        return Err(ExperimentError::param(
            "strengths",
            format!(
                "dead-sensor: {s} sensors, but the session has {}",
                session.sensors.len()
            ),
        ));
    }
    let mut tasks: Vec<Task> = (0..params.reps)
        .map(|rep| Task {
            sweep: None,
            strength: 0,
            rep,
        })
        .collect();
    for (i, sw) in params.sweeps.iter().enumerate() {
        if applicability(session, params.family, sw.perturbation).is_some() {
            continue;
        }
        for s in 0..sw.strengths.len() {
            for rep in 0..params.reps {
                tasks.push(Task {
                    sweep: Some(i),
                    strength: s,
                    rep,
                });
            }
        }
    }
    Ok(tasks)
}

/// Run every sweep. Cancellable between tasks; `progress` gets the share of tasks done.
pub fn run_robustness(
    session: &Session,
    params: &RobustnessParams,
    progress: &Progress,
) -> Result<RobustnessResult, ExperimentError> {
    let tasks = robustness_tasks(session, params)?;
    let start = Instant::now();
    progress.set(0.0, "robustness: preparing");
    let prepared = prepare(session, params, progress)?;
    let setup_seconds = start.elapsed().as_secs_f64();
    let total = tasks.len();
    let done = AtomicUsize::new(0);
    let results = tasks
        .par_iter()
        .map(|t| {
            progress.checkpoint()?;
            let r = robustness_task(session, params, &prepared, *t)?;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set(
                d as f64 / total as f64,
                format!("robustness: {d}/{total} runs"),
            );
            Ok(r)
        })
        .collect::<Result<Vec<_>, ExperimentError>>()?;
    progress.set(1.0, format!("robustness: {total}/{total} runs done"));
    Ok(assemble_robustness(
        session,
        params,
        &tasks,
        &results,
        setup_seconds,
        start.elapsed().as_secs_f64(),
        rayon::current_num_threads(),
    ))
}

/// The curves, clean scores and break points from the tasks' scores (in `tasks` order).
pub fn assemble_robustness(
    session: &Session,
    params: &RobustnessParams,
    tasks: &[Task],
    results: &[TaskScores],
    setup_seconds: f64,
    wall_seconds: f64,
    threads: usize,
) -> RobustnessResult {
    let not_applicable: Vec<Option<String>> = params
        .sweeps
        .iter()
        .map(|sw| applicability(session, params.family, sw.perturbation))
        .collect();
    // Assemble: results follow `tasks` order.
    let m = params.methods.len();
    let scores_of = |pred: &dyn Fn(&Task) -> bool, method: usize| -> (Vec<f64>, f64) {
        let mut v = Vec::new();
        let mut secs = 0.0;
        for (t, r) in tasks.iter().zip(results) {
            if pred(t) {
                v.push(r.scores[method]);
                secs += r.seconds / m as f64;
            }
        }
        (v, secs)
    };
    let clean: Vec<CleanScore> = params
        .methods
        .iter()
        .enumerate()
        .map(|(mi, &method)| {
            let (scores, _) = scores_of(&|t: &Task| t.sweep.is_none(), mi);
            CleanScore {
                method,
                score: MeanSd::of(scores.iter().copied()),
                scores,
            }
        })
        .collect();
    let mut curves = Vec::new();
    for (si, sw) in params.sweeps.iter().enumerate() {
        for (mi, &method) in params.methods.iter().enumerate() {
            let clean_mean = clean[mi].score.mean;
            let mut points = Vec::new();
            let mut task_seconds = 0.0;
            if not_applicable[si].is_none() {
                for (k, &strength) in sw.strengths.iter().enumerate() {
                    let (scores, secs) =
                        scores_of(&|t: &Task| t.sweep == Some(si) && t.strength == k, mi);
                    task_seconds += secs;
                    let score = MeanSd::of(scores.iter().copied());
                    points.push(SweepPoint {
                        strength,
                        relative: (clean_mean > 0.0).then(|| score.mean / clean_mean),
                        score,
                        scores,
                    });
                }
            }
            let xy: Vec<(f64, f64)> = points.iter().map(|p| (p.strength, p.score.mean)).collect();
            curves.push(Curve {
                method,
                perturbation: sw.perturbation,
                scope: sw.perturbation.scope(),
                not_applicable: not_applicable[si].clone(),
                break_point: break_point(
                    sw.perturbation.neutral(),
                    clean_mean,
                    &xy,
                    params.fraction,
                ),
                points,
                task_seconds,
            });
        }
    }
    RobustnessResult {
        params: params.clone(),
        session: session.meta.name.clone(),
        score_name: params.family.score_name().into(),
        clean,
        curves,
        setup_seconds,
        wall_seconds,
        threads,
    }
}

/// Why a perturbation cannot be applied to this session and family (None: it can).
fn applicability(session: &Session, family: Family, p: Perturbation) -> Option<String> {
    let one_frame = session.grasps.iter().all(|g| g.frames.len() <= 1);
    match p {
        Perturbation::Truncation | Perturbation::MissingFrames if one_frame => Some(
            "every grasp is a single frame: there is no sequence to cut or frames to drop".into(),
        ),
        Perturbation::NewObjects if family == Family::Recognition => Some(
            "each object is its own class here: a never-seen object is a class the model was never taught".into(),
        ),
        _ => None,
    }
}

/// Prepare what every task shares: the stability data and its clean dictionary, or the
/// clean feature sequences and labels.
pub fn prepare(
    session: &Session,
    params: &RobustnessParams,
    progress: &Progress,
) -> Result<Prepared, ExperimentError> {
    let kind = match params.family {
        Family::Stability => {
            let st = &params.stability;
            let data = StabilityData::from_session(session, &st.data)?;
            let dictionary = learn_dictionary(&data, st, progress)?;
            let (sparse, raw) = stability_features(&data, &dictionary, st.config.gamma)?;
            PreparedKind::Stability(Box::new(StabilityPrep {
                data,
                dictionary,
                sparse,
                raw,
            }))
        }
        Family::Recognition => {
            let rc = &params.recognition;
            let (labels, classes) = session_labels(session, &rc.label_set)?;
            let clean = feature_sequences(
                session,
                &SequenceParams {
                    features: rc.features,
                    taxel_noise_variance: 0.0,
                    seed: params.seed,
                },
            )?;
            let table = if params.methods.iter().any(|m| m.uses_table()) {
                let raw = session_features(session).map_err(cluster_err)?;
                let norm =
                    Normaliser::fit(Normalisation::ZScore, raw.view()).map_err(cluster_err)?;
                Some((norm.transform(raw.view()).map_err(cluster_err)?, norm))
            } else {
                None
            };
            PreparedKind::Recognition(Box::new(RecognitionPrep {
                clean,
                labels,
                n_classes: classes.len(),
                table,
            }))
        }
    };
    Ok(Prepared { kind })
}

/// One task's scores, timed.
pub fn robustness_task(
    session: &Session,
    params: &RobustnessParams,
    prepared: &Prepared,
    task: Task,
) -> Result<TaskScores, ExperimentError> {
    let t0 = Instant::now();
    let scores = run_task(session, params, prepared, task)?;
    Ok(TaskScores {
        scores,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn run_task(
    session: &Session,
    params: &RobustnessParams,
    prepared: &Prepared,
    task: Task,
) -> Result<Vec<f64>, ExperimentError> {
    let sweep = task.sweep.map(|i| &params.sweeps[i]);
    let pert = sweep.map(|sw| (sw.perturbation, sw.strengths[task.strength]));
    // The perturbed session, where the perturbation acts on the data.
    let perturbed = match pert.and_then(|(p, s)| p.session_kind().map(|k| (k, s))) {
        Some((kind, strength)) => Some(perturb(
            session,
            &PerturbParams {
                kind,
                strength,
                seed: Rng::stream(params.seed, PERTURB_STREAM + task.rep as u64).next_u64(),
                saturate: params.saturate,
            },
        )?),
        None => None,
    };
    match &prepared.kind {
        PreparedKind::Stability(prep) => {
            stability_task(params, prep, pert, perturbed.as_ref(), task.rep)
        }
        PreparedKind::Recognition(prep) => {
            recognition_task(params, prep, pert, perturbed.as_ref(), task.rep)
        }
    }
}

// ---------------------------------------------------------------------------------------
// Grasp stability
// ---------------------------------------------------------------------------------------

fn learn_dictionary(
    data: &StabilityData,
    st: &StabilitySetup,
    progress: &Progress,
) -> Result<Dictionary, ExperimentError> {
    let params = DictionaryParams {
        num_bases: st.config.num_bases,
        beta: st.config.beta,
        ..st.settings.dictionary.clone()
    };
    params
        .validate()
        .map_err(|e| ExperimentError::param("dictionary", e.to_string()))?;
    let fit = params
        .fit_within(data.x.view(), progress)
        .map_err(StabilityError::from)?;
    Ok(fit.dictionary)
}

/// Grasp features of both methods from scaled key-frame images (grasps × sensors·dim).
fn features_of_images(
    images: Array2<f64>,
    sensors: usize,
    dim: usize,
    dictionary: &Dictionary,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    let g = images.nrows();
    // One grasp's image is its sensors' patches side by side: a view, not a copy.
    let patches = images
        .view()
        .into_shape_with_order((g * sensors, dim))
        .map_err(|e| ExperimentError::Data(e.to_string()))?;
    let codes = dictionary
        .encode(patches, gamma)
        .map_err(StabilityError::from)?;
    Ok((grasp_features(codes, sensors), images))
}

fn stability_features(
    data: &StabilityData,
    dictionary: &Dictionary,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    features_of_images(
        data.images(),
        data.sensor_count(),
        data.dim(),
        dictionary,
        gamma,
    )
}

/// A perturbed session's features under the clean session's scaling and dictionary.
fn stability_features_scaled_as(
    prep: &StabilityPrep,
    perturbed: &Session,
    gamma: f64,
) -> Result<(Array2<f64>, Array2<f64>), ExperimentError> {
    let pressures = KeyFramePatches::from_session(perturbed, PatchScaling::None)
        .map_err(StabilityError::from)?
        .pressures;
    let images = match &prep.data.patches.scaler {
        Some(s) => s.transform(pressures.view()),
        None => pressures,
    };
    features_of_images(
        images,
        prep.data.sensor_count(),
        prep.data.dim(),
        &prep.dictionary,
        gamma,
    )
}

/// Train on `train` rows of (`train_x`, labels), predict `test` rows of `test_x`.
fn svm_confusion(
    train_x: &Array2<f64>,
    test_x: &Array2<f64>,
    labels: &[bool],
    train: &[usize],
    test: &[usize],
    svm: &LinearSvmParams,
) -> Result<Confusion, ExperimentError> {
    let xt = gather(train_x.view(), train);
    let yt: Vec<bool> = train.iter().map(|&i| labels[i]).collect();
    let model = svm
        .fit(xt.view(), &yt)
        .map_err(|e| ExperimentError::Data(format!("SVM: {e}")))?;
    let truth: Vec<bool> = test.iter().map(|&i| labels[i]).collect();
    let pred: Vec<bool> = test.iter().map(|&i| model.predict(test_x.row(i))).collect();
    Ok(Confusion::from_predictions(&truth, &pred))
}

/// Keep `train` grasps so that failures make `share` of them (every success kept; at least
/// one failure); unchanged when failures are already that rare.
fn imbalance_train(train: &[usize], labels: &[bool], share: f64, rng: &mut Rng) -> Vec<usize> {
    let (mut fail, succ): (Vec<usize>, Vec<usize>) = train.iter().partition(|&&i| labels[i]);
    let want = if share >= 1.0 {
        fail.len()
    } else {
        ((share / (1.0 - share) * succ.len() as f64).round() as usize).max(1)
    };
    if want < fail.len() {
        rng.shuffle(&mut fail);
        fail.truncate(want);
    }
    let mut out: Vec<usize> = succ.into_iter().chain(fail).collect();
    out.sort_unstable();
    out
}

/// At most `n` grasps of each class of `train`, chosen at random.
fn few_train(train: &[usize], classes: &[usize], n: usize, rng: &mut Rng) -> Vec<usize> {
    let mut order = train.to_vec();
    rng.shuffle(&mut order);
    let mut count = std::collections::BTreeMap::<usize, usize>::new();
    let mut out: Vec<usize> = order
        .into_iter()
        .filter(|&i| {
            let c = count.entry(classes[i]).or_insert(0);
            *c += 1;
            *c <= n
        })
        .collect();
    out.sort_unstable();
    out
}

fn stability_task(
    params: &RobustnessParams,
    prep: &StabilityPrep,
    pert: Option<(Perturbation, f64)>,
    perturbed: Option<&Session>,
    rep: usize,
) -> Result<Vec<f64>, ExperimentError> {
    let st = &params.stability;
    let gamma = st.config.gamma;
    let labels = &prep.data.labels;
    let rep_seed = Rng::stream(params.seed, rep as u64).next_u64();
    let mut rng = Rng::stream(params.seed, PROTOCOL_STREAM + rep as u64);
    // (train features, test features) of both methods.
    let owned;
    let (train_sparse, train_raw, test_sparse, test_raw) = match (pert, perturbed) {
        (Some((p, _)), Some(ps)) if p.scope() == Scope::All => {
            // The sensor is noisy all along: the session's scaling and dictionary are
            // learned on what it recorded.
            let data = StabilityData::from_session(ps, &st.data)?;
            // A task's own progress: cancellation is checked between tasks (each well
            // under a second), and the run's progress counts tasks, not iterations.
            let dict = learn_dictionary(&data, st, &Progress::new())?;
            owned = [stability_features(&data, &dict, gamma)?];
            (&owned[0].0, &owned[0].1, &owned[0].0, &owned[0].1)
        }
        (_, Some(ps)) => {
            owned = [stability_features_scaled_as(prep, ps, gamma)?];
            (&prep.sparse, &prep.raw, &owned[0].0, &owned[0].1)
        }
        _ => (&prep.sparse, &prep.raw, &prep.sparse, &prep.raw),
    };
    let mut confusion = [Confusion::default(), Confusion::default()];
    let mut add = |train: &[usize], test: &[usize]| -> Result<(), ExperimentError> {
        let c0 = svm_confusion(
            train_sparse,
            test_sparse,
            labels,
            train,
            test,
            &st.settings.svm,
        )?;
        let c1 = svm_confusion(train_raw, test_raw, labels, train, test, &st.settings.svm)?;
        confusion[0].add(&c0);
        confusion[1].add(&c1);
        Ok(())
    };
    if let Some((Perturbation::NewObjects, share)) = pert {
        let (train, test) = hold_out_objects(&prep.data, share, &mut rng)?;
        add(&train, &test)?;
    } else {
        let folds = stratified_k_fold(labels, st.folds, rep_seed)
            .map_err(|e| ExperimentError::Data(e.to_string()))?;
        let classes: Vec<usize> = labels.iter().map(|&l| l as usize).collect();
        for f in 0..folds.count {
            let mut train = folds.train_indices(f);
            match pert {
                Some((Perturbation::Imbalance, share)) => {
                    train = imbalance_train(&train, labels, share, &mut rng);
                }
                Some((Perturbation::FewExamples, n)) => {
                    train = few_train(&train, &classes, n as usize, &mut rng);
                }
                _ => {}
            }
            add(&train, &folds.test_indices(f))?;
        }
    }
    Ok(params
        .methods
        .iter()
        .map(|m| {
            let c = match m {
                Method::SparseSvm => &confusion[0],
                _ => &confusion[1],
            };
            c.weighted_success_rate().unwrap_or(0.0)
        })
        .collect())
}

/// Hold out round(share · objects) objects (at least one, and at least one left to learn
/// from), drawn until the held-out grasps hold both outcomes.
fn hold_out_objects(
    data: &StabilityData,
    share: f64,
    rng: &mut Rng,
) -> Result<(Vec<usize>, Vec<usize>), ExperimentError> {
    let n_obj = data.object_names.len();
    if n_obj < 2 {
        return Err(ExperimentError::Data(
            "new-objects needs at least two objects".into(),
        ));
    }
    let n_held = ((share * n_obj as f64).round() as usize).clamp(1, n_obj - 1);
    for _ in 0..1000 {
        let perm = rng.permutation(n_obj);
        let mut held = vec![false; n_obj];
        for &o in &perm[..n_held] {
            held[o] = true;
        }
        let (test, train): (Vec<usize>, Vec<usize>) =
            (0..data.grasp_count()).partition(|&g| held[data.objects[g]]);
        let both = |idx: &[usize]| {
            idx.iter().any(|&g| data.labels[g]) && idx.iter().any(|&g| !data.labels[g])
        };
        if both(&test) && both(&train) {
            return Ok((train, test));
        }
    }
    Err(ExperimentError::Data(format!(
        "no draw of {n_held} held-out objects gives both outcomes on each side"
    )))
}

// ---------------------------------------------------------------------------------------
// Object recognition (DS, GS)
// ---------------------------------------------------------------------------------------

/// Express `perturbed` (normalised on itself) in the clean session's normalisation, as a
/// model calibrated on the clean session would see it.
fn renormalise(perturbed: &FeatureSequences, clean: &FeatureSequences) -> FeatureSequences {
    let mut out = perturbed.clone();
    for m in &mut out.sequences {
        for mut row in m.rows_mut() {
            for (j, v) in row.iter_mut().enumerate() {
                let raw = perturbed.min[j] + *v * (perturbed.max[j] - perturbed.min[j]);
                let range = clean.max[j] - clean.min[j];
                *v = if range > 0.0 {
                    (raw - clean.min[j]) / range
                } else {
                    0.0
                };
            }
        }
    }
    out.min = clean.min.clone();
    out.max = clean.max.clone();
    out
}

fn recognition_task(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    pert: Option<(Perturbation, f64)>,
    perturbed: Option<&Session>,
    rep: usize,
) -> Result<Vec<f64>, ExperimentError> {
    let rc = &params.recognition;
    let scope = pert.map(|(p, _)| p.scope());
    let sequences = params.methods.iter().any(|m| !m.uses_table());
    let feats = match perturbed {
        Some(ps) if sequences => {
            let f = feature_sequences(
                ps,
                &SequenceParams {
                    features: rc.features,
                    taxel_noise_variance: 0.0,
                    seed: params.seed,
                },
            )?;
            Some(if scope == Some(Scope::All) {
                f
            } else {
                renormalise(&f, &prep.clean)
            })
        }
        _ => None,
    };
    let train_seqs = match (&feats, scope) {
        (Some(f), Some(Scope::All)) => f,
        _ => &prep.clean,
    };
    let test_seqs = feats.as_ref().unwrap_or(&prep.clean);
    // Table I features: (training rows, test rows), z-scored as the clean session unless
    // the perturbation is there all along.
    let table = match (&prep.table, perturbed) {
        (Some((clean, norm)), Some(ps)) => {
            let raw = session_features(ps).map_err(cluster_err)?;
            if scope == Some(Scope::All) {
                let own = Normaliser::fit(Normalisation::ZScore, raw.view())
                    .and_then(|n| n.transform(raw.view()))
                    .map_err(cluster_err)?;
                Some((own.clone(), own))
            } else {
                let t = norm.transform(raw.view()).map_err(cluster_err)?;
                Some((clean.clone(), t))
            }
        }
        (Some((clean, _)), None) => Some((clean.clone(), clean.clone())),
        _ => None,
    };
    // The same order as `run_recognition`'s repetition `rep` (without noise).
    let mut rng = Rng::stream(params.seed, rep as u64);
    let (teach, order) = protocol_order(&prep.labels, prep.n_classes, &mut rng);
    let n_test = ((rc.test_fraction * order.len() as f64).round() as usize).min(order.len());
    let n_train = order.len() - n_test;
    let mut aux = Rng::stream(params.seed, PROTOCOL_STREAM + rep as u64);
    let keep = training_kept(
        pert,
        &prep.labels,
        prep.n_classes,
        &order[..n_train],
        true,
        &mut aux,
    );
    // The unsupervised methods learn from every grasp; a training perturbation leaves
    // them the same subset of grasps as it leaves the supervised ones to learn from.
    let all: Vec<usize> = (0..prep.labels.len()).collect();
    let kept_all = training_kept(pert, &prep.labels, prep.n_classes, &all, false, &mut aux);
    let subset: Vec<usize> = all.iter().copied().filter(|&g| kept_all[g]).collect();
    let sub_labels: Vec<usize> = subset.iter().map(|&g| prep.labels[g]).collect();
    // The subset's sequences, copied once for DU and GU.
    let sub_seqs: Vec<Array2<f64>> =
        if (params.methods.iter()).any(|m| matches!(m, Method::Du | Method::Gu)) {
            subset
                .iter()
                .map(|&g| test_seqs.sequences[g].clone())
                .collect()
        } else {
            Vec::new()
        };
    let k = rc.clusters.unwrap_or(prep.n_classes);
    let cluster_seed = Rng::stream(params.seed, CLUSTER_STREAM + rep as u64).next_u64();
    let mut out = Vec::with_capacity(params.methods.len());
    for &method in &params.methods {
        let score = match method {
            Method::Ds | Method::Gs => {
                let kind = if method == Method::Ds {
                    SupervisedLearner::Ds
                } else {
                    SupervisedLearner::Gs
                };
                supervised_score(
                    kind, rc, prep, train_seqs, test_seqs, &teach, &order, n_train, &keep,
                )?
            }
            Method::Du | Method::Gu => {
                let threshold = if method == Method::Du {
                    rc.du_threshold
                } else {
                    rc.gu_threshold
                };
                let cp = ClusteringParams {
                    learner: if method == Method::Du {
                        UnsupervisedLearner::Du
                    } else {
                        UnsupervisedLearner::Gu
                    },
                    features: rc.features,
                    thresholds: vec![threshold],
                    reps: 1,
                    seed: params.seed,
                    label_set: rc.label_set.clone(),
                    ds: rc.ds.clone(),
                    gs: rc.gs.clone(),
                    gu_aggregate: rc.gu_aggregate,
                    gu_min_grasps: rc.gu_min_grasps,
                    baseline_max_k: 0,
                    // The rest as the clustering experiment's defaults.
                    ..ClusteringParams::default()
                };
                one_run(&cp, &sub_seqs, &sub_labels, test_seqs.dim(), threshold, rep)?.nmi
            }
            Method::KMeans | Method::Som => {
                let Some((_, test)) = &table else {
                    return Err(ExperimentError::Data("no Table I features".into()));
                };
                let data = gather(test.view(), &subset);
                let pred = if method == Method::KMeans {
                    SequentialKMeansParams {
                        k,
                        passes: 1,
                        seed: cluster_seed,
                    }
                    .fit(data.view())
                    .and_then(|m| m.assign(data.view()))
                } else {
                    som_setup(k, cluster_seed)
                        .fit(data.view())
                        .and_then(|m| m.assign(data.view()))
                }
                .map_err(cluster_err)?;
                scores(&sub_labels, &pred).nmi
            }
            Method::RbfSvm => {
                let Some((train_x, test_x)) = &table else {
                    return Err(ExperimentError::Data("no Table I features".into()));
                };
                rbf_accuracy(params, prep, train_x, test_x, pert, rep)?
            }
            Method::SparseSvm | Method::RawSvm => {
                return Err(ExperimentError::param(
                    "methods",
                    format!("{} is a grasp-stability method", method.key()),
                ));
            }
        };
        out.push(score);
    }
    Ok(out)
}

/// DS or GS through the supervised protocol: teach one grasp per class, then predict and
/// learn the training part (the grasps `keep` leaves), then predict the test part.
#[allow(clippy::too_many_arguments)]
fn supervised_score(
    kind: SupervisedLearner,
    rc: &RecognitionSetup,
    prep: &RecognitionPrep,
    train_seqs: &FeatureSequences,
    test_seqs: &FeatureSequences,
    teach: &[usize],
    order: &[usize],
    n_train: usize,
    keep: &[bool],
) -> Result<f64, ExperimentError> {
    let mut learner = new_learner(kind, prep.clean.dim(), prep.n_classes, &rc.ds, &rc.gs)?;
    for &g in teach {
        learner.train_sequence(train_seqs.sequences[g].view(), prep.labels[g]);
    }
    let mut hits = 0usize;
    for (i, &g) in order.iter().enumerate() {
        let is_test = i >= n_train;
        if !is_test && !keep[i] {
            continue;
        }
        let seqs = if is_test { test_seqs } else { train_seqs };
        let seq = seqs.sequences[g].view();
        let dist = learner.predict_sequence(seq);
        if is_test {
            hits += usize::from(learner.decide(dist.view()) == prep.labels[g]);
        } else {
            learner.train_sequence(seq, prep.labels[g]);
        }
    }
    let n_test = order.len() - n_train;
    Ok(if n_test > 0 {
        hits as f64 / n_test as f64
    } else {
        0.0
    })
}

/// Stratified k-fold accuracy of the RBF SVM: trained on `train_x` rows of the training
/// folds (thinned by a training perturbation), tested on `test_x` rows of the test fold.
fn rbf_accuracy(
    params: &RobustnessParams,
    prep: &RecognitionPrep,
    train_x: &Array2<f64>,
    test_x: &Array2<f64>,
    pert: Option<(Perturbation, f64)>,
    rep: usize,
) -> Result<f64, ExperimentError> {
    let rc = &params.recognition;
    let labels = &prep.labels;
    let fold_seed = Rng::stream(params.seed, rep as u64).next_u64();
    let fold_of = stratified_folds(labels, rc.svm_folds, fold_seed);
    let mut aux = Rng::stream(params.seed, SVM_STREAM + rep as u64);
    let svm_err = |e: crate::svm::kernel_svm::KernelSvmError| ExperimentError::Data(e.to_string());
    let mut correct = 0usize;
    for f in 0..rc.svm_folds {
        let train: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] != f).collect();
        let test: Vec<usize> = (0..labels.len()).filter(|&i| fold_of[i] == f).collect();
        let kept = training_kept(pert, labels, prep.n_classes, &train, false, &mut aux);
        let train: Vec<usize> = train
            .iter()
            .zip(&kept)
            .filter(|(_, k)| **k)
            .map(|(&i, _)| i)
            .collect();
        let y: Vec<usize> = train.iter().map(|&i| labels[i]).collect();
        let model = rc
            .svm
            .fit(gather(train_x.view(), &train).view(), &y)
            .map_err(svm_err)?;
        let pred = model
            .predict(gather(test_x.view(), &test).view())
            .map_err(svm_err)?;
        correct += test
            .iter()
            .zip(&pred)
            .filter(|(i, p)| labels[**i] == **p)
            .count();
    }
    Ok(correct as f64 / labels.len().max(1) as f64)
}

/// Which grasps of the training part are learned from: all, or those left by class
/// imbalance (half the classes, drawn at random, keep `share` of their training grasps)
/// or few examples (the first n of each class; n − 1 when one grasp per class was
/// `taught` before the training part).
fn training_kept(
    pert: Option<(Perturbation, f64)>,
    labels: &[usize],
    n_classes: usize,
    train_part: &[usize],
    taught: bool,
    rng: &mut Rng,
) -> Vec<bool> {
    let mut seen = vec![0usize; n_classes];
    let total: Vec<usize> = (0..n_classes)
        .map(|c| train_part.iter().filter(|&&g| labels[g] == c).count())
        .collect();
    let limit: Vec<usize> = match pert {
        Some((Perturbation::FewExamples, n)) => {
            vec![(n as usize).saturating_sub(usize::from(taught)); n_classes]
        }
        Some((Perturbation::Imbalance, share)) => {
            let mut classes: Vec<usize> = (0..n_classes).collect();
            rng.shuffle(&mut classes);
            let mut limit = total.clone();
            for &c in &classes[..n_classes / 2] {
                limit[c] = (share * total[c] as f64).round() as usize;
            }
            limit
        }
        _ => total,
    };
    train_part
        .iter()
        .map(|&g| {
            let c = labels[g];
            seen[c] += 1;
            seen[c] <= limit[c]
        })
        .collect()
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
