//! GS: the generative supervised learner (paper Sec. IV-B): one regression OIESGP expert per
//! class predicting the next observation from the window of the previous ones, and a Bayes
//! filter over the classes (eq. 29) with independent Gaussian likelihoods (eq. 30) whose
//! variance is the noisy predictive variance.
//!
//! - The filter runs in log space and is renormalised each step (the reference code keeps
//!   an unnormalised product in probability space that can under- or overflow).
//! - Expert c is trained on the pairs (window of o_1 … o_{t−1}, o_t), t = 1 … T, the first
//!   window being all padding; prediction scores o_t against the same windows, so every
//!   step of a grasp is scored (the first from the experts' "start of grasp" prediction).
//! - A grasp's class is the argmax of the posterior at its last step (the paper's rule).

use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use super::{LearnerError, SequenceClassifier};
use crate::gp::{Likelihood, SequenceWindows, Sogp, SogpParams, Window};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct GsParams {
    pub gp: SogpParams,
}

impl Default for GsParams {
    /// The paper's generative settings: lengthscales 10.0, regression, adaptation on.
    fn default() -> Self {
        GsParams {
            gp: SogpParams {
                lengthscale: 10.0,
                likelihood: Likelihood::Regression,
                ..SogpParams::default()
            },
        }
    }
}

impl GsParams {
    pub fn validate(&self) -> Result<(), LearnerError> {
        self.gp.validate()?;
        if self.gp.likelihood != Likelihood::Regression {
            return Err(LearnerError::param(
                "gp.likelihood",
                "GS needs the regression likelihood",
            ));
        }
        Ok(())
    }
}

#[derive(Clone, Debug)]
pub struct Gs {
    params: GsParams,
    dim: usize,
    models: Vec<Sogp>,
    window: Window,
    log_post: Vec<f64>,
}

/// ln N(o | μ, S·I) summed over the dimensions.
pub(crate) fn log_likelihood(o: &[f64], mean: &[f64], var: f64) -> f64 {
    let sq: f64 = o.iter().zip(mean).map(|(a, b)| (a - b) * (a - b)).sum();
    -0.5 * o.len() as f64 * (2.0 * std::f64::consts::PI * var).ln() - sq / (2.0 * var)
}

impl Gs {
    pub fn new(dim: usize, params: &GsParams) -> Result<Gs, LearnerError> {
        params.validate()?;
        Sogp::new(dim, dim, &params.gp)?;
        Ok(Gs {
            params: params.clone(),
            dim,
            models: Vec::new(),
            window: Window::new(dim, params.gp.tau),
            log_post: Vec::new(),
        })
    }

    /// The windows each step of `seq` is predicted from: the window of the inputs before it.
    fn prediction_windows(&self, steps: &[f64]) -> SequenceWindows {
        let before_last = steps.len().saturating_sub(self.dim);
        SequenceWindows::new(self.dim, self.params.gp.tau, &steps[..before_last])
    }

    /// Expert `c`'s prediction of every step of `seq` (means T × D, predictive variances T).
    pub fn expert_predictions(
        &mut self,
        c: usize,
        seq: ArrayView2<f64>,
    ) -> (Array2<f64>, Vec<f64>) {
        let seq = seq.as_standard_layout();
        let steps = super::steps(&seq, self.dim);
        let t_len = steps.len() / self.dim;
        let mut means = Array2::zeros((t_len, self.dim));
        let mut vars = Vec::with_capacity(t_len);
        if t_len > 0 {
            let windows = self.prediction_windows(steps);
            self.models[c].observe_sequence(&windows, 0, |t, m| {
                for (d, v) in m.mean().iter().enumerate() {
                    means[[t, d]] = *v;
                }
                vars.push(m.predictive_variance());
            });
        }
        (means, vars)
    }

    /// ln p(o_t | expert) of every step of a sequence (`steps`, T × D) for each of
    /// `experts` (T × experts), with `ll(j, o_t, mean, predictive variance)`. Each expert
    /// goes over the whole sequence in turn, its state in the cache.
    fn step_log_likelihoods(
        &mut self,
        steps: &[f64],
        experts: &[usize],
        mut ll: impl FnMut(usize, &[f64], &[f64], f64) -> f64,
    ) -> Array2<f64> {
        let t_len = steps.len() / self.dim;
        let mut out = Array2::zeros((t_len, experts.len()));
        if t_len == 0 {
            return out;
        }
        let windows = self.prediction_windows(steps);
        let dim = self.dim;
        for (j, &c) in experts.iter().enumerate() {
            self.models[c].observe_sequence(&windows, 0, |t, m| {
                let o = &steps[t * dim..(t + 1) * dim];
                out[[t, j]] = ll(j, o, m.mean(), m.predictive_variance());
            });
        }
        out
    }

