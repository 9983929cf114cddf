//! The sparse online GP of Csató & Opper with a basis-vector (BV) budget, as the OIESGP
//! uses it (paper Sec. III-A; notes Secs. 3–5), over recursive-kernel windows.
//!
//! Choices against the reference code (notes Sec. 9), made on purpose:
//! - Noise sigma_n² lives in the likelihood (C++ style): k* = sigma_f², the regression
//!   predictive variance is s² + sigma_n², the probit is Φ(y m / √(s² + sigma_n²)).
//! - Probit q and r are the exact derivatives of ln Φ (textbook), not the code's −z form;
//!   the first point uses the probit form too, not the regression form.
//! - Novelty γ = k* − kᵀQk against `novelty_eps`·k* (relative, as in the C++ code).
//! - Deletion score |α_i|²/(Q_ii + C_ii) (paper eq. 10, C++) and the matching KL-optimal
//!   (Q + C) removal of Csató & Opper.
//! - Hyperparameter gradients are exact for the Gaussian-site form of the posterior
//!   (α = (K + Λ)⁻¹ỹ, C = −(K + Λ)⁻¹ with the sites held fixed): dm = dkᵀα + vᵀdK α and
//!   ds² = dk* + 2vᵀdk + vᵀdK v with v = Ck; for regression the noise also moves the sites
//!   (Λ = sigma_n² I). This is exact for GP regression whose BVs hold all the data; the code
//!   drops the dα term and flips a sign (notes Sec. 5).
//! - The rebuild after a hyperparameter update re-runs the online updates over the stored
//!   BVs and their targets with the new kernel, so a probit model stays a probit model
//!   (the code rebuilds every model, classifiers too, as a regression on the ±1 labels);
//!   for regression this is the exact GP on the BVs, as in the code.
//! - Every point is trained as it arrives (the code buffers points while optimising and
//!   trains them later in random order).

mod adapt;
mod gram;
mod online;
mod pairs;
mod shared;
mod state;
#[cfg(test)]
mod tests;

use super::wide::dispatch_wide;
use ndarray::Array2;
use serde::{Deserialize, Serialize};

use super::GpError;
use super::inputs::{Inputs, Shift};
use super::kernel::{KernelParams, LagMajor, RecursiveArd, dot_rows};
use super::normal::{log_norm_cdf, pdf_over_cdf};
use super::sngd::SngdParams;
use super::window::{SequenceWindows, Stamp, Window};
use adapt::Adaptation;

/// Smallest latent variance a prediction may report (the C++ clamp).
const VAR_FLOOR: f64 = 1e-12;

