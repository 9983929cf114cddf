//! Cross-validation folds and the paper's scores.
//!
//! Labels are booleans: `false` = success (stable grasp), `true` = failure (the class the
//! paper most wants to catch). Scores are fractions in [0, 1]:
//!
//! - weighted success rate (eq. 4) = (CCS/TS + CCF/TF) / 2,
//! - failure recall = CCF/TF (the paper's "success rate for classifying failed grasps"),
//!
//! where TS/TF are the true successes/failures and CCS/CCF those classified correctly.
//! Cross-validated scores pool the test predictions of all folds (every sample is tested
//! exactly once) into one confusion matrix; the per-fold weighted success rates give the
//! standard error used by the parsimony rule.

use std::cell::RefCell;

use ndarray::{Array2, ArrayView2};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use super::SvmError;
use super::linear::{LinearSvmParams, SvmWorkspace};
use crate::rng::Rng;

/// 2 × 2 confusion counts: `matrix[true class][predicted class]`, class 0 = success
/// (label false), class 1 = failure (label true).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Confusion {
    pub matrix: [[usize; 2]; 2],
}

impl Confusion {
    pub fn from_predictions(truth: &[bool], predicted: &[bool]) -> Self {
        let mut c = Confusion::default();
        for (&t, &p) in truth.iter().zip(predicted) {
            c.matrix[t as usize][p as usize] += 1;
        }
        c
    }

    pub fn add(&mut self, other: &Confusion) {
        for t in 0..2 {
            for p in 0..2 {
                self.matrix[t][p] += other.matrix[t][p];
            }
        }
    }

    /// TS: true successes.
    pub fn total_successes(&self) -> usize {
        self.matrix[0][0] + self.matrix[0][1]
    }

    /// TF: true failures.
    pub fn total_failures(&self) -> usize {
        self.matrix[1][0] + self.matrix[1][1]
    }

    pub fn total(&self) -> usize {
        self.total_successes() + self.total_failures()
    }

    /// CCS / TS (None without successes).
    pub fn success_recall(&self) -> Option<f64> {
        let ts = self.total_successes();
        (ts > 0).then(|| self.matrix[0][0] as f64 / ts as f64)
    }

    /// CCF / TF (None without failures).
    pub fn failure_recall(&self) -> Option<f64> {
        let tf = self.total_failures();
        (tf > 0).then(|| self.matrix[1][1] as f64 / tf as f64)
    }

    /// (CCS/TS + CCF/TF) / 2, the paper's eq. 4 (None unless both classes occur).
    pub fn weighted_success_rate(&self) -> Option<f64> {
        Some(0.5 * (self.success_recall()? + self.failure_recall()?))
    }

    pub fn accuracy(&self) -> Option<f64> {
        let n = self.total();
        (n > 0).then(|| (self.matrix[0][0] + self.matrix[1][1]) as f64 / n as f64)
    }
}

/// An assignment of samples to folds.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct Folds {
    /// Fold of every sample.
    pub fold_of: Vec<usize>,
    pub count: usize,
}

impl Folds {
    pub fn test_indices(&self, fold: usize) -> Vec<usize> {
        (0..self.fold_of.len())
            .filter(|&i| self.fold_of[i] == fold)
            .collect()
    }

    pub fn train_indices(&self, fold: usize) -> Vec<usize> {
        (0..self.fold_of.len())
            .filter(|&i| self.fold_of[i] != fold)
            .collect()
    }
}

/// Stratified k-fold: each class shuffled (seeded) and dealt round-robin to the folds,
/// the second class continuing where the first stopped, so fold sizes differ by at most
/// one and every fold holds each class in proportion (±1).
pub fn stratified_k_fold(labels: &[bool], k: usize, seed: u64) -> Result<Folds, SvmError> {
    let n = labels.len();
    if k < 2 {
        return Err(SvmError::Param(format!("k-fold needs k ≥ 2, got {k}")));
    }
    if n < k {
        return Err(SvmError::Data(format!("{n} samples cannot fill {k} folds")));
    }
    let mut rng = Rng::stream(seed, 0xF01D);
    let mut fold_of = vec![0; n];
    let mut next = 0;
    for class in [false, true] {
        let mut idx: Vec<usize> = (0..n).filter(|&i| labels[i] == class).collect();
        rng.shuffle(&mut idx);
        for i in idx {
            fold_of[i] = next % k;
            next += 1;
        }
    }
    Ok(Folds { fold_of, count: k })
}

