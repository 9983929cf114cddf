//! Speed–accuracy frontiers by model size: sweep a method's size knobs on one session,
//! score every size over seeded repetitions (mean and standard error), time its training
//! and its prediction, and recommend the cheapest size whose score is within one standard
//! error of the best ("model no more than a scene needs").
//!
//! Knobs: DS and GS — capacity (BV budget of every expert) × tau (kernel lags), scored by
//! the supervised protocol of [`super::recognition`]; sparse coding + SVM — `num_bases`,
//! each with its best (beta, gamma) of the given lists, scored by stratified 10-fold cross
//! validation repeated with seeded fold assignments (the dictionary is learned on all
//! patches without labels, as in the paper and the grid search).
//!
//! Cheapest means the least prediction time by default: a model is trained once (or, online,
//! on the grasps it is taught) but predicts at every observation for as long as it is used,
//! and for sparse coding + SVM the training time is dominated by the dictionary, an offline
//! cost. [`CostAxis::Training`] ranks by training time instead.

use std::str::FromStr;
use std::time::Instant;

use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::ExperimentError;
use super::recognition::{RecognitionParams, SupervisedLearner, run_recognition};
use super::stability::{DataOptions, PipelineSettings, StabilityData, grasp_features};
use crate::features::FeatureSet;
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::session::Session;
use crate::sparse::DictionaryParams;
use crate::svm::{cross_validate, mean_se, stratified_k_fold};

/// A method whose size the frontier sweeps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FrontierMethod {
    Ds,
    Gs,
    /// Sparse coding + linear SVM (the first paper's pipeline).
    SparseSvm,
}

impl FrontierMethod {
    pub fn name(self) -> &'static str {
        match self {
            FrontierMethod::Ds => "DS",
            FrontierMethod::Gs => "GS",
            FrontierMethod::SparseSvm => "sparse coding + SVM",
        }
    }
}

impl FromStr for FrontierMethod {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "ds" => Ok(FrontierMethod::Ds),
            "gs" => Ok(FrontierMethod::Gs),
            "sparse-svm" => Ok(FrontierMethod::SparseSvm),
            other => Err(ExperimentError::param(
                "method",
                format!("`{other}` is not ds, gs or sparse-svm"),
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
    /// DS/GS: the feature set.
    pub features: FeatureSet,
    /// DS/GS: the score compared.
    #[serde(default)]
    pub score: RecognitionScore,
    /// Seeded repetitions per size (DS/GS: protocol orders; sparse coding: fold
    /// assignments of the 10-fold cross validation).
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
                for (name, v) in [("beta", &self.beta), ("gamma", &self.gamma)] {
                    if let Some(b) = v.iter().find(|b| !(**b > 0.0 && b.is_finite())) {
                        return Err(ExperimentError::param(name, format!("{b} is not > 0")));
                    }
                }
            }
        }
        Ok(())
    }
}

