//! Speed–accuracy frontiers by model size: sweep a method's size knobs on one session,
//! score every size over seeded repetitions (mean and standard error), time its training
//! and its prediction, and recommend the cheapest size whose score is within one standard
//! error of the best ("model no more than a scene needs").
//!
//! Knobs: DS and GS — capacity (BV budget of every expert) × tau (kernel lags), scored by
//! the supervised protocol of [`super::recognition`]; sparse coding + SVM — `num_bases`,
//! each with its best (beta, gamma) of the given lists, scored by stratified 10-fold cross
//! validation repeated with seeded fold assignments (the dictionary is learned on all
//! patches without labels, as in the paper and the grid search); DU and GU — the novelty
//! threshold, scored by NMI over seeded orders with the effective clusters it leaves (the
//! runs of [`super::clustering`]); sequential k-means and the SOM — k centres / units on
//! the Table I features; the RBF SVM — C × gamma, scored by repeated stratified 5-fold
//! accuracy on the Table I features.
//!
//! A frontier is computed as work items (one repetition at one size, or one dictionary)
//! whose seeds follow from the run's seed and the item alone, so a sharded sweep
//! (`crate::sweep`) merges into exactly the local result.
//!
//! Cheapest means the least prediction time by default: a model is trained once (or, online,
//! on the grasps it is taught) but predicts at every observation for as long as it is used,
//! and for sparse coding + SVM the training time is dominated by the dictionary, an offline
//! cost. [`CostAxis::Training`] ranks by training time instead.

use std::str::FromStr;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use ndarray::Array2;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::ExperimentError;
use super::clustering::{
    ClusteringItem, ClusteringOutput, ClusteringParams, ClusteringPrep, ClusteringRun,
    UnsupervisedLearner, baseline_seed, clustering_item, distinct, prepare_clustering, som_setup,
};
use super::recognition::{
    RecognitionParams, RecognitionPrep, SupervisedLearner, prepare_recognition,
    recognition_repetition, session_labels,
};
use super::stability::{DataOptions, PipelineSettings, StabilityData, grasp_features};
use crate::cluster::grasp_features::{Normalisation, Normaliser, session_features};
use crate::cluster::{SequentialKMeansParams, scores};
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::session::Session;
use crate::sparse::DictionaryParams;
use crate::svm::kernel_svm::{self, KernelSvmParams};
use crate::svm::{cross_validate, mean_se, stratified_k_fold};

/// A method whose size the frontier sweeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrontierMethod {
    Ds,
    Gs,
    /// Sparse coding + linear SVM (the first paper's pipeline).
    SparseSvm,
    Du,
    Gu,
    /// Sequential k-means on the Table I features.
    Kmeans,
    /// The sequential SOM on the Table I features.
    Som,
    /// The offline RBF SVM on the Table I features.
    RbfSvm,
}

impl FrontierMethod {
    pub fn name(self) -> &'static str {
        match self {
            FrontierMethod::Ds => "DS",
            FrontierMethod::Gs => "GS",
            FrontierMethod::SparseSvm => "sparse coding + SVM",
            FrontierMethod::Du => "DU",
            FrontierMethod::Gu => "GU",
            FrontierMethod::Kmeans => "k-means",
            FrontierMethod::Som => "SOM",
            FrontierMethod::RbfSvm => "RBF SVM",
        }
    }

    /// DS, GS, DU and GU run on feature sequences (one frontier per feature set); the
    /// others on fixed features.
    pub fn uses_features(self) -> bool {
        matches!(
            self,
            FrontierMethod::Ds | FrontierMethod::Gs | FrontierMethod::Du | FrontierMethod::Gu
        )
    }
}

/// The `--method` names.
pub const METHOD_NAMES: &str = "ds, gs, sparse-svm, du, gu, kmeans, som or rbf-svm";

impl FromStr for FrontierMethod {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "ds" => Ok(FrontierMethod::Ds),
            "gs" => Ok(FrontierMethod::Gs),
            "sparse-svm" => Ok(FrontierMethod::SparseSvm),
            "du" => Ok(FrontierMethod::Du),
            "gu" => Ok(FrontierMethod::Gu),
            "kmeans" => Ok(FrontierMethod::Kmeans),
            "som" => Ok(FrontierMethod::Som),
            "rbf-svm" => Ok(FrontierMethod::RbfSvm),
            other => Err(ExperimentError::param(
                "method",
                format!("`{other}` is not {METHOD_NAMES}"),
            )),
        }
    }
}

/// Which time defines the cheapest model.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CostAxis {
    /// Prediction time per step (online learners) or per grasp.
    #[default]
    Prediction,
    /// Training time per step (online learners) or per grasp of the whole fit.
    Training,
}

