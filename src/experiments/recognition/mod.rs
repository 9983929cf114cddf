//! The supervised protocol of the second paper (Sec. V-D1, Table II, Figs. 6–9) for DS and
//! GS, repeated with seeds and run in parallel over the repetitions.
//!
//! One repetition: every class's grasps are shuffled; one grasp per class is taught first
//! (in random class order, no prediction); the remaining grasps follow in stratified random
//! order (rounds holding one grasp of every class still left, each round shuffled). Each
//! grasp is predicted, then trained on, over the first 1 − `test_fraction` of that order;
//! the last `test_fraction` is predicted only. Scores: "all" = accuracy over every
//! predicted grasp, "final 20%" = accuracy over the test part, accuracy per trial set (the
//! predicted order cut into `trial_sets` equal parts, Fig. 6), the confusion matrix over all
//! predicted grasps (Fig. 7), and early classification on the test part: the decision from
//! the first ⌈f·T⌉ steps for each fraction f (Fig. 9).

use std::str::FromStr;
use std::time::Instant;

use ndarray::{Array2, s};
use serde::{Deserialize, Serialize};

use crate::catalogue::MethodId;
use crate::experiments::ExperimentError;
use crate::experiments::feature_choice::{AUTO_FOLDS, FeatureChoice, FoldScorer, choose_features};
use crate::experiments::labels::session_labels;
use crate::experiments::parallel::compute_items;
use crate::experiments::result::{MeanSd, SizeReason};
use crate::features::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
use crate::jobs::Progress;
use crate::learners::{Ds, DsParams, Gs, GsParams, SequenceClassifier, lengthscales};
use crate::rng::Rng;
use crate::session::Session;

mod bench;
pub mod report;

pub use bench::*;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum SupervisedLearner {
    Ds,
    Gs,
}

impl SupervisedLearner {
    /// The learner as the catalogue names it.
    pub fn method(self) -> MethodId {
        match self {
            SupervisedLearner::Ds => MethodId::Ds,
            SupervisedLearner::Gs => MethodId::Gs,
        }
    }

    /// The learner the catalogue's `method` is (None: not DS or GS).
    pub fn of(method: MethodId) -> Option<SupervisedLearner> {
        match method {
            MethodId::Ds => Some(SupervisedLearner::Ds),
            MethodId::Gs => Some(SupervisedLearner::Gs),
            MethodId::SparseSvm
            | MethodId::RawSvm
            | MethodId::Du
            | MethodId::Gu
            | MethodId::KMeans
            | MethodId::Som
            | MethodId::RbfSvm
            | MethodId::Classifier(_) => None,
        }
    }
}

impl FromStr for SupervisedLearner {
    type Err = ExperimentError;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "ds" => Ok(SupervisedLearner::Ds),
            "gs" => Ok(SupervisedLearner::Gs),
            other => Err(ExperimentError::param(
                "learner",
                format!("`{other}` is not ds or gs"),
            )),
        }
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecognitionParams {
    pub learner: SupervisedLearner,
    pub features: FeatureSet,
    /// Repetitions of the protocol (the paper: 50).
    pub reps: usize,
    pub seed: u64,
    /// Share of the predicted order that is test only (the paper: 0.2).
    pub test_fraction: f64,
    /// Trial sets of Fig. 6.
    pub trial_sets: usize,
    /// Label set holding the classes.
    pub label_set: String,
    /// Variance of Gaussian noise on the raw taxels (Fig. 8: 100 and 1000); 0 for none.
    pub taxel_noise_variance: f64,
    /// Fractions of each test sequence for early classification.
    pub early_fractions: Vec<f64>,
    pub ds: DsParams,
    pub gs: GsParams,
    /// Why the experts have their capacity and tau (older results: the paper's).
    #[serde(default)]
    pub size_reason: SizeReason,
}

impl Default for RecognitionParams {
    fn default() -> Self {
        RecognitionParams {
            learner: SupervisedLearner::Gs,
            features: FeatureSet::ALL,
            reps: 50,
            seed: 0,
            test_fraction: 0.2,
            trial_sets: 10,
            label_set: "object".into(),
            taxel_noise_variance: 0.0,
            early_fractions: (1..=10).map(|i| i as f64 / 10.0).collect(),
            ds: DsParams::default(),
            gs: GsParams::default(),
            size_reason: SizeReason::PaperDefault,
        }
    }
}

