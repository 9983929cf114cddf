//! Small dense kernels on row-major slices, shared by the solvers (no bounds-checked
//! indexing in the inner loops).

/// Relative pivot below which a matrix counts as singular.
const PIVOT_TOL: f64 = 1e-10;

/// Dot product with four accumulators (lets the compiler vectorise).
#[inline]
pub fn dot(a: &[f64], b: &[f64]) -> f64 {
    let n = a.len().min(b.len());
    let (a, b) = (&a[..n], &b[..n]);
    let mut acc = [0.0f64; 4];
    let ca = a.chunks_exact(4);
    let cb = b.chunks_exact(4);
    let (ra, rb) = (ca.remainder(), cb.remainder());
    for (x, y) in ca.zip(cb) {
        acc[0] += x[0] * y[0];
        acc[1] += x[1] * y[1];
        acc[2] += x[2] * y[2];
        acc[3] += x[3] * y[3];
    }
    let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
    for (x, y) in ra.iter().zip(rb) {
        s += x * y;
    }
    s
}

/// Cholesky factor of the s × s matrix `a` (row-major, stride s; only its lower triangle
/// is read) into `l` (lower triangle, stride s). `Err(r)` when the pivot at row r is not positive enough
/// (relative to the diagonal); rows before r are then valid.
///
/// Row by row as [`chol_append`] computes each row, but four rows at a time: their entries
/// left of the four are independent of one another, so the four dot products (and
/// divisions) at each column run side by side instead of one after the other. Every entry
/// is the same sum in the same order, so the factor is that of [`chol_append`] to the bit.
pub fn cholesky(s: usize, a: &[f64], l: &mut [f64]) -> Result<(), usize> {
    let mut i = 0;
    while i + ROWS <= s {
        let (done, rest) = l.split_at_mut(i * s);
        for j in 0..i {
            let lj = &done[j * s..j * s + j + 1];
            let sums = dot_rows(std::array::from_fn(|m| &rest[m * s..m * s + j]), &lj[..j]);
            for (m, sum) in sums.iter().enumerate() {
                rest[m * s + j] = (a[(i + m) * s + j] - sum) / lj[j];
            }
        }
        for r in i..i + ROWS {
            if !chol_row_from(r, s, l, &a[r * s..r * s + r + 1], i) {
                return Err(r);
            }
        }
        i += ROWS;
    }
    for r in i..s {
        if !chol_append(r, s, l, &a[r * s..r * s + r + 1]) {
            return Err(r);
        }
    }
    Ok(())
}

/// Rows of a block of [`cholesky`].
pub const ROWS: usize = 4;

/// [`dot`] of each of four rows with `y` (as long as `y`), each summed exactly as [`dot`]
/// sums it.
#[inline]
pub fn dot_rows(x: [&[f64]; ROWS], y: &[f64]) -> [f64; ROWS] {
    let n = y.len();
    let x = x.map(|r| &r[..n]);
    let whole = n / 4 * 4;
    let acc = accumulate_rows(&x, y, whole);
    let mut out = [0.0; ROWS];
    for ((out, acc), x) in out.iter_mut().zip(&acc).zip(&x) {
        let mut s = (acc[0] + acc[1]) + (acc[2] + acc[3]);
        for (xt, yt) in x[whole..].iter().zip(&y[whole..]) {
            s += xt * yt;
        }
        *out = s;
    }
    out
}

