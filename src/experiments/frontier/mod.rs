//! Speed–accuracy frontiers by model size: sweep a method's size knobs on one session,
//! score every size over seeded repetitions (mean and standard error), time its training
//! and its prediction, and recommend the cheapest size whose score is within one standard
//! error of the best ("model no more than a scene needs").
//!
//! Knobs: DS and GS — capacity (BV budget of every expert) × tau (kernel lags), scored by
//! the supervised protocol of [`crate::experiments::recognition`]; sparse coding + SVM — `num_bases`,
//! each with its best (beta, gamma) of the given lists, scored by stratified 10-fold cross
//! validation repeated with seeded fold assignments (the dictionary is learned on all
//! patches without labels, as in the paper and the grid search); DU and GU — the novelty
//! threshold, scored by NMI over seeded orders with the effective clusters it leaves (the
//! runs of [`crate::experiments::clustering`]); sequential k-means and the SOM — k centres / units on
//! the Table I features; the RBF SVM — C × gamma, scored by repeated stratified 5-fold
//! accuracy on the Table I features.
//!
//! Each method answers through its object (`method::FrontierMethod`, one per family in a
//! module of its own; `registry::frontier_method` says which): its knobs, its items, one
//! item, its points.
//!
//! A frontier is computed as work items (one repetition at one size, or one dictionary)
//! whose seeds follow from the run's seed and the item alone, so a sharded sweep
//! (`crate::sweep`) merges into exactly the local result.
//!
//! Cheapest means the least prediction time by default: a model is trained once (or, online,
//! on the grasps it is taught) but predicts at every observation for as long as it is used,
//! and for sparse coding + SVM the training time is dominated by the dictionary, an offline
//! cost. [`CostAxis::Training`] ranks by training time instead.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use crate::catalogue::MethodId;
use crate::experiments::ExperimentError;
use crate::experiments::clustering::{ClusteringRun, UnsupervisedLearner};
use crate::experiments::feature_choice::FeatureChoice;
use crate::experiments::parallel::compute_items;
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::session::Session;
use crate::svm::mean_se;

mod method;
mod points;
mod registered;
mod registry;
pub mod report;
mod run;
mod sparse;
mod supervised;
mod table_one;
mod unsupervised;

pub use method::{FrontierItem, FrontierOutput, FrontierPrep, SparseCell, SweepKnob};
use method::{
    FrontierMethod, MethodPoints, no_sequences, plain_label, plain_short_label, wrong_item,
};
use points::*;
use registry::frontier_method;
pub use run::*;

/// The methods a frontier can sweep: every method of the catalogue with a size knob.
pub fn methods() -> impl Iterator<Item = MethodId> {
    MethodId::all().filter(|&m| frontier_method(m).is_some())
}

/// The knobs a frontier of `method` sweeps, in order, with its default values (none for a
/// method without a frontier): what a form asks for, whatever the method.
pub fn size_knobs(method: MethodId) -> Vec<SweepKnob> {
    let params = FrontierParams::for_method(method);
    frontier_method(method).map_or_else(Vec::new, |m| m.size_knobs(&params))
}

/// The largest count a whole knob takes (far above any size a frontier can fit; it keeps
/// the count exact in a `usize` whatever the caller passes).
pub const MAX_WHOLE: f64 = u32::MAX as f64;

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
    pub method: MethodId,
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
    /// A registered method's sizes, one value per knob (empty: the method's own list).
    #[serde(default)]
    pub sizes: Vec<Vec<f64>>,
}

impl FrontierParams {
    /// The default sweep of a method.
    pub fn for_method(method: MethodId) -> Self {
        FrontierParams {
            method,
            features: method
                .classifier()
                .map_or(FeatureSet::ALL, |c| c.features()),
            score: RecognitionScore::All,
            reps: 10,
            seed: 0,
            cost: CostAxis::Prediction,
            capacities: vec![2, 5, 10, 20, 50, 100],
            taus: vec![1, 2, 5, 15, 30],
            num_bases: vec![2, 3, 5, 10, 15, 20, 29, 40, 60],
            beta: vec![0.5, 1.0, 2.0],
            gamma: vec![0.5, 1.0, 2.0],
            thresholds: match UnsupervisedLearner::of(method) {
                // DU's experts grow as the threshold falls (about 80 at 0.2, 180 at 0.1);
                // below 0.2 a run costs minutes.
                Some(UnsupervisedLearner::Du) => vec![0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8],
                // GU's cluster count falls from ~30 to ~3 between 0.05 and 0.3.
                Some(UnsupervisedLearner::Gu) => vec![0.05, 0.08, 0.1, 0.12, 0.15, 0.2, 0.3],
                // No threshold to sweep.
                None => Vec::new(),
            },
            expert_capacity: None,
            expert_tau: None,
            ks: vec![2, 4, 6, 8, 10, 12, 16, 20],
            svm_c: vec![1.0, 10.0, 100.0, 1000.0],
            svm_gamma: vec![1e-3, 3e-3, 1e-2, 3e-2, 1e-1],
            sizes: Vec::new(),
        }
    }