impl RecognitionParams {
    pub fn validate(&self) -> Result<(), ExperimentError> {
        if self.reps == 0 {
            return Err(ExperimentError::param("reps", "must be at least 1"));
        }
        if !(self.test_fraction > 0.0 && self.test_fraction < 1.0) {
            return Err(ExperimentError::param(
                "test_fraction",
                "must lie in (0, 1)",
            ));
        }
        if self.trial_sets == 0 {
            return Err(ExperimentError::param("trial_sets", "must be at least 1"));
        }
        if self
            .early_fractions
            .iter()
            .any(|f| !(*f > 0.0 && *f <= 1.0))
        {
            return Err(ExperimentError::param(
                "early_fractions",
                "each must lie in (0, 1]",
            ));
        }
        self.ds.validate()?;
        self.gs.validate()?;
        SequenceParams {
            // `auto` becomes a family before the run (`choose_auto_features`).
            features: if self.features.is_auto() {
                FeatureSet::ALL
            } else {
                self.features
            },
            taxel_noise_variance: self.taxel_noise_variance,
            seed: self.seed,
        }
        .validate()?;
        Ok(())
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RepetitionResult {
    pub rep: usize,
    /// Accuracy over every predicted grasp ("All" of Table II).
    pub all: f64,
    /// Accuracy over the test part ("Final 20%").
    pub final_20: f64,
    pub trial_sets: Vec<f64>,
    /// Early-classification accuracy on the test part, one per fraction.
    pub early: Vec<f64>,
    /// Counts [true class][predicted class] over every predicted grasp.
    pub confusion: Vec<Vec<usize>>,
    /// Every predicted grasp, in the order predicted.
    #[serde(default)]
    pub predictions: Vec<Prediction>,
    /// Learned lengthscales [class][feature] at the end.
    pub lengthscales: Vec<Vec<f64>>,
    /// Seconds spent predicting / training and the steps each covered.
    pub predict_seconds: f64,
    pub predict_steps: usize,
    pub train_seconds: f64,
    pub train_steps: usize,
}

/// One prediction of a repetition (classes index `RecognitionResult::classes`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Prediction {
    /// Index into `Session::grasps`.
    pub grasp: usize,
    pub truth: usize,
    pub predicted: usize,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecognitionSummary {
    pub all: MeanSd,
    pub final_20: MeanSd,
    pub trial_sets: Vec<MeanSd>,
    pub early: Vec<MeanSd>,
    pub confusion: Vec<Vec<usize>>,
    /// Mean over repetitions of the learned lengthscales [class][feature].
    pub lengthscales: Vec<Vec<f64>>,
    /// Mean microseconds per prediction step (all classes) and per training step.
    pub predict_step_us: f64,
    pub train_step_us: f64,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RecognitionResult {
    pub params: RecognitionParams,
    pub classes: Vec<String>,
    pub feature_names: Vec<String>,
    /// The families the inputs held (`all` resolved on the session; None in older results).
    #[serde(default)]
    pub features_used: Option<FeatureSet>,
    /// How `auto` chose the family (None: the family was given).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub feature_choice: Option<FeatureChoice>,
    pub summary: RecognitionSummary,
    pub repetitions: Vec<RepetitionResult>,
    pub wall_seconds: f64,
    /// CPU seconds of the whole process over the run (None where /proc is missing).
    pub cpu_seconds: Option<f64>,
}

/// A fresh learner of the chosen kind with one expert per class.
pub fn new_learner(
    kind: SupervisedLearner,
    dim: usize,
    n_classes: usize,
    ds: &DsParams,
    gs: &GsParams,
) -> Result<Box<dyn SequenceClassifier>, ExperimentError> {
    let mut l: Box<dyn SequenceClassifier> = match kind {
        SupervisedLearner::Ds => Box::new(Ds::new(dim, ds)?),
        SupervisedLearner::Gs => Box::new(Gs::new(dim, gs)?),
    };
    for _ in 0..n_classes {
        l.add_class()?;
    }
    Ok(l)
}

/// The protocol's order: one grasp per class first (the teaching phase), then the rest in
/// stratified random rounds. Returns (teaching grasps, predicted order).
pub fn protocol_order(
    labels: &[usize],
    n_classes: usize,
    rng: &mut Rng,
) -> (Vec<usize>, Vec<usize>) {
    let mut per_class: Vec<Vec<usize>> = vec![Vec::new(); n_classes];
    for (g, &l) in labels.iter().enumerate() {
        per_class[l].push(g);
    }
    for v in &mut per_class {
        rng.shuffle(v);
    }
    let mut classes: Vec<usize> = (0..n_classes)
        .filter(|&c| !per_class[c].is_empty())
        .collect();
    rng.shuffle(&mut classes);
    let teach: Vec<usize> = classes.iter().map(|&c| per_class[c][0]).collect();
    let mut order = Vec::new();
    let rounds = per_class.iter().map(|v| v.len()).max().unwrap_or(0);
    for r in 1..rounds {
        let mut round: Vec<usize> = (0..n_classes)
            .filter_map(|c| per_class[c].get(r).copied())
            .collect();
        rng.shuffle(&mut round);
        order.extend(round);
    }
    (teach, order)
}

fn accuracy(hits: &[bool]) -> f64 {
    if hits.is_empty() {
        return 0.0;
    }
    hits.iter().filter(|&&h| h).count() as f64 / hits.len() as f64
}

/// The step count that a fraction f of a T-step sequence covers: ⌈f·T⌉, at least 1.
pub fn prefix_len(f: f64, t: usize) -> usize {
    ((f * t as f64).ceil() as usize).clamp(1, t.max(1))
}

fn run_repetition(
    params: &RecognitionParams,
    session: &Session,
    base: &FeatureSequences,
    labels: &[usize],
    n_classes: usize,
    rep: usize,
    progress: &Progress,
) -> Result<RepetitionResult, ExperimentError> {
    let mut rng = Rng::stream(params.seed, rep as u64);
    let noisy;
    let feats = if params.taxel_noise_variance > 0.0 {
        noisy = feature_sequences(
            session,
            &SequenceParams {
                features: params.features,
                taxel_noise_variance: params.taxel_noise_variance,
                seed: rng.next_u64(),
            },
        )?;
        &noisy
    } else {
        base
    };
    let seqs = &feats.sequences;
    let mut learner = new_learner(
        params.learner,
        feats.dim(),
        n_classes,
        &params.ds,
        &params.gs,
    )?;
    let (teach, order) = protocol_order(labels, n_classes, &mut rng);
    let (mut train_s, mut train_steps) = (0.0, 0usize);
    let (mut pred_s, mut pred_steps) = (0.0, 0usize);
    for &g in &teach {
        let t0 = Instant::now();
        learner.train_sequence(seqs[g].view(), labels[g]);
        train_s += t0.elapsed().as_secs_f64();
        train_steps += seqs[g].nrows();
    }
    let n_test = ((params.test_fraction * order.len() as f64).round() as usize).min(order.len());
    let n_train = order.len() - n_test;
    let mut hits = Vec::with_capacity(order.len());
    let mut confusion = vec![vec![0usize; n_classes]; n_classes];
    let mut predictions = Vec::with_capacity(order.len());
    let mut early_hits = vec![Vec::new(); params.early_fractions.len()];
    for (i, &g) in order.iter().enumerate() {
        let seq = seqs[g].view();
        let t0 = Instant::now();
        let dist = learner.predict_sequence(seq);
        pred_s += t0.elapsed().as_secs_f64();
        pred_steps += seq.nrows();
        let pred = learner.decide(dist.view());
        hits.push(pred == labels[g]);
        confusion[labels[g]][pred] += 1;
        predictions.push(Prediction {
            grasp: g,
            truth: labels[g],
            predicted: pred,
        });
        if i < n_train {
            let t0 = Instant::now();
            learner.train_sequence(seq, labels[g]);
            train_s += t0.elapsed().as_secs_f64();
            train_steps += seq.nrows();
        } else {
            for (f, h) in params.early_fractions.iter().zip(early_hits.iter_mut()) {
                let k = prefix_len(*f, dist.nrows());
                h.push(learner.decide(dist.slice(s![..k, ..])) == labels[g]);
            }
        }
        progress.set_fraction((i + 1) as f64 / order.len() as f64);
    }
    let set_len = order.len().div_ceil(params.trial_sets).max(1);
    Ok(RepetitionResult {
        rep,
        all: accuracy(&hits),
        final_20: accuracy(&hits[n_train..]),
        trial_sets: hits.chunks(set_len).map(accuracy).collect(),
        early: early_hits.iter().map(|h| accuracy(h)).collect(),
        confusion,
        predictions,
        lengthscales: lengthscales(learner.as_ref())
            .rows()
            .into_iter()
            .map(|r| r.to_vec())
            .collect(),
        predict_seconds: pred_s,
        predict_steps: pred_steps,
        train_seconds: train_s,
        train_steps,
    })
}

/// What every repetition shares: the labels, the class names and the clean feature
/// sequences.
pub struct RecognitionPrep {
    pub labels: Vec<usize>,
    pub classes: Vec<String>,
    pub feats: FeatureSequences,
}

/// Check the parameters and prepare what every repetition shares.
pub fn prepare_recognition(
    session: &Session,
    params: &RecognitionParams,
) -> Result<RecognitionPrep, ExperimentError> {
    params.validate()?;
    let (labels, classes) = session_labels(session, &params.label_set)?;
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features: params.features,
            taxel_noise_variance: 0.0,
            seed: params.seed,
        },
    )?;
    Ok(RecognitionPrep {
        labels,
        classes,
        feats,
    })
}

/// Repetition `rep` of the protocol, on its own random stream (`Rng::stream(seed, rep)`),
/// so any machine computes it alike.
pub fn recognition_repetition(
    params: &RecognitionParams,
    session: &Session,
    prep: &RecognitionPrep,
    rep: usize,
    progress: &Progress,
) -> Result<RepetitionResult, ExperimentError> {
    run_repetition(
        params,
        session,
        &prep.feats,
        &prep.labels,
        prep.classes.len(),
        rep,
        progress,
    )
}

/// The result from the repetitions (in order) and the run's timings.
pub fn assemble_recognition(
    params: &RecognitionParams,
    prep: RecognitionPrep,
    reps: Vec<RepetitionResult>,
    wall_seconds: f64,
    cpu_seconds: Option<f64>,
) -> RecognitionResult {
    let summary = summarise(&reps, prep.classes.len(), prep.feats.dim(), params);
    RecognitionResult {
        params: params.clone(),
        classes: prep.classes,
        features_used: Some(prep.feats.families),
        feature_choice: None,
        feature_names: prep.feats.names,
        summary,
        repetitions: reps,
        wall_seconds,
        cpu_seconds,
    }
}

/// Run the supervised protocol `params.reps` times (in parallel, each repetition on its own
/// random stream, so results do not depend on the thread count).
pub fn run_recognition(
    session: &Session,
    params: &RecognitionParams,
    progress: &Progress,
) -> Result<RecognitionResult, ExperimentError> {
    let start = Instant::now();
    let cpu_start = cpu_seconds(true);
    // Choosing the inputs costs about AUTO_REPETITIONS repetitions of the protocol.
    let auto = if params.features.is_auto() {
        AUTO_REPETITIONS
    } else {
        0.0
    };
    let parts = progress.parts(&[auto, params.reps as f64]);
    let (params, feature_choice) = choose_auto_features(session, params, &parts[0])?;
    let params = &params;
    let prep = prepare_recognition(session, params)?;
    let progress = &parts[1];
    progress.set(0.0, "recognition: starting");
    let items: Vec<usize> = (0..params.reps).collect();
    // Repetitions cost alike.
    let reps = compute_items(
        &items,
        progress,
        "recognition",
        "repetitions",
        |_| 1.0,
        |&rep, part| recognition_repetition(params, session, &prep, rep, part),
    )?;
    Ok(RecognitionResult {
        feature_choice,
        ..assemble_recognition(
            params,
            prep,
            reps,
            start.elapsed().as_secs_f64(),
            cpu_seconds(true).zip(cpu_start).map(|(b, a)| b - a),
        )
    })
}

/// What `--features auto`'s cross validation costs, in repetitions of the protocol: every
/// candidate family (five on the iCub) in every fold (five), each fold teaching four
/// fifths of the grasps (`benches/estimates.rs`: 24 s on iCub for DS, a repetition 0.8 s).
pub const AUTO_REPETITIONS: f64 = 25.0;

/// `params` with `auto` replaced by the family its experts' cross validation on `session`
/// chooses (and how), or as they are.
pub fn choose_auto_features(
    session: &Session,
    params: &RecognitionParams,
    progress: &Progress,
) -> Result<(RecognitionParams, Option<FeatureChoice>), ExperimentError> {
    if !params.features.is_auto() {
        return Ok((params.clone(), None));
    }
    progress.set(0.0, "auto features: cross validation");
    let choice = choose_features(
        session,
        &ExpertsScorer {
            learner: params.learner,
            ds: &params.ds,
            gs: &params.gs,
        },
        &params.label_set,
        AUTO_FOLDS,
        params.seed,
        progress,
    )?;
    let chosen = RecognitionParams {
        features: choice.chosen,
        ..params.clone()
    };
    Ok((chosen, Some(choice)))
}

/// DS or GS experts scored on a fold: taught the training grasps in the protocol's order
/// (one per class, then stratified rounds), then asked each held-out grasp.
pub struct ExpertsScorer<'a> {
    pub learner: SupervisedLearner,
    pub ds: &'a DsParams,
    pub gs: &'a GsParams,
}