/// The four accumulators of [`dot`] for each row over the first `whole` columns (a
/// multiple of 4; every row and `y` at least that long).
#[cfg(target_arch = "x86_64")]
#[inline]
fn accumulate_rows(x: &[&[f64]; ROWS], y: &[f64], whole: usize) -> [[f64; 4]; ROWS] {
    use std::arch::x86_64::{
        __m128d, _mm_add_pd, _mm_loadu_pd, _mm_mul_pd, _mm_setzero_pd, _mm_storeu_pd,
    };
    assert!(y.len() >= whole && x.iter().all(|r| r.len() >= whole));
    // Written out in SSE2 (part of every x86-64): one register per row holds accumulators
    // 0 and 1 and another 2 and 3, as [`dot`] pairs them. Left to itself the compiler
    // vectorises across the rows and spends its time shuffling.
    // SAFETY: SSE2 is enabled on every x86-64 target.
    let zero = unsafe { _mm_setzero_pd() };
    let (mut lo, mut hi): ([__m128d; ROWS], [__m128d; ROWS]) = ([zero; ROWS], [zero; ROWS]);
    for c in (0..whole).step_by(4) {
        // SAFETY: c + 4 ≤ whole, within `y` and every row (asserted above).
        unsafe {
            let (ylo, yhi) = (
                _mm_loadu_pd(y.as_ptr().add(c)),
                _mm_loadu_pd(y.as_ptr().add(c + 2)),
            );
            for r in 0..ROWS {
                let p = x[r].as_ptr().add(c);
                lo[r] = _mm_add_pd(lo[r], _mm_mul_pd(_mm_loadu_pd(p), ylo));
                hi[r] = _mm_add_pd(hi[r], _mm_mul_pd(_mm_loadu_pd(p.add(2)), yhi));
            }
        }
    }
    let mut acc = [[0.0f64; 4]; ROWS];
    for r in 0..ROWS {
        // SAFETY: each store writes two values into a four-value array.
        unsafe {
            _mm_storeu_pd(acc[r].as_mut_ptr(), lo[r]);
            _mm_storeu_pd(acc[r].as_mut_ptr().add(2), hi[r]);
        }
    }
    acc
}

#[cfg(not(target_arch = "x86_64"))]
#[inline]
fn accumulate_rows(x: &[&[f64]; ROWS], y: &[f64], whole: usize) -> [[f64; 4]; ROWS] {
    let mut acc = [[0.0f64; 4]; ROWS];
    for c in (0..whole).step_by(4) {
        let yb = &y[c..c + 4];
        for (acc, x) in acc.iter_mut().zip(x) {
            let xb = &x[c..c + 4];
            for q in 0..4 {
                acc[q] += xb[q] * yb[q];
            }
        }
    }
    acc
}

/// Grow the factor of the leading n × n block (row stride `stride`) by one row and column:
/// `a_row` holds the new row of the matrix up to and with its diagonal (n + 1 values), and
/// row n of L is one forward substitution against the rows above. This is exactly row n of
/// [`cholesky`] (the same operations in the same order). False when the new pivot is not
/// positive enough relative to its diagonal entry (row n is then not valid).
pub fn chol_append(n: usize, stride: usize, l: &mut [f64], a_row: &[f64]) -> bool {
    chol_row_from(n, stride, l, a_row, 0)
}

/// [`chol_append`] with the entries of row n left of column `from` already in place.
fn chol_row_from(n: usize, stride: usize, l: &mut [f64], a_row: &[f64], from: usize) -> bool {
    let (done, rest) = l.split_at_mut(n * stride);
    let li = &mut rest[..n + 1];
    for j in from..n {
        let lj = &done[j * stride..j * stride + j + 1];
        let sum = a_row[j] - dot(&li[..j], &lj[..j]);
        li[j] = sum / lj[j];
    }
    let sum = a_row[n] - dot(&li[..n], &li[..n]);
    // (NaN fails the first test.)
    if sum.is_nan() || sum <= PIVOT_TOL * a_row[n] || sum.is_infinite() {
        return false;
    }
    li[n] = sum.sqrt();
    true
}

