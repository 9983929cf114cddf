//! The squared distances between every pair of a session's distinct inputs under one
//! kernel's lengthscales, and the unit kernel between every pair of its windows, computed
//! once and read by every model with those hyperparameters.
//!
//! A model's own distance table computes, at each step, the new input's distances to the
//! inputs its BVs hold. When every window is made of a known session's inputs (a clustering
//! sweep learns and re-assigns the same grasps under many thresholds and orders), each of
//! those distances is an entry of the session's pair table, and a model looks its rows up
//! instead. The entries come from the function that computes a table's rows
//! ([`LagMajor::lag_sq_dist`], the observed input against the stored one), so every kernel
//! value is bit-identical.
//!
//! The windows of the sequences (tau inputs each, padded at the start) are the BVs a model
//! can hold and the windows it observes, so the unit kernel K_tau between two of them is
//! also computed once: the recursion over the lags, from the same distances in the same
//! order ([`super::Inputs::unit_k`]'s), so again the same bits. A model that observes one
//! of them reads its kernel vector from that window's row, without an exponential.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use rayon::prelude::*;

use super::bits::{Prehashed, hash_bits, same_bits};
use super::kernel::{LANES, LagMajor, RecursiveArd, exp_nonpos};
use super::wide::dispatch_wide;

/// Distinct inputs a pair table holds at most: its rows take 8·n² bytes (128 MiB here).
pub const MAX_PAIR_INPUTS: usize = 4096;

/// No further input of the same hash.
const END: u32 = u32::MAX;

/// The window id of a window not held (a read of its kernel values gives none).
pub(super) const NO_WINDOW: u32 = u32::MAX;

#[derive(Debug)]
pub struct PairDistances {
    dim: usize,
    /// The lengthscales the distances are scaled by.
    lengthscales: Vec<f64>,
    /// Distinct raw inputs (`dim` values each); input 0 is the all-zero padding lag.
    raw: Vec<f64>,
    /// Row length: the inputs rounded up to whole vectors.
    stride: usize,
    /// Squared distance of observed input a to stored input b at `rows[a * stride + b]`.
    rows: Vec<f64>,
    /// Each input's squared norm (its distance to a padding lag).
    norms: Vec<f64>,
    /// Hash of a raw input → the last input of that hash; `next` chains the others.
    lookup: HashMap<u64, u32, BuildHasherDefault<Prehashed>>,
    next: Vec<u32>,
    /// The unit kernel between the windows (None past [`MAX_PAIR_INPUTS`] windows).
    windows: Option<Windows>,
}

/// The distinct windows of the sequences and the unit kernel K_tau between every pair.
#[derive(Debug)]
struct Windows {
    tau: usize,
    /// 1/sigma_rho of the recursion, to the bit.
    inv_rho: f64,
    /// The inputs of window w, oldest first: `inputs[w * tau..(w + 1) * tau]`.
    inputs: Vec<u32>,
    /// Row length: the windows rounded up to whole vectors.
    stride: usize,
    /// K_tau of observed window a against BV window b at `k[a * stride + b]` (NaN past
    /// the windows).
    k: Vec<f64>,
    lookup: HashMap<u64, u32, BuildHasherDefault<Prehashed>>,
    next: Vec<u32>,
    len: usize,
}

