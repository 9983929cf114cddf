//! Seeded dictionary initialisation.
//!
//! The starting dictionary decides which local minimum alternating minimisation reaches
//! (SPARSE-NOTES: a data/SVD start ends lower than a random one), so it is a parameter.

use ndarray::{Array2, ArrayView2};
use serde::{Deserialize, Serialize};

use crate::rng::Rng;

/// How the first dictionary is chosen. Every atom is scaled to norm sqrt(c).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum DictInit {
    /// The reference code's start: uniform(−0.5, 0.5) entries, each atom made zero-mean.
    Random,
    /// K distinct patches drawn at random (seeded), the largest-norm ones preferred
    /// (drawn with probability ∝ ||x||², k-means++ style without the distance update).
    Patches,
    /// The principal directions of the patches (right singular vectors of X, largest
    /// first, sign fixed so the largest-magnitude entry is positive); when K exceeds the
    /// patch dimension the remaining atoms are seeded patches as in `Patches`.
    #[default]
    Svd,
}

/// The initial dictionary (K × n) for patches `x` (N × n).
pub fn initial_dictionary(
    init: DictInit,
    x: ArrayView2<f64>,
    k: usize,
    c: f64,
    seed: u64,
) -> Array2<f64> {
    let (_, n) = x.dim();
    let mut rng = Rng::stream(seed, 0x1D1C);
    let mut d = Array2::<f64>::zeros((k, n));
    match init {
        DictInit::Random => {
            for j in 0..k {
                let mut row: Vec<f64> = (0..n).map(|_| rng.uniform() - 0.5).collect();
                let mean = row.iter().sum::<f64>() / n as f64;
                row.iter_mut().for_each(|v| *v -= mean);
                d.row_mut(j).assign(&ndarray::ArrayView1::from(&row));
            }
        }
        DictInit::Patches => {
            fill_with_patches(&mut d, 0, x, &mut rng);
        }
        DictInit::Svd => {
            let xtx = x.t().dot(&x);
            let (vals, vecs) = symmetric_eigen(xtx.view());
            let mut order: Vec<usize> = (0..n).collect();
            order.sort_by(|&a, &b| vals[b].total_cmp(&vals[a]));
            let rank = order
                .iter()
                .take_while(|&&i| vals[i] > 1e-12 * vals[order[0]].max(1e-300))
                .count();
            let m = k.min(rank);
            for (j, &i) in order.iter().take(m).enumerate() {
                let mut v: Vec<f64> = (0..n).map(|r| vecs[[r, i]]).collect();
                let big = v
                    .iter()
                    .copied()
                    .fold(0.0f64, |a, b| if b.abs() > a.abs() { b } else { a });
                if big < 0.0 {
                    v.iter_mut().for_each(|e| *e = -*e);
                }
                d.row_mut(j).assign(&ndarray::ArrayView1::from(&v));
            }
            fill_with_patches(&mut d, m, x, &mut rng);
        }
    }
    normalise_rows(&mut d, c, &mut rng);
    d
}

/// Rows `from..` of `d` become distinct patches drawn with probability ∝ ||x||².
fn fill_with_patches(d: &mut Array2<f64>, from: usize, x: ArrayView2<f64>, rng: &mut Rng) {
    let k = d.nrows();
    if from >= k {
        return;
    }
    let mut w: Vec<f64> = x.rows().into_iter().map(|r| r.dot(&r)).collect();
    for j in from..k {
        let total: f64 = w.iter().sum();
        let pick = if total > 0.0 {
            let mut u = rng.uniform() * total;
            let mut idx = w.len() - 1;
            for (i, &wi) in w.iter().enumerate() {
                if u < wi {
                    idx = i;
                    break;
                }
                u -= wi;
            }
            Some(idx)
        } else {
            None
        };
        match pick {
            Some(i) => {
                d.row_mut(j).assign(&x.row(i));
                w[i] = 0.0;
            }
            None => {
                for v in d.row_mut(j).iter_mut() {
                    *v = rng.normal();
                }
            }
        }
    }
}

/// Scale every row to norm sqrt(c) (a zero row becomes a seeded random direction).
pub(crate) fn normalise_rows(d: &mut Array2<f64>, c: f64, rng: &mut Rng) {
    for mut row in d.rows_mut() {
        let mut nrm = row.dot(&row).sqrt();
        if nrm.is_nan() || nrm <= 1e-300 {
            for v in row.iter_mut() {
                *v = rng.normal();
            }
            nrm = row.dot(&row).sqrt();
        }
        row.mapv_inplace(|v| v * c.sqrt() / nrm);
    }
}

