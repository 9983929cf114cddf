//! The online update of the posterior (Csató & Opper): a new point projected onto the BVs
//! or added as a BV, the deletion of the least informative BV at the budget, and the repair
//! of Q = K_B⁻¹ when rounding has made it drift.

use ndarray::Array2;

use super::super::kernel::{LANES, dot, dot_rows};
use super::super::quotient::{hardware_fma, in_range, quotient};
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

    /// The posterior update at the observed window with likelihood term `r`. Returns true
    /// when the point became BV n − 1 (a full update): C, Q and α already hold it, but
    /// its window is stored by the caller ([`Sogp::store_bv`]), which at the budget first
    /// learns whether the deletion that follows removes it again.
    pub(super) fn posterior_update(&mut self, r: f64) -> bool {
        // The O(n²) updates, in wide vectors where available.
        dispatch_wide!(["avx512f", "avx2"] Sogp::posterior_update_portable, (
            this: &mut Sogp = self,
            r: f64 = r,
        ) -> bool)
    }

    #[inline(always)]
    pub(super) fn posterior_update_portable(&mut self, r: f64) -> bool {
        let (n, s, no) = (self.n, self.stride, self.n_out);
        dot_rows(&self.q, s, n, &self.k, &mut self.ehat[..n]);
        let k = &self.k[..n];
        let sf2 = self.kernel.sigma_f2();
        let kqk: f64 = k.iter().zip(&self.ehat[..n]).map(|(k, e)| k * e).sum();
        let gamma = (sf2 - kqk).max(0.0);
        if gamma >= self.eps * sf2 && gamma > 0.0 {
            // Full update: the point becomes BV n. Row and column n of Q are written
            // whole; those of C start from zero (kept as `0 + x`, which differs from x in
            // the sign of a zero).
            let ig = 1.0 / gamma;
            let ehat = &self.ehat[..n];
            for (i, &ei) in ehat.iter().enumerate() {
                let row = &mut self.q[i * s..i * s + n + 1];
                // (ig·e_i)·e_j, the association of ig * e_i * e_j.
                let g = ig * ei;
                for (q, ej) in row[..n].iter_mut().zip(ehat) {
                    *q += g * ej;
                }
                row[n] = -ig * ei;
            }
            for (i, &ei) in ehat.iter().enumerate() {
                self.q[n * s + i] = -ig * ei;
            }
            self.q[n * s + n] = ig;
            for d in 0..no {
                let qd = self.qv[d];
                for (a, ck) in self.alpha.iter_mut().skip(d).step_by(no).zip(&self.ck[..n]) {
                    *a += ck * qd;
                }
                self.alpha[n * no + d] = qd;
            }
            let ck = &self.ck[..n];
            for (i, &si) in ck.iter().enumerate() {
                let row = &mut self.c[i * s..i * s + n + 1];
                let g = r * si;
                for (c, sj) in row[..n].iter_mut().zip(ck) {
                    *c += g * sj;
                }
                row[n] = 0.0 + g;
            }
            let row = &mut self.c[n * s..n * s + n + 1];
            for (c, sj) in row[..n].iter_mut().zip(ck) {
                *c = 0.0 + r * sj;
            }
            row[n] = 0.0 + r;
            self.n += 1;
            self.version += 1;
            true
        } else {
            // Projected update onto the current BVs, with Csató's η = 1/(1 + γ r).
            let eta = 1.0 / (1.0 + gamma * r);
            if !(eta.is_finite() && eta > 0.0) {
                return false;
            }
            for (e, ck) in self.ehat[..n].iter_mut().zip(&self.ck[..n]) {
                *e += ck;
            }
            let ehat = &self.ehat[..n];
            for d in 0..no {
                let qd = self.qv[d];
                for (a, e) in self.alpha.iter_mut().skip(d).step_by(no).zip(ehat) {
                    *a += eta * e * qd;
                }
            }
            let re = r * eta;
            for (i, &ei) in ehat.iter().enumerate() {
                // ((r·η)·e_i)·e_j, the association of r * eta * e_i * e_j.
                let g = re * ei;
                for (c, ej) in self.c[i * s..i * s + n].iter_mut().zip(ehat) {
                    *c += g * ej;
                }
            }
            self.version += 1;
            false
        }
    }

    /// Store the observed window, its target and (when adapting) its kernel derivatives
    /// as BV `slot`. The derivatives in `kx` are against BVs 0..`others` as they stood
    /// before the window became a BV, `slot` among them when it replaces a deleted BV.
    /// The distinct inputs are the caller's.
    pub(super) fn store_bv(&mut self, slot: usize, others: usize) {
        let (w, no) = (self.wlen, self.n_out);
        self.bv_raw[slot * w..(slot + 1) * w].copy_from_slice(&self.x_raw);
        self.bv_scaled[slot * w..(slot + 1) * w].copy_from_slice(&self.x_scaled);
        self.bv_y[slot * no..(slot + 1) * no].copy_from_slice(&self.y_tmp);
        if let Some(a) = self.adapt.as_mut() {
            self.basis.set(slot, &self.x_scaled);
            let (pk, lanes) = (a.buf.pk, a.buf.lanes);
            for j in (0..others).filter(|&j| j != slot) {
                let pair = &mut a.buf.kb[tri(slot, j) * pk..(tri(slot, j) + 1) * pk];
                for (p, v) in pair.iter_mut().enumerate() {
                    *v = a.buf.kx[p * lanes + j];
                }
            }
            let diag = &mut a.buf.kb[tri(slot, slot) * pk..(tri(slot, slot) + 1) * pk];
            diag.fill(0.0);
            diag[pk - 1] = 1.0;
        }
    }

    /// Store the observed window as the new BV n − 1 (a full update below the budget).
    pub(super) fn store_new_bv(&mut self) {
        let slot = self.n - 1;
        let inv_rho = 1.0 / self.kernel.params().sigma_rho;
        self.inputs
            .add_bv(slot, &self.x_raw, &self.x_scaled, inv_rho);
        self.store_bv(slot, slot);
    }

    /// After a full update past the budget: remove the BV with the lowest
    /// |α_i|²/(Q_ii + C_ii) (paper eq. 10). The new BV n − 1 is not stored yet: when it
    /// is the one removed, it never is (most of the time at the budget); otherwise it is
    /// stored straight into the slot of the BV removed, where the last BV would move.
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
        let last = self.n - 1;
        self.remove(best);
        if best != last {
            // The inputs change as they did when the new BV was stored before the
            // deletion: acquired, then BV `best`'s released, then moved into its slot.
            let inv_rho = 1.0 / self.kernel.params().sigma_rho;
            self.inputs
                .add_bv(last, &self.x_raw, &self.x_scaled, inv_rho);
            self.inputs.release_bv(best);
            self.inputs.move_bv(last, best);
            self.store_bv(best, last);
            self.move_posterior(last, best);
        }
        self.drop_last();
    }

    /// Remove BV `i` with the (Q + C) removal of Csató & Opper; the last BV moves into
    /// its slot.
    pub fn delete(&mut self, i: usize) {
        self.own_inputs();
        if i >= self.n {
            return;
        }
        let last = self.n - 1;
        self.remove(i);
        self.inputs.release_bv(i);
        if i != last {
            self.move_bv(last, i);
        }
        self.drop_last();
    }

    /// The last BV's α is cleared and the BV count falls by one.
    fn drop_last(&mut self) {
        let (no, n) = (self.n_out, self.n);
        for a in &mut self.alpha[(n - 1) * no..n * no] {
            *a = 0.0;
        }
        self.n -= 1;
        self.version += 1;
    }

    /// The (Q + C) removal of BV `i` from C, Q and α, which leaves its row and column
    /// stale (the last BV's replace them, or the BV count falls).
    fn remove(&mut self, i: usize) {
        // The wide paths are compiled with FMA (AVX-512F implies it), the only ones that
        // take the quotients by reciprocal.
        let fma = hardware_fma();
        dispatch_wide!(["avx512f", "fma"] Sogp::remove_portable, (this: &mut Sogp = self, i: usize = i, fma: bool = fma))
    }

    /// The removal runs on BV i's column where it stands; then the last BV moves into
    /// slot i. This is the order a swap of i with the last BV followed by the removal of
    /// the last gives (every entry is updated on its own, so the results are the same to
    /// the last bit), without moving the other rows.
    ///
    /// Both increments of an entry (j, m), `q_j q_m / Q_ii` and `(q_j + c_j)(q_m + c_m) /
    /// (Q_ii + C_ii)`, are symmetric in (j, m) to the last bit (the products commute), so
    /// they are computed once for m below j's block of [`LANES`] BVs, added to row j where
    /// they stand and to column j as they are: nearly half the divisions, which bound the
    /// removal. Within the block a row takes all of it (whole vectors, no scalar tail).
    /// Row i is skipped: the last BV's overwrites it.
    ///
    /// With hardware FMA and every factor and pivot within [`in_range`] (nearly always)
    /// the quotients come from the pivots' reciprocals, to the same last bit as the
    /// division ([`quotient`]), at a fraction of the divider's time.
    #[inline(always)]
    pub(super) fn remove_portable(&mut self, i: usize, fma: bool) {
        let (s, no, n) = (self.stride, self.n_out, self.n);
        let qs = self.q[i * s + i].max(1e-300);
        let den = (self.q[i * s + i] + self.c[i * s + i]).max(1e-300);
        // Column i copied out (with q_m + c_m) so that the updates run over contiguous rows.
        for j in 0..n {
            let (qj, cj) = (self.q[j * s + i], self.c[j * s + i]);
            self.col_q[j] = qj;
            self.col_qc[j] = qj + cj;
        }
        let (cq, cqc) = (&self.col_q[..n], &self.col_qc[..n]);
        for d in 0..no {
            let a_star = self.alpha[i * no + d];
            for (a, qc) in self.alpha.iter_mut().skip(d).step_by(no).zip(cqc) {
                *a -= a_star * qc / den;
            }
        }
        let by_reciprocal = fma
            && in_range(qs)
            && in_range(den)
            && cq
                .iter()
                .zip(cqc)
                .all(|(q, qc)| in_range(*q) & in_range(*qc));
        if by_reciprocal {
            self.remove_rows::<true>(i, qs, den);
        } else {
            self.remove_rows::<false>(i, qs, den);
        }
    }

    /// The removal's increments of C and Q (see [`Sogp::remove_portable`]), the quotients
    /// by [`quotient`] when `RECIPROCAL`, else by division.
    #[inline(always)]
    fn remove_rows<const RECIPROCAL: bool>(&mut self, i: usize, qs: f64, den: f64) {
        let (s, n) = (self.stride, self.n);
        let (yq, yd) = (1.0 / qs, 1.0 / den);
        let div = |a: f64, b: f64, y: f64| {
            if RECIPROCAL { quotient(a, b, y) } else { a / b }
        };
        let (cq, cqc) = (&self.col_q[..n], &self.col_qc[..n]);
        let (dq, dc) = (&mut self.del_q[..n], &mut self.del_c[..n]);
        for j in (0..n).filter(|&j| j != i) {
            let (qj, qcj) = (cq[j], cqc[j]);
            // Row j to the end of its block; column i among them is overwritten later.
            let end = (j + 1).next_multiple_of(LANES).min(n);
            let crow = &mut self.c[j * s..j * s + end];
            let qrow = &mut self.q[j * s..j * s + end];
            for ((((c, q), (qm, qcm)), dqm), dcm) in crow
                .iter_mut()
                .zip(qrow.iter_mut())
                .zip(cq.iter().zip(cqc))
                .zip(dq.iter_mut())
                .zip(dc.iter_mut())
            {
                let d1 = div(qj * qm, qs, yq);
                let d = d1 - div(qcj * qcm, den, yd);
                *c += d;
                *q -= d1;
                *dqm = d1;
                *dcm = d;
            }
            // The same increments into column j of the rows before its block.
            let before = j / LANES * LANES;
            let rows = self.c.chunks_exact_mut(s).zip(self.q.chunks_exact_mut(s));
            for ((crow, qrow), (dcm, dqm)) in rows.zip(dc[..before].iter().zip(&dq[..before])) {
                crow[j] += dcm;
                qrow[j] -= dqm;
            }
        }
    }

    /// Move BV `from` (the last) into slot `to`, whose BV is gone: its row and column of C
    /// and Q, α, window, target, inputs and Gram derivatives.
    fn move_bv(&mut self, from: usize, to: usize) {
        let (w, no) = (self.wlen, self.n_out);
        self.move_posterior(from, to);
        self.bv_raw.copy_within(from * w..(from + 1) * w, to * w);
        self.bv_scaled.copy_within(from * w..(from + 1) * w, to * w);
        if self.adapt.is_some() {
            self.basis.copy(from, to);
        }
        self.inputs.move_bv(from, to);
        self.bv_y.copy_within(from * no..(from + 1) * no, to * no);
        if let Some(a) = self.adapt.as_mut() {
            let pk = a.buf.pk;
            let kb = &mut a.buf.kb;
            for r in (0..from).filter(|&r| r != to) {
                kb.copy_within(tri(from, r) * pk..(tri(from, r) + 1) * pk, tri(to, r) * pk);
            }
            kb.copy_within(
                tri(from, from) * pk..(tri(from, from) + 1) * pk,
                tri(to, to) * pk,
            );
        }
    }

    /// Move the last BV's row and column of C and Q (the pair with itself to the
    /// diagonal) and its α into slot `to`.
    fn move_posterior(&mut self, from: usize, to: usize) {
        let (s, no) = (self.stride, self.n_out);
        for m in [&mut self.c, &mut self.q] {
            let diag = m[from * s + from];
            m.copy_within(from * s..from * s + from, to * s);
            m[to * s + to] = diag;
            for r in (0..from).filter(|&r| r != to) {
                m[r * s + to] = m[r * s + from];
            }
        }
        self.alpha.copy_within(from * no..(from + 1) * no, to * no);
    }
}
