//! The unsupervised experiments of the second paper (Sec. VII, Figs. 11–13, Table IV).
//!
//! One run = one random order of all grasps (`Rng::stream(seed, rep)`, the same orders at
//! every threshold) and one novelty threshold: the learner (DU or GU) goes once over the
//! grasps (learning phase), then every grasp is re-assigned to the learned models. Scores
//! (purity, ARI, NMI) compare that re-assignment with the true objects; "clusters" counts
//! the clusters created, "effective" those that receive at least one grasp on
//! re-assignment. Runs are grouped by effective clusters for the NMI curve (Fig. 13) and the
//! scores at 10 effective clusters (Table IV). Sequential k-means and the SOM run on the
//! z-scored Table I features with as many centres / units as effective clusters wanted,
//! over the same number of seeded orders.

use std::collections::BTreeMap;
use std::str::FromStr;
use std::sync::Arc;
use std::time::Instant;

use serde::{Deserialize, Serialize};

pub mod forked;
pub mod report;
mod run;

pub use run::*;

use crate::catalogue::MethodId;
use crate::cluster::order_agreement::{ThresholdChoice, ThresholdCriterion, choose_threshold};
use crate::cluster::{Schedule, SequentialKMeansParams, SomParams, scores};
use crate::experiments::ExperimentError;
use crate::experiments::feature_choice::{AUTO_FOLDS, FeatureChoice, choose_features};
use crate::experiments::labels::session_labels;
use crate::experiments::parallel::compute_items;
use crate::experiments::recognition::{ExpertsScorer, SupervisedLearner};
use crate::experiments::result::MeanSd;
use crate::features::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
use crate::features::{Normalisation, Normaliser, table_one::session_features};
use crate::gp::{PairDistances, Sogp};
use crate::jobs::Progress;
use crate::learners::{
    DsParams, Du, DuParams, EvtDraws, Gs, GsParams, Gu, GuAggregate, GuNoise, GuParams,
};
use crate::rng::Rng;
use crate::session::Session;
use ndarray::Array2;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum UnsupervisedLearner {
    Du,
    Gu,
}

impl UnsupervisedLearner {
    /// The learner as the catalogue names it.
    pub fn method(self) -> MethodId {
        match self {
            UnsupervisedLearner::Du => MethodId::Du,
            UnsupervisedLearner::Gu => MethodId::Gu,
        }
    }

    /// The learner the catalogue's `method` is (None: not DU or GU).
    pub fn of(method: MethodId) -> Option<UnsupervisedLearner> {
        match method {
            MethodId::Du => Some(UnsupervisedLearner::Du),
            MethodId::Gu => Some(UnsupervisedLearner::Gu),
            MethodId::SparseSvm
            | MethodId::RawSvm
            | MethodId::Ds
            | MethodId::Gs
            | MethodId::KMeans
            | MethodId::Som
            | MethodId::RbfSvm
            | MethodId::Classifier(_) => None,
        }
    }
}