/// The DS/GS score a frontier compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RecognitionScore {
    /// Accuracy over every predicted grasp (Table II "all").
    #[default]
    All,
    /// Accuracy over the test-only last 20 % (Table II "final 20 %").
    Final20,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrontierParams {
    pub method: FrontierMethod,
    /// DS/GS/DU/GU: the feature set.
    pub features: FeatureSet,
    /// DS/GS: the score compared.
    #[serde(default)]
    pub score: RecognitionScore,
    /// Seeded repetitions per size (DS/GS: protocol orders; sparse coding and RBF SVM:
    /// fold assignments of the cross validation; DU/GU, k-means, SOM: presentation orders).
    pub reps: usize,
    pub seed: u64,
    pub cost: CostAxis,
    /// DS/GS knobs.
    pub capacities: Vec<usize>,
    pub taus: Vec<usize>,
    /// Sparse coding knobs: every num_bases with its best (beta, gamma) of these lists.
    pub num_bases: Vec<usize>,
    pub beta: Vec<f64>,
    pub gamma: Vec<f64>,
    /// DU/GU knob: novelty thresholds.
    #[serde(default)]
    pub thresholds: Vec<f64>,
    /// DU/GU: the experts' capacity and tau (None: the paper's 50 and 15).
    #[serde(default)]
    pub expert_capacity: Option<usize>,
    #[serde(default)]
    pub expert_tau: Option<usize>,
    /// k-means / SOM knob: centres / units (the SOM's grid is 2 × ⌈k/2⌉).
    #[serde(default)]
    pub ks: Vec<usize>,
    /// RBF SVM knobs: penalties C × kernel widths gamma.
    #[serde(default)]
    pub svm_c: Vec<f64>,
    #[serde(default)]
    pub svm_gamma: Vec<f64>,
}

impl FrontierParams {
    /// The default sweep of a method.
    pub fn for_method(method: FrontierMethod) -> Self {
        FrontierParams {
            method,
            features: FeatureSet::All,
            score: RecognitionScore::All,
            reps: 10,
            seed: 0,
            cost: CostAxis::Prediction,
            capacities: vec![2, 5, 10, 20, 50, 100],
            taus: vec![1, 2, 5, 15, 30],
            num_bases: vec![2, 3, 5, 10, 15, 20, 29, 40, 60],
            beta: vec![0.5, 1.0, 2.0],
            gamma: vec![0.5, 1.0, 2.0],
            thresholds: match method {
                // DU's experts grow as the threshold falls (about 80 at 0.2, 180 at 0.1);
                // below 0.2 a run costs minutes.
                FrontierMethod::Du => vec![0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8],
                // GU's cluster count falls from ~30 to ~3 between 0.05 and 0.3.
                _ => vec![0.05, 0.08, 0.1, 0.12, 0.15, 0.2, 0.3],
            },
            expert_capacity: None,
            expert_tau: None,
            ks: vec![2, 4, 6, 8, 10, 12, 16, 20],
            svm_c: vec![1.0, 10.0, 100.0, 1000.0],
            svm_gamma: vec![1e-3, 3e-3, 1e-2, 3e-2, 1e-1],
        }
    }

    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.reps < 2 {
            return Err(ExperimentError::param(
                "reps",
                "a standard error needs at least 2 repetitions",
            ));
        }
        match self.method {
            FrontierMethod::Ds | FrontierMethod::Gs => {
                if self.capacities.is_empty() || self.taus.is_empty() {
                    return Err(ExperimentError::param(
                        "capacities",
                        "DS/GS need at least one capacity and one tau",
                    ));
                }
                if self.capacities.contains(&0) || self.taus.contains(&0) {
                    return Err(ExperimentError::param(
                        "capacities",
                        "capacity and tau must be ≥ 1",
                    ));
                }
            }
            FrontierMethod::SparseSvm => {
                if self.num_bases.is_empty() || self.beta.is_empty() || self.gamma.is_empty() {
                    return Err(ExperimentError::param(
                        "num_bases",
                        "sparse coding needs num_bases, beta and gamma values",
                    ));
                }
                if self.num_bases.contains(&0) {
                    return Err(ExperimentError::param("num_bases", "must be ≥ 1"));
                }
                positive("beta", &self.beta)?;
                positive("gamma", &self.gamma)?;
            }
            FrontierMethod::Du | FrontierMethod::Gu => {
                if self.thresholds.is_empty() {
                    return Err(ExperimentError::param(
                        "thresholds",
                        "DU/GU need at least one threshold",
                    ));
                }
                if let Some(t) = self.thresholds.iter().find(|t| !(0.0..=1.0).contains(*t)) {
                    return Err(ExperimentError::param(
                        "thresholds",
                        format!("{t} is not in [0, 1]"),
                    ));
                }
                if self.expert_capacity == Some(0) || self.expert_tau == Some(0) {
                    return Err(ExperimentError::param(
                        "expert_capacity",
                        "the experts' capacity and tau must be ≥ 1",
                    ));
                }
            }
            FrontierMethod::Kmeans | FrontierMethod::Som => {
                if self.ks.is_empty() || self.ks.contains(&0) {
                    return Err(ExperimentError::param(
                        "ks",
                        "k-means and the SOM need cluster counts ≥ 1",
                    ));
                }
            }
            FrontierMethod::RbfSvm => {
                if self.svm_c.is_empty() || self.svm_gamma.is_empty() {
                    return Err(ExperimentError::param(
                        "svm_c",
                        "the RBF SVM needs at least one C and one gamma",
                    ));
                }
                positive("svm_c", &self.svm_c)?;
                positive("svm_gamma", &self.svm_gamma)?;
            }
        }
        Ok(())
    }
}

fn positive(name: &'static str, v: &[f64]) -> Result<(), ExperimentError> {
    match v.iter().find(|b| !(**b > 0.0 && b.is_finite())) {
        Some(b) => Err(ExperimentError::param(name, format!("{b} is not > 0"))),
        None => Ok(()),
    }
}

