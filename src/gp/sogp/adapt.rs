//! Hyperparameter adaptation: the exact gradient of the log predictive probability (paper
//! eq. 15), its stochastic natural-gradient steps, and the rebuild of the posterior under
//! new hyperparameters.

use super::super::kernel::{KernelParams, RecursiveArd};
use super::super::sngd::Sngd;
use super::gram::{GradBuffers, gram_quad_forms, tri};
use super::{Likelihood, Sogp};

#[derive(Clone, Debug)]
pub(super) struct Adaptation {
    pub(super) sngd: Sngd,
    pub(super) buf: GradBuffers,
}

impl Sogp {
    /// Start adaptation once enough points were seen; apply a completed SNGD window.
    pub(super) fn after_update(&mut self) {
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
            self.sync_basis();
            self.fill_gram_derivatives(&mut buf);
            self.adapt = Some(Box::new(Adaptation { sngd, buf }));
        }
    }

    /// Gradient of ln p(y | x) w.r.t. theta = [ln l, sigma_rho, ln sigma_f, ln sigma_n]
    /// into `buf.grad`, from the observation, `qv` (= ∂ln p/∂m) and the Gram derivatives.
    pub(super) fn gradient(&self, buf: &mut GradBuffers, dlogp_ds: f64) {
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
    pub(super) fn adaptation_step(&mut self, dlogp_ds: f64) -> bool {
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
        self.own_inputs();
        self.leave_pairs();
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
            if let Some((r, _, _)) = self.likelihood_terms()
                && self.posterior_update(r)
            {
                self.store_new_bv();
                self.retained.push(i);
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
            self.sync_basis();
        }
        self.version += 1;
        self.observed = None;
    }

    /// ln p(y | window) under the current posterior and its gradient w.r.t.
    /// [`KernelParams::theta`] (for analysis and tests; training uses the cached form).
    pub fn log_predictive_gradient(&mut self, window: &[f64], y: &[f64]) -> (f64, Vec<f64>) {
        self.observe(window);
        // The gradient reads K_t per lag, which an observation keeps only while adapting.
        self.evaluate_keeping(true);
        self.ensure_scaled();
        self.y_tmp.copy_from_slice(&y[..self.n_out]);
        let mut buf = GradBuffers::new(
            self.kernel.dim(),
            self.kernel.tau(),
            self.stride,
            self.basis.stride(),
        );
        self.sync_basis();
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
