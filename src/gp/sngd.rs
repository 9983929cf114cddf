//! Stochastic natural gradient ascent on the hyperparameters (paper Sec. III-C).
//!
//! Over a window of `window` (s_g) gradient samples the inverse Fisher matrix is tracked
//! with the Sherman–Morrison formula for the running average F ← (1−ε)F + ε g gᵀ with the
//! paper's constant ε = 1/s_g (eq. 20; the reference code uses 1/t and a t·H term that is
//! not the exact inverse, notes Sec. 5), starting each window from `lambda0`·I as the code
//! does. With the exact recursion the examples' lambda0 = 0.01 would leave a prior Fisher of
//! 100·I dominating the window (steps of ~1e-3); lambda0 = 1 makes a window of consistent
//! gradients give about a unit natural-gradient step. At the end of a window the step is θ ← θ + η_j Ĩ⁻¹ ḡ with η_j = 1/j (eq. 21; the
//! code takes unit steps and Polyak-averages instead). Each component of the step is
//! clamped to `step_bound` and to 80 % of the distance to its box bound (the code's
//! safeguards). Adaptation stops for good when ‖Δθ‖² < `stop_threshold` for `stop_count`
//! consecutive updates (the paper's rule, with the squared norm as in its Sec. V-C).

use super::wide::dispatch_wide;
use serde::{Deserialize, Serialize};

use super::GpError;

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SngdParams {
    /// Sampling window s_g: gradient samples per hyperparameter update.
    pub window: usize,
    /// Initial inverse Fisher scale at the start of each window.
    pub lambda0: f64,
    /// Training points a model sees before adaptation starts (the code's 2 × capacity).
    pub start_after: usize,
    /// Largest change of one hyperparameter in one update.
    pub step_bound: f64,
    /// c_g of the stopping rule.
    pub stop_threshold: f64,
    /// Consecutive small steps that stop adaptation.
    pub stop_count: usize,
}

impl Default for SngdParams {
    fn default() -> Self {
        SngdParams {
            window: 30,
            lambda0: 1.0,
            start_after: 100,
            step_bound: 0.1,
            stop_threshold: 1e-4,
            stop_count: 10,
        }
    }
}

impl SngdParams {
    pub fn validate(&self) -> Result<(), GpError> {
        if self.window < 2 {
            return Err(GpError::param("window", "must be at least 2"));
        }
        if !(self.lambda0.is_finite() && self.lambda0 > 0.0) {
            return Err(GpError::param("lambda0", "must be positive"));
        }
        if !(self.step_bound.is_finite() && self.step_bound > 0.0) {
            return Err(GpError::param("step_bound", "must be positive"));
        }
        if !(self.stop_threshold.is_finite() && self.stop_threshold >= 0.0) {
            return Err(GpError::param("stop_threshold", "must be non-negative"));
        }
        if self.stop_count == 0 {
            return Err(GpError::param("stop_count", "must be at least 1"));
        }
        Ok(())
    }
}

/// The optimiser's state for one model.
///
/// Saved as its parameters, bounds, theta and the window in progress (the running mean
/// gradient, the inverse Fisher estimate and the samples in it) with its counters; `hg`
/// and `h_next` are scratch of [`Sngd::push`], written before they are read.
#[derive(Clone, Debug)]
pub struct Sngd {
    params: SngdParams,
    lo: Vec<f64>,
    hi: Vec<f64>,
    theta: Vec<f64>,
    g_bar: Vec<f64>,
    /// Inverse Fisher estimate, row-major P × P.
    h: Vec<f64>,
    hg: Vec<f64>,
    h_next: Vec<f64>,
    t: usize,
    updates: usize,
    calm: usize,
    stopped: bool,
}

impl Sngd {
    pub fn new(theta: Vec<f64>, lo: Vec<f64>, hi: Vec<f64>, params: SngdParams) -> Sngd {
        let p = theta.len();
        let mut s = Sngd {
            params,
            lo,
            hi,
            theta,
            g_bar: vec![0.0; p],
            h: vec![0.0; p * p],
            hg: vec![0.0; p],
            h_next: vec![0.0; p * p],
            t: 0,
            updates: 0,
            calm: 0,
            stopped: false,
        };
        s.restart_window();
        s
    }

    fn restart_window(&mut self) {
        let p = self.theta.len();
        self.t = 0;
        self.g_bar.fill(0.0);
        self.h.fill(0.0);
        for i in 0..p {
            self.h[i * p + i] = self.params.lambda0;
        }
    }

    pub fn theta(&self) -> &[f64] {
        &self.theta
    }
    pub fn stopped(&self) -> bool {
        self.stopped
    }
    pub fn updates(&self) -> usize {
        self.updates
    }
    pub fn params(&self) -> &SngdParams {
        &self.params
    }

    /// h_next = (H − ε (Hg)(Hg)ᵀ/denom)/(1 − ε), in wide vectors where available (the
    /// same operations in the same order, so bit-identical).
    fn sherman_morrison(&mut self, eps: f64, denom: f64) {
        dispatch_wide!(["avx512f"] Sngd::sherman_morrison_portable, (
            this: &mut Sngd = self,
            eps: f64 = eps,
            denom: f64 = denom,
        ))
    }

    #[inline(always)]
    fn sherman_morrison_portable(&mut self, eps: f64, denom: f64) {
        let p = self.theta.len();
        for ((hn, h), hgi) in self
            .h_next
            .chunks_exact_mut(p)
            .zip(self.h.chunks_exact(p))
            .zip(&self.hg)
        {
            for ((o, hij), hgj) in hn.iter_mut().zip(h).zip(&self.hg) {
                *o = (hij - eps * hgi * hgj / denom) / (1.0 - eps);
            }
        }
    }