/// One model size on the frontier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrontierPoint {
    /// A short label for the chart, e.g. "5·1" (capacity·tau), "K 29", "θ 0.3", "k 10" or
    /// "C 10 γ 0.01".
    pub label: String,
    /// The whole configuration in words, for a tooltip.
    pub detail: String,
    /// The knobs by name (capacity, tau; num_bases, beta, gamma; threshold; k; c, gamma),
    /// and for the clusterers the mean `effective` clusters (and DU/GU's `created` ones),
    /// for the RBF SVM the mean `support_vectors`.
    pub knobs: Vec<(String, f64)>,
    /// Mean score over the repetitions and its standard error (sd / √reps).
    pub score: f64,
    pub score_se: f64,
    pub reps: usize,
    /// Microseconds per unit (step or grasp, see [`Frontier::unit`]), medians over the
    /// repetitions (the machine's load varies); sparse coding's training time is one timed
    /// dictionary and SVM fit plus the median coding time.
    pub train_us: f64,
    pub predict_us: f64,
}

impl FrontierPoint {
    pub fn cost(&self, axis: CostAxis) -> f64 {
        match axis {
            CostAxis::Prediction => self.predict_us,
            CostAxis::Training => self.train_us,
        }
    }

    pub fn knob(&self, name: &str) -> Option<f64> {
        self.knobs.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
}

/// A method's frontier on one session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Frontier {
    pub session: String,
    pub params: FrontierParams,
    /// The score compared, in words ("accuracy (all)", "weighted success rate").
    pub score_name: String,
    /// What the times are per: "step" (DS/GS) or "grasp" (the others).
    pub unit: String,
    pub points: Vec<FrontierPoint>,
    /// Indices of the non-dominated points by training / prediction time (cheapest first).
    pub pareto_training: Vec<usize>,
    pub pareto_prediction: Vec<usize>,
    /// The highest mean score, and the cheapest point within one SE of it.
    pub best: usize,
    pub recommended: usize,
    /// The papers' default size, where the sweep holds it.
    pub paper_default: Option<usize>,
    pub wall_seconds: f64,
}

impl Frontier {
    /// "DS, all features" or "sparse coding + SVM".
    pub fn label(&self) -> String {
        self.params.label()
    }

    /// A short name for a chart legend: "DS all", "GU encoder", "SC+SVM", "SOM".
    pub fn short_label(&self) -> String {
        match self.params.method {
            FrontierMethod::SparseSvm => "SC+SVM".into(),
            m if m.uses_features() => format!("{} {}", m.name(), self.params.features.name()),
            m => m.name().to_string(),
        }
    }
}

/// The best point (highest mean score; ties: the cheaper) and the recommended one: the
/// cheapest on `axis` among the points whose mean score is at least the best's mean minus
/// the best's standard error (ties: the higher score). None without points.
pub fn recommend(points: &[FrontierPoint], axis: CostAxis) -> Option<(usize, usize)> {
    let cheaper = |a: usize, b: usize| points[a].cost(axis).total_cmp(&points[b].cost(axis));
    let best = (0..points.len()).max_by(|&a, &b| {
        points[a]
            .score
            .total_cmp(&points[b].score)
            .then(cheaper(b, a))
    })?;
    let bar = points[best].score - points[best].score_se.max(0.0);
    let recommended = (0..points.len())
        .filter(|&i| points[i].score >= bar)
        .min_by(|&a, &b| {
            cheaper(a, b)
                .then(points[b].score.total_cmp(&points[a].score))
                .then(a.cmp(&b))
        })?;
    Some((best, recommended))
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    match v.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => v[n / 2],
        n => 0.5 * (v[n / 2 - 1] + v[n / 2]),
    }
}

/// Folds of the RBF SVM's cross validation (the second paper's "SVM 5-fold").
pub const SVM_FOLDS: usize = 5;

/// The papers' k of the clustering baselines (Table IV: 10 clusters, the SOM 2 × 5).
const PAPER_K: usize = 10;

/// The paper's model size of sparse coding + SVM (the pipeline's default configuration).
const SPARSE_PAPER_NUM_BASES: usize = 29;

/// A unit of a frontier's work. Its seeds follow from the run's seed and the item alone,
/// so any machine computes it alike.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierItem {
    /// DS/GS: repetition `rep` of the supervised protocol at one size.
    Recognition {
        capacity: usize,
        tau: usize,
        rep: usize,
    },
    /// Sparse coding: one dictionary, coded and cross-validated at every gamma and
    /// repetition.
    Dictionary { num_bases: usize, beta: f64 },
    /// DU/GU: one learning run at one threshold, in order `rep`.
    Threshold { threshold: f64, rep: usize },
    /// k-means / SOM: k centres / units, order `rep`.
    Clusters { k: usize, rep: usize },
    /// RBF SVM: repetition `rep` of the cross validation at (C, gamma).
    Svm { c: f64, gamma: f64, rep: usize },
}

/// One (num_bases, beta, gamma) cell: its scores over the repetitions and its timings.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SparseCell {
    pub num_bases: usize,
    pub beta: f64,
    pub gamma: f64,
    pub scores: Vec<f64>,
    /// Microseconds per grasp.
    pub train_us: f64,
    pub predict_us: f64,
}