impl FromStr for UnsupervisedLearner {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "du" => Ok(UnsupervisedLearner::Du),
            "gu" => Ok(UnsupervisedLearner::Gu),
            other => Err(ExperimentError::param(
                "learner",
                format!("`{other}` is not du or gu"),
            )),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusteringParams {
    pub learner: UnsupervisedLearner,
    pub features: FeatureSet,
    /// Novelty thresholds to sweep (the paper: 0.1 … 0.95).
    pub thresholds: Vec<f64>,
    /// Random orders per threshold (the paper: 50).
    pub reps: usize,
    pub seed: u64,
    pub label_set: String,
    pub ds: DsParams,
    pub gs: GsParams,
    /// GU's combination of per-step novelties.
    pub gu_aggregate: GuAggregate,
    /// What GU's m (the draws of its extreme-value statistics) counts.
    pub gu_draws: EvtDraws,
    /// The noise in GU's Σ: the experts' shared sigma_n² or a per-dimension estimate.
    pub gu_noise: GuNoise,
    /// The floor of GU's per-dimension noise variance.
    pub gu_noise_floor: f64,
    /// GU: clusters trained on fewer grasps are left out of the re-assignment.
    #[serde(default = "every_gu_cluster")]
    pub gu_min_grasps: usize,
    /// DU: the same rule (1, the paper's DU, keeps every cluster).
    #[serde(default = "every_gu_cluster")]
    pub du_min_grasps: usize,
    /// Run sequential k-means and the SOM for 2 … `baseline_max_k` clusters (0: skip).
    pub baseline_max_k: usize,
    /// How to choose a threshold without labels (None: no choice).
    #[serde(default)]
    pub choose_threshold: Option<ThresholdCriterion>,
}

impl Default for ClusteringParams {
    fn default() -> Self {
        ClusteringParams {
            learner: UnsupervisedLearner::Du,
            features: FeatureSet::ALL,
            thresholds: paper_thresholds(),
            reps: 50,
            seed: 0,
            label_set: "object".into(),
            ds: DsParams::default(),
            gs: GsParams::default(),
            gu_aggregate: GuAggregate::Mean,
            gu_draws: EvtDraws::Grasps,
            gu_noise: GuNoise::Shared,
            gu_noise_floor: GuParams::default().noise_floor,
            gu_min_grasps: GuParams::default().min_grasps,
            du_min_grasps: DuParams::default().min_grasps,
            baseline_max_k: 20,
            choose_threshold: Some(ThresholdCriterion::OrderAgreement),
        }
    }
}

/// A project saved before DU's and GU's `min_grasps` existed re-assigned to every cluster.
pub(crate) fn every_gu_cluster() -> usize {
    1
}

/// The paper's sweep, 0.1, 0.15, … 0.95.
pub fn paper_thresholds() -> Vec<f64> {
    (2..=19).map(|i| i as f64 * 0.05).collect()
}

/// The thresholds swept by default for `learner`: the paper's grid, and for GU also steps of
/// 0.01 over 0.05 … 0.25, where its cluster count changes (from about 30 clusters created to 4; at
/// 0.3 it already keeps 2–3), so that runs near 10 effective clusters are not left to
/// chance.
pub fn default_thresholds(learner: UnsupervisedLearner) -> Vec<f64> {
    let mut t = paper_thresholds();
    if learner == UnsupervisedLearner::Gu {
        t.push(0.05);
        t.extend((6..25).filter(|i| i % 5 != 0).map(|i| i as f64 * 0.01));
        t.sort_by(f64::total_cmp);
    }
    t
}

impl ClusteringParams {
    /// The defaults with `learner` and its threshold grid.
    pub fn for_learner(learner: UnsupervisedLearner) -> ClusteringParams {
        ClusteringParams {
            learner,
            thresholds: default_thresholds(learner),
            ..ClusteringParams::default()
        }
    }

    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.reps == 0 {
            return Err(ExperimentError::param("reps", "must be at least 1"));
        }
        if self.thresholds.is_empty() {
            return Err(ExperimentError::param("thresholds", "needs at least one"));
        }
        if self.thresholds.iter().any(|t| !(0.0..=1.0).contains(t)) {
            return Err(ExperimentError::param(
                "thresholds",
                "each must lie in [0, 1]",
            ));
        }
        self.ds.validate()?;
        self.gs.validate()?;
        Ok(())
    }
}

/// One learning run at one threshold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusteringRun {
    pub threshold: f64,
    pub rep: usize,
    pub clusters: usize,
    pub effective: usize,
    pub purity: f64,
    pub ari: f64,
    pub nmi: f64,
    /// Microseconds per observation of the learning phase (predict + novelty + train).
    pub learn_step_us: f64,
    /// Microseconds per observation of the re-assignment (every expert scores the grasp);
    /// 0 in results saved before it was timed.
    #[serde(default)]
    pub assign_step_us: f64,
    /// The cluster of every grasp (session order) after re-assignment. Every run has it
    /// until the threshold is chosen; the result keeps it for the first order only, so a
    /// view can show the clustering at each threshold.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub assignment: Option<Vec<usize>>,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ThresholdSummary {
    pub threshold: f64,
    pub clusters: MeanSd,
    pub effective: MeanSd,
    pub purity: MeanSd,
    pub ari: MeanSd,
    pub nmi: MeanSd,
}

/// Scores of every run that ended with `effective` effective clusters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct EffectivePoint {
    pub effective: usize,
    pub runs: usize,
    pub purity: MeanSd,
    pub ari: MeanSd,
    pub nmi: MeanSd,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ClusteringResult {
    pub params: ClusteringParams,
    pub runs: Vec<ClusteringRun>,
    /// Figs. 11–12.
    pub sweep: Vec<ThresholdSummary>,
    /// Fig. 13 for the learner.
    pub by_effective: Vec<EffectivePoint>,
    pub kmeans: Vec<EffectivePoint>,
    pub som: Vec<EffectivePoint>,
    /// Table IV rows (None when no run reached exactly 10 effective clusters).
    pub at_10: Option<EffectivePoint>,
    pub kmeans_at_10: Option<EffectivePoint>,
    pub som_at_10: Option<EffectivePoint>,
    /// The SOM set-up of the baseline (grid 2 × ⌈k/2⌉ for k units).
    pub som_setup: SomParams,
    pub wall_seconds: f64,
    /// The threshold chosen without labels, and the criterion's curve.
    #[serde(default)]
    pub threshold_choice: Option<ThresholdChoice>,
    /// The true class of every grasp (session order) and the class names.
    #[serde(default)]
    pub labels: Vec<usize>,
    #[serde(default)]
    pub class_names: Vec<String>,
    /// The families the inputs held (`all` resolved on the session; None in older results).
    #[serde(default)]
    pub features_used: Option<FeatureSet>,
    /// How `auto` chose the family (None: the family was given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature_choice: Option<FeatureChoice>,
}