/// Folds by group (object): no group is split between train and test. `k = None` gives
/// one fold per group (leave-one-object-out); otherwise the groups, largest first (ties
/// in seeded random order), each go to the fold with the fewest samples so far.
pub fn group_k_fold(groups: &[usize], k: Option<usize>, seed: u64) -> Result<Folds, SvmError> {
    let n_groups = groups.iter().copied().max().map_or(0, |m| m + 1);
    let present: Vec<usize> = {
        let mut seen = vec![false; n_groups];
        groups.iter().for_each(|&g| seen[g] = true);
        (0..n_groups).filter(|&g| seen[g]).collect()
    };
    let k_eff = k.unwrap_or(present.len());
    if k_eff < 2 {
        return Err(SvmError::Param(format!(
            "leave-objects-out needs ≥ 2 folds, got {k_eff}"
        )));
    }
    if present.len() < k_eff {
        return Err(SvmError::Data(format!(
            "{} objects cannot fill {k_eff} folds",
            present.len()
        )));
    }
    let mut size = vec![0usize; n_groups];
    groups.iter().for_each(|&g| size[g] += 1);
    let mut order = present.clone();
    Rng::stream(seed, 0x6B0F).shuffle(&mut order);
    // Stable sort keeps the shuffled order among equal sizes.
    order.sort_by(|a, b| size[*b].cmp(&size[*a]));
    let mut fold_of_group = vec![usize::MAX; n_groups];
    if k.is_none() {
        for (f, &g) in present.iter().enumerate() {
            fold_of_group[g] = f;
        }
    } else {
        let mut load = vec![0usize; k_eff];
        for &g in &order {
            let f = (0..k_eff).min_by_key(|&f| (load[f], f)).unwrap_or(0);
            fold_of_group[g] = f;
            load[f] += size[g];
        }
    }
    Ok(Folds {
        fold_of: groups.iter().map(|&g| fold_of_group[g]).collect(),
        count: k_eff,
    })
}

/// Scores of one fold.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct FoldScore {
    pub fold: usize,
    pub train: usize,
    pub test: usize,
    pub confusion: Confusion,
    /// None when the test fold lacks a class (possible when leaving objects out).
    pub weighted_success_rate: Option<f64>,
}

/// Cross-validated scores.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CvResult {
    pub folds: Vec<FoldScore>,
    /// Confusion of the pooled test predictions (every sample once).
    pub confusion: Confusion,
    pub weighted_success_rate: f64,
    pub failure_recall: f64,
    pub success_recall: f64,
    pub accuracy: f64,
    /// Mean and standard error (sd / sqrt(m)) of the per-fold weighted success rates
    /// over the m folds that hold both classes.
    pub fold_wsr_mean: f64,
    pub fold_wsr_se: f64,
    /// Predicted label of every sample (from the fold that tested it).
    pub predictions: Vec<bool>,
    /// SVM decision value of every sample from the fold that tested it: positive = failure
    /// (label true), so `predictions[i] == (decisions[i] > 0)`.
    #[serde(default)]
    pub decisions: Vec<f64>,
}