impl PairDistances {
    /// The table of the distinct inputs of `steps` (each a run of inputs of `kernel`'s
    /// dimension) and the all-zero one, under `kernel`'s lengthscales. None when they are
    /// more than [`MAX_PAIR_INPUTS`].
    pub fn new<'a>(
        kernel: &RecursiveArd,
        steps: impl IntoIterator<Item = &'a [f64]>,
    ) -> Option<PairDistances> {
        let dim = kernel.dim();
        let mut p = PairDistances {
            dim,
            lengthscales: kernel.params().lengthscales.clone(),
            raw: Vec::new(),
            stride: 0,
            rows: Vec::new(),
            norms: Vec::new(),
            lookup: HashMap::default(),
            next: Vec::new(),
            windows: None,
        };
        p.insert(&vec![0.0; dim]);
        // Every sequence's inputs as ids, after tau padding inputs (id 0).
        let tau = kernel.tau();
        let mut padded: Vec<Vec<u32>> = Vec::new();
        for s in steps {
            let mut ids = vec![0; tau];
            for x in s.chunks_exact(dim) {
                let id = match p.id(x) {
                    Some(id) => id,
                    None if p.len() == MAX_PAIR_INPUTS => return None,
                    None => {
                        p.insert(x);
                        p.len() as u32 - 1
                    }
                };
                ids.push(id);
            }
            padded.push(ids);
        }
        let n = p.len();
        let mut data = LagMajor::new(dim, 1, n);
        let mut scaled = vec![0.0; n * dim];
        for (i, (x, s)) in p
            .raw
            .chunks_exact(dim)
            .zip(scaled.chunks_exact_mut(dim))
            .enumerate()
        {
            kernel.scale_into(x, s);
            data.set(i, s);
        }
        p.stride = data.stride();
        p.norms = (0..n).map(|i| data.norm(0, i)).collect();
        p.rows = vec![0.0; n * p.stride];
        p.fill_rows(&data, &scaled);
        p.windows = Windows::new(&p, &padded, tau, 1.0 / kernel.params().sigma_rho);
        Some(p)
    }

    fn insert(&mut self, x: &[f64]) {
        let id = self.len() as u32;
        let h = hash_bits(x);
        self.next.push(self.lookup.insert(h, id).unwrap_or(END));
        self.raw.extend_from_slice(x);
    }

    fn fill_rows(&mut self, data: &LagMajor, scaled: &[f64]) {
        dispatch_wide!(["avx512f", "avx2"] PairDistances::fill_rows_portable, (
            this: &mut PairDistances = self,
            data: &LagMajor = data,
            scaled: &[f64] = scaled,
        ))
    }

    #[inline(always)]
    fn fill_rows_portable(&mut self, data: &LagMajor, scaled: &[f64]) {
        let s = self.stride;
        for (x, row) in scaled
            .chunks_exact(self.dim)
            .zip(self.rows.chunks_exact_mut(s))
        {
            data.lag_sq_dist(0, x, s, row);
        }
    }

    /// Distinct inputs held.
    pub fn len(&self) -> usize {
        self.next.len()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Bytes of one input's row.
    pub fn row_bytes(&self) -> usize {
        self.stride * std::mem::size_of::<f64>()
    }

    /// Input dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// True if a model with `kernel` computes the distances held here: the same dimension
    /// and lengthscales to the bit (the other hyperparameters do not enter a distance).
    pub fn fits(&self, kernel: &RecursiveArd) -> bool {
        let l = &kernel.params().lengthscales;
        kernel.dim() == self.dim
            && l.len() == self.lengthscales.len()
            && l.iter()
                .zip(&self.lengthscales)
                .all(|(a, b)| a.to_bits() == b.to_bits())
    }

    /// The input with the bits of `x`, if held.
    #[inline]
    pub fn id(&self, x: &[f64]) -> Option<u32> {
        self.id_hashed(hash_bits(x), x)
    }

    /// [`PairDistances::id`] of `x` whose [`hash_bits`] is `h`.
    #[inline]
    pub(super) fn id_hashed(&self, h: u64, x: &[f64]) -> Option<u32> {
        let mut j = *self.lookup.get(&h)?;
        while j != END {
            let at = j as usize * self.dim;
            if same_bits(&self.raw[at..at + self.dim], x) {
                return Some(j);
            }
            j = self.next[j as usize];
        }
        None
    }

    /// The squared distances of input `a`, observed, to every input stored (one per input,
    /// then padding to the stride).
    #[inline(always)]
    pub(super) fn row(&self, a: u32) -> &[f64] {
        let at = a as usize * self.stride;
        &self.rows[at..at + self.stride]
    }

    /// Squared norm of input `j` (its distance to a padding lag).
    #[inline(always)]
    pub(super) fn norm(&self, j: u32) -> f64 {
        self.norms[j as usize]
    }

    /// The window whose inputs are `ids` (oldest first), if held for a recursion with
    /// 1/sigma_rho `inv_rho`; else [`NO_WINDOW`].
    pub(super) fn window(&self, ids: &[u32], inv_rho: f64) -> u32 {
        match &self.windows {
            Some(w) if w.fits(ids.len(), inv_rho) => w.find(ids).unwrap_or(NO_WINDOW),
            _ => NO_WINDOW,
        }
    }

    /// K_tau of observed window `a` against every window held (those past them NaN);
    /// None if `a` is not held.
    #[inline(always)]
    pub(super) fn window_row(&self, a: u32) -> Option<&[f64]> {
        let w = self.windows.as_ref()?;
        let a = a as usize;
        (a < w.len).then(|| &w.k[a * w.stride..(a + 1) * w.stride])
    }
}

