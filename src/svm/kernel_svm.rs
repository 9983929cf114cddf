//! An offline RBF-kernel support vector machine: the second paper's "SVM 5-fold" baseline
//! (Table II) on the per-grasp features of its Table I.
//!
//! C-SVC dual, min ½ αᵀQα − eᵀα subject to 0 ≤ α ≤ C and yᵀα = 0, with
//! Q_ij = y_i y_j K(x_i, x_j) and K(x, x') = exp(−γ ‖x − x'‖²), solved by sequential minimal
//! optimisation with the second-order working-set selection of Fan, Chen & Lin (2005), as in
//! LIBSVM. Several classes: one-vs-one, one machine per pair, majority vote (ties to the
//! lower class id), as LIBSVM (and RapidMiner's SVM, which the paper used) does.
//! Features can be standardised inside the model, so that cross-validation fits the scaling
//! on the training folds only.

use ndarray::{Array2, ArrayView1, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::features::{FeatureError, Normalisation, Normaliser};
use crate::rng::Rng;

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum KernelSvmError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
    #[error("invalid data: {0}")]
    InvalidData(String),
    /// The scaling of the inputs failed (its source kept).
    #[error("{0}")]
    Features(#[from] FeatureError),
}

fn invalid(name: &'static str, reason: impl Into<String>) -> KernelSvmError {
    KernelSvmError::InvalidParameter {
        name,
        reason: reason.into(),
    }
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KernelSvmParams {
    /// Penalty on margin violations.
    pub c: f64,
    /// RBF kernel width: K(x, x') = exp(−γ ‖x − x'‖²).
    pub gamma: f64,
    /// Stopping tolerance on the maximal KKT violation (LIBSVM's `eps`, 1e-3).
    pub tol: f64,
    /// Cap on SMO iterations per binary machine; a machine that reaches it is kept and
    /// marked as not converged.
    pub max_iter: usize,
    /// Feature scaling fitted on the training samples and applied before the kernel.
    pub scaling: Option<Normalisation>,
}

impl Default for KernelSvmParams {
    fn default() -> Self {
        KernelSvmParams {
            c: 10.0,
            gamma: 0.01,
            tol: 1e-3,
            max_iter: 1_000_000,
            scaling: Some(Normalisation::ZScore),
        }
    }
}

/// One binary machine: decision(x) = Σ coef_i K(sv_i, x) − rho, positive for the first class.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BinarySvm {
    /// Class ids (positive, negative).
    pub classes: (usize, usize),
    pub support_vectors: Array2<f64>,
    /// α_i y_i of each support vector.
    pub coef: Vec<f64>,
    pub rho: f64,
    pub iterations: usize,
    pub converged: bool,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KernelSvm {
    pub gamma: f64,
    /// Class ids seen in training, ascending.
    pub classes: Vec<usize>,
    pub scaler: Option<Normaliser>,
    /// One machine per pair of classes (empty with a single class).
    pub machines: Vec<BinarySvm>,
}

fn rbf(gamma: f64, a: ArrayView1<f64>, b: ArrayView1<f64>) -> f64 {
    let d2: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum();
    (-gamma * d2).exp()
}

/// Smallest curvature used along a working pair (LIBSVM's TAU) when K is not positive
/// definite along it (e.g. duplicate samples).
const TAU: f64 = 1e-12;

/// SMO on one binary problem over the samples `idx` (rows of the Gram matrix `k`) with labels
/// ±1. Returns α, ρ, the number of iterations and whether the KKT tolerance was reached.
fn smo(
    k: &Array2<f64>,
    idx: &[usize],
    y: &[f64],
    c: f64,
    tol: f64,
    max_iter: usize,
) -> (Vec<f64>, f64, usize, bool) {
    let n = idx.len();
    let kk = |a: usize, b: usize| k[[idx[a], idx[b]]];
    let mut alpha = vec![0.0; n];
    // gradient of the dual objective, Qα − e
    let mut grad = vec![-1.0; n];
    let in_up = |a: f64, y: f64| (y > 0.0 && a < c) || (y < 0.0 && a > 0.0);
    let in_low = |a: f64, y: f64| (y > 0.0 && a > 0.0) || (y < 0.0 && a < c);
    let mut iterations = 0;
    let mut converged = false;
    while iterations < max_iter {
        // i: the most violating index from above
        let mut g_max = f64::NEG_INFINITY;
        let mut i = usize::MAX;
        for t in 0..n {
            if in_up(alpha[t], y[t]) && -y[t] * grad[t] >= g_max {
                g_max = -y[t] * grad[t];
                i = t;
            }
        }
        // j: the second-order choice from below; g_min closes the KKT gap
        let mut g_min = f64::INFINITY;
        let mut j = usize::MAX;
        let mut best = f64::INFINITY;
        if i != usize::MAX {
            for t in 0..n {
                if !in_low(alpha[t], y[t]) {
                    continue;
                }
                let v = -y[t] * grad[t];
                g_min = g_min.min(v);
                let b = g_max - v;
                if b > 0.0 {
                    let mut a = kk(i, i) + kk(t, t) - 2.0 * kk(i, t);
                    if a <= 0.0 {
                        a = TAU;
                    }
                    let obj = -b * b / a;
                    if obj <= best {
                        best = obj;
                        j = t;
                    }
                }
            }
        }
        if i == usize::MAX || j == usize::MAX || g_max - g_min < tol {
            converged = true;
            break;
        }
        iterations += 1;
        let (old_i, old_j) = (alpha[i], alpha[j]);
        let kij = kk(i, j);
        if y[i] != y[j] {
            let quad = (kk(i, i) + kk(j, j) - 2.0 * kij).max(TAU);
            let delta = (-grad[i] - grad[j]) / quad;
            let diff = alpha[i] - alpha[j];
            alpha[i] += delta;
            alpha[j] += delta;
            if diff > 0.0 {
                if alpha[j] < 0.0 {
                    alpha[j] = 0.0;
                    alpha[i] = diff;
                }
            } else if alpha[i] < 0.0 {
                alpha[i] = 0.0;
                alpha[j] = -diff;
            }
            if diff > 0.0 {
                if alpha[i] > c {
                    alpha[i] = c;
                    alpha[j] = c - diff;
                }
            } else if alpha[j] > c {
                alpha[j] = c;
                alpha[i] = c + diff;
            }
        } else {
            let quad = (kk(i, i) + kk(j, j) - 2.0 * kij).max(TAU);
            let delta = (grad[i] - grad[j]) / quad;
            let sum = alpha[i] + alpha[j];
            alpha[i] -= delta;
            alpha[j] += delta;
            if sum > c {
                if alpha[i] > c {
                    alpha[i] = c;
                    alpha[j] = sum - c;
                }
                if alpha[j] > c {
                    alpha[j] = c;
                    alpha[i] = sum - c;
                }
            } else {
                if alpha[j] < 0.0 {
                    alpha[j] = 0.0;
                    alpha[i] = sum;
                }
                if alpha[i] < 0.0 {
                    alpha[i] = 0.0;
                    alpha[j] = sum;
                }
            }
        }
        let (di, dj) = (alpha[i] - old_i, alpha[j] - old_j);
        for t in 0..n {
            grad[t] += y[t] * (y[i] * kk(i, t) * di + y[j] * kk(j, t) * dj);
        }
    }
    // ρ: the mean of y_i ∇_i over free vectors, else the middle of the feasible interval
    let (mut ub, mut lb) = (f64::INFINITY, f64::NEG_INFINITY);
    let (mut free, mut sum_free) = (0usize, 0.0);
    for t in 0..n {
        let yg = y[t] * grad[t];
        if alpha[t] >= c {
            if y[t] < 0.0 {
                ub = ub.min(yg);
            } else {
                lb = lb.max(yg);
            }
        } else if alpha[t] <= 0.0 {
            if y[t] > 0.0 {
                ub = ub.min(yg);
            } else {
                lb = lb.max(yg);
            }
        } else {
            free += 1;
            sum_free += yg;
        }
    }
    let rho = if free > 0 {
        sum_free / free as f64
    } else if ub.is_finite() && lb.is_finite() {
        0.5 * (ub + lb)
    } else if ub.is_finite() {
        ub
    } else {
        lb
    };
    (alpha, rho, iterations, converged)
}

impl KernelSvmParams {
    pub fn validate(&self) -> Result<(), KernelSvmError> {
        if !(self.c.is_finite() && self.c > 0.0) {
            return Err(invalid(
                "c",
                format!("must be positive and finite, got {}", self.c),
            ));
        }
        if !(self.gamma.is_finite() && self.gamma > 0.0) {
            return Err(invalid(
                "gamma",
                format!("must be positive and finite, got {}", self.gamma),
            ));
        }
        if !(self.tol.is_finite() && self.tol > 0.0) {
            return Err(invalid(
                "tol",
                format!("must be positive, got {}", self.tol),
            ));
        }
        if self.max_iter == 0 {
            return Err(invalid("max_iter", "needs at least one iteration"));
        }
        Ok(())
    }

    /// Train on the rows of `x` with class ids `y` (arbitrary ids, at least one sample).
    /// With a single class there is nothing to separate: the model has that one class,
    /// no machine, and predicts it everywhere.
    pub fn fit(&self, x: ArrayView2<f64>, y: &[usize]) -> Result<KernelSvm, KernelSvmError> {
        self.validate()?;
        check_features(x)?;
        if y.len() != x.nrows() {
            return Err(KernelSvmError::InvalidData(format!(
                "{} samples but {} labels",
                x.nrows(),
                y.len()
            )));
        }
        let scaler = match self.scaling {
            Some(kind) => Some(Normaliser::fit(kind, x)?),
            None => None,
        };
        let x = scale(&scaler, x)?;
        let n = x.nrows();
        let mut gram = Array2::zeros((n, n));
        for a in 0..n {
            for b in a..n {
                let v = rbf(self.gamma, x.row(a), x.row(b));
                gram[[a, b]] = v;
                gram[[b, a]] = v;
            }
        }
        let mut classes = y.to_vec();
        classes.sort_unstable();
        classes.dedup();
        let mut machines = Vec::new();
        for (p, &pos) in classes.iter().enumerate() {
            for &neg in &classes[p + 1..] {
                let idx: Vec<usize> = (0..n).filter(|&s| y[s] == pos || y[s] == neg).collect();
                let labels: Vec<f64> = idx
                    .iter()
                    .map(|&s| if y[s] == pos { 1.0 } else { -1.0 })
                    .collect();
                let (alpha, rho, iterations, converged) =
                    smo(&gram, &idx, &labels, self.c, self.tol, self.max_iter);
                let support: Vec<usize> = (0..idx.len()).filter(|&t| alpha[t] > 0.0).collect();
                let mut support_vectors = Array2::zeros((support.len(), x.ncols()));
                for (r, &t) in support.iter().enumerate() {
                    support_vectors.row_mut(r).assign(&x.row(idx[t]));
                }
                machines.push(BinarySvm {
                    classes: (pos, neg),
                    support_vectors,
                    coef: support.iter().map(|&t| alpha[t] * labels[t]).collect(),
                    rho,
                    iterations,
                    converged,
                });
            }
        }
        Ok(KernelSvm {
            gamma: self.gamma,
            classes,
            scaler,
            machines,
        })
    }
}

fn check_features(x: ArrayView2<f64>) -> Result<(), KernelSvmError> {
    if x.nrows() == 0 || x.ncols() == 0 {
        return Err(KernelSvmError::InvalidData(format!(
            "needs samples and features, got {} × {}",
            x.nrows(),
            x.ncols()
        )));
    }
    if x.iter().any(|v| !v.is_finite()) {
        return Err(KernelSvmError::InvalidData(
            "a feature is not finite".into(),
        ));
    }
    Ok(())
}

fn scale(scaler: &Option<Normaliser>, x: ArrayView2<f64>) -> Result<Array2<f64>, KernelSvmError> {
    match scaler {
        Some(s) => Ok(s.transform(x)?),
        None => Ok(x.to_owned()),
    }
}

impl BinarySvm {
    pub fn decision(&self, gamma: f64, x: ArrayView1<f64>) -> f64 {
        self.support_vectors
            .rows()
            .into_iter()
            .zip(&self.coef)
            .map(|(sv, &c)| c * rbf(gamma, sv, x))
            .sum::<f64>()
            - self.rho
    }
}

impl KernelSvm {
    /// Class id of every row of `x`: one-vs-one majority vote, ties to the lower id.
    pub fn predict(&self, x: ArrayView2<f64>) -> Result<Vec<usize>, KernelSvmError> {
        check_features(x)?;
        let x = scale(&self.scaler, x)?;
        Ok(x.rows()
            .into_iter()
            .map(|row| {
                let mut votes = vec![0usize; self.classes.len()];
                for m in &self.machines {
                    let winner = if m.decision(self.gamma, row) > 0.0 {
                        m.classes.0
                    } else {
                        m.classes.1
                    };
                    if let Ok(k) = self.classes.binary_search(&winner) {
                        votes[k] += 1;
                    }
                }
                // max_by_key keeps the last maximum: scan in reverse for the lowest id
                let best = (0..votes.len())
                    .rev()
                    .max_by_key(|&k| votes[k])
                    .unwrap_or(0);
                self.classes[best]
            })
            .collect())
    }

    /// Whether every binary machine met the KKT tolerance.
    pub fn converged(&self) -> bool {
        self.machines.iter().all(|m| m.converged)
    }
}

/// Accuracy of stratified k-fold cross-validation.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CvResult {
    pub folds: usize,
    pub seed: u64,
    /// Correct predictions over all held-out samples / samples.
    pub accuracy: f64,
    pub fold_accuracy: Vec<f64>,
    /// Folds whose training samples held a single class (a class too rare for the number
    /// of folds): no machine could be trained there and the fold's model predicts that
    /// class for every sample (the fallback of [`KernelSvmParams::fit`]).
    #[serde(default)]
    pub one_class_folds: Vec<usize>,
}

/// Stratified fold of every sample: each class's samples, in a seeded random order, are
/// dealt to the folds in turn, so every fold holds about 1/folds of every class.
pub fn stratified_folds(y: &[usize], folds: usize, seed: u64) -> Vec<usize> {
    let mut classes = y.to_vec();
    classes.sort_unstable();
    classes.dedup();
    let mut rng = Rng::new(seed);
    let mut fold_of = vec![0; y.len()];
    let mut next = 0;
    for c in classes {
        let mut members: Vec<usize> = (0..y.len()).filter(|&i| y[i] == c).collect();
        rng.shuffle(&mut members);
        for i in members {
            fold_of[i] = next % folds;
            next += 1;
        }
    }
    fold_of
}

/// Stratified `folds`-fold cross-validation of `params` on (`x`, `y`).
pub fn cross_validate(
    params: &KernelSvmParams,
    x: ArrayView2<f64>,
    y: &[usize],
    folds: usize,
    seed: u64,
) -> Result<CvResult, KernelSvmError> {
    params.validate()?;
    if folds < 2 || folds > y.len() {
        return Err(invalid(
            "folds",
            format!("needs 2 ≤ folds ≤ samples ({}), got {folds}", y.len()),
        ));
    }
    if y.len() != x.nrows() {
        return Err(KernelSvmError::InvalidData(format!(
            "{} samples but {} labels",
            x.nrows(),
            y.len()
        )));
    }
    let fold_of = stratified_folds(y, folds, seed);
    let mut correct = 0;
    let mut fold_accuracy = Vec::with_capacity(folds);
    let mut one_class_folds = Vec::new();
    for f in 0..folds {
        let train: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] != f).collect();
        let test: Vec<usize> = (0..y.len()).filter(|&i| fold_of[i] == f).collect();
        let model = params.fit(x.select(ndarray::Axis(0), &train).view(), &pick(y, &train))?;
        if model.classes.len() < 2 {
            one_class_folds.push(f);
        }
        let pred = model.predict(x.select(ndarray::Axis(0), &test).view())?;
        let ok = pred
            .iter()
            .zip(&test)
            .filter(|(p, i)| **p == y[**i])
            .count();
        correct += ok;
        fold_accuracy.push(ok as f64 / test.len().max(1) as f64);
    }
    Ok(CvResult {
        folds,
        seed,
        accuracy: correct as f64 / y.len() as f64,
        fold_accuracy,
        one_class_folds,
    })
}