/// Remove row and column p from the factor of the leading n × n block (row stride
/// `stride`), leaving the factor of the matrix without them in the leading (n − 1) ×
/// (n − 1) block. Rows before p do not change. Each later row moves up one and loses its
/// entry in column p, x; the trailing block must then factor `L₃₃ L₃₃ᵀ + x xᵀ`, which
/// Givens rotations of the columns of [L₃₃ x] give (one rotation per column, zeroing x's
/// entry against the diagonal: O((n − p)²), against O(n³) for a new factor). `rot` is
/// scratch of at least 2 (n − 1 − p) values.
///
/// An update only increases the trailing pivots, so in exact arithmetic every pivot
/// passes the test of [`cholesky`] again; false when one does not (rounding, or a factor
/// that was not that of a positive definite matrix): rows from p on are then not valid
/// and must be refactorised.
pub fn chol_delete(n: usize, stride: usize, l: &mut [f64], p: usize, rot: &mut [f64]) -> bool {
    // Row by row (contiguous in memory): new row t is old row t + 1 without column p,
    // with the rotations of the columns before it applied, then its own rotation.
    let (cs, sn) = rot[..2 * (n - 1 - p)].split_at_mut(n - 1 - p);
    for t in p..n - 1 {
        let (head, tail) = l.split_at_mut((t + 1) * stride);
        let new = &mut head[t * stride..t * stride + t + 1];
        let old = &tail[..t + 2];
        new[..p].copy_from_slice(&old[..p]);
        let mut x = old[p];
        for j in p..t {
            let (c, s, v) = (cs[j - p], sn[j - p], old[j + 1]);
            new[j] = c * v + s * x;
            x = c * x - s * v;
        }
        let d = old[t + 1];
        let r = (d * d + x * x).sqrt();
        let a_tt = dot(&new[..t], &new[..t]) + r * r;
        // (NaN anywhere in the row makes a_tt NaN and fails the first test.)
        if !a_tt.is_finite() || r * r <= PIVOT_TOL * a_tt {
            return false;
        }
        cs[t - p] = d / r;
        sn[t - p] = x / r;
        new[t] = r;
    }
    true
}

/// Solve L Lᵀ x = b for the leading r × r block of a factor stored with row stride
/// `stride` (as written by [`cholesky`] with s = stride; rows before a failed pivot are valid).
pub fn chol_solve(r: usize, stride: usize, l: &[f64], b: &[f64], x: &mut [f64]) {
    for i in 0..r {
        let row = &l[i * stride..i * stride + i + 1];
        x[i] = (b[i] - dot(&row[..i], &x[..i])) / row[i];
    }
    for i in (0..r).rev() {
        let mut s = x[i];
        for m in i + 1..r {
            s -= l[m * stride + i] * x[m];
        }
        x[i] = s / l[i * stride + i];
    }
}