    /// For each of `experts`, ln p(o_1 … o_T | expert) summed over the steps of `seq`, with
    /// `ll(j, o_t, mean, predictive variance)` the log-likelihood of a step under
    /// `experts[j]`. As in the filter of [`SequenceClassifier::predict_sequence`], a step
    /// where every expert gives −∞ carries no evidence and is skipped. From a uniform prior
    /// the argmax of these sums is the argmax of the final posterior over `experts`.
    pub fn summed_log_likelihoods(
        &mut self,
        seq: ArrayView2<f64>,
        experts: &[usize],
        ll: impl FnMut(usize, &[f64], &[f64], f64) -> f64,
    ) -> Vec<f64> {
        let seq = seq.as_standard_layout();
        let steps = super::steps(&seq, self.dim);
        let lls = self.step_log_likelihoods(steps, experts, ll);
        let mut totals = vec![0.0; experts.len()];
        for step in lls.rows() {
            if step.iter().any(|l| *l > f64::NEG_INFINITY) {
                for (total, l) in totals.iter_mut().zip(step) {
                    *total += l;
                }
            }
        }
        totals
    }

    /// The filter of [`SequenceClassifier::predict_step`] over one step's log-likelihoods
    /// (in `dist`, replaced by the posterior).
    fn filter_step(&mut self, dist: &mut [f64]) {
        // A step so far from every expert that all of them give −∞ (e.g. inputs of 1e200)
        // carries no evidence and is skipped, since adding it would make −∞ − (−∞) = NaN
        // below.
        if dist.iter().any(|ll| *ll > f64::NEG_INFINITY) {
            for (lp, ll) in self.log_post.iter_mut().zip(dist.iter()) {
                *lp += ll;
            }
        }
        let top = self
            .log_post
            .iter()
            .cloned()
            .fold(f64::NEG_INFINITY, f64::max);
        let z: f64 = self.log_post.iter().map(|v| (v - top).exp()).sum();
        let ln_z = top + z.ln();
        for (lp, p) in self.log_post.iter_mut().zip(dist.iter_mut()) {
            *lp -= ln_z;
            *p = lp.exp();
        }
    }
}

impl SequenceClassifier for Gs {
    fn dim(&self) -> usize {
        self.dim
    }

    fn n_classes(&self) -> usize {
        self.models.len()
    }

    fn add_class(&mut self) -> Result<usize, LearnerError> {
        self.models
            .push(Sogp::new(self.dim, self.dim, &self.params.gp)?);
        self.log_post.push(0.0);
        Ok(self.models.len() - 1)
    }

    fn models(&self) -> &[Sogp] {
        &self.models
    }

    fn predict_sequence(&mut self, seq: ArrayView2<f64>) -> Array2<f64> {
        let seq = seq.as_standard_layout();
        let steps = super::steps(&seq, self.dim);
        let experts: Vec<usize> = (0..self.models.len()).collect();
        let mut out = self.step_log_likelihoods(steps, &experts, |_, o, mean, var| {
            log_likelihood(o, mean, var)
        });
        self.start_sequence();
        for mut row in out.rows_mut() {
            self.filter_step(row.as_slice_mut().unwrap_or_default());
        }
        out
    }

    fn train_sequence(&mut self, seq: ArrayView2<f64>, class: usize) {
        if class >= self.models.len() {
            return;
        }
        let seq = seq.as_standard_layout();
        self.window.reset();
        for o in super::steps(&seq, self.dim).chunks_exact(self.dim) {
            self.train_step(o, class);
        }
    }

    fn start_sequence(&mut self) {
        self.window.reset();
        let c = self.models.len();
        self.log_post.fill(-(c as f64).ln());
    }

    fn predict_step(&mut self, o: &[f64], dist: &mut [f64]) {
        for (m, ll) in self.models.iter_mut().zip(dist.iter_mut()) {
            m.observe_window(&self.window);
            *ll = log_likelihood(o, m.mean(), m.predictive_variance());
        }
        self.filter_step(dist);
        self.window.push(o);
    }

    fn train_step(&mut self, o: &[f64], class: usize) {
        if class >= self.models.len() {
            return;
        }
        let m = &mut self.models[class];
        m.observe_window(&self.window);
        m.update(o);
        self.window.push(o);
    }

    fn decide(&self, dist: ArrayView2<f64>) -> usize {
        super::argmax_of_last(dist)
    }
}