/// Train on each fold's complement, test on the fold (folds in parallel; the numbers do
/// not depend on the thread count: fold f's SVM is seeded with stream f of `params.seed`).
/// The SVM standardises on the training fold only.
pub fn cross_validate(
    x: ArrayView2<f64>,
    y: &[bool],
    folds: &Folds,
    params: &LinearSvmParams,
) -> Result<CvResult, SvmError> {
    let n = x.nrows();
    if y.len() != n || folds.fold_of.len() != n {
        return Err(SvmError::Data(format!(
            "{n} samples, {} labels, {} fold assignments",
            y.len(),
            folds.fold_of.len()
        )));
    }
    // The primal Newton solver starts every fold from the all-data model (same optimum,
    // fewer steps).
    let warm = match params.resolved_solver() {
        super::linear::Solver::PrimalNewton => {
            let all: Vec<usize> = (0..n).collect();
            Some(with_workspace(|ws| params.fit_rows(x, &all, y, None, ws))?)
        }
        _ => None,
    };
    type FoldOut = Result<(FoldScore, Vec<(usize, bool, f64)>), SvmError>;
    let per_fold: Vec<FoldOut> = (0..folds.count)
        .into_par_iter()
        .map(|f| {
            let train = folds.train_indices(f);
            let test = folds.test_indices(f);
            let yt: Vec<bool> = train.iter().map(|&i| y[i]).collect();
            let mut p = params.clone();
            p.seed = Rng::stream(params.seed, f as u64).next_u64();
            let model = with_workspace(|ws| p.fit_rows(x, &train, &yt, warm.as_ref(), ws))?;
            let preds: Vec<(usize, bool, f64)> = test
                .iter()
                .map(|&i| (i, model.predict(x.row(i)), model.decision(x.row(i))))
                .collect();
            let truth: Vec<bool> = test.iter().map(|&i| y[i]).collect();
            let pred: Vec<bool> = preds.iter().map(|p| p.1).collect();
            let confusion = Confusion::from_predictions(&truth, &pred);
            Ok((
                FoldScore {
                    fold: f,
                    train: train.len(),
                    test: test.len(),
                    confusion,
                    weighted_success_rate: confusion.weighted_success_rate(),
                },
                preds,
            ))
        })
        .collect();
    let mut fold_scores = Vec::with_capacity(folds.count);
    let mut predictions = vec![false; n];
    let mut decisions = vec![0.0; n];
    let mut confusion = Confusion::default();
    for r in per_fold {
        let (score, preds) = r?;
        confusion.add(&score.confusion);
        for (i, p, d) in preds {
            predictions[i] = p;
            decisions[i] = d;
        }
        fold_scores.push(score);
    }
    let wsrs: Vec<f64> = fold_scores
        .iter()
        .filter_map(|f| f.weighted_success_rate)
        .collect();
    let (fold_wsr_mean, fold_wsr_se) = mean_se(&wsrs);
    Ok(CvResult {
        folds: fold_scores,
        weighted_success_rate: confusion.weighted_success_rate().unwrap_or(f64::NAN),
        failure_recall: confusion.failure_recall().unwrap_or(f64::NAN),
        success_recall: confusion.success_recall().unwrap_or(f64::NAN),
        accuracy: confusion.accuracy().unwrap_or(f64::NAN),
        confusion,
        fold_wsr_mean,
        fold_wsr_se,
        predictions,
        decisions,
    })
}

thread_local! {
    /// The SVM's buffers on this thread, kept across folds and cross validations (the
    /// grid search cross-validates hundreds of times on rows of one size).
    static WORKSPACE: RefCell<SvmWorkspace> = RefCell::new(SvmWorkspace::default());
}

/// Run `f` with this thread's SVM workspace (a fit never re-enters it; should it, the
/// nested fit gets a fresh one).
fn with_workspace<T>(f: impl FnOnce(&mut SvmWorkspace) -> T) -> T {
    WORKSPACE.with(|cell| match cell.try_borrow_mut() {
        Ok(mut ws) => f(&mut ws),
        Err(_) => f(&mut SvmWorkspace::default()),
    })
}

/// Mean and standard error of the mean (sample sd / sqrt(m); 0 for m < 2).
pub fn mean_se(v: &[f64]) -> (f64, f64) {
    let m = v.len();
    if m == 0 {
        return (f64::NAN, f64::NAN);
    }
    let mean = v.iter().sum::<f64>() / m as f64;
    if m < 2 {
        return (mean, 0.0);
    }
    let var = v.iter().map(|x| (x - mean) * (x - mean)).sum::<f64>() / (m - 1) as f64;
    (mean, (var / m as f64).sqrt())
}

/// Rows `idx` of `x`.
pub fn gather(x: ArrayView2<f64>, idx: &[usize]) -> Array2<f64> {
    let d = x.ncols();
    let mut out = Array2::<f64>::zeros((idx.len(), d));
    for (r, &i) in idx.iter().enumerate() {
        out.row_mut(r).assign(&x.row(i));
    }
    out
}
