//! The kernel caches of the hyperparameter gradient: the unit-kernel derivatives of every
//! BV pair (a packed lower triangle) and of the observed window against every BV, and the
//! quadratic forms over them.

use super::super::wide::dispatch_wide;
use super::Sogp;

/// Position of the pair (i, j) in a packed lower triangle (K and its derivatives are
/// symmetric: storing one triangle halves the memory the gradient streams through).
#[inline(always)]
pub(super) fn tri(i: usize, j: usize) -> usize {
    let (a, b) = if i >= j { (i, j) } else { (j, i) };
    a * (a + 1) / 2 + b
}

/// Buffers for the hyperparameter gradient: per BV pair (`kb`, packed lower triangle) the
/// unit-kernel derivatives [∂/∂ln l_1 … ∂/∂ln l_D, ∂/∂sigma_rho] followed by the unit
/// kernel value itself; the same for the observed window against each BV (`kx`, one row
/// of `lanes` values per entry, as the many-BV kernel writes them).
#[derive(Clone, Debug)]
pub(super) struct GradBuffers {
    pub(super) pk: usize,
    pub(super) lanes: usize,
    pub(super) kb: Vec<f64>,
    pub(super) kx: Vec<f64>,
    /// Scratch of fill_gram_derivatives: rows as in `kx`, and K_t per lag.
    pub(super) tmp: Vec<f64>,
    pub(super) lag_k: Vec<f64>,
    pub(super) w: Vec<f64>,
    pub(super) kw: Vec<f64>,
    pub(super) kv: Vec<f64>,
    pub(super) cw: Vec<f64>,
    pub(super) cv: Vec<f64>,
    pub(super) grad: Vec<f64>,
}

impl GradBuffers {
    pub(super) fn new(dim: usize, tau: usize, stride: usize, lanes: usize) -> GradBuffers {
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

impl Sogp {
    /// Store every BV in the lag-major [`Sogp::basis`]. Only the gradient reads it, so it
    /// is kept up to date while adapting and filled here when adaptation starts or a
    /// one-off gradient needs it.
    pub(super) fn sync_basis(&mut self) {
        let w = self.wlen;
        for i in 0..self.n {
            self.basis.set(i, &self.bv_scaled[i * w..(i + 1) * w]);
        }
    }

    /// The Gram matrix's unit-kernel derivatives and values, one BV against all earlier
    /// ones at a time (K is symmetric).
    pub(super) fn fill_gram_derivatives(&self, buf: &mut GradBuffers) {
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
    pub(super) fn observation_derivatives(&self, buf: &mut GradBuffers) {
        let lanes = buf.lanes;
        let (g, kv) = buf.kx.split_at_mut((buf.pk - 1) * lanes);
        kv[..lanes].copy_from_slice(&self.lag_k[(self.kernel.tau() - 1) * lanes..]);
        self.kernel
            .unit_grad_many(&self.x_scaled, &self.basis, self.n, &self.lag_k, g);
    }
}

/// vᵀdK w and vᵀdK v for every unit-kernel entry p of the Gram derivatives `kb` (packed
/// lower triangle, `pk` entries per pair). Entries
/// go in register blocks of 8, 4, 2 and 1, each summed over the pairs in the same order.
pub(super) fn gram_quad_forms(
    kb: &[f64],
    pk: usize,
    v: &[f64],
    w: &[f64],
    cw: &mut [f64],
    cv: &mut [f64],
) {
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
pub(super) fn gram_quad_forms_portable(
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
pub(super) fn quad_block<const B: usize>(
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