impl Windows {
    /// The distinct windows of the `padded` input ids (tau padding ids, then a sequence's)
    /// and their unit kernel under recursion divisor 1/`inv_rho`, the distances read from
    /// `p`; None past [`MAX_PAIR_INPUTS`] windows.
    fn new(p: &PairDistances, padded: &[Vec<u32>], tau: usize, inv_rho: f64) -> Option<Windows> {
        let mut w = Windows {
            tau,
            inv_rho,
            inputs: Vec::new(),
            stride: 0,
            k: Vec::new(),
            lookup: HashMap::default(),
            next: Vec::new(),
            len: 0,
        };
        for ids in padded {
            for win in ids.windows(tau) {
                if w.find(win).is_none() {
                    if w.len == MAX_PAIR_INPUTS {
                        return None;
                    }
                    let h = hash_ids(win);
                    w.next.push(w.lookup.insert(h, w.len as u32).unwrap_or(END));
                    w.inputs.extend_from_slice(win);
                    w.len += 1;
                }
            }
        }
        w.stride = w.len.div_ceil(LANES) * LANES;
        // Lag-major for the rows' recursion over every window at once.
        let mut lag_major = vec![0; tau * w.stride];
        for (b, win) in w.inputs.chunks_exact(tau).enumerate() {
            for (l, &id) in win.iter().enumerate() {
                lag_major[l * w.stride + b] = id;
            }
        }
        w.k = vec![f64::NAN; w.len * w.stride];
        let stride = w.stride;
        w.k.par_chunks_mut(stride)
            .enumerate()
            .for_each(|(a, row)| fill_window_row(p, &lag_major, stride, tau, inv_rho, a, row));
        for row in w.k.chunks_exact_mut(stride) {
            row[w.len..].fill(f64::NAN);
        }
        Some(w)
    }

    fn fits(&self, tau: usize, inv_rho: f64) -> bool {
        tau == self.tau && inv_rho.to_bits() == self.inv_rho.to_bits()
    }

    fn find(&self, win: &[u32]) -> Option<u32> {
        let mut j = *self.lookup.get(&hash_ids(win))?;
        while j != END {
            let at = j as usize * self.tau;
            if self.inputs[at..at + self.tau] == *win {
                return Some(j);
            }
            j = self.next[j as usize];
        }
        None
    }
}

/// Hash of a window's input ids (FxHash's mix).
fn hash_ids(ids: &[u32]) -> u64 {
    const K: u64 = 0x51_7c_c1_b7_27_22_0a_95;
    ids.iter().fold(0u64, |h, &v| {
        (h.rotate_left(5) ^ u64::from(v)).wrapping_mul(K)
    })
}

/// Row `a` of the window kernel: the recursion over the lags against every window at
/// once, each lag's distances read from the pair table.
fn fill_window_row(
    p: &PairDistances,
    ids: &[u32],
    stride: usize,
    tau: usize,
    inv_rho: f64,
    a: usize,
    row: &mut [f64],
) {
    dispatch_wide!(["avx512f", "avx2"] fill_window_row_portable, (
        p: &PairDistances = p,
        ids: &[u32] = ids,
        stride: usize = stride,
        tau: usize = tau,
        inv_rho: f64 = inv_rho,
        a: usize = a,
        row: &mut [f64] = row,
    ))
}