    /// Add one gradient sample of the log-likelihood (to be increased). Returns true when
    /// the window completed and `theta` changed.
    pub fn push(&mut self, g: &mut [f64]) -> bool {
        if self.stopped {
            return false;
        }
        // A non-finite component carries no information (the code sets it to 0).
        for v in g.iter_mut() {
            if !v.is_finite() {
                *v = 0.0;
            }
        }
        let p = self.theta.len();
        self.t += 1;
        let inv_t = 1.0 / self.t as f64;
        for (m, v) in self.g_bar.iter_mut().zip(g.iter()) {
            *m += (v - *m) * inv_t;
        }
        let eps = 1.0 / self.params.window as f64;
        for i in 0..p {
            self.hg[i] = (0..p).map(|j| self.h[i * p + j] * g[j]).sum();
        }
        let ghg: f64 = self.hg.iter().zip(g.iter()).map(|(a, b)| a * b).sum();
        let denom = (1.0 - eps) + eps * ghg;
        let mut ok = denom > 0.0 && denom.is_finite();
        if ok {
            self.sherman_morrison(eps, denom);
            ok = self.h_next.iter().all(|v| v.is_finite());
        }
        if ok {
            std::mem::swap(&mut self.h, &mut self.h_next);
        }
        if self.t < self.params.window {
            return false;
        }
        self.updates += 1;
        let eta = 1.0 / self.updates as f64;
        let mut norm2 = 0.0;
        for i in 0..p {
            let mut d = eta
                * (0..p)
                    .map(|j| self.h[i * p + j] * self.g_bar[j])
                    .sum::<f64>();
            if !d.is_finite() {
                d = 0.0;
            }
            let room = if d >= 0.0 {
                self.hi[i] - self.theta[i]
            } else {
                self.theta[i] - self.lo[i]
            };
            let cap = (0.8 * room.max(0.0)).min(self.params.step_bound);
            d = d.clamp(-cap, cap);
            self.theta[i] += d;
            norm2 += d * d;
        }
        if norm2 < self.params.stop_threshold {
            self.calm += 1;
        } else {
            self.calm = 0;
        }
        if self.calm >= self.params.stop_count {
            self.stopped = true;
        }
        self.restart_window();
        true
    }
}

/// An [`Sngd`] as it is saved.
#[derive(Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct SngdState {
    params: SngdParams,
    #[serde(with = "super::floats")]
    lower: Vec<f64>,
    #[serde(with = "super::floats")]
    upper: Vec<f64>,
    #[serde(with = "super::floats")]
    theta: Vec<f64>,
    /// The window in progress: its mean gradient, inverse Fisher estimate (P × P,
    /// row-major) and gradient samples.
    #[serde(with = "super::floats")]
    mean_gradient: Vec<f64>,
    #[serde(with = "super::floats")]
    inverse_fisher: Vec<f64>,
    samples: usize,
    updates: usize,
    /// Consecutive small steps so far.
    calm: usize,
    stopped: bool,
}

impl Serialize for Sngd {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        SngdState {
            params: self.params.clone(),
            lower: self.lo.clone(),
            upper: self.hi.clone(),
            theta: self.theta.clone(),
            mean_gradient: self.g_bar.clone(),
            inverse_fisher: self.h.clone(),
            samples: self.t,
            updates: self.updates,
            calm: self.calm,
            stopped: self.stopped,
        }
        .serialize(s)
    }
}

impl<'de> Deserialize<'de> for Sngd {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Sngd, D::Error> {
        Sngd::from_state(SngdState::deserialize(d)?).map_err(serde::de::Error::custom)
    }
}

impl Sngd {
    fn from_state(s: SngdState) -> Result<Sngd, GpError> {
        s.params.validate().map_err(|e| e.within("params"))?;
        let p = s.theta.len();
        if p == 0 {
            return Err(GpError::state("theta", "is empty"));
        }
        for (name, v, len) in [
            ("lower", &s.lower, p),
            ("upper", &s.upper, p),
            ("theta", &s.theta, p),
            ("mean_gradient", &s.mean_gradient, p),
            ("inverse_fisher", &s.inverse_fisher, p * p),
        ] {
            if v.len() != len {
                return Err(GpError::state(
                    name,
                    format!("{} values, expected {len}", v.len()),
                ));
            }
            if let Some((i, x)) = super::floats::first_non_finite(v) {
                return Err(GpError::state(
                    format!("{name}[{i}]"),
                    format!("{x} is not finite"),
                ));
            }
        }
        if let Some(i) = (0..p).find(|&i| s.lower[i] > s.upper[i]) {
            return Err(GpError::state(
                format!("lower[{i}]"),
                format!("{} is above the upper bound {}", s.lower[i], s.upper[i]),
            ));
        }
        if s.samples >= s.params.window {
            return Err(GpError::state(
                "samples",
                format!("{} in a window of {}", s.samples, s.params.window),
            ));
        }
        if s.calm > s.params.stop_count || (s.calm == s.params.stop_count) != s.stopped {
            return Err(GpError::state(
                "calm",
                format!(
                    "{} small steps with stop_count {} and stopped {}",
                    s.calm, s.params.stop_count, s.stopped
                ),
            ));
        }
        Ok(Sngd {
            params: s.params,
            lo: s.lower,
            hi: s.upper,
            theta: s.theta,
            g_bar: s.mean_gradient,
            h: s.inverse_fisher,
            hg: vec![0.0; p],
            h_next: vec![0.0; p * p],
            t: s.samples,
            updates: s.updates,
            calm: s.calm,
            stopped: s.stopped,
        })
    }
}
