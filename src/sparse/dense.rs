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

/// Cholesky factor of the s × s matrix `a` (row-major, stride s) into `l` (lower
/// triangle, stride s). `Err(r)` when the pivot at row r is not positive enough
/// (relative to the diagonal); rows before r are then valid.
pub fn cholesky(s: usize, a: &[f64], l: &mut [f64]) -> Result<(), usize> {
    for i in 0..s {
        let (done, rest) = l.split_at_mut(i * s);
        let li = &mut rest[..s];
        for j in 0..i {
            let lj = &done[j * s..j * s + j + 1];
            let sum = a[i * s + j] - dot(&li[..j], &lj[..j]);
            li[j] = sum / lj[j];
        }
        let sum = a[i * s + i] - dot(&li[..i], &li[..i]);
        // (NaN fails the first test.)
        if sum.is_nan() || sum <= PIVOT_TOL * a[i * s + i] || sum.is_infinite() {
            return Err(i);
        }
        li[i] = sum.sqrt();
    }
    Ok(())
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