/// What an item leaves. Times are microseconds per step (DS/GS) or per grasp.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum FrontierOutput {
    Recognition {
        all: f64,
        final_20: f64,
        train_us: f64,
        predict_us: f64,
    },
    Dictionary {
        cells: Vec<SparseCell>,
    },
    Threshold {
        run: ClusteringRun,
        train_us: f64,
        predict_us: f64,
    },
    Clusters {
        nmi: f64,
        effective: usize,
        train_us: f64,
        predict_us: f64,
    },
    Svm {
        accuracy: f64,
        /// Support vectors summed over the one-vs-one machines: kernel evaluations per
        /// prediction.
        support_vectors: usize,
        train_us: f64,
        predict_us: f64,
    },
}

/// What every item of a frontier shares.
pub enum FrontierPrep {
    Recognition(Box<RecognitionParams>, RecognitionPrep),
    Sparse(Box<StabilityData>),
    Clustering(Box<ClusteringParams>, ClusteringPrep),
    /// The Table I features (z-scored for the clusterers; raw for the SVM, which scales
    /// inside each training fold) and the objects.
    Table {
        x: Array2<f64>,
        labels: Vec<usize>,
    },
}

impl FrontierParams {
    /// "DS, all features", "sparse coding + SVM", "sequential k-means".
    pub fn label(&self) -> String {
        match self.method {
            m if m.uses_features() => format!("{}, {} features", m.name(), self.features.name()),
            FrontierMethod::Kmeans => "sequential k-means".into(),
            m => m.name().to_string(),
        }
    }

    /// The protocol of DS/GS at the paper's size (items set capacity and tau).
    fn recognition(&self) -> RecognitionParams {
        RecognitionParams {
            learner: match self.method {
                FrontierMethod::Ds => SupervisedLearner::Ds,
                _ => SupervisedLearner::Gs,
            },
            features: self.features,
            reps: self.reps,
            seed: self.seed,
            early_fractions: Vec::new(),
            ..RecognitionParams::default()
        }
    }

    /// The clustering run of DU/GU over the thresholds, without the baselines.
    fn clustering(&self) -> ClusteringParams {
        let learner = match self.method {
            FrontierMethod::Du => UnsupervisedLearner::Du,
            _ => UnsupervisedLearner::Gu,
        };
        let mut p = ClusteringParams {
            features: self.features,
            thresholds: self.thresholds.clone(),
            reps: self.reps,
            seed: self.seed,
            baseline_max_k: 0,
            ..ClusteringParams::for_learner(learner)
        };
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = self.expert_capacity.unwrap_or(gp.capacity);
            gp.tau = self.expert_tau.unwrap_or(gp.tau);
        }
        p
    }

    fn sizes(&self) -> Vec<(usize, usize)> {
        self.capacities
            .iter()
            .flat_map(|&c| self.taus.iter().map(move |&t| (c, t)))
            .collect()
    }

    fn svm_cells(&self) -> Vec<(f64, f64)> {
        self.svm_c
            .iter()
            .flat_map(|&c| self.svm_gamma.iter().map(move |&g| (c, g)))
            .collect()
    }

    fn sparse_rep_seeds(&self) -> Vec<u64> {
        (0..self.reps)
            .map(|r| Rng::stream(self.seed, r as u64).next_u64())
            .collect()
    }
}

fn data_err(e: impl std::fmt::Display) -> ExperimentError {
    ExperimentError::Data(e.to_string())
}

/// Check the parameters against the session and prepare what every item shares.
pub fn prepare_frontier(
    session: &Session,
    params: &FrontierParams,
) -> Result<FrontierPrep, ExperimentError> {
    params.validate()?;
    Ok(match params.method {
        FrontierMethod::Ds | FrontierMethod::Gs => {
            let p = params.recognition();
            let prep = prepare_recognition(session, &p)?;
            FrontierPrep::Recognition(Box::new(p), prep)
        }
        FrontierMethod::SparseSvm => FrontierPrep::Sparse(Box::new(StabilityData::from_session(
            session,
            &DataOptions::default(),
        )?)),
        FrontierMethod::Du | FrontierMethod::Gu => {
            let p = params.clustering();
            let prep = prepare_clustering(session, &p)?;
            FrontierPrep::Clustering(Box::new(p), prep)
        }
        FrontierMethod::Kmeans | FrontierMethod::Som | FrontierMethod::RbfSvm => {
            let (labels, _) = session_labels(session, "object")?;
            let raw = session_features(session).map_err(data_err)?;
            if let Some(k) = params.ks.iter().find(|&&k| k > raw.nrows())
                && params.method != FrontierMethod::RbfSvm
            {
                return Err(ExperimentError::param(
                    "ks",
                    format!("{k} clusters for {} grasps", raw.nrows()),
                ));
            }
            let x = if params.method == FrontierMethod::RbfSvm {
                raw
            } else {
                Normaliser::fit(Normalisation::ZScore, raw.view())
                    .and_then(|n| n.transform(raw.view()))
                    .map_err(data_err)?
            };
            FrontierPrep::Table { x, labels }
        }
    })
}

