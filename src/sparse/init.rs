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
        // A 12 × 12 one (a rotation angle that does not annihilate its entry still converges
        // on 3 × 3 matrices), the small one at 1e-20 (the stopping test is relative), and one
        // with a zero entry between equal diagonal entries (0/0 in the rotation angle).
        let c = Array2::from_shape_fn((14, 12), |_| rng.normal());
        let larger = c.t().dot(&c);
        let tiny = &small * 1e-20;
        let zero_entry = array![[2.0, 0.0, 1.0], [0.0, 2.0, 1.0], [1.0, 1.0, 3.0]];
        for a in [small, large, larger, tiny, zero_entry] {
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

    /// Four patches X = Z Q: Z has orthogonal columns of norms (1, 3, σ₃) and Q is the
    /// rotation with rows q₁ = (0.6, 0.8, 0), q₂ = (−0.8, 0.6, 0), q₃ = (0, 0, 1), so XᵀX =
    /// Qᵀ diag(1, 9, σ₃²) Q has the eigenvectors q_i.
    fn rotated_patches(sigma3: f64) -> Array2<f64> {
        let z = array![
            [1.0, 1.0, 1.0],
            [1.0, -1.0, 1.0],
            [1.0, 1.0, -1.0],
            [1.0, -1.0, -1.0]
        ];
        let z = &z * &array![[0.5, 1.5, 0.5 * sigma3]];
        let q = array![[0.6, 0.8, 0.0], [-0.8, 0.6, 0.0], [0.0, 0.0, 1.0]];
        z.dot(&q)
    }

    fn assert_rows(d: &Array2<f64>, want: &[[f64; 3]]) {
        for (j, w) in want.iter().enumerate() {
            for (t, &v) in w.iter().enumerate() {
                assert!(
                    (d[[j, t]] - v).abs() < 1e-10,
                    "atom {j}: {}, want {w:?}",
                    d.row(j)
                );
            }
        }
    }

    #[test]
    fn svd_atoms_are_the_principal_directions_largest_first_with_a_positive_largest_entry() {
        // σ₃ = 2: the eigenvalues 9, 4, 1 order the atoms q₂, q₃, q₁, q₂ with its sign
        // flipped (its largest entry is −0.8). Every atom has norm √c.
        let c: f64 = 2.0;
        let want =
            [[0.8, -0.6, 0.0], [0.0, 0.0, 1.0], [0.6, 0.8, 0.0]].map(|r| r.map(|v| v * c.sqrt()));
        let x = rotated_patches(2.0);
        for k in [2, 3] {
            let d = initial_dictionary(DictInit::Svd, x.view(), k, c, 1);
            assert_eq!(d.dim(), (k, 3));
            assert_rows(&d, &want[..k]);
        }
        // σ₃ = 0 and patches of norm about 1e-4: rank 2 (the rank test is relative to the
        // largest eigenvalue, here 9e-8): the atoms are q₂ and q₁ (eigenvalues 9e-8 and
        // 1e-8), then not the null direction q₃ but patches, as beyond the dimension.
        let x = rotated_patches(0.0) * 1e-4;
        for k in [3, 5] {
            let d = initial_dictionary(DictInit::Svd, x.view(), k, c, 1);
            assert_rows(&d, &[want[0], want[2]]);
            for j in 2..k {
                assert!(
                    scaled_patch(d.row(j), &x, c).is_some(),
                    "atom {j}: {}",
                    d.row(j)
                );
            }
        }
        // Integer patches (XᵀX exact) whose eigenvectors from the rotations include two
        // with a negative largest entry: each atom / √c is a unit eigenvector of XᵀX, their
        // eigenvalues (Rayleigh quotients) decrease, and each largest entry is positive.
        let x = array![
            [3.0, 3.0, 2.0, 2.0],
            [1.0, -1.0, -2.0, 0.0],
            [-1.0, 0.0, -2.0, 3.0],
            [-2.0, -3.0, -1.0, -1.0],
            [-3.0, 0.0, -2.0, 0.0],
            [-3.0, 1.0, 1.0, 0.0]
        ];
        let xtx = x.t().dot(&x);
        let d = initial_dictionary(DictInit::Svd, x.view(), 4, c, 1);
        let mut last = f64::INFINITY;
        for row in d.rows() {
            let v = &row / c.sqrt();
            let q = v.dot(&xtx.dot(&v));
            assert!(
                (&xtx.dot(&v) - &(&v * q)).iter().all(|e| e.abs() < 1e-9),
                "{v}"
            );
            assert!(q < last, "eigenvalue {q} after {last}");
            last = q;
            let big = v
                .iter()
                .fold(0.0f64, |m, &e| if e.abs() > m.abs() { e } else { m });
            assert!(big > 0.0, "{v}");
        }
    }

    /// The row of `x` that `atom` is, scaled to norm √c.
    fn scaled_patch(atom: ndarray::ArrayView1<f64>, x: &Array2<f64>, c: f64) -> Option<usize> {
        x.rows().into_iter().position(|r| {
            let n = r.dot(&r).sqrt();
            n > 0.0
                && r.iter()
                    .zip(atom)
                    .all(|(a, b)| (a * c.sqrt() / n - b).abs() < 1e-12)
        })
    }

    #[test]
    fn random_atoms_are_zero_mean_with_norm_sqrt_c() {
        let x = rotated_patches(2.0);
        let d = initial_dictionary(DictInit::Random, x.view(), 6, 3.0, 4);
        for row in d.rows() {
            assert!(row.sum().abs() < 1e-12, "{row}");
            assert!((row.dot(&row) - 3.0).abs() < 1e-12, "{row}");
        }
        assert_ne!(d.row(0), d.row(1));
    }

    #[test]
    fn patch_atoms_are_distinct_non_zero_patches_drawn_by_squared_norm() {
        // Five patches, two of them zero: three atoms are the three others, each once.
        let x = array![
            [0.0, 0.0, 0.0],
            [1.0, 2.0, 2.0],
            [0.0, 0.0, 0.0],
            [4.0, 0.0, 3.0],
            [0.0, -1.0, 0.0]
        ];
        for seed in 0..20 {
            let d = initial_dictionary(DictInit::Patches, x.view(), 3, 1.0, seed);
            let mut picked: Vec<usize> = d
                .rows()
                .into_iter()
                .map(|a| scaled_patch(a, &x, 1.0).expect("an atom that is no patch"))
                .collect();
            picked.sort();
            assert_eq!(picked, vec![1, 3, 4], "seed {seed}");
        }
        // One atom from patches of squared norms 1 and 99: the second is drawn with
        // probability 0.99, so in 200 seeds at least 180 times (the binomial's mean is 198,
        // its sd 1.4); a uniform draw would give about 100.
        let x = array![[1.0, 0.0, 0.0], [0.0, 0.0, 99f64.sqrt()]];
        let heavy = (0..200)
            .filter(|&seed| {
                initial_dictionary(DictInit::Patches, x.view(), 1, 1.0, seed)[[0, 2]] > 0.5
            })
            .count();
        assert!(heavy >= 180, "{heavy} of 200");
        // No patch with any energy: the atoms are seeded random directions of norm √c.
        let zero = Array2::<f64>::zeros((4, 3));
        let d = initial_dictionary(DictInit::Patches, zero.view(), 2, 2.0, 5);
        for row in d.rows() {
            assert!((row.dot(&row) - 2.0).abs() < 1e-12, "{row}");
        }
        assert_ne!(d.row(0), d.row(1));
    }

    #[test]
    fn normalising_gives_norm_sqrt_c_and_a_random_direction_to_a_zero_or_nan_row() {
        let mut d = array![[3.0, 4.0, 0.0], [0.0, 0.0, 0.0], [f64::NAN, 1.0, 0.0]];
        normalise_rows(&mut d, 4.0, &mut Rng::new(3));
        assert!(
            (&d.row(0) - &ndarray::arr1(&[1.2, 1.6, 0.0]))
                .iter()
                .all(|v| v.abs() < 1e-15)
        );
        for row in d.rows() {
            assert!((row.dot(&row) - 4.0).abs() < 1e-12, "{row}");
        }
    }
}
