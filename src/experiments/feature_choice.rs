//! `--features auto`: the input family of a sequence method chosen from the data. Every
//! candidate family the session has (the paper's `all`, `moments`, `encoders`, `raw`,
//! `change`) is scored by seeded, stratified k-fold cross validation on the training
//! session alone, at the method's default size; the choice is the cheapest family (fewest
//! features per step) whose mean accuracy is within one standard error of the best's, the
//! rule the frontier recommends sizes by ([`one_se_rule`]).
//!
//! A [`FoldScorer`] fits a method on some grasps and scores it on others. DS and GS are
//! scored by their own experts (`recognition::ExpertsScorer`): taught the training folds in
//! the protocol's order, then asked the held-out fold. DU and GU learn without labels, and
//! their score needs a novelty threshold that is itself chosen from the data; they are
//! scored by the experts they are built from (DU by DS's, GU by GS's): the family in which
//! those experts tell the classes apart. A registered method is scored by its own `fit`
//! and `predict` (`classifier::ClassifierScorer`).
//!
//! Cost: (candidate families) × `folds` fits on (folds − 1)/folds of the session, that is
//! about `folds − 1` times one fit of the method per family. On the iCub set (5 families,
//! 5 folds) that is about 20 fits of 200 grasps' worth.

use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::ExperimentError;
use super::labels::session_labels;
use super::parallel::compute_items;
use crate::catalogue::MethodId;
use crate::features::sequence::SequenceError;
use crate::features::{FeatureSequences, FeatureSet, SequenceParams, feature_sequences};
use crate::jobs::Progress;
use crate::rng::Rng;
use crate::session::Session;
use crate::svm::kernel_svm::stratified_folds;
use crate::svm::mean_se;

/// Folds of the choice's cross validation: small, as the choice is a step before the run.
pub const AUTO_FOLDS: usize = 5;

/// A method fitted on some grasps of a session and scored on others.
pub trait FoldScorer: Sync {
    /// The method whose cross validation the scores are.
    fn method(&self) -> MethodId;
    /// A size it cannot be scored at, before any fold is fitted.
    fn check(&self) -> Result<(), ExperimentError> {
        Ok(())
    }
    /// The share of `test` that the method, fitted on `train`, predicts right.
    #[allow(clippy::too_many_arguments)]
    fn accuracy(
        &self,
        feats: &FeatureSequences,
        labels: &[usize],
        n_classes: usize,
        train: &[usize],
        test: &[usize],
        seed: u64,
        progress: &Progress,
    ) -> Result<f64, ExperimentError>;
}

/// One candidate family's cross-validated accuracy.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FamilyScore {
    pub features: FeatureSet,
    /// Features per step on the session (the cost the rule compares).
    pub dim: usize,
    /// Mean accuracy over the folds and its standard error (sd / √folds).
    pub score: f64,
    pub score_se: f64,
}

/// Which family `auto` chose on a session, and why.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FeatureChoice {
    pub chosen: FeatureSet,
    /// The family of the highest mean accuracy.
    pub best: FeatureSet,
    /// The method whose cross validation scored the families.
    pub scored_by: MethodId,
    pub folds: usize,
    pub seed: u64,
    pub candidates: Vec<FamilyScore>,
    pub seconds: f64,
}

impl FeatureChoice {
    /// "raw (60 features per step): the fewest within one SE of the best (raw) by 5-fold
    /// accuracy of DS: all 0.530 ± 0.020, …".
    pub fn text(&self) -> String {
        let dim = self
            .candidates
            .iter()
            .find(|c| c.features == self.chosen)
            .map_or(0, |c| c.dim);
        let scores: Vec<String> = self
            .candidates
            .iter()
            .map(|c| format!("{} {:.3} ± {:.3}", c.features, c.score, c.score_se))
            .collect();
        format!(
            "auto chose {} ({dim} features per step): the fewest within one SE of the best ({}) \
             by {}-fold accuracy of {} on the training session, seed {}: {}",
            self.chosen,
            self.best,
            self.folds,
            self.scored_by.title(),
            self.seed,
            scores.join(", ")
        )
    }
}

/// The families `auto` chooses among on `session`: the paper's `all`, then `moments`,
/// `encoders`, `raw` and `change`, each where the session has its columns (`all` only
/// where it differs from `moments`, i.e. with encoders).
pub fn candidates(session: &Session) -> Vec<FeatureSet> {
    [
        FeatureSet::ALL,
        FeatureSet::MOMENTS,
        FeatureSet::ENCODERS,
        FeatureSet::RAW,
        FeatureSet::CHANGE,
    ]
    .into_iter()
    .filter(|f| f.dim(session).is_some())
    .filter(|f| !(f.is_all() && f.resolve(session) == FeatureSet::MOMENTS))
    .collect()
}