/// The items of a frontier, in the order its points are assembled: every size (or knob
/// value) with its repetitions in order.
pub fn frontier_items(params: &FrontierParams) -> Vec<FrontierItem> {
    let reps = 0..params.reps;
    match params.method {
        FrontierMethod::Ds | FrontierMethod::Gs => params
            .sizes()
            .into_iter()
            .flat_map(|(capacity, tau)| {
                reps.clone()
                    .map(move |rep| FrontierItem::Recognition { capacity, tau, rep })
            })
            .collect(),
        FrontierMethod::SparseSvm => params
            .num_bases
            .iter()
            .flat_map(|&num_bases| {
                params
                    .beta
                    .iter()
                    .map(move |&beta| FrontierItem::Dictionary { num_bases, beta })
            })
            .collect(),
        FrontierMethod::Du | FrontierMethod::Gu => params
            .thresholds
            .iter()
            .flat_map(|&threshold| {
                reps.clone()
                    .map(move |rep| FrontierItem::Threshold { threshold, rep })
            })
            .collect(),
        FrontierMethod::Kmeans | FrontierMethod::Som => params
            .ks
            .iter()
            .flat_map(|&k| {
                reps.clone()
                    .map(move |rep| FrontierItem::Clusters { k, rep })
            })
            .collect(),
        FrontierMethod::RbfSvm => params
            .svm_cells()
            .into_iter()
            .flat_map(|(c, gamma)| {
                reps.clone()
                    .map(move |rep| FrontierItem::Svm { c, gamma, rep })
            })
            .collect(),
    }
}

fn wrong_item(item: &FrontierItem, params: &FrontierParams) -> ExperimentError {
    ExperimentError::param(
        "item",
        format!(
            "{item:?} is not an item of a {} frontier",
            params.method.name()
        ),
    )
}

fn micros(secs: f64, units: usize) -> f64 {
    1e6 * secs / units.max(1) as f64
}

/// Compute one item.
pub fn frontier_item(
    session: &Session,
    params: &FrontierParams,
    prep: &FrontierPrep,
    item: &FrontierItem,
    progress: &Progress,
) -> Result<FrontierOutput, ExperimentError> {
    match (prep, *item) {
        (
            FrontierPrep::Recognition(base, prep),
            FrontierItem::Recognition { capacity, tau, rep },
        ) => {
            let mut p = (**base).clone();
            for gp in [&mut p.ds.gp, &mut p.gs.gp] {
                gp.capacity = capacity;
                gp.tau = tau;
            }
            let r = recognition_repetition(&p, session, prep, rep)?;
            Ok(FrontierOutput::Recognition {
                all: r.all,
                final_20: r.final_20,
                train_us: micros(r.train_seconds, r.train_steps),
                predict_us: micros(r.predict_seconds, r.predict_steps),
            })
        }
        (FrontierPrep::Sparse(data), FrontierItem::Dictionary { num_bases, beta }) => {
            sparse_dictionary(params, data, num_bases, beta, progress)
                .map(|cells| FrontierOutput::Dictionary { cells })
        }
        (FrontierPrep::Clustering(base, prep), FrontierItem::Threshold { threshold, rep }) => {
            let ClusteringOutput::Run { run } =
                clustering_item(base, prep, ClusteringItem::Run { threshold, rep })?
            else {
                return Err(wrong_item(item, params));
            };
            // Per grasp, as the other clusterers: the observations of a grasp, each
            // scored by every expert.
            let seqs = &prep.feats.sequences;
            let per_grasp =
                seqs.iter().map(|s| s.nrows()).sum::<usize>() as f64 / seqs.len().max(1) as f64;
            Ok(FrontierOutput::Threshold {
                train_us: run.learn_step_us * per_grasp,
                predict_us: run.assign_step_us * per_grasp,
                run,
            })
        }
        (FrontierPrep::Table { x, labels }, FrontierItem::Clusters { k, rep }) => {
            let seed = baseline_seed(params.seed, k, rep);
            let t0 = Instant::now();
            let (pred, train) = match params.method {
                FrontierMethod::Kmeans => {
                    let m = SequentialKMeansParams { k, passes: 1, seed }
                        .fit(x.view())
                        .map_err(data_err)?;
                    let train = t0.elapsed().as_secs_f64();
                    (m.assign(x.view()).map_err(data_err)?, train)
                }
                FrontierMethod::Som => {
                    let m = som_setup(k, seed).fit(x.view()).map_err(data_err)?;
                    let train = t0.elapsed().as_secs_f64();
                    (m.assign(x.view()).map_err(data_err)?, train)
                }
                _ => return Err(wrong_item(item, params)),
            };
            let predict = t0.elapsed().as_secs_f64() - train;
            Ok(FrontierOutput::Clusters {
                nmi: scores(labels, &pred).nmi,
                effective: distinct(&pred),
                train_us: micros(train, x.nrows()),
                predict_us: micros(predict, x.nrows()),
            })
        }
        (FrontierPrep::Table { x, labels }, FrontierItem::Svm { c, gamma, rep }) => {
            let p = KernelSvmParams {
                c,
                gamma,
                ..KernelSvmParams::default()
            };
            // The fold seeds of the `baselines` grid search: the same cell scores alike.
            let seed = Rng::stream(params.seed, rep as u64).next_u64();
            let cv = kernel_svm::cross_validate(&p, x.view(), labels, SVM_FOLDS, seed)
                .map_err(data_err)?;
            let t0 = Instant::now();
            let model = p.fit(x.view(), labels).map_err(data_err)?;
            let train = t0.elapsed().as_secs_f64();
            let t1 = Instant::now();
            std::hint::black_box(model.predict(x.view()).map_err(data_err)?);
            let predict = t1.elapsed().as_secs_f64();
            Ok(FrontierOutput::Svm {
                accuracy: cv.accuracy,
                support_vectors: model
                    .machines
                    .iter()
                    .map(|m| m.support_vectors.nrows())
                    .sum(),
                train_us: micros(train, x.nrows()),
                predict_us: micros(predict, x.nrows()),
            })
        }
        _ => Err(wrong_item(item, params)),
    }
}