fn pick(y: &[usize], idx: &[usize]) -> Vec<usize> {
    idx.iter().map(|&i| y[i]).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params(c: f64, gamma: f64) -> KernelSvmParams {
        KernelSvmParams {
            c,
            gamma,
            scaling: None,
            ..Default::default()
        }
    }

    /// Two samples with a large C (the hard-margin solution): the dual 2α − α²(1 − K) peaks
    /// at α = 1/(1 − K), ρ = 0 by symmetry, and the decision at each sample is ±1.
    #[test]
    fn two_points_hard_margin_by_hand() {
        let x = Array2::from_shape_vec((2, 1), vec![0.0, 1.0]).unwrap();
        let gamma = 0.5;
        let k = (-gamma * 1.0f64).exp();
        let m = params(1e6, gamma).fit(x.view(), &[3, 8]).unwrap();
        let svm = &m.machines[0];
        assert_eq!(svm.classes, (3, 8));
        assert!(svm.rho.abs() < 1e-9, "{}", svm.rho);
        for &c in &svm.coef {
            assert!((c.abs() - 1.0 / (1.0 - k)).abs() < 1e-6, "{c}");
        }
        assert!((svm.decision(gamma, x.row(0)) - 1.0).abs() < 1e-6);
        assert!((svm.decision(gamma, x.row(1)) + 1.0).abs() < 1e-6);
        assert_eq!(m.predict(x.view()).unwrap(), vec![3, 8]);
    }

    #[test]
    fn separable_blobs() {
        let mut rng = Rng::new(4);
        let n = 60;
        let x = Array2::from_shape_fn((n, 2), |(i, d)| {
            let c = (i % 3) as f64;
            (if d == 0 { 4.0 * c } else { -2.0 * c }) + 0.5 * rng.normal()
        });
        let y: Vec<usize> = (0..n).map(|i| 10 + i % 3).collect();
        let m = params(10.0, 0.5).fit(x.view(), &y).unwrap();
        assert!(m.converged());
        assert_eq!(m.machines.len(), 3);
        assert_eq!(m.predict(x.view()).unwrap(), y);
    }

    /// XOR: no linear separator exists, the RBF machine separates it.
    #[test]
    fn xor_needs_the_kernel() {
        let mut rng = Rng::new(8);
        let n = 200;
        let x = Array2::from_shape_fn((n, 2), |_| rng.range(-1.0, 1.0));
        let y: Vec<usize> = x
            .rows()
            .into_iter()
            .map(|r| usize::from(r[0] * r[1] > 0.0))
            .collect();
        let cv = cross_validate(&params(100.0, 2.0), x.view(), &y, 5, 1).unwrap();
        assert!(cv.accuracy > 0.9, "{}", cv.accuracy);
        // with a nearly flat kernel (≈ linear) it cannot do much better than chance
        let flat = cross_validate(&params(1.0, 1e-4), x.view(), &y, 5, 1).unwrap();
        assert!(flat.accuracy < 0.7, "{}", flat.accuracy);
    }

    #[test]
    fn folds_are_stratified_and_seeded() {
        let y: Vec<usize> = (0..50).map(|i| i / 10).collect();
        let f = stratified_folds(&y, 5, 3);
        assert_eq!(f, stratified_folds(&y, 5, 3));
        assert_ne!(f, stratified_folds(&y, 5, 4));
        for fold in 0..5 {
            for c in 0..5 {
                let count = (0..50).filter(|&i| f[i] == fold && y[i] == c).count();
                assert_eq!(count, 2);
            }
        }
    }

    #[test]
    fn bad_parameters_and_data_are_errors() {
        let x = Array2::from_shape_fn((6, 2), |(i, j)| (i * j) as f64);
        let y = [0, 1, 0, 1, 0, 1];
        assert!(params(0.0, 1.0).fit(x.view(), &y).is_err());
        assert!(params(1.0, f64::NAN).fit(x.view(), &y).is_err());
        assert!(params(1.0, 1.0).fit(x.view(), &y[..5]).is_err());
        assert!(cross_validate(&params(1.0, 1.0), x.view(), &y, 1, 0).is_err());
        let mut bad = x.clone();
        bad[[0, 0]] = f64::INFINITY;
        assert!(params(1.0, 1.0).fit(bad.view(), &y).is_err());
        // one class: a constant predictor
        let m = params(1.0, 1.0).fit(x.view(), &[4; 6]).unwrap();
        assert_eq!(m.predict(x.view()).unwrap(), vec![4; 6]);
    }

    /// The paper's offline SVM baseline: 5-fold accuracy 0.995 (0.001) on the Table I
    /// features of the iCub dataset.
    #[test]
    fn icub_five_fold_accuracy() {
        let Some(dir) = crate::test_datasets::dataset("icub-grasp") else {
            return;
        };
        let session = crate::session::import_icub(&dir).unwrap();
        let x = crate::features::table_one::session_features(&session).unwrap();
        let set = session.label_set("object").unwrap();
        let y = session.labels_of(set);
        // a cell of the grid the `baselines` command searches
        let p = KernelSvmParams {
            c: 10.0,
            gamma: 0.003,
            ..Default::default()
        };
        let cv = cross_validate(&p, x.view(), &y, 5, 0).unwrap();
        assert!(cv.accuracy >= 0.995, "5-fold accuracy {}", cv.accuracy);
        // too narrow a kernel memorises the training grasps and fails on new ones
        let narrow = KernelSvmParams { gamma: 0.1, ..p };
        let cv = cross_validate(&narrow, x.view(), &y, 5, 0).unwrap();
        assert!(cv.accuracy < 0.8, "5-fold accuracy {}", cv.accuracy);
    }
}
