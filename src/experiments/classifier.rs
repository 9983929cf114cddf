//! Stratified k-fold cross validation of a registered method ([`crate::catalogue::Classifier`])
//! on a session's feature sequences: the score the frontier, the robustness sweeps and a
//! method's own tests compare it by. The folds of repetition r follow from the seed and r
//! alone, so a sharded sweep scores alike.

use std::time::Instant;

use ndarray::ArrayView2;

use super::ExperimentError;
use super::feature_choice::FoldScorer;
use super::labels::session_labels;
use crate::catalogue::{Classifier, ClassifierError, Training};
use crate::features::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::session::Session;
use crate::svm::kernel_svm::stratified_folds;

/// What every repetition shares: the sequences and the classes.
pub struct ClassifierPrep {
    pub feats: FeatureSequences,
    pub labels: Vec<usize>,
    pub n_classes: usize,
}

/// One repetition's accuracy and its times (microseconds per grasp).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CvScore {
    pub accuracy: f64,
    pub train_us: f64,
    pub predict_us: f64,
}

pub fn classifier_err(e: ClassifierError) -> ExperimentError {
    match e {
        ClassifierError::Cancelled => ExperimentError::Cancelled,
        ClassifierError::Param { knob, reason } => ExperimentError::param(knob, reason),
        other => ExperimentError::Classifier(other),
    }
}

/// The session's sequences of `features` and its classes under `label_set`.
pub fn prepare_classifier(
    session: &Session,
    features: FeatureSet,
    label_set: &str,
) -> Result<ClassifierPrep, ExperimentError> {
    let (labels, classes) = session_labels(session, label_set)?;
    let feats = feature_sequences(
        session,
        &SequenceParams {
            features,
            taxel_noise_variance: 0.0,
            seed: 0,
        },
    )?;
    Ok(ClassifierPrep {
        feats,
        labels,
        n_classes: classes.len(),
    })
}

/// Fit on the grasps `train` of `train_seqs` and the share of `test` that `test_seqs`
/// predicts right (the two differ when a perturbation acts on one side only).
#[allow(clippy::too_many_arguments)]
pub fn train_test(
    method: &dyn Classifier,
    size: &[f64],
    train_seqs: &FeatureSequences,
    test_seqs: &FeatureSequences,
    labels: &[usize],
    n_classes: usize,
    train: &[usize],
    test: &[usize],
    seed: u64,
    progress: &Progress,
) -> Result<CvScore, ExperimentError> {
    let x: Vec<ArrayView2<f64>> = train
        .iter()
        .map(|&g| train_seqs.sequences[g].view())
        .collect();
    let y: Vec<usize> = train.iter().map(|&g| labels[g]).collect();
    let t0 = Instant::now();
    let model = method
        .fit(
            size,
            &Training {
                sequences: &x,
                labels: &y,
                n_classes,
                seed,
            },
            progress,
        )
        .map_err(classifier_err)?;
    let train_secs = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let right = test
        .iter()
        .filter(|&&g| model.predict(test_seqs.sequences[g].view()) == labels[g])
        .count();
    let predict_secs = t1.elapsed().as_secs_f64();
    Ok(CvScore {
        accuracy: right as f64 / test.len().max(1) as f64,
        train_us: 1e6 * train_secs / train.len().max(1) as f64,
        predict_us: 1e6 * predict_secs / test.len().max(1) as f64,
    })
}

/// Repetition `rep` of stratified `folds`-fold cross validation at `size`: the accuracy
/// over every grasp, each predicted by the model of the folds it was not in.
pub fn cv_repetition(
    method: &dyn Classifier,
    size: &[f64],
    prep: &ClassifierPrep,
    folds: usize,
    seed: u64,
    rep: usize,
    progress: &Progress,
) -> Result<CvScore, ExperimentError> {
    method.check(size).map_err(classifier_err)?;
    let n = prep.labels.len();
    if folds < 2 || folds > n {
        return Err(ExperimentError::param(
            "folds",
            format!("{folds} folds for {n} grasps"),
        ));
    }
    let fold_seed = Rng::stream(seed, rep as u64).next_u64();
    let fold_of = stratified_folds(&prep.labels, folds, fold_seed);
    let (mut right, mut train_us, mut predict_us) = (0.0, 0.0, 0.0);
    for f in 0..folds {
        progress.checkpoint()?;
        let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&g| fold_of[g] == f);
        if test.is_empty() {
            continue;
        }
        let s = train_test(
            method,
            size,
            &prep.feats,
            &prep.feats,
            &prep.labels,
            prep.n_classes,
            &train,
            &test,
            fold_seed ^ f as u64,
            progress,
        )?;
        right += s.accuracy * test.len() as f64;
        train_us += s.train_us / folds as f64;
        predict_us += s.predict_us / folds as f64;
    }
    Ok(CvScore {
        accuracy: right / n as f64,
        train_us,
        predict_us,
    })
}

/// A registered method at `size`, scored on a fold by its own fit and predict.
pub struct ClassifierScorer<'a> {
    pub method: &'static dyn Classifier,
    pub size: &'a [f64],
}

impl FoldScorer for ClassifierScorer<'_> {
    fn method(&self) -> crate::catalogue::MethodId {
        self.method.info().id
    }

    fn check(&self) -> Result<(), ExperimentError> {
        self.method.check(self.size).map_err(classifier_err)
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
        let s = train_test(
            self.method,
            self.size,
            feats,
            feats,
            labels,
            n_classes,
            train,
            test,
            seed,
            progress,
        )?;
        Ok(s.accuracy)
    }
}
