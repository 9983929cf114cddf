//! The online update of the posterior (Csató & Opper): a new point projected onto the BVs
//! or added as a BV, the deletion of the least informative BV at the budget, and the repair
//! of Q = K_B⁻¹ when rounding has made it drift.

use ndarray::Array2;

use super::super::kernel::dot;
use super::super::wide::dispatch_wide;
use super::gram::tri;
use super::{DRIFT_TOL, Sogp};
use crate::linalg::Cholesky;

impl Sogp {
    /// The BVs' Gram matrix K_B (row-major, n × n).
    pub(super) fn gram(&self) -> Vec<f64> {
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
    pub(super) fn diag_residual(q: &[f64], s: usize, gram: &[f64], n: usize) -> f64 {
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
    pub(super) fn check_inverse(&mut self) {
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

    pub(super) fn posterior_update(&mut self, r: f64) {
        // The O(n²) updates, in wide vectors where available.
        dispatch_wide!(["avx512f", "avx2"] Sogp::posterior_update_portable, (
            this: &mut Sogp = self,
            r: f64 = r,
        ))
    }

    #[inline(always)]
    pub(super) fn posterior_update_portable(&mut self, r: f64) {
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
    pub(super) fn delete_least_informative(&mut self) {
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
    pub(super) fn delete_portable(&mut self, i: usize) {
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

    pub(super) fn swap_bv(&mut self, i: usize, j: usize) {
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
}