/// Solve L Lᵀ X = B in place for the r × m matrix B (row-major, stride m), with the factor
/// from [`cholesky`] (stride r): row operations only, so the inner loops are contiguous.
pub fn chol_solve_rows(r: usize, l: &[f64], b: &mut [f64], m: usize) {
    for i in 0..r {
        let (done, rest) = b.split_at_mut(i * m);
        let bi = &mut rest[..m];
        for q in 0..i {
            let f = l[i * r + q];
            if f != 0.0 {
                for (x, y) in bi.iter_mut().zip(&done[q * m..(q + 1) * m]) {
                    *x -= f * y;
                }
            }
        }
        let inv = 1.0 / l[i * r + i];
        bi.iter_mut().for_each(|x| *x *= inv);
    }
    for i in (0..r).rev() {
        let (head, tail) = b.split_at_mut((i + 1) * m);
        let bi = &mut head[i * m..];
        for q in i + 1..r {
            let f = l[q * r + i];
            if f != 0.0 {
                for (x, y) in bi.iter_mut().zip(&tail[(q - i - 1) * m..(q - i) * m]) {
                    *x -= f * y;
                }
            }
        }
        let inv = 1.0 / l[i * r + i];
        bi.iter_mut().for_each(|x| *x *= inv);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::ArrayView2;

    /// A lower-triangular L with integer entries and positive diagonal (s × s, row-major).
    /// A = L Lᵀ has integer entries, and every step of its Cholesky factor (products,
    /// sums, divisions by a diagonal entry that divide exactly, square roots of squares)
    /// and of the triangular solves of an integer right-hand side A x is exact, so the
    /// results must equal L and x to the bit.
    #[rustfmt::skip]
    const L: [f64; 36] = [
         2.0,  0.0,  0.0,  0.0, 0.0, 0.0,
         1.0,  3.0,  0.0,  0.0, 0.0, 0.0,
        -1.0,  2.0,  4.0,  0.0, 0.0, 0.0,
         3.0, -1.0,  1.0,  2.0, 0.0, 0.0,
         0.0,  2.0, -2.0,  1.0, 5.0, 0.0,
         1.0,  1.0,  3.0, -1.0, 2.0, 3.0,
    ];

    /// M Mᵀ for the 6 × 6 matrix M (row-major).
    fn gram(m: &[f64]) -> Vec<f64> {
        let m = ArrayView2::from_shape((6, 6), m).unwrap();
        m.dot(&m.t()).into_iter().collect()
    }

    /// The lower triangle (with the diagonal) of the leading r × r block of a row-major
    /// matrix with row stride `stride`.
    fn lower(r: usize, stride: usize, m: &[f64]) -> Vec<f64> {
        (0..r)
            .flat_map(|i| (0..=i).map(move |j| m[i * stride + j]))
            .collect()
    }

    /// Size, eigenvalues and row stride of the update tests: A = Q diag(λ) Qᵀ with Q a
    /// Householder reflection and λ_i = 10⁻ⁱ, so κ₂(A) = 10⁶ and ‖A‖₂ = ‖L‖₂² = 1. The
    /// stride exceeds the size, as in the solver (stride K, active set smaller).
    const N: usize = 7;
    const STRIDE: usize = 9;
    const KAPPA: f64 = 1e6;

    fn conditioned() -> Vec<f64> {
        let v = [1.0, 2.0, -1.0, 3.0, 1.0, -2.0, 1.0];
        let vv: f64 = v.iter().map(|x| x * x).sum();
        let q = |i: usize, j: usize| f64::from(u8::from(i == j)) - 2.0 * v[i] * v[j] / vv;
        let mut a = vec![0.0; N * N];
        for i in 0..N {
            for j in 0..N {
                a[i * N + j] = (0..N)
                    .map(|m| q(i, m) * 10f64.powi(-(m as i32)) * q(j, m))
                    .sum();
            }
        }
        a
    }

    /// The symmetric matrix `a` (n × n) with its rows and columns in the order `idx`.
    fn permuted(a: &[f64], n: usize, idx: &[usize]) -> Vec<f64> {
        idx.iter()
            .flat_map(|&i| idx.iter().map(move |&j| a[i * n + j]))
            .collect()
    }

    /// A new factor of the m × m matrix `a`, at stride STRIDE (NaN beyond the triangle).
    fn factor(m: usize, a: &[f64]) -> Vec<f64> {
        let mut l = vec![f64::NAN; STRIDE * STRIDE];
        for i in 0..m {
            assert!(chol_append(i, STRIDE, &mut l, &a[i * m..i * m + i + 1]));
        }
        l
    }

    /// The Givens update is backward stable (Stewart 1979; Higham, "Accuracy and
    /// Stability of Numerical Algorithms", §10.1 for the factor it starts from): the
    /// updated L factors A + E with |E| ≲ c m u ‖A‖₂, so L L̃ᵀ must match the reduced
    /// matrix to 10 m u, and the factor itself, whose perturbation is at most κ₂ times
    /// the relative backward error (Sun 1991), a new factor to 10 m u κ₂ (7.8e-9 here).
    fn assert_factors(m: usize, a: &[f64], got: &[f64], what: &str) {
        let u = f64::EPSILON / 2.0;
        let backward = 10.0 * m as f64 * u;
        let forward = backward * KAPPA;
        let fresh = factor(m, a);
        for i in 0..m {
            for j in 0..=i {
                let prod = dot(
                    &got[i * STRIDE..i * STRIDE + j + 1],
                    &got[j * STRIDE..j * STRIDE + j + 1],
                );
                let e = (prod - a[i * m + j]).abs();
                assert!(e <= backward, "{what}: (L Lᵀ − A)[{i}][{j}] = {e:e}");
                let e = (got[i * STRIDE + j] - fresh[i * STRIDE + j]).abs();
                assert!(e <= forward, "{what}: L[{i}][{j}] differs by {e:e}");
            }
        }
    }

    #[test]
    fn removing_a_row_and_column_leaves_the_factor_of_the_reduced_matrix() {
        let a = conditioned();
        for p in [0, N / 2, N - 1] {
            let mut l = factor(N, &a);
            let before = l.clone();
            let mut rot = vec![f64::NAN; 2 * N];
            assert!(chol_delete(N, STRIDE, &mut l, p, &mut rot), "p = {p}");
            // The rows before p are untouched.
            assert_eq!(lower(p, STRIDE, &l), lower(p, STRIDE, &before), "p = {p}");
            let rest: Vec<usize> = (0..N).filter(|&i| i != p).collect();
            assert_factors(N - 1, &permuted(&a, N, &rest), &l, &format!("delete {p}"));
            // Deleting again (the solver drops several coefficients at once, last first).
            if p > 0 {
                assert!(chol_delete(N - 1, STRIDE, &mut l, p - 1, &mut rot));
                let rest: Vec<usize> = (0..N).filter(|&i| i != p && i != p - 1).collect();
                assert_factors(
                    N - 2,
                    &permuted(&a, N, &rest),
                    &l,
                    &format!("delete {p}, {}", p - 1),
                );
            }
        }
    }

    #[test]
    fn appending_to_an_updated_factor_gives_the_factor_of_the_grown_matrix() {
        // Basis j leaves (an update) and comes back as the last row (an append): the
        // factor of A with row and column j moved to the end.
        let a = conditioned();
        for j in [0, N / 2, N - 1] {
            let mut l = factor(N, &a);
            let mut rot = vec![0.0; 2 * N];
            assert!(chol_delete(N, STRIDE, &mut l, j, &mut rot));
            let order: Vec<usize> = (0..N).filter(|&i| i != j).chain([j]).collect();
            let moved = permuted(&a, N, &order);
            assert!(chol_append(N - 1, STRIDE, &mut l, &moved[(N - 1) * N..]));
            assert_factors(N, &moved, &l, &format!("basis {j} to the end"));
        }
    }

    #[test]
    fn a_deletion_from_a_factor_that_is_not_positive_definite_fails() {
        // A zero last row stands for a factor whose last pivot was lost: the rotations
        // leave it zero, so its updated pivot is 0. NaN anywhere after p fails as well.
        let a = conditioned();
        let mut rot = vec![0.0; 2 * N];
        for p in [0, N / 2] {
            let mut l = factor(N, &a);
            l[(N - 1) * STRIDE..(N - 1) * STRIDE + N].fill(0.0);
            assert!(!chol_delete(N, STRIDE, &mut l, p, &mut rot), "p = {p}");
            let mut l = factor(N, &a);
            l[(N - 1) * STRIDE + N / 2 + 1] = f64::NAN;
            assert!(!chol_delete(N, STRIDE, &mut l, p, &mut rot), "p = {p}");
        }
        // The last row is simply dropped: nothing to update, nothing to fail.
        let mut l = factor(N, &a);
        l[(N - 1) * STRIDE..(N - 1) * STRIDE + N].fill(0.0);
        assert!(chol_delete(N, STRIDE, &mut l, N - 1, &mut rot));
    }

    #[test]
    fn dot_sums_the_products_of_the_shorter_length() {
        let a: Vec<f64> = (1..=11).map(|v| v as f64).collect();
        let b: Vec<f64> = (1..=11).map(|v| (3 * v % 7) as f64 - 3.0).collect();
        for n in 0..=11 {
            let want: f64 = (0..n).map(|i| a[i] * b[i]).sum();
            assert_eq!(dot(&a[..n], &b[..n]), want, "n = {n}");
            // A longer second (or first) argument is cut to the shorter one.
            assert_eq!(dot(&a[..n], &b), want, "n = {n}");
            assert_eq!(dot(&a, &b[..n]), want, "n = {n}");
        }
    }

    /// The factor by blocks of four rows is the factor row by row to the bit, at every size
    /// around the blocks, and fails at the same pivot with the same rows before it.
    #[test]
    fn the_factor_by_blocks_of_rows_is_the_factor_row_by_row() {
        let mut rng = crate::rng::Rng::new(5);
        for s in 1..=14 {
            for singular_at in [None, Some(s / 2), Some(s - 1)] {
                // A = M Mᵀ + I, with row r of M made a copy of row r − 1 and no identity at
                // r when singular_at = r > 0 (a zero pivot there).
                let mut m: Vec<f64> = (0..s * s).map(|_| rng.normal()).collect();
                if let Some(r) = singular_at.filter(|&r| r > 0) {
                    let prev = m[(r - 1) * s..r * s].to_vec();
                    m[r * s..(r + 1) * s].copy_from_slice(&prev);
                }
                let mut a = vec![0.0; s * s];
                for i in 0..s {
                    for j in 0..s {
                        let mut v: f64 = (0..s).map(|t| m[i * s + t] * m[j * s + t]).sum();
                        let ridge = singular_at.is_none_or(|r| r == 0 || (i != r && i != r - 1));
                        if i == j && ridge {
                            v += 1.0;
                        }
                        a[i * s + j] = v;
                    }
                }
                let mut by_rows = vec![f64::NAN; s * s];
                let mut failed_at = None;
                for r in 0..s {
                    if !chol_append(r, s, &mut by_rows, &a[r * s..r * s + r + 1]) {
                        failed_at = Some(r);
                        break;
                    }
                }
                let mut blocked = vec![f64::NAN; s * s];
                let got = cholesky(s, &a, &mut blocked);
                assert_eq!(
                    got.err(),
                    failed_at,
                    "size {s}, singular at {singular_at:?}"
                );
                let valid = failed_at.unwrap_or(s);
                let bits = |l: &[f64]| -> Vec<u64> {
                    lower(valid, s, l).iter().map(|v| v.to_bits()).collect()
                };
                assert_eq!(bits(&blocked), bits(&by_rows), "size {s}");
            }
        }
    }

    #[test]
    fn the_factor_of_an_integer_product_is_the_integer_factor_and_solves_exactly() {
        let a = gram(&L);
        // The strict upper triangle of the output is not the factor's: NaN there shows
        // that neither the solves nor the factorisation read it.
        let mut l = vec![f64::NAN; 36];
        assert_eq!(cholesky(6, &a, &mut l), Ok(()));
        assert_eq!(lower(6, 6, &l), lower(6, 6, &L));

        let x = [1.0, -2.0, 3.0, 0.0, 5.0, -1.0];
        let b: Vec<f64> = (0..6).map(|i| dot(&a[i * 6..i * 6 + 6], &x)).collect();
        let mut got = [f64::NAN; 6];
        chol_solve(6, 6, &l, &b, &mut got);
        assert_eq!(got, x);
        // The leading 4 × 4 block of the factor (stride 6) is the factor of A's leading
        // block.
        let b4: Vec<f64> = (0..4).map(|i| dot(&a[i * 6..i * 6 + 4], &x[..4])).collect();
        let mut got4 = [f64::NAN; 4];
        chol_solve(4, 6, &l, &b4, &mut got4);
        assert_eq!(got4, x[..4]);

        // Three right-hand sides at once, B = A X (6 × 3).
        #[rustfmt::skip]
        let xs = [
             1.0,  0.0, 2.0,
            -2.0,  1.0, 0.0,
             3.0,  0.0, -1.0,
             0.0,  4.0, 1.0,
             5.0, -1.0, 0.0,
            -1.0,  2.0, 3.0,
        ];
        let a_x = ArrayView2::from_shape((6, 6), &a)
            .unwrap()
            .dot(&ArrayView2::from_shape((6, 3), &xs).unwrap());
        let mut bs: Vec<f64> = a_x.into_iter().collect();
        chol_solve_rows(6, &l, &mut bs, 3);
        assert_eq!(bs, xs);
    }

    #[test]
    fn a_singular_matrix_fails_at_its_first_dependent_row_with_the_rows_before_valid() {
        // L with a zero at (3, 3): row 3 of A = L Lᵀ depends on rows 0–2, so the pivot
        // there is exactly 0.
        let mut m = L;
        m[3 * 6 + 3] = 0.0;
        let a = gram(&m);
        let mut l = vec![f64::NAN; 36];
        assert_eq!(cholesky(6, &a, &mut l), Err(3));
        assert_eq!(lower(3, 6, &l), lower(3, 6, &L));
        // Those rows solve the leading 3 × 3 system (stride 6).
        let x = [2.0, -1.0, 1.0];
        let b: Vec<f64> = (0..3).map(|i| dot(&a[i * 6..i * 6 + 3], &x)).collect();
        let mut got = [f64::NAN; 3];
        chol_solve(3, 6, &l, &b, &mut got);
        assert_eq!(got, x);
    }

    #[test]
    fn the_pivot_tolerance_is_relative_to_the_diagonal() {
        // [[1, 1], [1, 1 + e]] has the last pivot e: below 1e-10 for e = 2⁻⁴⁰ ≈ 9.1e-13,
        // above for e = 2⁻³⁰ ≈ 9.3e-10; scaling the matrix by 2⁻⁷⁰ or 2⁷⁰ (exact)
        // changes neither.
        let mut l = [0.0; 4];
        for scale in [1.0, 2f64.powi(-70), 2f64.powi(70)] {
            for (e, want) in [(2f64.powi(-40), Err(1)), (2f64.powi(-30), Ok(()))] {
                let a = [scale, scale, scale, scale * (1.0 + e)];
                assert_eq!(cholesky(2, &a, &mut l), want, "e = {e}, scale = {scale}");
            }
            // A 1 × 1 matrix passes whatever its (positive) size, and 0 fails.
            assert_eq!(cholesky(1, &[scale], &mut l), Ok(()));
            assert_eq!(l[0], scale.sqrt());
        }
        // Relative to the row's own diagonal entry: [[2⁻²⁰, 1], [1, 2²⁰ + p]] has the
        // last pivot p (exactly), against 1e-10 · (2²⁰ + p) ≈ 1.05e-4.
        for (p, want) in [(2f64.powi(-16), Err(1)), (2f64.powi(-10), Ok(()))] {
            let a = [2f64.powi(-20), 1.0, 1.0, 2f64.powi(20) + p];
            assert_eq!(cholesky(2, &a, &mut l), want, "p = {p}");
        }
        assert_eq!(cholesky(1, &[0.0], &mut l), Err(0));
        assert_eq!(cholesky(1, &[-1.0], &mut l), Err(0));
        // Not a number or infinite is a failed pivot, not a factor of NaN.
        assert_eq!(cholesky(1, &[f64::NAN], &mut l), Err(0));
        assert_eq!(cholesky(1, &[f64::INFINITY], &mut l), Err(0));
        assert_eq!(cholesky(2, &[4.0, f64::NAN, f64::NAN, 9.0], &mut l), Err(1));
        assert_eq!(cholesky(2, &[4.0, 2.0, 2.0, f64::NAN], &mut l), Err(1));
        assert_eq!(
            cholesky(2, &[4.0, f64::INFINITY, f64::INFINITY, 9.0], &mut l),
            Err(1)
        );
    }
}