    /// Every combination of one value per knob, the first knob slowest.
    pub fn sizes_of_lists(lists: &[Vec<f64>]) -> Vec<Vec<f64>> {
        lists.iter().fold(vec![Vec::new()], |sizes, values| {
            sizes
                .iter()
                .flat_map(|s| {
                    values.iter().map(move |&v| {
                        let mut next = s.clone();
                        next.push(v);
                        next
                    })
                })
                .collect()
        })
    }

    /// Each knob's values over a method's sizes, in first-seen order.
    pub fn lists_of_sizes(sizes: &[Vec<f64>]) -> Vec<Vec<f64>> {
        let knobs = sizes.first().map_or(0, Vec::len);
        (0..knobs)
            .map(|k| {
                let mut values: Vec<f64> = Vec::new();
                for s in sizes {
                    if !values.contains(&s[k]) {
                        values.push(s[k]);
                    }
                }
                values
            })
            .collect()
    }

    /// "DS, all features", "sparse coding + SVM", "sequential k-means".
    pub fn label(&self) -> String {
        frontier_method(self.method).map_or_else(|| plain_label(self), |m| m.label(self))
    }

    /// Sweeps `lists` instead: one list per knob of [`size_knobs`], in order.
    pub fn set_size_knobs(&mut self, lists: &[Vec<f64>]) -> Result<(), ExperimentError> {
        let method = self.object()?;
        let knobs = method.size_knobs(self);
        if lists.len() != knobs.len() {
            return Err(ExperimentError::param(
                "sizes",
                format!(
                    "{} has {} size knobs, not {}",
                    self.method.key(),
                    knobs.len(),
                    lists.len()
                ),
            ));
        }
        for (k, list) in knobs.iter().zip(lists) {
            if k.whole
                && let Some(v) =
                    (list.iter()).find(|v| !(v.fract() == 0.0 && (0.0..=MAX_WHOLE).contains(*v)))
            {
                return Err(ExperimentError::param(
                    k.name,
                    format!("{v} is not a whole number"),
                ));
            }
        }
        method.set_size_knobs(self, lists);
        Ok(())
    }

    pub fn validate(&self) -> Result<(), ExperimentError> {
        self.checked().map(|_| ())
    }

    /// The method's frontier object.
    fn object(&self) -> Result<&'static dyn FrontierMethod, ExperimentError> {
        frontier_method(self.method).ok_or_else(|| {
            ExperimentError::param(
                "method",
                format!("{} has no size to sweep", self.method.key()),
            )
        })
    }

    /// The method's frontier object, once the parameters are valid.
    fn checked(&self) -> Result<&'static dyn FrontierMethod, ExperimentError> {
        let method = self.object()?;
        if self.reps < 2 {
            return Err(ExperimentError::param(
                "reps",
                "a standard error needs at least 2 repetitions",
            ));
        }
        method.validate(self)?;
        Ok(method)
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
    /// A short label for the chart, e.g. "capacity 5 · τ 1", "K 29", "θ 0.3", "k 10" or
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
    /// How `auto` chose the feature set (None: it was given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature_choice: Option<FeatureChoice>,
}

impl Frontier {
    /// "DS, all features" or "sparse coding + SVM".
    pub fn label(&self) -> String {
        self.params.label()
    }

    /// A short name for a chart legend: "DS all", "GU encoder", "SC+SVM", "SOM".
    pub fn short_label(&self) -> String {
        let p = &self.params;
        frontier_method(p.method).map_or_else(|| plain_short_label(p), |m| m.short_label(p))
    }
}

/// The best point (highest mean score; ties: the cheaper) and the recommended one: the
/// cheapest on `axis` among the points whose mean score is at least the best's mean minus
/// the best's standard error (ties: the higher score). None without points.
pub fn recommend(points: &[FrontierPoint], axis: CostAxis) -> Option<(usize, usize)> {
    super::feature_choice::one_se_rule(
        points.len(),
        |i| points[i].score,
        |i| points[i].score_se,
        |i| points[i].cost(axis),
    )
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

    #[test]
    fn every_method_sweeps_the_knob_values_it_is_given() {
        for m in methods() {
            let knobs = size_knobs(m);
            assert!(!knobs.is_empty(), "{m}");
            let firsts: Vec<Vec<f64>> = knobs.iter().map(|k| vec![k.values[0]]).collect();
            let mut p = FrontierParams::for_method(m);
            p.set_size_knobs(&firsts).unwrap();
            p.validate().unwrap();
            let swept = frontier_method(m).unwrap().size_knobs(&p);
            let swept: Vec<Vec<f64>> = swept.into_iter().map(|k| k.values).collect();
            assert_eq!(swept, firsts, "{m}");
        }
        // A count refuses a fraction, by the knob's name; every knob needs its list.
        let mut ds = FrontierParams::for_method(MethodId::Ds);
        let err = ds.set_size_knobs(&[vec![2.5], vec![1.0]]).unwrap_err();
        assert!(err.to_string().contains("`capacities`"), "{err}");
        assert!(ds.set_size_knobs(&[vec![2.0]]).is_err());
        let mut raw = FrontierParams::for_method(MethodId::RawSvm);
        assert!(raw.set_size_knobs(&[]).is_err());
    }
}