/// Every threshold's run on presentation order `rep` (in the thresholds' order), learned
/// together and forked where their decisions part ([`forked`]): the runs each threshold
/// learns alone, bit for bit. DU's experts read their distances and kernel vectors from
/// `pairs` when given (the same numbers).
#[allow(clippy::too_many_arguments)]
pub fn order_runs(
    params: &ClusteringParams,
    seqs: &[ndarray::Array2<f64>],
    labels: &[usize],
    dim: usize,
    thresholds: &[f64],
    rep: usize,
    pairs: Option<&Arc<PairDistances>>,
    progress: &Progress,
) -> Result<Vec<ClusteringRun>, ExperimentError> {
    let Some(&first) = thresholds.first() else {
        return Ok(Vec::new());
    };
    let order = Rng::stream(params.seed, rep as u64).permutation(seqs.len());
    let outcomes = match params.learner {
        UnsupervisedLearner::Du => {
            let mut du = Du::new(
                dim,
                &DuParams {
                    ds: params.ds.clone(),
                    threshold: first,
                    min_grasps: params.du_min_grasps,
                },
            )?;
            if let Some(pairs) = pairs {
                du.use_pairs(pairs.clone());
            }
            forked::learn_order(du, seqs, &order, thresholds, progress)?
        }
        UnsupervisedLearner::Gu => {
            let gu = Gu::new(
                dim,
                &GuParams {
                    gs: params.gs.clone(),
                    threshold: first,
                    aggregate: params.gu_aggregate,
                    draws: params.gu_draws,
                    noise: params.gu_noise,
                    noise_floor: params.gu_noise_floor,
                    min_grasps: params.gu_min_grasps,
                },
            )?;
            forked::learn_order(gu, seqs, &order, thresholds, progress)?
        }
    };
    let steps = seqs.iter().map(|s| s.nrows()).sum::<usize>().max(1) as f64;
    Ok(outcomes
        .into_iter()
        .zip(thresholds)
        .map(|(o, &threshold)| {
            let sc = scores(labels, &o.assignment);
            ClusteringRun {
                threshold,
                rep,
                clusters: o.clusters,
                effective: distinct(&o.assignment),
                purity: sc.purity,
                ari: sc.ari,
                nmi: sc.nmi,
                learn_step_us: 1e6 * o.learn_seconds / steps,
                assign_step_us: 1e6 * o.assign_seconds / steps,
                assignment: Some(o.assignment),
            }
        })
        .collect())
}

/// One learning run at one threshold.
#[allow(clippy::too_many_arguments)]
pub fn one_run(
    params: &ClusteringParams,
    seqs: &[ndarray::Array2<f64>],
    labels: &[usize],
    dim: usize,
    threshold: f64,
    rep: usize,
    pairs: Option<&Arc<PairDistances>>,
    progress: &Progress,
) -> Result<ClusteringRun, ExperimentError> {
    order_runs(
        params,
        seqs,
        labels,
        dim,
        &[threshold],
        rep,
        pairs,
        progress,
    )?
    .pop()
    .ok_or_else(|| ExperimentError::param("thresholds", "needs at least one"))
}

/// Clusters that hold at least one grasp.
pub fn distinct(pred: &[usize]) -> usize {
    let mut v = pred.to_vec();
    v.sort_unstable();
    v.dedup();
    v.len()
}

/// Group (effective, purity, ari, nmi) tuples by effective clusters.
fn by_effective(points: impl Iterator<Item = Scored>) -> Vec<EffectivePoint> {
    let mut groups: BTreeMap<usize, Vec<(f64, f64, f64)>> = BTreeMap::new();
    for (e, p, a, n) in points {
        groups.entry(e).or_default().push((p, a, n));
    }
    groups
        .into_iter()
        .map(|(effective, v)| EffectivePoint {
            effective,
            runs: v.len(),
            purity: MeanSd::of(v.iter().map(|x| x.0)),
            ari: MeanSd::of(v.iter().map(|x| x.1)),
            nmi: MeanSd::of(v.iter().map(|x| x.2)),
        })
        .collect()
}

fn at(points: &[EffectivePoint], k: usize) -> Option<EffectivePoint> {
    points.iter().find(|p| p.effective == k).cloned()
}

/// The SOM of the baseline with `k` units.
pub fn som_setup(k: usize, seed: u64) -> SomParams {
    let (rows, cols) = if k < 2 { (1, 1) } else { (2, k.div_ceil(2)) };
    SomParams {
        rows,
        cols,
        radius: Schedule::Exponential {
            start: (cols as f64 / 2.0).max(1.0),
            end: 0.3,
        },
        seed,
        ..SomParams::default()
    }
}

/// The seed of the baselines' run with `k` centres / units in order `rep`.
pub fn baseline_seed(seed: u64, k: usize, rep: usize) -> u64 {
    Rng::stream(seed, (k * 100_000 + rep) as u64).next_u64()
}

/// (effective clusters, purity, ARI, NMI) of one clustering.
pub type Scored = (usize, f64, f64, f64);
