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

use super::wide::dispatch_wide;
use ndarray::Array2;
use serde::{Deserialize, Serialize};

use super::GpError;
use super::inputs::{Inputs, Shift};
use super::kernel::{KernelParams, LagMajor, RecursiveArd, SequenceWindows, Stamp, Window, dot};
use super::normal::{log_norm_cdf, pdf_over_cdf};
use super::sngd::{Sngd, SngdParams};
use crate::linalg::Cholesky;

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

/// Position of the pair (i, j) in a packed lower triangle (K and its derivatives are
/// symmetric: storing one triangle halves the memory the gradient streams through).
#[inline(always)]
fn tri(i: usize, j: usize) -> usize {
    let (a, b) = if i >= j { (i, j) } else { (j, i) };
    a * (a + 1) / 2 + b
}

/// Buffers for the hyperparameter gradient: per BV pair (`kb`, packed lower triangle) the
/// unit-kernel derivatives [∂/∂ln l_1 … ∂/∂ln l_D, ∂/∂sigma_rho] followed by the unit
/// kernel value itself; the same for the observed window against each BV (`kx`, one row
/// of `lanes` values per entry, as the many-BV kernel writes them).
#[derive(Clone, Debug)]
struct GradBuffers {
    pk: usize,
    lanes: usize,
    kb: Vec<f64>,
    kx: Vec<f64>,
    /// Scratch of fill_gram_derivatives: rows as in `kx`, and K_t per lag.
    tmp: Vec<f64>,
    lag_k: Vec<f64>,
    w: Vec<f64>,
    kw: Vec<f64>,
    kv: Vec<f64>,
    cw: Vec<f64>,
    cv: Vec<f64>,
    grad: Vec<f64>,
}

impl GradBuffers {
    fn new(dim: usize, tau: usize, stride: usize, lanes: usize) -> GradBuffers {
        let pk = dim + 2;
        GradBuffers {
            pk,
            lanes,
            // Padded so that the quadratic forms may read a whole register block past the
            // last pair.
            kb: vec![0.0; tri(stride, 0) * pk + QUAD_PAD],
            kx: vec![0.0; lanes * pk],
            tmp: vec![0.0; lanes * pk],
            lag_k: vec![0.0; tau * lanes],
            w: vec![0.0; stride],
            kw: vec![0.0; pk],
            kv: vec![0.0; pk],
            cw: vec![0.0; pk],
            cv: vec![0.0; pk],
            grad: vec![0.0; dim + 3],
        }
    }
}

#[derive(Clone, Debug)]
struct Adaptation {
    sngd: Sngd,
    buf: GradBuffers,
}