impl FoldScorer for ExpertsScorer<'_> {
    fn method(&self) -> MethodId {
        self.learner.method()
    }

    fn accuracy(
        &self,
        feats: &FeatureSequences,
        labels: &[usize],
        n_classes: usize,
        train: &[usize],
        test: &[usize],
        seed: u64,
        progress: &Progress,
    ) -> Result<f64, ExperimentError> {
        let mut experts = new_learner(self.learner, feats.dim(), n_classes, self.ds, self.gs)?;
        let train_labels: Vec<usize> = train.iter().map(|&g| labels[g]).collect();
        let (teach, order) = protocol_order(&train_labels, n_classes, &mut Rng::stream(seed, 0));
        for i in teach.into_iter().chain(order) {
            progress.checkpoint()?;
            experts.train_sequence(feats.sequences[train[i]].view(), train_labels[i]);
        }
        let right = test
            .iter()
            .filter(|&&g| {
                let dist = experts.predict_sequence(feats.sequences[g].view());
                experts.decide(dist.view()) == labels[g]
            })
            .count();
        Ok(right as f64 / test.len().max(1) as f64)
    }
}

fn summarise(
    reps: &[RepetitionResult],
    n_classes: usize,
    dim: usize,
    params: &RecognitionParams,
) -> RecognitionSummary {
    let n_sets = reps.iter().map(|r| r.trial_sets.len()).max().unwrap_or(0);
    let mut confusion = vec![vec![0usize; n_classes]; n_classes];
    let mut ls = Array2::<f64>::zeros((n_classes, dim));
    for r in reps {
        for (a, b) in confusion.iter_mut().zip(&r.confusion) {
            for (x, y) in a.iter_mut().zip(b) {
                *x += y;
            }
        }
        for (c, row) in r.lengthscales.iter().enumerate() {
            for (j, v) in row.iter().enumerate() {
                ls[[c, j]] += v / reps.len() as f64;
            }
        }
    }
    let per_step = |secs: f64, steps: usize| {
        if steps == 0 {
            0.0
        } else {
            1e6 * secs / steps as f64
        }
    };
    RecognitionSummary {
        all: MeanSd::of(reps.iter().map(|r| r.all)),
        final_20: MeanSd::of(reps.iter().map(|r| r.final_20)),
        trial_sets: (0..n_sets)
            .map(|i| MeanSd::of(reps.iter().filter_map(|r| r.trial_sets.get(i).copied())))
            .collect(),
        early: (0..params.early_fractions.len())
            .map(|i| MeanSd::of(reps.iter().map(|r| r.early[i])))
            .collect(),
        confusion,
        lengthscales: ls.rows().into_iter().map(|r| r.to_vec()).collect(),
        predict_step_us: per_step(
            reps.iter().map(|r| r.predict_seconds).sum(),
            reps.iter().map(|r| r.predict_steps).sum(),
        ),
        train_step_us: per_step(
            reps.iter().map(|r| r.train_seconds).sum(),
            reps.iter().map(|r| r.train_steps).sum(),
        ),
    }
}

