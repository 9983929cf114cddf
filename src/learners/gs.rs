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

/// Saved with serde as its parameters, experts, window and the filter's log posterior;
/// loading (deserialising) checks them against each other (see [`super`]).
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(try_from = "GsState")]
pub struct Gs {
    params: GsParams,
    dim: usize,
    models: Vec<Sogp>,
    window: Window,
    #[serde(rename = "log_posterior")]
    #[serde(serialize_with = "crate::gp::floats::serialize")]
    log_post: Vec<f64>,
}

/// A [`Gs`] as it is saved: the fields of [`Gs`].
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct GsState {
    params: GsParams,
    dim: usize,
    #[serde(deserialize_with = "super::deserialize_models")]
    models: Vec<Sogp>,
    #[serde(deserialize_with = "super::deserialize_window")]
    window: Window,
    /// The filter's state within a sequence (−∞ for a class ruled out, NaN after a step
    /// of NaN inputs): any value.
    #[serde(with = "crate::gp::floats")]
    log_posterior: Vec<f64>,
}

impl TryFrom<GsState> for Gs {
    type Error = LearnerError;

    fn try_from(s: GsState) -> Result<Gs, LearnerError> {
        s.params.validate().map_err(|e| e.within("params"))?;
        super::check_loadable_size(s.dim, s.dim, &s.params.gp)?;
        let mut gs = Gs::new(s.dim, &s.params)?;
        super::check_experts(&s.models, s.dim, s.dim, &s.params.gp)?;
        super::check_window(&s.window, s.dim, s.params.gp.tau)?;
        super::check_per_class("log_posterior", s.log_posterior.len(), s.models.len())?;
        gs.models = s.models;
        gs.window = s.window;
        gs.log_post = s.log_posterior;
        Ok(gs)
    }
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

    /// The parameters the learner was built with.
    pub fn params(&self) -> &GsParams {
        &self.params
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

    /// One step of a sequence as [`SequenceClassifier::predict_step`] takes it, before the
    /// filter: each expert's prediction of `o` from the window of the steps before it
    /// (`each(c, mean, predictive variance)`), then `o` joins the window.
    pub(crate) fn predict_each(&mut self, o: &[f64], mut each: impl FnMut(usize, &[f64], f64)) {
        for (c, m) in self.models.iter_mut().enumerate() {
            m.observe_window(&self.window);
            each(c, m.mean(), m.predictive_variance());
        }
        self.window.push(o);
    }

    /// The filter of [`SequenceClassifier::predict_step`] over one step's log-likelihoods
    /// (in `dist`, replaced by the posterior).
    pub(crate) fn filter_step(&mut self, dist: &mut [f64]) {
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
        self.predict_each(o, |c, mean, var| {
            if let Some(ll) = dist.get_mut(c) {
                *ll = log_likelihood(o, mean, var);
            }
        });
        self.filter_step(dist);
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

#[cfg(test)]
mod tests {
    use super::super::testing::{bits, grasps, load_error, quick_adaptation, round_trip};
    use super::*;

    fn small(adapting: bool) -> GsParams {
        GsParams {
            gp: SogpParams {
                capacity: 10,
                tau: 4,
                adaptation: adapting.then(quick_adaptation),
                ..GsParams::default().gp
            },
        }
    }

    /// GS trained on three objects until its experts are at their budget (and, adapting,
    /// have stepped their hyperparameters many times), saved halfway through a grasp
    /// filtered step by step, and loaded: the filter goes on, a fourth object gets an
    /// expert, and predicting, the experts' predictions and training give the saved
    /// learner's values bit for bit, ending in the same state.
    #[test]
    fn a_loaded_gs_goes_on_as_the_saved_one_bit_for_bit() {
        for adapting in [true, false] {
            let mut a = Gs::new(3, &small(adapting)).unwrap();
            for _ in 0..3 {
                a.add_class().unwrap();
            }
            // Longer: each step trains one expert only.
            let s1 = grasps(1, 60, 3, 3);
            for (c, g) in &s1 {
                a.train_sequence(g.view(), *c);
            }
            let streamed = &s1[1].1;
            let mut dist = [0.0; 3];
            a.start_sequence();
            for o in streamed.rows().into_iter().take(4) {
                a.predict_step(o.as_slice().unwrap(), &mut dist);
            }
            assert!(a.models().iter().all(|m| m.n_basis() == 10));
            if adapting {
                assert!(a.models().iter().all(|m| m.hyper_updates() >= 5));
            }
            let mut b = round_trip(&a);
            let (mut da, mut db) = ([0.0; 3], [0.0; 3]);
            for o in streamed.rows().into_iter().skip(4) {
                let o = o.as_slice().unwrap();
                a.predict_step(o, &mut da);
                b.predict_step(o, &mut db);
                assert_eq!(bits(&da), bits(&db));
            }
            assert_eq!((a.add_class().unwrap(), b.add_class().unwrap()), (3, 3));
            for (i, (c, g)) in grasps(2, 40, 4, 3).iter().enumerate() {
                let (pa, pb) = (a.predict_sequence(g.view()), b.predict_sequence(g.view()));
                assert_eq!(bits(&pa), bits(&pb), "grasp {i}");
                let (ma, va) = a.expert_predictions(*c, g.view());
                let (mb, vb) = b.expert_predictions(*c, g.view());
                assert_eq!((bits(&ma), bits(&va)), (bits(&mb), bits(&vb)), "grasp {i}");
                if i % 2 == 0 {
                    a.train_sequence(g.view(), *c);
                    b.train_sequence(g.view(), *c);
                } else {
                    a.start_sequence();
                    b.start_sequence();
                    for o in g.rows() {
                        a.train_step(o.as_slice().unwrap(), *c);
                        b.train_step(o.as_slice().unwrap(), *c);
                    }
                }
            }
            let (ja, jb) = (serde_json::to_string(&a), serde_json::to_string(&b));
            assert_eq!(ja.unwrap(), jb.unwrap());
        }
    }

    /// A damaged state is an error naming what is wrong, and nothing panics.
    #[test]
    fn a_damaged_gs_state_is_an_error_naming_the_field() {
        let mut gs = Gs::new(3, &small(false)).unwrap();
        for _ in 0..2 {
            gs.add_class().unwrap();
        }
        for (c, g) in &grasps(3, 12, 2, 3) {
            gs.train_sequence(g.view(), *c);
        }
        // α holds n_basis × 3 outputs.
        load_error(&gs, "alpha", |v| {
            v["models"][1]["alpha"].as_array_mut().unwrap().truncate(6)
        });
        load_error(&gs, "models[0].n_out", |v| {
            let m = &mut v["models"][0];
            let n = m["n_basis"].as_u64().unwrap() as usize;
            m["n_out"] = 1.into();
            m["alpha"] = serde_json::json!(vec![0.0; n]);
            m["basis_targets"] = serde_json::json!(vec![0.0; n]);
        });
        // A probit model has one output.
        load_error(&gs, "models[1]: invalid state `n_out`", |v| {
            v["models"][1]["likelihood"] = "probit".into()
        });
        load_error(&gs, "log_posterior", |v| {
            v["log_posterior"].as_array_mut().unwrap().pop();
        });
        load_error(&gs, "window: invalid state `inputs`", |v| {
            v["window"]["inputs"].as_array_mut().unwrap().pop();
        });
        load_error(&gs, "kernel.sigma_n", |v| {
            v["models"][0]["kernel"]["sigma_n"] = (-0.1).into()
        });
        load_error(&gs, "params.gp.likelihood", |v| {
            v["params"]["gp"]["likelihood"] = "probit".into()
        });
    }
}