/// Updates between two checks of Q = K_B⁻¹ against the Gram matrix (a check costs about
/// n/2 updates' kernel evaluations, so this keeps it near 2 % of the training time).
const DRIFT_CHECK_EVERY: usize = 1024;
/// Largest max_i |(Q·K_B)_ii − 1| tolerated before Q is rebuilt.
const DRIFT_TOL: f64 = 1e-6;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Likelihood {
    /// Gaussian noise sigma_n² on every output.
    Regression,
    /// Probit on labels ±1 (one output): p(y|f) = Φ(y f / sigma_n).
    Probit,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SogpParams {
    /// BV budget.
    pub capacity: usize,
    /// Lags of the recursive kernel.
    pub tau: usize,
    /// A point becomes a BV when γ ≥ novelty_eps·k*.
    pub novelty_eps: f64,
    /// Initial lengthscale of every input dimension.
    pub lengthscale: f64,
    pub sigma_rho: f64,
    pub sigma_f: f64,
    pub sigma_n: f64,
    pub likelihood: Likelihood,
    /// Hyperparameter adaptation; None switches it off.
    pub adaptation: Option<SngdParams>,
}

impl Default for SogpParams {
    /// The paper's settings (Sec. V-C) with the discriminative lengthscale 1.0.
    fn default() -> Self {
        SogpParams {
            capacity: 50,
            tau: 15,
            novelty_eps: 1e-5,
            lengthscale: 1.0,
            sigma_rho: 1.01,
            sigma_f: 1.0,
            sigma_n: 0.1,
            likelihood: Likelihood::Probit,
            adaptation: Some(SngdParams::default()),
        }
    }
}

impl SogpParams {
    pub fn validate(&self) -> Result<(), GpError> {
        if self.capacity == 0 {
            return Err(GpError::param("capacity", "must be at least 1"));
        }
        if self.tau == 0 {
            return Err(GpError::param("tau", "must be at least 1"));
        }
        if !(self.novelty_eps.is_finite() && self.novelty_eps >= 0.0) {
            return Err(GpError::param("novelty_eps", "must be non-negative"));
        }
        if !(self.lengthscale.is_finite() && self.lengthscale > 0.0) {
            return Err(GpError::param("lengthscale", "must be positive"));
        }
        if let Some(a) = &self.adaptation {
            a.validate()?;
        }
        self.kernel_params(1).validate(1)
    }

    pub fn kernel_params(&self, dim: usize) -> KernelParams {
        KernelParams {
            lengthscales: vec![self.lengthscale; dim],
            sigma_rho: self.sigma_rho,
            sigma_f: self.sigma_f,
            sigma_n: self.sigma_n,
        }
    }
}

/// One OIESGP model. It saves and loads with serde: `state.rs` says what the file holds
/// and what is rebuilt; loading checks every field.
#[derive(Clone, Debug)]
pub struct Sogp {
    kernel: RecursiveArd,
    likelihood: Likelihood,
    n_out: usize,
    cap: usize,
    stride: usize,
    eps: f64,
    n: usize,
    wlen: usize,
    bv_raw: Vec<f64>,
    bv_scaled: Vec<f64>,
    /// The scaled BVs again, lag-major for the many-BV kernels of the gradient (current
    /// only while adapting, see [`Sogp::sync_basis`]).
    basis: LagMajor,
    /// The BVs' distinct inputs and the observed window's distances to them.
    inputs: Inputs,
    bv_y: Vec<f64>,
    alpha: Vec<f64>,
    c: Vec<f64>,
    q: Vec<f64>,
    x_raw: Vec<f64>,
    /// The stamp of the window in `x_raw` when it came from a [`Window`].
    x_stamp: Option<Stamp>,
    x_scaled: Vec<f64>,
    /// `x_scaled` holds `x_raw` scaled by the current kernel (it is scaled when needed).
    x_scaled_current: bool,
    k: Vec<f64>,
    ck: Vec<f64>,
    ehat: Vec<f64>,
    /// K_t after every lag for each BV at the observed window (tau rows of lanes), kept
    /// for the gradient of the same observation.
    lag_k: Vec<f64>,
    mean: Vec<f64>,
    qv: Vec<f64>,
    y_tmp: Vec<f64>,
    /// Scratch of the rebuild: the unit Gram of the BVs under new hyperparameters, and the
    /// old slots of the BVs kept so far.
    gram_new: Vec<f64>,
    retained: Vec<usize>,
    /// Scratch of a deletion: column i of Q and of Q + C for the BV i being deleted, and
    /// one row's increments of Q and C.
    col_q: Vec<f64>,
    col_qc: Vec<f64>,
    del_q: Vec<f64>,
    del_c: Vec<f64>,
    observed: Option<u64>,
    version: u64,
    seen: usize,
    inverse_rebuilds: usize,
    adaptation_params: Option<SngdParams>,
    adapt: Option<Box<Adaptation>>,
    adaptation_finished: bool,
}

impl Sogp {
    /// A model for inputs of `dim` dimensions and `n_out` outputs (1 for probit).
    pub fn new(dim: usize, n_out: usize, params: &SogpParams) -> Result<Sogp, GpError> {
        params.validate()?;
        if n_out == 0 || (params.likelihood == Likelihood::Probit && n_out != 1) {
            return Err(GpError::param(
                "n_out",
                "regression needs at least one output, probit exactly one",
            ));
        }
        let kernel = RecursiveArd::new(dim, params.tau, params.kernel_params(dim))?;
        let wlen = kernel.window_len();
        let stride = params.capacity + 1;
        let basis = LagMajor::new(dim, params.tau, stride);
        let lanes = basis.stride();
        Ok(Sogp {
            kernel,
            likelihood: params.likelihood,
            n_out,
            cap: params.capacity,
            stride,
            eps: params.novelty_eps,
            n: 0,
            wlen,
            bv_raw: vec![0.0; stride * wlen],
            bv_scaled: vec![0.0; stride * wlen],
            basis,
            inputs: Inputs::new(dim, params.tau, stride, lanes),
            bv_y: vec![0.0; stride * n_out],
            alpha: vec![0.0; stride * n_out],
            c: vec![0.0; stride * stride],
            q: vec![0.0; stride * stride],
            x_raw: vec![0.0; wlen],
            x_stamp: None,
            x_scaled: vec![0.0; wlen],
            x_scaled_current: false,
            k: vec![0.0; lanes],
            ck: vec![0.0; stride],
            ehat: vec![0.0; stride],
            lag_k: vec![0.0; params.tau * lanes],
            mean: vec![0.0; n_out],
            qv: vec![0.0; n_out],
            y_tmp: vec![0.0; n_out],
            gram_new: vec![0.0; stride * stride],
            retained: Vec::with_capacity(stride),
            col_q: vec![0.0; stride],
            col_qc: vec![0.0; stride],
            del_q: vec![0.0; stride],
            del_c: vec![0.0; stride],
            observed: None,
            version: 0,
            seen: 0,
            inverse_rebuilds: 0,
            adaptation_params: params.adaptation.clone(),
            adapt: None,
            adaptation_finished: false,
        })
    }

    pub fn n_basis(&self) -> usize {
        self.n
    }
    pub fn n_out(&self) -> usize {
        self.n_out
    }
    /// The BV budget.
    pub fn capacity(&self) -> usize {
        self.cap
    }
    pub fn likelihood(&self) -> Likelihood {
        self.likelihood
    }
    pub fn novelty_eps(&self) -> f64 {
        self.eps
    }
    /// The adaptation the model was built with (None: off).
    pub fn adaptation_params(&self) -> Option<&SngdParams> {
        self.adaptation_params.as_ref()
    }
    pub fn seen(&self) -> usize {
        self.seen
    }
    pub fn kernel(&self) -> &RecursiveArd {
        &self.kernel
    }
    pub fn kernel_params(&self) -> &KernelParams {
        self.kernel.params()
    }
    /// True while the hyperparameters are being adapted.
    pub fn adapting(&self) -> bool {
        self.adapt.is_some()
    }
    /// Hyperparameter updates made so far (0 when adaptation never started).
    pub fn hyper_updates(&self) -> usize {
        self.adapt.as_ref().map(|a| a.sngd.updates()).unwrap_or(0)
    }
    /// True once the stopping rule has fired.
    pub fn adaptation_finished(&self) -> bool {
        self.adaptation_finished
    }

    /// Q = K_B⁻¹, the inverse Gram matrix of the BVs (n × n).
    pub fn inverse_gram(&self) -> Array2<f64> {
        let (n, s) = (self.n, self.stride);
        Array2::from_shape_fn((n, n), |(i, j)| self.q[i * s + j])
    }

    /// How many times Q was rebuilt because it had drifted from K_B⁻¹.
    pub fn inverse_rebuilds(&self) -> usize {
        self.inverse_rebuilds
    }

    /// The BVs' raw windows (n × tau·dim) and their targets (n × n_out).
    pub fn basis(&self) -> (Array2<f64>, Array2<f64>) {
        let (n, w, no) = (self.n, self.wlen, self.n_out);
        (
            Array2::from_shape_fn((n, w), |(i, t)| self.bv_raw[i * w + t]),
            Array2::from_shape_fn((n, no), |(i, d)| self.bv_y[i * no + d]),
        )
    }

    fn bv(&self, i: usize) -> &[f64] {
        &self.bv_scaled[i * self.wlen..(i + 1) * self.wlen]
    }

    /// Evaluate the kernel vector, C·k and the mean at `window` (tau·dim values, oldest
    /// lag first); the following [`Sogp::update`] reuses them.
    pub fn observe(&mut self, window: &[f64]) {
        self.own_inputs();
        let shift = Shift::between(&self.x_raw, window, self.kernel.dim());
        self.observe_inputs(shift, window);
        // Copied even when equal as numbers: a BV keeps the window's bits.
        self.x_raw.copy_from_slice(window);
        self.x_stamp = None;
        self.x_scaled_current = false;
        self.evaluate();
    }

    /// [`Sogp::observe`] at a window of a sequence: its stamp tells whether it is the
    /// window observed last, or that one shifted by one input, without comparing them.
    pub fn observe_window(&mut self, window: &Window) {
        self.observe_stamped(window.as_slice(), window.stamp());
    }

    /// [`Sogp::observe_window`] of a window given as its values and stamp.
    fn observe_stamped(&mut self, window: &[f64], stamp: Stamp) {
        self.own_inputs();
        let shift = self.shift_to(stamp);
        self.observe_inputs(shift, window);
        self.take_window(shift, window, stamp);
        self.evaluate();
    }

    /// Keep the observed window (raw) and its stamp unless it is the one kept.
    fn take_window(&mut self, shift: Shift, window: &[f64], stamp: Stamp) {
        if shift != Shift::Same {
            self.x_raw.copy_from_slice(window);
            self.x_stamp = Some(stamp);
            self.x_scaled_current = false;
        }
    }

    /// How the window stamped `stamp` stands to the one observed last.
    fn shift_to(&self, stamp: Stamp) -> Shift {
        match self.x_stamp {
            Some(s) if s == stamp => Shift::Same,
            Some(s) if stamp.follows(s) => Shift::ByOne,
            _ => Shift::Other,
        }
    }

    /// Observe the windows of a sequence after `from`, `from` + 1, … and all of its
    /// inputs in turn (as [`Sogp::observe_window`] each), calling `each(t, self)` after the
    /// window of the first `from` + t inputs. The raw window an update would learn is kept
    /// only once, at the end: nothing updates the model in between, so only the last window
    /// keeps its K_t per lag, and only while adapting (an update's gradient reads them).
    pub fn observe_sequence(
        &mut self,
        windows: &SequenceWindows,
        from: usize,
        mut each: impl FnMut(usize, &Sogp),
    ) {
        self.own_inputs();
        for (t, n) in (from..=windows.len()).enumerate() {
            let (window, stamp) = windows.after(n);
            let shift = self.shift_to(stamp);
            self.observe_inputs(shift, window);
            if shift != Shift::Same {
                self.x_stamp = Some(stamp);
                self.x_scaled_current = false;
            }
            self.evaluate_keeping(n == windows.len() && self.adapt.is_some());
            each(t, self);
        }
        if from <= windows.len() {
            self.x_raw.copy_from_slice(windows.after(windows.len()).0);
        }
    }

    /// Evaluate again at the same window (the model changed).
    fn refresh(&mut self) {
        let x = std::mem::take(&mut self.x_raw);
        self.observe_inputs(Shift::Same, &x);
        self.x_raw = x;
        self.evaluate();
    }

    /// The kernel vector (from the inputs' distance rows), C·k and the mean; K_t per lag
    /// too while adapting (the next update's gradient reads them).
    fn evaluate(&mut self) {
        self.evaluate_keeping(self.adapt.is_some());
    }

    /// [`Sogp::evaluate`], keeping K_t per lag (for the gradient) only if `lags`.
    fn evaluate_keeping(&mut self, lags: bool) {
        let sf2 = self.kernel.sigma_f2();
        let n = self.n;
        let inv_rho = 1.0 / self.kernel.params().sigma_rho;
        if lags {
            self.inputs
                .unit_many(inv_rho, n, &mut self.lag_k, &mut self.k);
        } else {
            self.inputs.unit_k(inv_rho, n, &mut self.k);
        }
        for k in &mut self.k[..n] {
            *k *= sf2;
        }
        self.refresh_posterior();
    }

    /// Scale the observed window (a BV and the gradient need it).
    fn ensure_scaled(&mut self) {
        if !self.x_scaled_current {
            self.kernel.scale_into(&self.x_raw, &mut self.x_scaled);
            self.x_scaled_current = true;
        }
    }

    /// C·k and the mean from the kernel vector in `k`.
    fn refresh_posterior(&mut self) {
        dispatch_wide!(["avx512f", "avx2"] Sogp::refresh_posterior_portable, (this: &mut Sogp = self))
    }

    #[inline(always)]
    fn refresh_posterior_portable(&mut self) {
        let (n, s) = (self.n, self.stride);
        dot_rows(&self.c, s, n, &self.k, &mut self.ck[..n]);
        let no = self.n_out;
        if no == 1 {
            // The same additions in the same order, summed in a register rather than
            // through memory (one chain of n dependent additions).
            let mut m = 0.0;
            for (k, a) in self.k[..n].iter().zip(&self.alpha[..n]) {
                m += k * a;
            }
            self.mean[0] = m;
        } else {
            self.mean.fill(0.0);
            for i in 0..n {
                let ki = self.k[i];
                for (m, a) in self.mean.iter_mut().zip(&self.alpha[i * no..(i + 1) * no]) {
                    *m += ki * a;
                }
            }
        }
        self.observed = Some(self.version);
    }

    /// Posterior mean of each output at the observed window.
    pub fn mean(&self) -> &[f64] {
        &self.mean
    }

    /// Latent (noise-free) posterior variance at the observed window, within
    /// [1e-12, sigma_f²].
    pub fn latent_variance(&self) -> f64 {
        let n = self.n;
        let v = self.kernel.sigma_f2()
            + self.k[..n]
                .iter()
                .zip(&self.ck[..n])
                .map(|(a, b)| a * b)
                .sum::<f64>();
        if v.is_finite() {
            v.clamp(VAR_FLOOR, self.kernel.sigma_f2())
        } else {
            self.kernel.sigma_f2()
        }
    }

    /// Predictive variance of an observation: latent + sigma_n².
    pub fn predictive_variance(&self) -> f64 {
        self.latent_variance() + self.kernel.sigma_n2()
    }

    /// Probit models: q = p(y = +1) = Φ(m/√(s² + sigma_n²)) (paper eq. 24). 0.5 untrained.
    pub fn probability(&self) -> f64 {
        super::normal::norm_cdf(self.mean[0] / self.predictive_variance().sqrt())
    }

    /// Train on target `y` at the last observed window (observing again if the model changed).
    pub fn update(&mut self, y: &[f64]) {
        self.own_inputs();
        self.learn(y);
    }

    /// [`Sogp::update`] with the distinct inputs where they are (its own or shared).
    fn learn(&mut self, y: &[f64]) {
        if self.observed != Some(self.version) {
            self.refresh();
        }
        self.ensure_scaled();
        self.y_tmp.copy_from_slice(&y[..self.n_out]);
        let Some((mut r, dlogp_ds, _)) = self.likelihood_terms() else {
            return;
        };
        // The gradient is prequential: taken before the point is learnt (paper eq. 15).
        if self.adapt.is_some() && self.adaptation_step(dlogp_ds) {
            self.refresh();
            self.ensure_scaled();
            match self.likelihood_terms() {
                Some((r_new, _, _)) => r = r_new,
                None => return,
            }
            // The observation's kernel derivatives were taken under the old
            // hyperparameters and BVs; a full update stores them as the new BV's row.
            if let Some(mut ad) = self.adapt.take() {
                self.observation_derivatives(&mut ad.buf);
                self.adapt = Some(ad);
            }
        }
        let added = self.posterior_update(r);
        self.seen += 1;
        if added && self.n > self.cap {
            self.delete_least_informative();
        } else if added {
            self.store_new_bv();
        }
        if self.seen.is_multiple_of(DRIFT_CHECK_EVERY) {
            self.check_inverse();
        }
        self.after_update();
    }

    /// q (into self.qv), r, ∂ln p/∂S and ln p for the current target (S the predictive
    /// variance). None if not finite. The window is scaled here, as the gradient and the
    /// update that follow these terms read it.
    fn likelihood_terms(&mut self) -> Option<(f64, f64, f64)> {
        self.ensure_scaled();
        let s_tot = self.predictive_variance();
        let (r, ds, logp) = match self.likelihood {
            Likelihood::Regression => {
                let mut sq = 0.0;
                for d in 0..self.n_out {
                    let e = self.y_tmp[d] - self.mean[d];
                    self.qv[d] = e / s_tot;
                    sq += e * e;
                }
                let no = self.n_out as f64;
                let ds = sq / (2.0 * s_tot * s_tot) - no / (2.0 * s_tot);
                let logp =
                    -0.5 * no * (2.0 * std::f64::consts::PI * s_tot).ln() - sq / (2.0 * s_tot);
                (-1.0 / s_tot, ds, logp)
            }
            Likelihood::Probit => {
                let y = if self.y_tmp[0] >= 0.0 { 1.0 } else { -1.0 };
                self.y_tmp[0] = y;
                let sx = s_tot.sqrt();
                let z = y * self.mean[0] / sx;
                let ratio = pdf_over_cdf(z);
                self.qv[0] = y * ratio / sx;
                let r = -ratio * (z + ratio) / s_tot;
                (r, -ratio * z / (2.0 * s_tot), log_norm_cdf(z))
            }
        };
        let finite = r.is_finite() && ds.is_finite() && self.qv.iter().all(|v| v.is_finite());
        finite.then_some((r, ds, logp))
    }
}
