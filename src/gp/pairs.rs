//! The squared distances between every pair of a session's distinct inputs under one
//! kernel's lengthscales, computed once and read by every model with those lengthscales.
//!
//! A model's own distance table computes, at each step, the new input's distances to the
//! inputs its BVs hold. When every window is made of a known session's inputs (a clustering
//! sweep learns and re-assigns the same grasps under many thresholds and orders), each of
//! those distances is an entry of the session's pair table, and a model looks its rows up
//! instead. The entries come from the function that computes a table's rows
//! ([`LagMajor::lag_sq_dist`], the observed input against the stored one), so every kernel
//! value is bit-identical.

use std::collections::HashMap;
use std::hash::BuildHasherDefault;

use super::bits::{Prehashed, hash_bits, same_bits};
use super::kernel::{LagMajor, RecursiveArd};
use super::wide::dispatch_wide;

/// Distinct inputs a pair table holds at most: its rows take 8·n² bytes (128 MiB here).
pub const MAX_PAIR_INPUTS: usize = 4096;

/// No further input of the same hash.
const END: u32 = u32::MAX;

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
        };
        p.insert(&vec![0.0; dim]);
        for s in steps {
            for x in s.chunks_exact(dim) {
                if p.id(x).is_none() {
                    if p.len() == MAX_PAIR_INPUTS {
                        return None;
                    }
                    p.insert(x);
                }
            }
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