/// Sweep the method's size knobs on `session`.
pub fn run_frontier(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<Frontier, ExperimentError> {
    let start = Instant::now();
    let prep = prepare_frontier(session, params)?;
    let items = frontier_items(params);
    let label = params.label();
    let done = AtomicUsize::new(0);
    progress.set(0.0, format!("frontier {label}: starting"));
    let outputs = items
        .par_iter()
        .map(|item| {
            progress.checkpoint()?;
            let out = frontier_item(session, params, &prep, item, progress)?;
            let d = done.fetch_add(1, Ordering::Relaxed) + 1;
            progress.set(
                d as f64 / items.len() as f64,
                format!("frontier {label}: {d}/{} runs", items.len()),
            );
            Ok(out)
        })
        .collect::<Result<Vec<_>, ExperimentError>>()?;
    assemble_frontier(
        &session.meta.name,
        params,
        &items,
        outputs,
        start.elapsed().as_secs_f64(),
    )
}

/// The frontier from every item's output (in item order): the points, the best and the
/// recommended point, the Pareto fronts.
pub fn assemble_frontier(
    session: &str,
    params: &FrontierParams,
    items: &[FrontierItem],
    outputs: Vec<FrontierOutput>,
    wall_seconds: f64,
) -> Result<Frontier, ExperimentError> {
    if items.len() != outputs.len() {
        return Err(ExperimentError::Data(format!(
            "{} items but {} outputs",
            items.len(),
            outputs.len()
        )));
    }
    let pairs: Vec<(FrontierItem, FrontierOutput)> = items.iter().copied().zip(outputs).collect();
    let (points, paper_default, score_name, unit) = match params.method {
        FrontierMethod::Ds | FrontierMethod::Gs => {
            let (p, d, s) = recognition_points(params, &pairs);
            (p, d, s, "step")
        }
        FrontierMethod::SparseSvm => {
            let (p, d) = sparse_points(params, pairs);
            (p, d, "weighted success rate".to_string(), "grasp")
        }
        FrontierMethod::Du | FrontierMethod::Gu => (
            threshold_points(params, &pairs),
            None,
            "NMI".into(),
            "grasp",
        ),
        FrontierMethod::Kmeans | FrontierMethod::Som => {
            let (p, d) = cluster_points(params, &pairs);
            (p, d, "NMI".into(), "grasp")
        }
        FrontierMethod::RbfSvm => (
            svm_points(params, &pairs),
            None,
            format!("accuracy ({SVM_FOLDS}-fold)"),
            "grasp",
        ),
    };
    let (best, recommended) =
        recommend(&points, params.cost).ok_or_else(|| ExperimentError::Data("no sizes".into()))?;
    let front = |axis: CostAxis| {
        let x: Vec<f64> = points.iter().map(|p| p.cost(axis)).collect();
        let y: Vec<f64> = points.iter().map(|p| p.score).collect();
        crate::figures::pareto_front(&x, &y)
    };
    Ok(Frontier {
        session: session.to_string(),
        params: params.clone(),
        score_name,
        unit: unit.into(),
        pareto_training: front(CostAxis::Training),
        pareto_prediction: front(CostAxis::Prediction),
        points,
        best,
        recommended,
        paper_default,
        wall_seconds,
    })
}

/// A point from its repetitions' scores and times.
fn point(
    label: String,
    detail: String,
    knobs: Vec<(&str, f64)>,
    scores: &[f64],
    train_us: Vec<f64>,
    predict_us: Vec<f64>,
) -> FrontierPoint {
    let (score, score_se) = mean_se(scores);
    FrontierPoint {
        label,
        detail,
        knobs: knobs.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        score,
        score_se,
        reps: scores.len(),
        train_us: median(train_us),
        predict_us: median(predict_us),
    }
}

fn mean(v: impl Iterator<Item = f64>) -> f64 {
    let (s, n) = v.fold((0.0, 0usize), |(s, n), x| (s + x, n + 1));
    s / n.max(1) as f64
}

/// DS/GS: one point per capacity × tau.
fn recognition_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> (Vec<FrontierPoint>, Option<usize>, String) {
    let sizes = params.sizes();
    let base = params.recognition();
    let paper = (base.gs.gp.capacity, base.gs.gp.tau);
    let points = sizes
        .iter()
        .map(|&(capacity, tau)| {
            let (mut scores, mut train, mut predict) = (Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
                if let (
                    FrontierItem::Recognition {
                        capacity: c,
                        tau: t,
                        ..
                    },
                    FrontierOutput::Recognition {
                        all,
                        final_20,
                        train_us,
                        predict_us,
                    },
                ) = (item, out)
                    && (*c, *t) == (capacity, tau)
                {
                    scores.push(match params.score {
                        RecognitionScore::All => *all,
                        RecognitionScore::Final20 => *final_20,
                    });
                    train.push(*train_us);
                    predict.push(*predict_us);
                }
            }
            point(
                format!("{capacity}·{tau}"),
                format!(
                    "{}, {} features: capacity {capacity}, tau {tau}",
                    params.method.name(),
                    params.features.name()
                ),
                vec![("capacity", capacity as f64), ("tau", tau as f64)],
                &scores,
                train,
                predict,
            )
        })
        .collect();
    let paper_default = sizes.iter().position(|&s| s == paper);
    let score_name = match params.score {
        RecognitionScore::All => "accuracy (all)",
        RecognitionScore::Final20 => "accuracy (final 20 %)",
    };
    (points, paper_default, score_name.into())
}

/// Sparse coding: one dictionary coded at every gamma, each cross-validated over the
/// repetitions' fold assignments.
fn sparse_dictionary(
    params: &FrontierParams,
    data: &StabilityData,
    num_bases: usize,
    beta: f64,
    progress: &Progress,
) -> Result<Vec<SparseCell>, ExperimentError> {
    let settings = PipelineSettings::default();
    let rep_seeds = params.sparse_rep_seeds();
    let fit = DictionaryParams {
        num_bases,
        beta,
        ..settings.dictionary.clone()
    }
    .fit_within(data.x.view(), progress)?;
    let mut out = Vec::with_capacity(params.gamma.len());
    for &gamma in &params.gamma {
        progress.checkpoint()?;
        let codes = fit.dictionary.encode(data.x.view(), gamma)?;
        let features = grasp_features(codes, data.sensor_count());
        let t1 = Instant::now();
        let svm = settings.svm.fit(features.view(), &data.labels)?;
        let fit_secs = t1.elapsed().as_secs_f64();
        let mut scores = Vec::with_capacity(rep_seeds.len());
        let mut coding = Vec::with_capacity(rep_seeds.len());
        let mut deciding = Vec::with_capacity(rep_seeds.len());
        for &seed in &rep_seeds {
            // Coding and deciding are timed once per repetition; the median resists the
            // machine's load.
            let t0 = Instant::now();
            std::hint::black_box(fit.dictionary.encode(data.x.view(), gamma)?);
            coding.push(t0.elapsed().as_secs_f64());
            let t2 = Instant::now();
            std::hint::black_box(svm.predict_all(features.view()));
            deciding.push(t2.elapsed().as_secs_f64());
            let folds = stratified_k_fold(&data.labels, 10, seed)?;
            let svm = crate::svm::LinearSvmParams {
                seed,
                ..settings.svm.clone()
            };
            let cv = cross_validate(features.view(), &data.labels, &folds, &svm)?;
            scores.push(cv.weighted_success_rate);
        }
        let grasps = data.grasp_count() as f64;
        out.push(SparseCell {
            num_bases,
            beta,
            gamma,
            scores,
            train_us: 1e6 * (fit.secs + median(coding.clone()) + fit_secs) / grasps,
            predict_us: 1e6 * (median(coding) + median(deciding)) / grasps,
        });
    }
    Ok(out)
}

/// Sparse coding + SVM: per num_bases, the (beta, gamma) with the best mean score.
fn sparse_points(
    params: &FrontierParams,
    pairs: Vec<(FrontierItem, FrontierOutput)>,
) -> (Vec<FrontierPoint>, Option<usize>) {
    let cells: Vec<SparseCell> = pairs
        .into_iter()
        .flat_map(|(_, o)| match o {
            FrontierOutput::Dictionary { cells } => cells,
            _ => Vec::new(),
        })
        .collect();
    let mut ks = params.num_bases.clone();
    ks.sort_unstable();
    ks.dedup();
    let points: Vec<FrontierPoint> = ks
        .iter()
        .filter_map(|&k| {
            // Grid order breaks ties, so the choice does not depend on the thread count.
            cells
                .iter()
                .filter(|c| c.num_bases == k)
                .map(|c| (mean_se(&c.scores), c))
                .fold(
                    None,
                    |acc: Option<((f64, f64), &SparseCell)>, x| match acc {
                        Some(a) if a.0.0 >= x.0.0 => Some(a),
                        _ => Some(x),
                    },
                )
        })
        .map(|((score, score_se), c)| FrontierPoint {
            label: format!("K {}", c.num_bases),
            detail: format!(
                "sparse coding + SVM: num_bases {}, beta {}, gamma {}",
                c.num_bases, c.beta, c.gamma
            ),
            knobs: vec![
                ("num_bases".into(), c.num_bases as f64),
                ("beta".into(), c.beta),
                ("gamma".into(), c.gamma),
            ],
            score,
            score_se,
            reps: c.scores.len(),
            train_us: c.train_us,
            predict_us: c.predict_us,
        })
        .collect();
    let paper_default = ks.iter().position(|&k| k == SPARSE_PAPER_NUM_BASES);
    (points, paper_default)
}

/// DU/GU: one point per threshold, NMI over the orders with the clusters it leaves.
fn threshold_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> Vec<FrontierPoint> {
    let c = params.clustering();
    let expert = match params.method {
        FrontierMethod::Du => (c.ds.gp.capacity, c.ds.gp.tau),
        _ => (c.gs.gp.capacity, c.gs.gp.tau),
    };
    params
        .thresholds
        .iter()
        .map(|&threshold| {
            let runs: Vec<(&ClusteringRun, f64, f64)> = pairs
                .iter()
                .filter_map(|(_, o)| match o {
                    FrontierOutput::Threshold {
                        run,
                        train_us,
                        predict_us,
                    } if run.threshold == threshold => Some((run, *train_us, *predict_us)),
                    _ => None,
                })
                .collect();
            let effective = mean(runs.iter().map(|r| r.0.effective as f64));
            let created = mean(runs.iter().map(|r| r.0.clusters as f64));
            let nmi: Vec<f64> = runs.iter().map(|r| r.0.nmi).collect();
            point(
                format!("θ {threshold}"),
                format!(
                    "{}: threshold {threshold} (experts: capacity {}, tau {}); \
                     {effective:.1} effective clusters of {created:.1} created (means over \
                     the orders)",
                    params.label(),
                    expert.0,
                    expert.1
                ),
                vec![
                    ("threshold", threshold),
                    ("effective", effective),
                    ("created", created),
                ],
                &nmi,
                runs.iter().map(|r| r.1).collect(),
                runs.iter().map(|r| r.2).collect(),
            )
        })
        .collect()
}

/// k-means / SOM: one point per k.
fn cluster_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> (Vec<FrontierPoint>, Option<usize>) {
    let points = params
        .ks
        .iter()
        .map(|&k| {
            let (mut nmi, mut eff, mut train, mut predict) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
                if let (
                    FrontierItem::Clusters { k: kk, .. },
                    FrontierOutput::Clusters {
                        nmi: n,
                        effective,
                        train_us,
                        predict_us,
                    },
                ) = (item, out)
                    && *kk == k
                {
                    nmi.push(*n);
                    eff.push(*effective as f64);
                    train.push(*train_us);
                    predict.push(*predict_us);
                }
            }
            let effective = mean(eff.into_iter());
            let what = match params.method {
                FrontierMethod::Som => {
                    let s = som_setup(k, 0);
                    format!("SOM {} × {} units", s.rows, s.cols)
                }
                _ => format!("sequential k-means, k {k}"),
            };
            point(
                format!("k {k}"),
                format!("{what}; {effective:.1} effective clusters (mean over the orders)"),
                vec![("k", k as f64), ("effective", effective)],
                &nmi,
                train,
                predict,
            )
        })
        .collect();
    (points, params.ks.iter().position(|&k| k == PAPER_K))
}