/// Eigen-decomposition of a small symmetric matrix by cyclic Jacobi rotations:
/// (eigenvalues, eigenvectors as columns).
pub(crate) fn symmetric_eigen(a: ArrayView2<f64>) -> (Vec<f64>, Array2<f64>) {
    let n = a.nrows();
    let mut m = a.to_owned();
    let mut v = Array2::<f64>::eye(n);
    for _sweep in 0..100 {
        let mut off = 0.0;
        for p in 0..n {
            for q in p + 1..n {
                off += m[[p, q]] * m[[p, q]];
            }
        }
        let scale: f64 = (0..n).map(|i| m[[i, i]] * m[[i, i]]).sum::<f64>();
        if off <= 1e-30 * scale.max(1e-300) {
            break;
        }
        for p in 0..n {
            for q in p + 1..n {
                let apq = m[[p, q]];
                if apq.abs() < 1e-300 {
                    continue;
                }
                let theta = (m[[q, q]] - m[[p, p]]) / (2.0 * apq);
                let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
                let t = if theta == 0.0 { 1.0 } else { t };
                let cs = 1.0 / (t * t + 1.0).sqrt();
                let sn = t * cs;
                for r in 0..n {
                    let mrp = m[[r, p]];
                    let mrq = m[[r, q]];
                    m[[r, p]] = cs * mrp - sn * mrq;
                    m[[r, q]] = sn * mrp + cs * mrq;
                }
                for r in 0..n {
                    let mpr = m[[p, r]];
                    let mqr = m[[q, r]];
                    m[[p, r]] = cs * mpr - sn * mqr;
                    m[[q, r]] = sn * mpr + cs * mqr;
                }
                for r in 0..n {
                    let vrp = v[[r, p]];
                    let vrq = v[[r, q]];
                    v[[r, p]] = cs * vrp - sn * vrq;
                    v[[r, q]] = sn * vrp + cs * vrq;
                }
            }
        }
    }
    ((0..n).map(|i| m[[i, i]]).collect(), v)
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    /// A v = λ v alone holds for zero vectors too: the eigenvectors must also be
    /// orthonormal (Vᵀ V = I) and the eigenvalues must sum to the trace and multiply to the
    /// determinant (invariants of any similarity transform).
    #[test]
    fn jacobi_diagonalises() {
        let small = array![[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]];
        // A larger one with a repeated eigenvalue: B Bᵀ of a 6 × 4 B has rank 4, so 0 twice.
        let mut rng = Rng::new(7);
        let b = Array2::from_shape_fn((6, 4), |_| rng.normal());
        let large = b.dot(&b.t());
        for a in [small, large] {
            let n = a.nrows();
            let (vals, vecs) = symmetric_eigen(a.view());
            let scale = a.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            for (i, &val) in vals.iter().enumerate() {
                let v = vecs.column(i);
                let av = a.dot(&v);
                for r in 0..n {
                    assert!((av[r] - val * v[r]).abs() < 1e-10 * scale);
                }
            }
            let vtv = vecs.t().dot(&vecs);
            for i in 0..n {
                for j in 0..n {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((vtv[[i, j]] - want).abs() < 1e-12, "VᵀV[{i}][{j}]");
                }
            }
            let trace: f64 = (0..n).map(|i| a[[i, i]]).sum();
            assert!((vals.iter().sum::<f64>() - trace).abs() < 1e-10 * scale);
            // V diag(λ) Vᵀ rebuilds A.
            let rebuilt = vecs.dot(&Array2::from_diag(&ndarray::Array1::from(vals.clone())));
            let rebuilt = rebuilt.dot(&vecs.t());
            for (x, y) in rebuilt.iter().zip(a.iter()) {
                assert!((x - y).abs() < 1e-10 * scale);
            }
        }
        // The 3 × 3 one's determinant, by cofactors: 4(3 − 0.04) − 1(1 − 0.1) + 0.5(0.2 − 1.5).
        let (vals, _) =
            symmetric_eigen(array![[4.0, 1.0, 0.5], [1.0, 3.0, 0.2], [0.5, 0.2, 1.0]].view());
        let det = 4.0 * (3.0 - 0.04) - (1.0 - 0.1) + 0.5 * (0.2 - 1.5);
        assert!((vals.iter().product::<f64>() - det).abs() < 1e-12);
    }
}