/// One model size on the frontier.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FrontierPoint {
    /// A short label for the chart, e.g. "5·1" (capacity·tau) or "K 29".
    pub label: String,
    /// The whole configuration in words, for a tooltip.
    pub detail: String,
    /// The knobs by name (capacity, tau; or num_bases, beta, gamma).
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
    /// What the times are per: "step" (DS/GS) or "grasp" (sparse coding).
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
        match self.params.method {
            FrontierMethod::SparseSvm => self.params.method.name().to_string(),
            m => format!("{}, {} features", m.name(), self.params.features.name()),
        }
    }

    /// A short name for a chart legend: "DS all", "GS encoder", "SC+SVM".
    pub fn short_label(&self) -> String {
        match self.params.method {
            FrontierMethod::SparseSvm => "SC+SVM".into(),
            m => format!("{} {}", m.name(), self.params.features.name()),
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

/// Sweep the method's size knobs on `session`.
pub fn run_frontier(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<Frontier, ExperimentError> {
    params.validate()?;
    let start = Instant::now();
    let (points, paper_default, score_name, unit) = match params.method {
        FrontierMethod::Ds | FrontierMethod::Gs => {
            let (p, d, s) = recognition_points(session, params, progress)?;
            (p, d, s, "step")
        }
        FrontierMethod::SparseSvm => {
            let (p, d) = sparse_points(session, params, progress)?;
            (p, d, "weighted success rate".to_string(), "grasp")
        }
    };
    let (best, recommended) =
        recommend(&points, params.cost).ok_or_else(|| ExperimentError::Data("no sizes".into()))?;
    let front = |axis: CostAxis| {
        let x: Vec<f64> = points.iter().map(|p| p.cost(axis)).collect();
        let y: Vec<f64> = points.iter().map(|p| p.score).collect();
        crate::figures::pareto_front(&x, &y)
    };
    Ok(Frontier {
        session: session.meta.name.clone(),
        params: params.clone(),
        score_name,
        unit: unit.into(),
        pareto_training: front(CostAxis::Training),
        pareto_prediction: front(CostAxis::Prediction),
        points,
        best,
        recommended,
        paper_default,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

type Points = (Vec<FrontierPoint>, Option<usize>);

/// DS/GS: the supervised protocol at every capacity × tau.
fn recognition_points(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<(Vec<FrontierPoint>, Option<usize>, String), ExperimentError> {
    let learner = match params.method {
        FrontierMethod::Ds => SupervisedLearner::Ds,
        _ => SupervisedLearner::Gs,
    };
    let base = RecognitionParams {
        learner,
        features: params.features,
        reps: params.reps,
        seed: params.seed,
        early_fractions: Vec::new(),
        ..RecognitionParams::default()
    };
    let paper = (base.gs.gp.capacity, base.gs.gp.tau);
    let sizes: Vec<(usize, usize)> = params
        .capacities
        .iter()
        .flat_map(|&c| params.taus.iter().map(move |&t| (c, t)))
        .collect();
    let mut points = Vec::with_capacity(sizes.len());
    for (i, &(capacity, tau)) in sizes.iter().enumerate() {
        progress.checkpoint()?;
        let mut p = base.clone();
        for gp in [&mut p.ds.gp, &mut p.gs.gp] {
            gp.capacity = capacity;
            gp.tau = tau;
        }
        let r = run_recognition(session, &p, progress)?;
        let scores: Vec<f64> = r
            .repetitions
            .iter()
            .map(|x| match params.score {
                RecognitionScore::All => x.all,
                RecognitionScore::Final20 => x.final_20,
            })
            .collect();
        let (score, score_se) = mean_se(&scores);
        let per_step = |secs: f64, steps: usize| 1e6 * secs / steps.max(1) as f64;
        points.push(FrontierPoint {
            label: format!("{capacity}·{tau}"),
            detail: format!(
                "{}, {} features: capacity {capacity}, tau {tau}",
                learner_name(learner),
                params.features.name()
            ),
            knobs: vec![
                ("capacity".into(), capacity as f64),
                ("tau".into(), tau as f64),
            ],
            score,
            score_se,
            reps: scores.len(),
            train_us: median(
                r.repetitions
                    .iter()
                    .map(|x| per_step(x.train_seconds, x.train_steps))
                    .collect(),
            ),
            predict_us: median(
                r.repetitions
                    .iter()
                    .map(|x| per_step(x.predict_seconds, x.predict_steps))
                    .collect(),
            ),
        });
        progress.set(
            (i + 1) as f64 / sizes.len() as f64,
            format!("frontier: {}/{} sizes", i + 1, sizes.len()),
        );
    }
    let paper_default = sizes.iter().position(|&s| s == paper);
    let score_name = match params.score {
        RecognitionScore::All => "accuracy (all)",
        RecognitionScore::Final20 => "accuracy (final 20 %)",
    };
    Ok((points, paper_default, score_name.into()))
}

fn learner_name(l: SupervisedLearner) -> &'static str {
    match l {
        SupervisedLearner::Ds => "DS",
        SupervisedLearner::Gs => "GS",
    }
}

/// One (num_bases, beta, gamma) cell: its scores over the repetitions and its timings.
struct SparseCell {
    num_bases: usize,
    beta: f64,
    gamma: f64,
    scores: Vec<f64>,
    train_secs: f64,
    predict_secs: f64,
}

/// The paper's model size of sparse coding + SVM (the pipeline's default configuration).
const SPARSE_PAPER_NUM_BASES: usize = 29;

/// Sparse coding + SVM: per num_bases, the (beta, gamma) with the best mean score.
fn sparse_points(
    session: &Session,
    params: &FrontierParams,
    progress: &Progress,
) -> Result<Points, ExperimentError> {
    let data = StabilityData::from_session(session, &DataOptions::default())?;
    let settings = PipelineSettings::default();
    let grasps = data.grasp_count() as f64;
    let tasks: Vec<(usize, f64)> = params
        .num_bases
        .iter()
        .flat_map(|&k| params.beta.iter().map(move |&b| (k, b)))
        .collect();
    let rep_seeds: Vec<u64> = (0..params.reps)
        .map(|r| Rng::stream(params.seed, r as u64).next_u64())
        .collect();
    let done = std::sync::atomic::AtomicUsize::new(0);
    let cells: Vec<Vec<SparseCell>> = tasks
        .par_iter()
        .map(|&(num_bases, beta)| {
            progress.checkpoint()?;
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
                    // Coding and deciding are timed once per repetition; the median
                    // resists the machine's load.
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
                out.push(SparseCell {
                    num_bases,
                    beta,
                    gamma,
                    scores,
                    train_secs: fit.secs + median(coding.clone()) + fit_secs,
                    predict_secs: median(coding) + median(deciding),
                });
            }
            let d = done.fetch_add(1, std::sync::atomic::Ordering::Relaxed) + 1;
            progress.set(
                d as f64 / tasks.len() as f64,
                format!("frontier: {d}/{} dictionaries", tasks.len()),
            );
            Ok(out)
        })
        .collect::<Result<_, ExperimentError>>()?;
    let cells: Vec<SparseCell> = cells.into_iter().flatten().collect();
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
            train_us: 1e6 * c.train_secs / grasps,
            predict_us: 1e6 * c.predict_secs / grasps,
        })
        .collect();
    let paper_default = ks.iter().position(|&k| k == SPARSE_PAPER_NUM_BASES);
    Ok((points, paper_default))
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
