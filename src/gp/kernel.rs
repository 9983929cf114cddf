//! The recursive ARD kernel of the OIESGP (paper eqs. 13–14) over a window of the last
//! `tau` inputs (the window itself is in `window.rs`).
//!
//! K_0 = 1 and, for each lag from the oldest to the newest,
//! K_t = exp(−½ Δ_tᵀ M Δ_t) · exp((K_{t−1} − 1)/sigma_rho),  M = diag(l)⁻²,
//! with one lengthscale per input dimension shared by all lags. The kernel is
//! sigma_f²·K_tau (noise-free); the noise sigma_n² of eq. 14 is kept in the likelihood
//! (as the C++ reference does), which is the same model and keeps k(x, x) = sigma_f².
//!
//! `sigma_rho` is the recursion divisor itself (the reference code's `rho`; the paper's
//! default 1.01 is used as that divisor, see the notes, Sec. 2). Windows are zero padded at
//! the start of a sequence, never truncated, so that the recursion always runs tau lags.

use super::wide::dispatch_wide;
use serde::{Deserialize, Serialize};

use super::GpError;

/// The kernel's hyperparameters in their natural units.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct KernelParams {
    /// One lengthscale l_k per input dimension (shared across lags).
    pub lengthscales: Vec<f64>,
    /// Recursion divisor: larger values fade the past faster.
    pub sigma_rho: f64,
    /// Signal standard deviation.
    pub sigma_f: f64,
    /// Noise standard deviation (the noise variance is sigma_n²).
    pub sigma_n: f64,
}

/// Box bounds on the hyperparameters, from the reference examples (notes, Sec. 8).
pub const LENGTHSCALE_BOUNDS: (f64, f64) = (1e-3, 1e6);
pub const SIGMA_RHO_BOUNDS: (f64, f64) = (0.5, 1.1);
/// Bounds on sigma_f² and sigma_n².
pub const SIGMA_F2_BOUNDS: (f64, f64) = (1e-3, 10.0);
pub const SIGMA_N2_BOUNDS: (f64, f64) = (1e-3, 0.5);

impl KernelParams {
    pub fn validate(&self, dim: usize) -> Result<(), GpError> {
        if self.lengthscales.len() != dim {
            return Err(GpError::param(
                "lengthscales",
                format!(
                    "{} values for {dim} input dimensions",
                    self.lengthscales.len()
                ),
            ));
        }
        if let Some(l) = self
            .lengthscales
            .iter()
            .find(|l| !(l.is_finite() && **l > 0.0))
        {
            return Err(GpError::param(
                "lengthscales",
                format!("{l} is not positive"),
            ));
        }
        if !(self.sigma_rho.is_finite() && self.sigma_rho > 0.0) {
            return Err(GpError::param("sigma_rho", "must be positive"));
        }
        if !(self.sigma_f.is_finite() && self.sigma_f > 0.0) {
            return Err(GpError::param("sigma_f", "must be positive"));
        }
        if !(self.sigma_n.is_finite() && self.sigma_n > 0.0) {
            return Err(GpError::param("sigma_n", "must be positive"));
        }
        Ok(())
    }

    /// Number of entries of [`KernelParams::theta`].
    pub fn theta_len(dim: usize) -> usize {
        dim + 3
    }

    /// The vector the optimiser works on: [ln l_1 … ln l_D, sigma_rho, ln sigma_f, ln sigma_n].
    /// Logs keep the positive parameters positive; sigma_rho is bounded and stays linear.
    pub fn theta(&self) -> Vec<f64> {
        let mut t: Vec<f64> = self.lengthscales.iter().map(|l| l.ln()).collect();
        t.push(self.sigma_rho);
        t.push(self.sigma_f.ln());
        t.push(self.sigma_n.ln());
        t
    }

    pub fn from_theta(theta: &[f64]) -> KernelParams {
        let d = theta.len() - 3;
        KernelParams {
            lengthscales: theta[..d].iter().map(|t| t.exp()).collect(),
            sigma_rho: theta[d],
            sigma_f: theta[d + 1].exp(),
            sigma_n: theta[d + 2].exp(),
        }
    }

