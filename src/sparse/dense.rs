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