/// One OIESGP model.
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
    /// The scaled BVs again, lag-major for the many-BV kernels.
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
    /// Scratch: the column of Q and C of a BV being deleted.
    col_q: Vec<f64>,
    col_c: Vec<f64>,
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
            col_c: vec![0.0; stride],
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

    /// The BVs' Gram matrix K_B (row-major, n × n).
    fn gram(&self) -> Vec<f64> {
        let n = self.n;
        let sf2 = self.kernel.sigma_f2();
        let mut k = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                let v = sf2 * self.kernel.unit_scaled(self.bv(i), self.bv(j));
                k[i * n + j] = v;
                k[j * n + i] = v;
            }
        }
        k
    }

    /// max_i |(Q·K_B)_ii − 1| for a candidate Q (stride `s`), infinite if Q is not finite.
    fn diag_residual(q: &[f64], s: usize, gram: &[f64], n: usize) -> f64 {
        let mut worst = 0.0f64;
        for i in 0..n {
            let qk = dot(&q[i * s..i * s + n], &gram[i * n..(i + 1) * n]);
            let e = (qk - 1.0).abs();
            if !e.is_finite() {
                return f64::INFINITY;
            }
            worst = worst.max(e);
        }
        worst
    }

    /// Drift of Q from K_B⁻¹: max_i |(Q·K_B)_ii − 1| (0 for an exact inverse, infinite if
    /// Q holds a non-finite value).
    pub fn inverse_drift(&self) -> f64 {
        Self::diag_residual(&self.q, self.stride, &self.gram(), self.n)
    }

    /// Detect and repair the drift of Q. The rank-one growth and the (Q + C) deletions
    /// update Q = K_B⁻¹ incrementally, so rounding accumulates over long runs at the
    /// budget; every [`DRIFT_CHECK_EVERY`] updates the diagonal of Q·K_B is compared with
    /// 1 and, past [`DRIFT_TOL`] (or on a non-finite entry), Q is recomputed from K_B by
    /// Cholesky with jitter. The new Q is kept only if it is closer to the inverse (jitter
    /// on a near-singular K_B may not help). α and C are left alone: they are the
    /// posterior, and Q only drives the novelty γ and the deletion scores.
    fn check_inverse(&mut self) {
        let (n, s) = (self.n, self.stride);
        let gram = self.gram();
        let drift = Self::diag_residual(&self.q, s, &gram, n);
        if drift <= DRIFT_TOL {
            return;
        }
        let k = Array2::from_shape_fn((n, n), |(i, j)| gram[i * n + j]);
        let sf2 = self.kernel.sigma_f2();
        let Ok((chol, _)) = Cholesky::with_jitter(k.view(), 1e-12 * sf2, 1e-3 * sf2) else {
            return;
        };
        let inv = chol.inverse();
        let mut q = vec![0.0; s * s];
        for i in 0..n {
            for j in 0..n {
                q[i * s + j] = inv[[i, j]];
            }
        }
        if Self::diag_residual(&q, s, &gram, n) < drift {
            self.q = q;
            self.inverse_rebuilds += 1;
            self.version += 1;
        }
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
        let shift = Shift::between(&self.x_raw, window, self.kernel.dim());
        self.inputs.observe(&self.kernel, shift, window);
        // Copied even when equal as numbers: a BV keeps the window's bits.
        self.x_raw.copy_from_slice(window);
        self.x_stamp = None;
        self.x_scaled_current = false;
        self.evaluate();
    }

    /// [`Sogp::observe`] at a window of a sequence: its stamp tells whether it is the
    /// window observed last, or that one shifted by one input, without comparing them.
    pub fn observe_window(&mut self, window: &Window) {
        let stamp = window.stamp();
        let shift = self.shift_to(stamp);
        self.inputs.observe(&self.kernel, shift, window.as_slice());
        if shift != Shift::Same {
            self.x_raw.copy_from_slice(window.as_slice());
            self.x_stamp = Some(stamp);
            self.x_scaled_current = false;
        }
        self.evaluate();
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
    /// only once, at the end: nothing updates the model in between.
    pub fn observe_sequence(
        &mut self,
        windows: &SequenceWindows,
        from: usize,
        mut each: impl FnMut(usize, &Sogp),
    ) {
        for (t, n) in (from..=windows.len()).enumerate() {
            let (window, stamp) = windows.after(n);
            let shift = self.shift_to(stamp);
            self.inputs.observe(&self.kernel, shift, window);
            if shift != Shift::Same {
                self.x_stamp = Some(stamp);
                self.x_scaled_current = false;
            }
            self.evaluate();
            each(t, self);
        }
        if from <= windows.len() {
            self.x_raw.copy_from_slice(windows.after(windows.len()).0);
        }
    }

    /// Evaluate again at the same window (the model changed).
    fn refresh(&mut self) {
        self.inputs.observe(&self.kernel, Shift::Same, &self.x_raw);
        self.evaluate();
    }

    /// The kernel vector (from the inputs' distance rows), C·k and the mean.
    fn evaluate(&mut self) {
        let sf2 = self.kernel.sigma_f2();
        let n = self.n;
        let inv_rho = 1.0 / self.kernel.params().sigma_rho;
        self.inputs
            .unit_many(inv_rho, n, &mut self.lag_k, &mut self.k);
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
        for i in 0..n {
            self.ck[i] = dot(&self.c[i * s..i * s + n], &self.k[..n]);
        }
        let no = self.n_out;
        self.mean.fill(0.0);
        for i in 0..n {
            let ki = self.k[i];
            for (m, a) in self.mean.iter_mut().zip(&self.alpha[i * no..(i + 1) * no]) {
                *m += ki * a;
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
        self.posterior_update(r);
        self.seen += 1;
        if self.n > self.cap {
            self.delete_least_informative();
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

    fn posterior_update(&mut self, r: f64) {
        // The O(n²) updates, in wide vectors where available.
        dispatch_wide!(["avx512f", "avx2"] Sogp::posterior_update_portable, (
            this: &mut Sogp = self,
            r: f64 = r,
        ))
    }

    #[inline(always)]
    fn posterior_update_portable(&mut self, r: f64) {
        let (n, s, no) = (self.n, self.stride, self.n_out);
        for i in 0..n {
            self.ehat[i] = dot(&self.q[i * s..i * s + n], &self.k[..n]);
        }
        let sf2 = self.kernel.sigma_f2();
        let kqk: f64 = (0..n).map(|i| self.k[i] * self.ehat[i]).sum();
        let gamma = (sf2 - kqk).max(0.0);
        if gamma >= self.eps * sf2 && gamma > 0.0 {
            // Full update: the point becomes BV n.
            for j in 0..=n {
                self.c[n * s + j] = 0.0;
                self.c[j * s + n] = 0.0;
                self.q[n * s + j] = 0.0;
                self.q[j * s + n] = 0.0;
            }
            let ig = 1.0 / gamma;
            for i in 0..n {
                for j in 0..n {
                    self.q[i * s + j] += ig * self.ehat[i] * self.ehat[j];
                }
                self.q[i * s + n] = -ig * self.ehat[i];
                self.q[n * s + i] = -ig * self.ehat[i];
            }
            self.q[n * s + n] = ig;
            for d in 0..no {
                for i in 0..n {
                    self.alpha[i * no + d] += self.ck[i] * self.qv[d];
                }
                self.alpha[n * no + d] = self.qv[d];
            }
            for i in 0..=n {
                let si = if i < n { self.ck[i] } else { 1.0 };
                let row = &mut self.c[i * s..i * s + n + 1];
                for (c, sj) in row.iter_mut().zip(&self.ck[..n]) {
                    *c += r * si * sj;
                }
                row[n] += r * si;
            }
            let w = self.wlen;
            self.bv_raw[n * w..(n + 1) * w].copy_from_slice(&self.x_raw);
            self.bv_scaled[n * w..(n + 1) * w].copy_from_slice(&self.x_scaled);
            self.basis.set(n, &self.x_scaled);
            let inv_rho = 1.0 / self.kernel.params().sigma_rho;
            self.inputs.add_bv(n, &self.x_raw, &self.x_scaled, inv_rho);
            self.bv_y[n * no..(n + 1) * no].copy_from_slice(&self.y_tmp);
            if let Some(a) = self.adapt.as_mut() {
                let (pk, lanes) = (a.buf.pk, a.buf.lanes);
                for j in 0..n {
                    for p in 0..pk {
                        a.buf.kb[tri(n, j) * pk + p] = a.buf.kx[p * lanes + j];
                    }
                }
                let diag = &mut a.buf.kb[tri(n, n) * pk..(tri(n, n) + 1) * pk];
                diag.fill(0.0);
                diag[pk - 1] = 1.0;
            }
            self.n += 1;
        } else {
            // Projected update onto the current BVs, with Csató's η = 1/(1 + γ r).
            let eta = 1.0 / (1.0 + gamma * r);
            if !(eta.is_finite() && eta > 0.0) {
                return;
            }
            for i in 0..n {
                self.ehat[i] += self.ck[i];
            }
            for d in 0..no {
                for i in 0..n {
                    self.alpha[i * no + d] += eta * self.ehat[i] * self.qv[d];
                }
            }
            for i in 0..n {
                for j in 0..n {
                    self.c[i * s + j] += r * eta * self.ehat[i] * self.ehat[j];
                }
            }
        }
        self.version += 1;
    }

    /// Remove the BV with the lowest |α_i|²/(Q_ii + C_ii) (paper eq. 10).
    fn delete_least_informative(&mut self) {
        let (s, no) = (self.stride, self.n_out);
        let mut best = 0;
        let mut best_score = f64::INFINITY;
        for i in 0..self.n {
            let a2: f64 = (0..no).map(|d| self.alpha[i * no + d].powi(2)).sum();
            let den = (self.q[i * s + i] + self.c[i * s + i]).max(1e-300);
            let score = a2 / den;
            if score < best_score {
                best_score = score;
                best = i;
            }
        }
        self.delete(best);
    }

    /// Remove BV `i` with the (Q + C) removal of Csató & Opper.
    pub fn delete(&mut self, i: usize) {
        if i >= self.n {
            return;
        }
        dispatch_wide!(["avx512f", "avx2"] Sogp::delete_portable, (this: &mut Sogp = self, i: usize = i))
    }

    #[inline(always)]
    fn delete_portable(&mut self, i: usize) {
        let last = self.n - 1;
        self.swap_bv(i, last);
        let (s, no, l) = (self.stride, self.n_out, last);
        let qs = self.q[l * s + l].max(1e-300);
        let den = (self.q[l * s + l] + self.c[l * s + l]).max(1e-300);
        for d in 0..no {
            let a_star = self.alpha[l * no + d];
            for j in 0..l {
                let qc = self.q[j * s + l] + self.c[j * s + l];
                self.alpha[j * no + d] -= a_star * qc / den;
            }
            self.alpha[l * no + d] = 0.0;
        }
        // Column l copied out so that the rank-one updates run over contiguous rows.
        for j in 0..l {
            self.col_q[j] = self.q[j * s + l];
            self.col_c[j] = self.c[j * s + l];
        }
        let (cq, cc) = (&self.col_q[..l], &self.col_c[..l]);
        for j in 0..l {
            let (qj, cj) = (cq[j], cc[j]);
            let crow = &mut self.c[j * s..j * s + l];
            let qrow = &mut self.q[j * s..j * s + l];
            for (((c, q), qm), cm) in crow.iter_mut().zip(qrow.iter_mut()).zip(cq).zip(cc) {
                *c += qj * qm / qs - (qj + cj) * (qm + cm) / den;
                *q -= qj * qm / qs;
            }
        }
        self.inputs.release_bv(l);
        self.n -= 1;
        self.version += 1;
    }

    fn swap_bv(&mut self, i: usize, j: usize) {
        if i == j {
            return;
        }
        let (s, w, no) = (self.stride, self.wlen, self.n_out);
        for m in [&mut self.c, &mut self.q] {
            for r in 0..s {
                m.swap(i * s + r, j * s + r);
            }
            for r in 0..s {
                m.swap(r * s + i, r * s + j);
            }
        }
        for t in 0..w {
            self.bv_raw.swap(i * w + t, j * w + t);
            self.bv_scaled.swap(i * w + t, j * w + t);
        }
        self.basis.swap(i, j);
        self.inputs.swap_bv(i, j);
        for d in 0..no {
            self.bv_y.swap(i * no + d, j * no + d);
            self.alpha.swap(i * no + d, j * no + d);
        }
        if let Some(a) = self.adapt.as_mut() {
            // Rows and columns i and j trade places; the pair (i, j) itself stays.
            let pk = a.buf.pk;
            let kb = &mut a.buf.kb;
            for r in (0..s).filter(|&r| r != i && r != j) {
                for p in 0..pk {
                    kb.swap(tri(i, r) * pk + p, tri(j, r) * pk + p);
                }
            }
            for p in 0..pk {
                kb.swap(tri(i, i) * pk + p, tri(j, j) * pk + p);
            }
        }
    }

    /// Start adaptation once enough points were seen; apply a completed SNGD window.
    fn after_update(&mut self) {
        if self.adapt.is_some() || self.adaptation_finished {
            return;
        }
        if let Some(p) = &self.adaptation_params
            && self.seen >= p.start_after
        {
            let params = self.kernel.params();
            let dim = self.kernel.dim();
            let (lo, hi) = KernelParams::theta_bounds(dim);
            let sngd = Sngd::new(params.theta(), lo, hi, p.clone());
            let mut buf =
                GradBuffers::new(dim, self.kernel.tau(), self.stride, self.basis.stride());
            self.fill_gram_derivatives(&mut buf);
            self.adapt = Some(Box::new(Adaptation { sngd, buf }));
        }
    }

    /// The Gram matrix's unit-kernel derivatives and values, one BV against all earlier
    /// ones at a time (K is symmetric).
    fn fill_gram_derivatives(&self, buf: &mut GradBuffers) {
        let (pk, lanes) = (buf.pk, buf.lanes);
        for i in 0..self.n {
            let (g, kv) = buf.tmp.split_at_mut((pk - 1) * lanes);
            self.kernel
                .unit_many(self.bv(i), &self.basis, i + 1, &mut buf.lag_k, kv);
            self.kernel
                .unit_grad_many(self.bv(i), &self.basis, i + 1, &buf.lag_k, g);
            for j in 0..=i {
                for p in 0..pk {
                    let v = buf.tmp[p * lanes + j];
                    buf.kb[tri(i, j) * pk + p] = v;
                }
            }
        }
    }

    /// The unit-kernel derivatives and values of the observed window against every BV into
    /// `buf.kx`. K and K_t per lag are those of the observation (refresh); only the
    /// derivatives are new.
    fn observation_derivatives(&self, buf: &mut GradBuffers) {
        let lanes = buf.lanes;
        let (g, kv) = buf.kx.split_at_mut((buf.pk - 1) * lanes);
        kv[..lanes].copy_from_slice(&self.lag_k[(self.kernel.tau() - 1) * lanes..]);
        self.kernel
            .unit_grad_many(&self.x_scaled, &self.basis, self.n, &self.lag_k, g);
    }

    /// Gradient of ln p(y | x) w.r.t. theta = [ln l, sigma_rho, ln sigma_f, ln sigma_n]
    /// into `buf.grad`, from the observation, `qv` (= ∂ln p/∂m) and the Gram derivatives.
    fn gradient(&self, buf: &mut GradBuffers, dlogp_ds: f64) {
        let (n, no, pk) = (self.n, self.n_out, buf.pk);
        let sf2 = self.kernel.sigma_f2();
        let sn2 = self.kernel.sigma_n2();
        let lanes = buf.lanes;
        self.observation_derivatives(buf);
        for i in 0..n {
            buf.w[i] = (0..no).map(|d| self.qv[d] * self.alpha[i * no + d]).sum();
        }
        let v = &self.ck[..n];
        let w = &buf.w[..n];
        // Per unit-kernel entry p: dk·w, dk·v, vᵀdK w, vᵀdK v.
        // Sums over BVs in BV order, four entries at a time (independent chains).
        for p0 in (0..pk).step_by(4) {
            let rows = p0..(p0 + 4).min(pk);
            let (mut kw, mut kv) = ([0.0; 4], [0.0; 4]);
            for i in 0..n {
                for (q, p) in rows.clone().enumerate() {
                    let r = buf.kx[p * lanes + i];
                    kw[q] += r * w[i];
                    kv[q] += r * v[i];
                }
            }
            for (q, p) in rows.enumerate() {
                buf.kw[p] = kw[q];
                buf.kv[p] = kv[q];
            }
        }
        gram_quad_forms(&buf.kb, pk, v, w, &mut buf.cw, &mut buf.cv);
        // Kernel parameters: dk = sf²·d(unit k), dk* = 0 since K(x, x) = 1 at any theta.
        for p in 0..pk - 1 {
            buf.grad[p] =
                sf2 * (buf.kw[p] + buf.cw[p]) + dlogp_ds * sf2 * (2.0 * buf.kv[p] + buf.cv[p]);
        }
        // ln sigma_f: dk = 2k, dK = 2K, dk* = 2 sf².
        let u = pk - 1;
        buf.grad[u] =
            2.0 * sf2 * (buf.kw[u] + buf.cw[u] + dlogp_ds * (1.0 + 2.0 * buf.kv[u] + buf.cv[u]));
        // ln sigma_n: the predictive variance moves directly; regression sites move too.
        let vw: f64 = v.iter().zip(w).map(|(a, b)| a * b).sum();
        let vv: f64 = v.iter().map(|a| a * a).sum();
        buf.grad[u + 1] = match self.likelihood {
            Likelihood::Regression => 2.0 * sn2 * (vw + dlogp_ds * (vv + 1.0)),
            Likelihood::Probit => 2.0 * sn2 * dlogp_ds,
        };
    }

    /// Feed this step's gradient to SNGD; when a window completes, rebuild with the new
    /// hyperparameters. Returns true if the model was rebuilt.
    fn adaptation_step(&mut self, dlogp_ds: f64) -> bool {
        let Some(mut ad) = self.adapt.take() else {
            return false;
        };
        self.gradient(&mut ad.buf, dlogp_ds);
        let changed = ad.sngd.push(&mut ad.buf.grad);
        let theta = changed.then(|| ad.sngd.theta().to_vec());
        if ad.sngd.stopped() {
            self.adaptation_finished = true;
        } else {
            self.adapt = Some(ad);
        }
        match theta {
            Some(theta) => {
                self.set_kernel_params(KernelParams::from_theta(&theta));
                true
            }
            None => false,
        }
    }

    /// Replace the hyperparameters and rebuild the posterior by re-running the online
    /// updates over the stored BVs and targets (BVs that are no longer novel are absorbed).
    ///
    /// The unit Gram matrix of the BVs under the new kernel is computed once up front (with
    /// its derivatives when adapting, which the gradient needs anyway); the re-run reads its
    /// kernel vectors from it instead of evaluating the kernel again.
    pub fn set_kernel_params(&mut self, params: KernelParams) {
        let Ok(kernel) = RecursiveArd::new(self.kernel.dim(), self.kernel.tau(), params) else {
            return;
        };
        self.kernel = kernel;
        // The re-run below stores the BVs it keeps again.
        self.inputs.clear();
        let mut ad = self.adapt.take();
        let m = self.n;
        let (w, no, s) = (self.wlen, self.n_out, self.stride);
        for i in 0..m {
            let (raw, scaled) = (
                &self.bv_raw[i * w..(i + 1) * w],
                &mut self.bv_scaled[i * w..(i + 1) * w],
            );
            self.kernel.scale_into(raw, scaled);
            self.basis.set(i, scaled);
        }
        // Unit Gram (lower triangle, old slot order) under the new kernel.
        match ad.as_mut() {
            Some(ad) => {
                self.fill_gram_derivatives(&mut ad.buf);
                let pk = ad.buf.pk;
                for i in 0..m {
                    for j in 0..=i {
                        self.gram_new[i * s + j] = ad.buf.kb[tri(i, j) * pk + pk - 1];
                    }
                }
            }
            None => {
                for i in 0..m {
                    let row = &mut self.gram_new[i * s..(i + 1) * s];
                    let x = &self.bv_scaled[i * w..(i + 1) * w];
                    self.kernel
                        .unit_many(x, &self.basis, i + 1, &mut self.lag_k, &mut self.k);
                    row[..=i].copy_from_slice(&self.k[..=i]);
                }
            }
        }
        let saved_x = self.x_raw.clone();
        let saved_y = self.y_tmp.clone();
        let sf2 = self.kernel.sigma_f2();
        self.n = 0;
        self.alpha.fill(0.0);
        self.retained.clear();
        for i in 0..m {
            // Slots below i are rewritten only after slot i was read.
            self.x_raw.copy_from_slice(&self.bv_raw[i * w..(i + 1) * w]);
            self.x_scaled
                .copy_from_slice(&self.bv_scaled[i * w..(i + 1) * w]);
            self.y_tmp.copy_from_slice(&self.bv_y[i * no..(i + 1) * no]);
            for (k, &r) in self.k.iter_mut().zip(&self.retained) {
                *k = self.gram_new[i * s + r] * sf2;
            }
            self.refresh_posterior();
            if let Some((r, _, _)) = self.likelihood_terms() {
                let before = self.n;
                self.posterior_update(r);
                if self.n > before {
                    self.retained.push(i);
                }
            }
        }
        self.x_raw = saved_x;
        self.x_scaled_current = false;
        self.y_tmp = saved_y;
        if let Some(mut ad) = ad {
            if self.retained.len() < m {
                // Absorbed BVs leave the Gram derivatives: keep the retained pairs, in
                // order (every source lies at or after its destination).
                let pk = ad.buf.pk;
                for (a, &ra) in self.retained.iter().enumerate() {
                    for (b, &rb) in self.retained[..=a].iter().enumerate() {
                        let from = tri(ra, rb) * pk;
                        ad.buf.kb.copy_within(from..from + pk, tri(a, b) * pk);
                    }
                }
            }
            self.adapt = Some(ad);
        }
        self.version += 1;
        self.observed = None;
    }

    /// ln p(y | window) under the current posterior and its gradient w.r.t.
    /// [`KernelParams::theta`] (for analysis and tests; training uses the cached form).
    pub fn log_predictive_gradient(&mut self, window: &[f64], y: &[f64]) -> (f64, Vec<f64>) {
        self.observe(window);
        self.ensure_scaled();
        self.y_tmp.copy_from_slice(&y[..self.n_out]);
        let mut buf = GradBuffers::new(
            self.kernel.dim(),
            self.kernel.tau(),
            self.stride,
            self.basis.stride(),
        );
        self.fill_gram_derivatives(&mut buf);
        match self.likelihood_terms() {
            Some((_, ds, logp)) => {
                self.gradient(&mut buf, ds);
                (logp, buf.grad)
            }
            None => (f64::NEG_INFINITY, vec![0.0; buf.grad.len()]),
        }
    }
}

/// vᵀdK w and vᵀdK v for every unit-kernel entry p of the Gram derivatives `kb` (packed
/// lower triangle, `pk` entries per pair). Entries
/// go in register blocks of 8, 4, 2 and 1, each summed over the pairs in the same order.
fn gram_quad_forms(kb: &[f64], pk: usize, v: &[f64], w: &[f64], cw: &mut [f64], cv: &mut [f64]) {
    dispatch_wide!(["avx512f", "avx2"] gram_quad_forms_portable, (
        kb: &[f64] = kb,
        pk: usize = pk,
        v: &[f64] = v,
        w: &[f64] = w,
        cw: &mut [f64] = cw,
        cv: &mut [f64] = cv,
    ))
}

#[inline(always)]
fn gram_quad_forms_portable(
    kb: &[f64],
    pk: usize,
    v: &[f64],
    w: &[f64],
    cw: &mut [f64],
    cv: &mut [f64],
) {
    // One pass over the pairs with every entry in registers (lanes past pk read the next
    // pair and are dropped); wider entry counts go in several passes.
    match pk.div_ceil(8) {
        1 => _ = quad_block::<8>(kb, pk, 0, pk, v, w, cw, cv),
        2 => _ = quad_block::<16>(kb, pk, 0, pk, v, w, cw, cv),
        3 => _ = quad_block::<24>(kb, pk, 0, pk, v, w, cw, cv),
        4 => _ = quad_block::<32>(kb, pk, 0, pk, v, w, cw, cv),
        5 => _ = quad_block::<40>(kb, pk, 0, pk, v, w, cw, cv),
        6 => _ = quad_block::<48>(kb, pk, 0, pk, v, w, cw, cv),
        _ => {
            let mut p0 = 0;
            while p0 < pk {
                p0 += match pk - p0 {
                    r if r >= 8 => quad_block::<8>(kb, pk, p0, 8, v, w, cw, cv),
                    r if r >= 4 => quad_block::<4>(kb, pk, p0, 4, v, w, cw, cv),
                    r if r >= 2 => quad_block::<2>(kb, pk, p0, 2, v, w, cw, cv),
                    _ => quad_block::<1>(kb, pk, p0, 1, v, w, cw, cv),
                };
            }
        }
    }
}

/// Largest single-pass register block of [`quad_block`]: the read past the last pair stays
/// inside.
const QUAD_PAD: usize = 48;

/// Entries p0..p0 + B of [`gram_quad_forms`], accumulated in registers, of which the
/// first `keep` are stored (lanes past pk read the next pair and are dropped); returns
/// `keep`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn quad_block<const B: usize>(
    kb: &[f64],
    pk: usize,
    p0: usize,
    keep: usize,
    v: &[f64],
    w: &[f64],
    cw: &mut [f64],
    cv: &mut [f64],
) -> usize {
    let (mut a, mut b) = ([0.0f64; B], [0.0f64; B]);
    for i in 0..v.len() {
        for j in 0..=i {
            let (cwij, cvij) = if i == j {
                (v[i] * w[i], v[i] * v[i])
            } else {
                (v[i] * w[j] + v[j] * w[i], 2.0 * v[i] * v[j])
            };
            let o = tri(i, j) * pk + p0;
            let t = &kb[o..o + B];
            for q in 0..B {
                a[q] += cwij * t[q];
                b[q] += cvij * t[q];
            }
        }
    }
    cw[p0..p0 + keep].copy_from_slice(&a[..keep]);
    cv[p0..p0 + keep].copy_from_slice(&b[..keep]);
    keep
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The training path keeps the Gram derivatives incrementally (new rows from the
    /// observation's derivatives, swaps on deletion, compaction on rebuild) and reuses the
    /// observation's per-lag kernel values; after every update, through deletions and
    /// hyperparameter rebuilds, both must equal a fresh computation, and so must the
    /// gradient (which tests/gp_sogp.rs checks against finite differences).
    #[test]
    fn cached_gradient_terms_equal_a_fresh_computation() {
        for likelihood in [Likelihood::Probit, Likelihood::Regression] {
            let p = SogpParams {
                capacity: 6,
                tau: 3,
                likelihood,
                adaptation: Some(SngdParams {
                    window: 4,
                    start_after: 8,
                    stop_count: 1000,
                    ..SngdParams::default()
                }),
                ..SogpParams::default()
            };
            let (dim, tau) = (2, 3);
            let mut gp = Sogp::new(dim, 1, &p).unwrap();
            let mut checked = 0;
            for t in 0..400 {
                let f = t as f64;
                let mut x = [0.0; 6];
                // Every fifth window starts with a padding lag.
                for (i, v) in x
                    .iter_mut()
                    .enumerate()
                    .skip(if t % 5 == 0 { dim } else { 0 })
                {
                    *v = (0.37 * f + 1.3 * i as f64).sin();
                }
                let y = if (0.11 * f).sin() > 0.0 { 1.0 } else { -1.0 };
                if let Some(ad) = gp.adapt.as_ref() {
                    // The gradient the next update will take, from the cached terms.
                    let mut g = gp.clone();
                    g.observe(&x);
                    g.y_tmp[0] = y;
                    let (_, ds, _) = g.likelihood_terms().unwrap();
                    let mut buf = ad.buf.clone();
                    g.gradient(&mut buf, ds);
                    let (_, fresh) = g.log_predictive_gradient(&x, &[y]);
                    for (a, b) in buf.grad.iter().zip(&fresh) {
                        assert!(
                            (a - b).abs() <= 1e-12 * (1.0 + b.abs()),
                            "step {t}: {a} vs {b}"
                        );
                    }
                }
                gp.observe(&x);
                gp.update(&[y]);
                if let Some(ad) = gp.adapt.as_ref() {
                    let mut fresh = GradBuffers::new(dim, tau, gp.stride, gp.basis.stride());
                    gp.fill_gram_derivatives(&mut fresh);
                    let pk = fresh.pk;
                    for i in 0..gp.n {
                        for j in 0..=i {
                            for q in 0..pk {
                                let at = tri(i, j) * pk + q;
                                assert_eq!(
                                    ad.buf.kb[at], fresh.kb[at],
                                    "step {t}, pair ({i}, {j})"
                                );
                            }
                        }
                    }
                    checked += 1;
                }
            }
            assert!(gp.seen() > 2 * p.capacity && gp.n_basis() == p.capacity);
            assert!(gp.hyper_updates() >= 20, "{}", gp.hyper_updates());
            assert!(checked > 300);
        }
    }

    /// The kernel vector and the per-lag K_t of an observation, looked up from the
    /// distance rows of the distinct inputs, equal the direct evaluation of every pair bit
    /// for bit: along sequences (shifted windows), at their starts (padding lags), on a
    /// window observed twice, with inputs repeated across sequences, through deletions and
    /// hyperparameter rebuilds.
    #[test]
    fn kernel_from_input_rows_equals_the_direct_evaluation() {
        use crate::gp::Window;
        let (dim, tau) = (3, 4);
        let p = SogpParams {
            capacity: 9,
            tau,
            adaptation: Some(SngdParams {
                window: 4,
                start_after: 12,
                stop_count: 1000,
                ..SngdParams::default()
            }),
            ..SogpParams::default()
        };
        let mut gp = Sogp::new(dim, 1, &p).unwrap();
        let mut window = Window::new(dim, tau);
        let mut checked = 0;
        for t in 0..900 {
            if t % 11 == 0 {
                window.reset();
            }
            // Inputs on a coarse grid, so that sequences share inputs.
            let x: Vec<f64> = (0..dim)
                .map(|k| ((0.37 * t as f64 + 1.3 * k as f64).sin() * 2.0).round() / 2.0)
                .collect();
            window.push(&x);
            for _ in 0..1 + usize::from(t % 7 == 0) {
                gp.observe(window.as_slice());
                let mut xs = vec![0.0; gp.wlen];
                gp.kernel.scale_into(window.as_slice(), &mut xs);
                let lanes = gp.basis.stride();
                let (mut lag_k, mut k) = (vec![0.0; tau * lanes], vec![0.0; lanes]);
                gp.kernel
                    .unit_many(&xs, &gp.basis, gp.n, &mut lag_k, &mut k);
                let sf2 = gp.kernel.sigma_f2();
                for i in 0..gp.n {
                    let direct = sf2 * gp.kernel.unit_scaled(&xs, gp.bv(i));
                    assert_eq!(gp.k[i].to_bits(), direct.to_bits(), "step {t}, BV {i}");
                    for lag in 0..tau {
                        let at = lag * lanes + i;
                        assert_eq!(gp.lag_k[at].to_bits(), lag_k[at].to_bits(), "step {t}");
                    }
                }
                checked += gp.n;
            }
            gp.update(&[if (0.23 * t as f64).cos() > 0.0 {
                1.0
            } else {
                -1.0
            }]);
        }
        assert!(gp.n_basis() == p.capacity && gp.hyper_updates() >= 20);
        assert!(checked > 5000, "{checked}");
    }

    /// Observing a window by its stamp computes what comparing the windows computes, bit
    /// for bit: along sequences, at a window observed twice, after steps the model sat out
    /// (not a shift by one), after a reset, and from a copy of the window that went on with
    /// other inputs (its stamp must not pass for the original's).
    #[test]
    fn stamped_windows_observe_what_compared_windows_do() {
        use crate::gp::Window;
        let (dim, tau) = (2, 3);
        let p = SogpParams {
            capacity: 6,
            tau,
            adaptation: Some(SngdParams {
                window: 4,
                start_after: 8,
                stop_count: 1000,
                ..SngdParams::default()
            }),
            ..SogpParams::default()
        };
        let mut by_slice = Sogp::new(dim, 1, &p).unwrap();
        let mut by_stamp = by_slice.clone();
        let mut window = Window::new(dim, tau);
        let mut copy = window.clone();
        let mut compared = 0;
        for t in 0..600 {
            let f = t as f64;
            if t % 13 == 0 {
                window.reset();
            }
            let x = [(0.37 * f).sin(), (0.11 * f).cos()];
            window.push(&x);
            copy.push(&[x[1], x[0]]);
            if t % 17 == 4 {
                copy = window.clone();
            }
            // The model sits out some steps.
            if t % 7 == 3 {
                continue;
            }
            let w = if t % 17 == 5 { &copy } else { &window };
            for _ in 0..1 + usize::from(t % 5 == 0) {
                by_slice.observe(w.as_slice());
                by_stamp.observe_window(w);
                let n = by_slice.n;
                assert_eq!(n, by_stamp.n);
                for (a, b) in by_slice.k[..n].iter().zip(&by_stamp.k[..n]) {
                    assert_eq!(a.to_bits(), b.to_bits(), "step {t}");
                }
                assert_eq!(by_slice.mean[0].to_bits(), by_stamp.mean[0].to_bits());
                compared += n;
            }
            let y = if (0.23 * f).cos() > 0.0 { 1.0 } else { -1.0 };
            by_slice.update(&[y]);
            by_stamp.update(&[y]);
        }
        assert!(
            by_stamp.hyper_updates() >= 20 && compared > 2000,
            "{compared}"
        );
    }

    /// A model that observed a whole sequence at once, then learns at its last window,
    /// ends as one that observed the windows step by step: the window it learns is the
    /// sequence's last.
    #[test]
    fn a_sequence_observed_at_once_learns_its_last_window() {
        use crate::gp::{SequenceWindows, Window};
        let (dim, tau) = (2, 3);
        let p = SogpParams {
            capacity: 8,
            tau,
            ..SogpParams::default()
        };
        let mut at_once = Sogp::new(dim, 1, &p).unwrap();
        let mut by_step = at_once.clone();
        for g in 0..40 {
            let f = g as f64;
            let steps: Vec<f64> = (0..2 * (4 + g % 5))
                .map(|i| (0.37 * f + 0.9 * i as f64).sin())
                .collect();
            let y = if g % 3 == 0 { 1.0 } else { -1.0 };
            let mut seen = Vec::new();
            at_once.observe_sequence(&SequenceWindows::new(dim, tau, &steps), 1, |_, m| {
                seen.push(m.probability())
            });
            at_once.update(&[y]);
            let mut window = Window::new(dim, tau);
            for (o, q) in steps.chunks_exact(dim).zip(&seen) {
                window.push(o);
                by_step.observe_window(&window);
                assert_eq!(by_step.probability().to_bits(), q.to_bits(), "grasp {g}");
            }
            by_step.update(&[y]);
            assert_eq!(at_once.basis(), by_step.basis(), "grasp {g}");
            assert_eq!(at_once.alpha, by_step.alpha, "grasp {g}");
        }
        assert_eq!(at_once.n_basis(), p.capacity);
    }

    #[test]
    fn a_drifted_inverse_is_detected_and_rebuilt() {
        let p = SogpParams {
            capacity: 8,
            tau: 2,
            adaptation: None,
            likelihood: Likelihood::Regression,
            ..SogpParams::default()
        };
        let mut gp = Sogp::new(1, 1, &p).unwrap();
        // Train until the next update is a drift check, with the budget full.
        for t in 0..DRIFT_CHECK_EVERY - 1 {
            let x = [(t as f64 * 0.37).sin(), (t as f64 * 0.11).cos()];
            gp.observe(&x);
            gp.update(&[x[1]]);
        }
        assert!(gp.inverse_drift() < DRIFT_TOL, "{}", gp.inverse_drift());
        assert_eq!(gp.inverse_rebuilds(), 0);
        // Force a drift: perturb Q symmetrically.
        let (n, s) = (gp.n, gp.stride);
        assert!(n >= 2);
        gp.q[s] += 1e-2;
        gp.q[1] += 1e-2;
        gp.q[0] *= 1.05;
        assert!(gp.inverse_drift() > DRIFT_TOL);
        gp.observe(&[0.3, -0.2]);
        gp.update(&[0.1]);
        assert_eq!(gp.inverse_rebuilds(), 1);
        assert!(gp.inverse_drift() < DRIFT_TOL, "{}", gp.inverse_drift());
        // Q is again the inverse of K_B within rounding.
        let k = Array2::from_shape_vec((gp.n, gp.n), gp.gram()).unwrap();
        let qk = gp.inverse_gram().dot(&k);
        for ((i, j), v) in qk.indexed_iter() {
            let want = if i == j { 1.0 } else { 0.0 };
            assert!((v - want).abs() < 1e-6, "QK[{i},{j}] = {v}");
        }
    }
}