    /// Lower and upper bounds of each entry of theta.
    pub fn theta_bounds(dim: usize) -> (Vec<f64>, Vec<f64>) {
        let mut lo = vec![LENGTHSCALE_BOUNDS.0.ln(); dim];
        let mut hi = vec![LENGTHSCALE_BOUNDS.1.ln(); dim];
        lo.extend([
            SIGMA_RHO_BOUNDS.0,
            0.5 * SIGMA_F2_BOUNDS.0.ln(),
            0.5 * SIGMA_N2_BOUNDS.0.ln(),
        ]);
        hi.extend([
            SIGMA_RHO_BOUNDS.1,
            0.5 * SIGMA_F2_BOUNDS.1.ln(),
            0.5 * SIGMA_N2_BOUNDS.1.ln(),
        ]);
        (lo, hi)
    }
}

/// exp(x) for x ≤ 0 (the kernel's exponents are never positive), branch-free so that loops
/// over many BVs vectorise: Cody–Waite reduction x = k ln 2 + r, |r| ≤ ln2/2, a degree-12
/// Taylor polynomial (truncation below 2e-16 relative) and 2^k built from its exponent bits.
/// Arguments below −700 are clamped (the result, < 1e-304, is 0 for every use here).
#[inline(always)]
pub fn exp_nonpos(x: f64) -> f64 {
    const MAGIC: f64 = 6_755_399_441_055_744.0; // 1.5·2^52: adding it rounds to an integer
    // fdlibm's split of ln 2: k·LN2_HI is exact for |k| < 2^11.
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
    let x = x.clamp(-700.0, 0.0);
    let t = x * std::f64::consts::LOG2_E + MAGIC;
    let k = t - MAGIC;
    let r = (x - k * LN2_HI) - k * LN2_LO;
    let mut p = 1.0 / 479_001_600.0;
    for c in [
        1.0 / 39_916_800.0,
        1.0 / 3_628_800.0,
        1.0 / 362_880.0,
        1.0 / 40_320.0,
        1.0 / 5_040.0,
        1.0 / 720.0,
        1.0 / 120.0,
        1.0 / 24.0,
        1.0 / 6.0,
        0.5,
        1.0,
        1.0,
    ] {
        p = p * r + c;
    }
    // The low bits of t hold k; adding the bias and shifting gives the bits of 2^k.
    p * f64::from_bits(t.to_bits().wrapping_add(1023) << 52)
}