/// Score every candidate family of `session` by `folds`-fold cross validation of `scorer`
/// and choose one (see the module's comment).
pub fn choose_features(
    session: &Session,
    scorer: &dyn FoldScorer,
    label_set: &str,
    folds: usize,
    seed: u64,
    progress: &Progress,
) -> Result<FeatureChoice, ExperimentError> {
    let start = Instant::now();
    scorer.check()?;
    let (labels, classes) = session_labels(session, label_set)?;
    let n = labels.len();
    if folds < 2 || folds > n {
        return Err(ExperimentError::param(
            "folds",
            format!("{folds} folds for {n} grasps"),
        ));
    }
    // A family the session cannot give (`change` where every grasp has one frame) is no
    // candidate; any other error is the caller's.
    let mut families = Vec::new();
    let mut seqs: Vec<FeatureSequences> = Vec::new();
    for features in candidates(session) {
        let params = SequenceParams {
            features,
            taxel_noise_variance: 0.0,
            seed,
        };
        match feature_sequences(session, &params) {
            Ok(f) => {
                families.push(features);
                seqs.push(f);
            }
            Err(SequenceError::Session { .. }) => {}
            Err(e) => return Err(e.into()),
        }
    }
    if families.is_empty() {
        return Err(ExperimentError::Data(
            "the session has no input family to choose from".into(),
        ));
    }
    // Every family is scored on the same folds.
    let fold_of = stratified_folds(&labels, folds, Rng::stream(seed, 0).next_u64());
    let items: Vec<(usize, usize)> = (0..families.len())
        .flat_map(|c| (0..folds).map(move |f| (c, f)))
        .collect();
    // A family's folds cost with its features per step.
    let accuracies = compute_items(
        &items,
        progress,
        "auto features",
        "folds",
        |&(c, _)| seqs[c].dim() as f64,
        |&(c, f), progress| {
            let (test, train): (Vec<usize>, Vec<usize>) = (0..n).partition(|&g| fold_of[g] == f);
            if test.is_empty() {
                return Ok(None);
            }
            let seed = Rng::stream(seed, 1 + f as u64).next_u64();
            scorer
                .accuracy(
                    &seqs[c],
                    &labels,
                    classes.len(),
                    &train,
                    &test,
                    seed,
                    progress,
                )
                .map(Some)
        },
    )?;
    let candidates: Vec<FamilyScore> = families
        .iter()
        .enumerate()
        .map(|(c, &features)| {
            let acc: Vec<f64> = accuracies[c * folds..(c + 1) * folds]
                .iter()
                .flatten()
                .copied()
                .collect();
            let (score, score_se) = mean_se(&acc);
            FamilyScore {
                features,
                dim: seqs[c].dim(),
                score,
                score_se,
            }
        })
        .collect();
    let (best, chosen) = one_se_rule(
        candidates.len(),
        |i| candidates[i].score,
        |i| candidates[i].score_se,
        |i| candidates[i].dim as f64,
    )
    .expect("at least one candidate");
    Ok(FeatureChoice {
        chosen: candidates[chosen].features,
        best: candidates[best].features,
        scored_by: scorer.method(),
        folds,
        seed,
        candidates,
        seconds: start.elapsed().as_secs_f64(),
    })
}

/// The one-standard-error rule over `n` candidates: the best (highest mean score; ties: the
/// cheaper) and the cheapest whose mean is at least the best's mean minus the best's
/// standard error (ties: the higher score, then the first). None for no candidate.
pub fn one_se_rule(
    n: usize,
    score: impl Fn(usize) -> f64,
    se: impl Fn(usize) -> f64,
    cost: impl Fn(usize) -> f64,
) -> Option<(usize, usize)> {
    let cheaper = |a: usize, b: usize| cost(a).total_cmp(&cost(b));
    let best = (0..n).max_by(|&a, &b| score(a).total_cmp(&score(b)).then(cheaper(b, a)))?;
    let bar = score(best) - se(best).max(0.0);
    let recommended = (0..n).filter(|&i| score(i) >= bar).min_by(|&a, &b| {
        cheaper(a, b)
            .then(score(b).total_cmp(&score(a)))
            .then(a.cmp(&b))
    })?;
    Some((best, recommended))
}