#[inline(always)]
fn fill_window_row_portable(
    p: &PairDistances,
    ids: &[u32],
    stride: usize,
    tau: usize,
    inv_rho: f64,
    a: usize,
    row: &mut [f64],
) {
    row.fill(1.0);
    for l in 0..tau {
        let d = p.row(ids[l * stride + a]);
        for (k, &b) in row.iter_mut().zip(&ids[l * stride..(l + 1) * stride]) {
            let r = d.get(b as usize).copied().unwrap_or(f64::NAN);
            *k = exp_nonpos(-0.5 * r + (*k - 1.0) * inv_rho);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gp::KernelParams;
    use crate::gp::kernel::sq_dist;

    fn kernel(dim: usize, scale: f64) -> RecursiveArd {
        let params = KernelParams {
            lengthscales: (0..dim).map(|k| scale + 0.1 * k as f64).collect(),
            sigma_rho: 1.5,
            sigma_f: 1.0,
            sigma_n: 0.1,
        };
        RecursiveArd::new(dim, 3, params).unwrap()
    }

    /// Inputs of two sequences: 13 values each (three whole vectors of four and a tail,
    /// so both the vector sums and the tail are checked), one input repeated, one zero.
    fn sequences(dim: usize) -> Vec<Vec<f64>> {
        let v = |s: usize| -> Vec<f64> {
            (0..dim)
                .map(|k| ((s * 31 + k * 7) % 17) as f64 * 0.37 - 2.5)
                .collect()
        };
        let a: Vec<f64> = [v(1), v(2), vec![0.0; dim], v(3)].concat();
        let b: Vec<f64> = [v(4), v(2), v(5)].concat();
        vec![a, b]
    }

    /// Every entry is the direct distance of the scaled pair (observed input first), to
    /// the bit; each input is found by its bits (equal inputs once, the zero first), and
    /// an input not held is not found.
    #[test]
    fn every_pair_is_the_direct_distance_of_the_scaled_inputs() {
        let dim = 13;
        let k = kernel(dim, 0.7);
        let seqs = sequences(dim);
        let p = PairDistances::new(&k, seqs.iter().map(|s| &s[..])).unwrap();
        assert_eq!(p.len(), 6, "the zero and five distinct inputs");
        assert_eq!(p.id(&vec![0.0; dim]), Some(0));
        let inputs: Vec<&[f64]> = seqs.iter().flat_map(|s| s.chunks_exact(dim)).collect();
        let scale = |x: &[f64]| {
            let mut s = vec![0.0; dim];
            k.scale_into(x, &mut s);
            s
        };
        for a in &inputs {
            let ia = p.id(a).unwrap();
            assert_eq!(p.raw[ia as usize * dim..][..dim], **a);
            let row = p.row(ia);
            for b in &inputs {
                let ib = p.id(b).unwrap() as usize;
                let direct = sq_dist(&scale(a), &scale(b));
                assert_eq!(row[ib].to_bits(), direct.to_bits(), "{ia} to {ib}");
            }
            let norm = sq_dist(&vec![0.0; dim], &scale(a));
            assert_eq!(p.norm(ia).to_bits(), norm.to_bits());
        }
        let mut other = inputs[0].to_vec();
        other[5] += 1e-12;
        assert_eq!(p.id(&other), None);
        // -0 is another input (its bits differ), though at distance 0 from +0.
        let mut neg = vec![0.0; dim];
        neg[0] = -0.0;
        assert_eq!(p.id(&neg), None);
    }

    /// Every window of the sequences (three lags, padded at the start) is found by its
    /// inputs, and the window kernel's entry of each pair is the recursion evaluated
    /// directly on the scaled windows, to the bit; a window not in them, or another
    /// recursion divisor, is not found.
    #[test]
    fn every_pair_of_windows_is_the_direct_kernel_of_the_scaled_windows() {
        let dim = 5;
        let k = kernel(dim, 0.7);
        let inv_rho = 1.0 / k.params().sigma_rho;
        let seqs = sequences(dim);
        let p = PairDistances::new(&k, seqs.iter().map(|s| &s[..])).unwrap();
        let mut windows: Vec<Vec<f64>> = Vec::new();
        for s in &seqs {
            let padded = [vec![0.0; 3 * dim], s.clone()].concat();
            windows.extend(padded.windows(3 * dim).step_by(dim).map(|w| w.to_vec()));
        }
        let ids =
            |w: &[f64]| -> Vec<u32> { w.chunks_exact(dim).map(|x| p.id(x).unwrap()).collect() };
        let scaled = |w: &[f64]| {
            let mut s = vec![0.0; w.len()];
            k.scale_into(w, &mut s);
            s
        };
        for a in &windows {
            let wa = p.window(&ids(a), inv_rho);
            let row = p.window_row(wa).unwrap();
            for b in &windows {
                let wb = p.window(&ids(b), inv_rho) as usize;
                let direct = k.unit_scaled(&scaled(a), &scaled(b));
                assert_eq!(row[wb].to_bits(), direct.to_bits(), "{wa} against {wb}");
            }
        }
        let held = ids(&windows[4]);
        assert_ne!(p.window(&held, inv_rho), NO_WINDOW);
        let reversed: Vec<u32> = held.iter().rev().copied().collect();
        assert_eq!(p.window(&reversed, inv_rho), NO_WINDOW);
        assert_eq!(p.window(&held, 0.5 * inv_rho), NO_WINDOW);
        assert!(p.window_row(NO_WINDOW).is_none());
    }

    /// The lengthscales decide whether a model reads the table; more distinct inputs
    /// than the bound give no table.
    #[test]
    fn a_table_serves_its_lengthscales_and_holds_a_bounded_number_of_inputs() {
        let dim = 4;
        let seqs = sequences(dim);
        let p = PairDistances::new(&kernel(dim, 0.7), seqs.iter().map(|s| &s[..])).unwrap();
        assert!(p.fits(&kernel(dim, 0.7)));
        assert!(!p.fits(&kernel(dim, 0.8)));
        assert!(!p.fits(&kernel(dim + 1, 0.7)));
        let many: Vec<f64> = (0..MAX_PAIR_INPUTS * dim).map(|i| i as f64).collect();
        assert!(PairDistances::new(&kernel(dim, 0.7), [&many[..]]).is_none());
    }
}