/// Σ (a_i − b_i)² with four independent accumulators, so that the sum vectorises (a single
/// running sum is one long chain of dependent additions).
#[inline(always)]
pub fn sq_dist(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            let d = x[l] - y[l];
            acc[l] += d * d;
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += (x - y) * (x - y);
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// Σ a_i b_i with four independent accumulators.
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        for l in 0..4 {
            acc[l] += x[l] * y[l];
        }
    }
    let mut tail = 0.0;
    for (x, y) in ra.iter().zip(rb) {
        tail += x * y;
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `out[i] = dot(&m[i * stride..i * stride + n], x)` for the rows i of `out`, four rows
/// at a time. Each row is summed in [`dot`]'s order (the same bits); the four rows' sums
/// are independent chains of additions, which the processor overlaps (one row's chain
/// alone waits on the latency of each addition).
#[inline(always)]
pub fn dot_rows(m: &[f64], stride: usize, n: usize, x: &[f64], out: &mut [f64]) {
    let x = &x[..n];
    let full = n / 4 * 4;
    let mut blocks = out.chunks_exact_mut(4);
    let mut i = 0;
    for o in &mut blocks {
        let row = |q: usize| &m[(i + q) * stride..(i + q) * stride + n];
        let (r0, r1, r2, r3) = (row(0), row(1), row(2), row(3));
        let mut acc = [[0.0f64; 4]; 4];
        let chunks = r0[..full]
            .chunks_exact(4)
            .zip(r1[..full].chunks_exact(4))
            .zip(r2[..full].chunks_exact(4))
            .zip(r3[..full].chunks_exact(4))
            .zip(x[..full].chunks_exact(4));
        for ((((a0, a1), a2), a3), y) in chunks {
            for l in 0..4 {
                acc[0][l] += a0[l] * y[l];
                acc[1][l] += a1[l] * y[l];
                acc[2][l] += a2[l] * y[l];
                acc[3][l] += a3[l] * y[l];
            }
        }
        for (q, (o, a)) in o.iter_mut().zip(&acc).enumerate() {
            let mut tail = 0.0;
            for (v, y) in row(q)[full..].iter().zip(&x[full..]) {
                tail += v * y;
            }
            *o = (a[0] + a[1]) + (a[2] + a[3]) + tail;
        }
        i += 4;
    }
    for (q, o) in blocks.into_remainder().iter_mut().enumerate() {
        *o = dot(&m[(i + q) * stride..(i + q) * stride + n], x);
    }
}

/// BVs processed together by the many-BV kernels (one AVX-512 register, two AVX2 ones).
pub const LANES: usize = 8;

/// Scaled BV windows in a lag-major layout of blocks of [`LANES`] BVs: entry (lag, k) of
/// BV i at `((lag·blocks + i / LANES)·dim + k)·LANES + i % LANES`, so that the kernels run
/// over the BVs of a block in vector lanes (no horizontal sums) while reading one
/// contiguous stretch per block and lag; plus each BV lag's squared norm, its distance to
/// a padding lag.
#[derive(Clone, Debug)]
pub struct LagMajor {
    dim: usize,
    tau: usize,
    stride: usize,
    data: Vec<f64>,
    norms: Vec<f64>,
}

impl LagMajor {
    /// Room for `slots` BVs.
    pub fn new(dim: usize, tau: usize, slots: usize) -> LagMajor {
        let stride = slots.max(1).div_ceil(LANES) * LANES;
        LagMajor {
            dim,
            tau,
            stride,
            data: vec![0.0; tau * dim * stride],
            norms: vec![0.0; tau * stride],
        }
    }

    /// Length of the per-BV buffers the kernels take.
    pub fn stride(&self) -> usize {
        self.stride
    }

    /// Room for `slots` BVs in a store of one lag, the stored ones kept: with one lag, an
    /// entry's position does not depend on the stride.
    pub(super) fn grow_single_lag(&mut self, slots: usize) {
        debug_assert_eq!(self.tau, 1);
        self.stride = self.stride.max(slots.div_ceil(LANES) * LANES);
        self.data.resize(self.dim * self.stride, 0.0);
        self.norms.resize(self.stride, 0.0);
    }

    /// Position of entry (lag, k) of BV i.
    #[inline(always)]
    fn index(&self, lag: usize, k: usize, i: usize) -> usize {
        ((lag * (self.stride / LANES) + i / LANES) * self.dim + k) * LANES + i % LANES
    }

    /// Store a scaled window (oldest lag first) as BV `i`.
    pub fn set(&mut self, i: usize, window: &[f64]) {
        let s = self.stride;
        for (lag, l) in window.chunks_exact(self.dim).take(self.tau).enumerate() {
            for (k, v) in l.iter().enumerate() {
                let at = self.index(lag, k, i);
                self.data[at] = *v;
            }
        }
        let zero = [0.0; 4];
        for (lag, l) in window.chunks_exact(self.dim).take(self.tau).enumerate() {
            // sq_dist against zeros: the association the kernels use, so bit-identical.
            let mut acc = [0.0f64; 4];
            let cl = l.chunks_exact(4);
            let rest = cl.remainder();
            for c in cl {
                for q in 0..4 {
                    let e = zero[q] - c[q];
                    acc[q] += e * e;
                }
            }
            let mut tail = 0.0;
            for v in rest {
                tail += (0.0 - v) * (0.0 - v);
            }
            self.norms[lag * s + i] = (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail;
        }
    }

    /// Squared norm of lag `lag` of BV `i` (its distance to a padding lag).
    pub(super) fn norm(&self, lag: usize, i: usize) -> f64 {
        self.norms[lag * self.stride + i]
    }

    /// Copy BV `from` into slot `to`.
    pub fn copy(&mut self, from: usize, to: usize) {
        let s = self.stride;
        for lag in 0..self.tau {
            for k in 0..self.dim {
                let (a, b) = (self.index(lag, k, from), self.index(lag, k, to));
                self.data[b] = self.data[a];
            }
        }
        for r in 0..self.tau {
            self.norms[r * s + to] = self.norms[r * s + from];
        }
    }

    /// Squared distances between `xl` (one lag) and lag `lag` of BVs 0..m (m a multiple of
    /// [`LANES`]) into `d`, associated exactly as [`sq_dist`]: four partial sums over
    /// k mod 4, a sequential tail, (a0 + a1) + (a2 + a3) + tail. A padding lag (all zero)
    /// takes the stored norms.
    #[inline(always)]
    pub(super) fn lag_sq_dist(&self, lag: usize, xl: &[f64], m: usize, d: &mut [f64]) {
        let (dim, s) = (self.dim, self.stride);
        if xl.iter().all(|v| *v == 0.0) {
            d.copy_from_slice(&self.norms[lag * s..lag * s + m]);
            return;
        }
        let full = dim / 4 * 4;
        let lag_data = &self.data[lag * dim * s..(lag + 1) * dim * s];
        for (blk, db) in lag_data
            .chunks_exact(dim * LANES)
            .zip(d.chunks_exact_mut(LANES))
        {
            let (head, rest) = blk.split_at(full * LANES);
            let mut acc = [[0.0f64; LANES]; 4];
            for (rows, x4) in head.chunks_exact(4 * LANES).zip(xl.chunks_exact(4)) {
                for ((a, row), xk) in acc.iter_mut().zip(rows.chunks_exact(LANES)).zip(x4) {
                    for (a, r) in a.iter_mut().zip(row) {
                        let e = xk - r;
                        *a += e * e;
                    }
                }
            }
            let mut tail = [0.0f64; LANES];
            for (row, xk) in rest.chunks_exact(LANES).zip(&xl[full..]) {
                for (t, r) in tail.iter_mut().zip(row) {
                    *t += (xk - r) * (xk - r);
                }
            }
            for (l, out) in db.iter_mut().enumerate() {
                *out = (acc[0][l] + acc[1][l]) + (acc[2][l] + acc[3][l]) + tail[l];
            }
        }
    }
}

/// The recursive ARD kernel for inputs of `dim` dimensions over `tau` lags.
#[derive(Clone, Debug)]
pub struct RecursiveArd {
    dim: usize,
    tau: usize,
    params: KernelParams,
    inv_l: Vec<f64>,
    sigma_f2: f64,
    sigma_n2: f64,
}

impl RecursiveArd {
    pub fn new(dim: usize, tau: usize, params: KernelParams) -> Result<Self, GpError> {
        if dim == 0 {
            return Err(GpError::param("dim", "must be at least 1"));
        }
        if tau == 0 {
            return Err(GpError::param("tau", "must be at least 1"));
        }
        params.validate(dim)?;
        let inv_l = params.lengthscales.iter().map(|l| 1.0 / l).collect();
        Ok(RecursiveArd {
            dim,
            tau,
            sigma_f2: params.sigma_f * params.sigma_f,
            sigma_n2: params.sigma_n * params.sigma_n,
            params,
            inv_l,
        })
    }

    pub fn dim(&self) -> usize {
        self.dim
    }
    pub fn tau(&self) -> usize {
        self.tau
    }
    /// Length of a window: tau·dim.
    pub fn window_len(&self) -> usize {
        self.tau * self.dim
    }
    pub fn params(&self) -> &KernelParams {
        &self.params
    }
    pub fn sigma_f2(&self) -> f64 {
        self.sigma_f2
    }
    pub fn sigma_n2(&self) -> f64 {
        self.sigma_n2
    }

    /// Divide every input of `window` by its lengthscale, so that the recursion needs
    /// plain squared distances (done once per window, not once per pair).
    pub fn scale_into(&self, window: &[f64], out: &mut [f64]) {
        for (lag_in, lag_out) in window
            .chunks_exact(self.dim)
            .zip(out.chunks_exact_mut(self.dim))
        {
            for ((o, x), il) in lag_out.iter_mut().zip(lag_in).zip(&self.inv_l) {
                *o = x * il;
            }
        }
    }

    /// Unit-amplitude recursion K_tau between two scaled windows (oldest lag first).
    #[inline]
    pub fn unit_scaled(&self, a: &[f64], b: &[f64]) -> f64 {
        let inv_rho = 1.0 / self.params.sigma_rho;
        let mut k = 1.0;
        for (la, lb) in a.chunks_exact(self.dim).zip(b.chunks_exact(self.dim)) {
            let d = sq_dist(la, lb);
            k = exp_nonpos(-0.5 * d + (k - 1.0) * inv_rho);
        }
        k
    }

    /// Unit K_tau between the scaled window `x` and BVs 0..n of `basis`, into `out`.
    /// `lag_k` (tau rows of `basis.stride()`) receives K_t after every lag, for
    /// [`RecursiveArd::unit_grad_many`]; `out` is at least `basis.stride()` long. Lanes n..
    /// up to the next multiple of [`LANES`] hold values of stale slots, to be ignored. Lags
    /// run in the outer loop so that the recursion of all BVs advances together. Every value
    /// is bit-identical to [`RecursiveArd::unit_scaled`] of the pair.
    pub fn unit_many(
        &self,
        x: &[f64],
        basis: &LagMajor,
        n: usize,
        lag_k: &mut [f64],
        out: &mut [f64],
    ) {
        dispatch_wide!(["avx512f", "avx2"] RecursiveArd::unit_many_portable, (
            this: &RecursiveArd = self,
            x: &[f64] = x,
            basis: &LagMajor = basis,
            n: usize = n,
            lag_k: &mut [f64] = lag_k,
            out: &mut [f64] = out,
        ))
    }

    #[inline(always)]
    fn unit_many_portable(
        &self,
        x: &[f64],
        basis: &LagMajor,
        n: usize,
        lag_k: &mut [f64],
        out: &mut [f64],
    ) {
        let (dim, s, m) = (self.dim, basis.stride, n.div_ceil(LANES) * LANES);
        let inv_rho = 1.0 / self.params.sigma_rho;
        out[..m].fill(1.0);
        for lag in 0..self.tau {
            let row = &mut lag_k[lag * s..lag * s + m];
            basis.lag_sq_dist(lag, &x[lag * dim..(lag + 1) * dim], m, row);
            for (k, r) in out[..m].iter_mut().zip(row.iter_mut()) {
                *k = exp_nonpos(-0.5 * *r + (*k - 1.0) * inv_rho);
                *r = *k;
            }
        }
    }

    /// The derivatives of [`RecursiveArd::unit_scaled_grad`] between `x` and BVs 0..n, from
    /// the K_t that [`RecursiveArd::unit_many`] left in `lag_k` for the same `x`, in one
    /// pass over the BVs' data: `grad` holds dim + 1 rows of `basis.stride()` values, row
    /// j < dim ∂K/∂ln l_j and row dim ∂K/∂sigma_rho, one column per BV (all lengthscales
    /// at once). Bit-identical to the pairwise form.
    pub fn unit_grad_many(
        &self,
        x: &[f64],
        basis: &LagMajor,
        n: usize,
        lag_k: &[f64],
        grad: &mut [f64],
    ) {
        dispatch_wide!(["avx512f", "avx2"] RecursiveArd::unit_grad_many_portable, (
            this: &RecursiveArd = self,
            x: &[f64] = x,
            basis: &LagMajor = basis,
            n: usize = n,
            lag_k: &[f64] = lag_k,
            grad: &mut [f64] = grad,
        ))
    }

    /// Each entry's derivative is its own recursion over the lags, so the entries are taken
    /// a block of BVs and `G` lengthscales at a time, each through all the lags in
    /// registers: `G` independent chains hide the recursion's latency, and no partial sum
    /// goes through memory between lags. Every entry sees the same operations in the same
    /// order as lag by lag over all the entries: the same bits.
    #[inline(always)]
    fn unit_grad_many_portable(
        &self,
        x: &[f64],
        basis: &LagMajor,
        n: usize,
        lag_k: &[f64],
        grad: &mut [f64],
    ) {
        let (dim, s, m) = (self.dim, basis.stride, n.div_ceil(LANES) * LANES);
        let inv_rho = 1.0 / self.params.sigma_rho;
        for c in 0..m / LANES {
            let mut j = 0;
            while j + 4 <= dim {
                self.lengthscale_chains::<4>(x, basis, lag_k, grad, c, j, inv_rho);
                j += 4;
            }
            while j < dim {
                self.lengthscale_chains::<1>(x, basis, lag_k, grad, c, j, inv_rho);
                j += 1;
            }
            // ∂K/∂sigma_rho, with K_0 = 1 before the oldest lag.
            let mut g = [0.0; LANES];
            let mut kp = [1.0; LANES];
            for k in lag_k[c * LANES..].chunks(s).take(self.tau) {
                let k: &[f64; LANES] = k[..LANES].try_into().unwrap_or(&[f64::NAN; LANES]);
                for l in 0..LANES {
                    g[l] = k[l] * (g[l] * inv_rho + (1.0 - kp[l]) * inv_rho * inv_rho);
                }
                kp = *k;
            }
            grad[dim * s + c * LANES..][..LANES].copy_from_slice(&g);
        }
    }

    /// ∂K/∂ln l_j for the `G` lengthscales from `j0` and the BVs of block `c`.
    #[inline(always)]
    #[allow(clippy::too_many_arguments)]
    fn lengthscale_chains<const G: usize>(
        &self,
        x: &[f64],
        basis: &LagMajor,
        lag_k: &[f64],
        grad: &mut [f64],
        c: usize,
        j0: usize,
        inv_rho: f64,
    ) {
        let (dim, s) = (self.dim, basis.stride);
        let mut g = [[0.0; LANES]; G];
        let lags = basis.data[c * dim * LANES + j0 * LANES..]
            .chunks(dim * s)
            .zip(lag_k[c * LANES..].chunks(s))
            .zip(x[j0..].chunks(dim))
            .take(self.tau);
        for ((b, k), xl) in lags {
            let k: &[f64; LANES] = k[..LANES].try_into().unwrap_or(&[f64::NAN; LANES]);
            for (q, g) in g.iter_mut().enumerate() {
                let xj = xl[q];
                let b: &[f64; LANES] = b[q * LANES..(q + 1) * LANES]
                    .try_into()
                    .unwrap_or(&[f64::NAN; LANES]);
                for l in 0..LANES {
                    g[l] = k[l] * (g[l] * inv_rho + (xj - b[l]) * (xj - b[l]));
                }
            }
        }
        for (q, g) in g.iter().enumerate() {
            grad[(j0 + q) * s + c * LANES..][..LANES].copy_from_slice(g);
        }
    }

    /// K_tau and its derivatives (recursive, eqs. 22–23 in the parameters of `theta`):
    /// `grad[j]` = ∂K/∂ln l_j for j < dim, `grad[dim]` = ∂K/∂sigma_rho.
    pub fn unit_scaled_grad(&self, a: &[f64], b: &[f64], grad: &mut [f64]) -> f64 {
        dispatch_wide!(["avx2"] RecursiveArd::unit_scaled_grad_portable, (
            this: &RecursiveArd = self,
            a: &[f64] = a,
            b: &[f64] = b,
            grad: &mut [f64] = grad,
        ) -> f64)
    }

    #[inline(always)]
    fn unit_scaled_grad_portable(&self, a: &[f64], b: &[f64], grad: &mut [f64]) -> f64 {
        let rho = self.params.sigma_rho;
        let inv_rho = 1.0 / rho;
        grad[..=self.dim].fill(0.0);
        let mut k = 1.0;
        for (la, lb) in a.chunks_exact(self.dim).zip(b.chunks_exact(self.dim)) {
            let d = sq_dist(la, lb);
            let k_prev = k;
            k = exp_nonpos(-0.5 * d + (k_prev - 1.0) * inv_rho);
            for ((g, x), y) in grad[..self.dim].iter_mut().zip(la).zip(lb) {
                *g = k * (*g * inv_rho + (x - y) * (x - y));
            }
            grad[self.dim] = k * (grad[self.dim] * inv_rho + (1.0 - k_prev) * inv_rho * inv_rho);
        }
        k
    }

    /// sigma_f²·K_tau between two raw windows (noise-free).
    pub fn eval(&self, a: &[f64], b: &[f64]) -> f64 {
        let mut sa = vec![0.0; a.len()];
        let mut sb = vec![0.0; b.len()];
        self.scale_into(a, &mut sa);
        self.scale_into(b, &mut sb);
        self.sigma_f2 * self.unit_scaled(&sa, &sb)
    }
}