/// For the replay view: the class distribution at every step of grasp `grasp`, from a
/// learner taught every other grasp in the protocol's seeded order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GraspTrace {
    pub grasp: usize,
    pub true_class: usize,
    pub classes: Vec<String>,
    /// [step][class]
    pub distribution: Vec<Vec<f64>>,
    pub decided: usize,
}

pub fn grasp_trace(
    session: &Session,
    params: &RecognitionParams,
    grasp: usize,
) -> Result<GraspTrace, ExperimentError> {
    params.validate()?;
    let (labels, classes) = session_labels(session, &params.label_set)?;
    if grasp >= labels.len() {
        return Err(ExperimentError::param("grasp", format!("no grasp {grasp}")));
    }
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features: params.features,
            taxel_noise_variance: params.taxel_noise_variance,
            seed: params.seed,
        },
    )?;
    let mut learner = new_learner(
        params.learner,
        feats.dim(),
        classes.len(),
        &params.ds,
        &params.gs,
    )?;
    let mut rng = Rng::stream(params.seed, 0);
    let (teach, order) = protocol_order(&labels, classes.len(), &mut rng);
    for g in teach.into_iter().chain(order).filter(|&g| g != grasp) {
        learner.train_sequence(feats.sequences[g].view(), labels[g]);
    }
    let dist = learner.predict_sequence(feats.sequences[grasp].view());
    Ok(GraspTrace {
        grasp,
        true_class: labels[grasp],
        classes,
        decided: learner.decide(dist.view()),
        distribution: dist.rows().into_iter().map(|r| r.to_vec()).collect(),
    })
}