/// RBF SVM: one point per (C, gamma).
fn svm_points(
    params: &FrontierParams,
    pairs: &[(FrontierItem, FrontierOutput)],
) -> Vec<FrontierPoint> {
    params
        .svm_cells()
        .into_iter()
        .map(|(c, gamma)| {
            let (mut acc, mut sv, mut train, mut predict) =
                (Vec::new(), Vec::new(), Vec::new(), Vec::new());
            for (item, out) in pairs {
                if let (
                    FrontierItem::Svm {
                        c: cc, gamma: gg, ..
                    },
                    FrontierOutput::Svm {
                        accuracy,
                        support_vectors,
                        train_us,
                        predict_us,
                    },
                ) = (item, out)
                    && (*cc, *gg) == (c, gamma)
                {
                    acc.push(*accuracy);
                    sv.push(*support_vectors as f64);
                    train.push(*train_us);
                    predict.push(*predict_us);
                }
            }
            let support = mean(sv.into_iter());
            point(
                format!("C {c} γ {gamma}"),
                format!(
                    "RBF SVM: C {c}, gamma {gamma}; {support:.0} support vectors over its \
                     one-vs-one machines"
                ),
                vec![("c", c), ("gamma", gamma), ("support_vectors", support)],
                &acc,
                train,
                predict,
            )
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn point(score: f64, se: f64, predict_us: f64, train_us: f64) -> FrontierPoint {
        FrontierPoint {
            label: String::new(),
            detail: String::new(),
            knobs: Vec::new(),
            score,
            score_se: se,
            reps: 5,
            train_us,
            predict_us,
        }
    }

    #[test]
    fn the_recommended_point_is_the_cheapest_within_one_se_of_the_best() {
        let points = vec![
            point(0.90, 0.01, 1.0, 9.0), // cheapest, but more than one SE below the best
            point(0.975, 0.01, 2.0, 8.0), // within one SE of the best (≥ 0.97)
            point(0.98, 0.01, 9.0, 1.0), // the best
            point(0.97, 0.02, 4.0, 2.0), // exactly at the bar, but dearer than 1
        ];
        assert_eq!(recommend(&points, CostAxis::Prediction), Some((2, 1)));
        // By training time, the best itself is the cheapest.
        assert_eq!(recommend(&points, CostAxis::Training), Some((2, 2)));
        // The bar is the best's SE, not the candidate's: a wide SE does not qualify 0.
        let mut wide = points.clone();
        wide[0].score_se = 0.5;
        assert_eq!(recommend(&wide, CostAxis::Prediction), Some((2, 1)));
        assert_eq!(recommend(&[], CostAxis::Prediction), None);
    }
}
