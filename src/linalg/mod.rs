//! Small dense linear algebra on `ndarray`: Cholesky factorisation, solves and the
//! inverse of symmetric positive definite matrices.
//!
//! The engines only ever factor small matrices (a K × K dictionary system with K ≤ a few
//! hundred, a GP Gram matrix of at most a few hundred basis vectors), where a plain
//! row-oriented Cholesky is as fast as a library call and needs no system BLAS/LAPACK.
//! [`dense`] holds the kernels on row-major slices that sparse coding and the linear SVM
//! run in their inner loops.

pub(crate) mod dense;

use ndarray::{Array1, Array2, ArrayView1, ArrayView2};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LinalgError {
    #[error("matrix is not square ({rows} × {cols})")]
    NotSquare { rows: usize, cols: usize },
    #[error("matrix is not positive definite (pivot {pivot} at row {row})")]
    NotPositiveDefinite { row: usize, pivot: f64 },
    #[error("dimension mismatch: matrix is {n} × {n}, vector has {len} entries")]
    Dimension { n: usize, len: usize },
}

/// Lower-triangular Cholesky factor L with A = L Lᵀ.
#[derive(Debug, Clone)]
pub struct Cholesky {
    l: Array2<f64>,
}

impl Cholesky {
    pub fn new(a: ArrayView2<f64>) -> Result<Self, LinalgError> {
        let (rows, cols) = a.dim();
        if rows != cols {
            return Err(LinalgError::NotSquare { rows, cols });
        }
        let n = rows;
        let mut l = Array2::<f64>::zeros((n, n));
        for i in 0..n {
            for j in 0..=i {
                let mut sum = a[[i, j]];
                for k in 0..j {
                    sum -= l[[i, k]] * l[[j, k]];
                }
                if i == j {
                    if sum.is_nan() || sum <= 0.0 || !sum.is_finite() {
                        return Err(LinalgError::NotPositiveDefinite { row: i, pivot: sum });
                    }
                    l[[i, i]] = sum.sqrt();
                } else {
                    l[[i, j]] = sum / l[[j, j]];
                }
            }
        }
        Ok(Cholesky { l })
    }

    /// Factor A + jitter·I, raising the jitter tenfold (from `start`) until it succeeds or
    /// passes `max`. Returns the factor and the jitter used.
    pub fn with_jitter(
        a: ArrayView2<f64>,
        start: f64,
        max: f64,
    ) -> Result<(Self, f64), LinalgError> {
        match Cholesky::new(a) {
            Ok(c) => return Ok((c, 0.0)),
            Err(LinalgError::NotSquare { rows, cols }) => {
                return Err(LinalgError::NotSquare { rows, cols });
            }
            Err(_) => {}
        }
        let mut jitter = start;
        loop {
            let mut aj = a.to_owned();
            aj.diag_mut().mapv_inplace(|d| d + jitter);
            match Cholesky::new(aj.view()) {
                Ok(c) => return Ok((c, jitter)),
                Err(e) if jitter >= max => return Err(e),
                Err(_) => jitter *= 10.0,
            }
        }
    }

    pub fn dim(&self) -> usize {
        self.l.nrows()
    }

    pub fn factor(&self) -> &Array2<f64> {
        &self.l
    }

    /// Solve A x = b.
    pub fn solve(&self, b: ArrayView1<f64>) -> Result<Array1<f64>, LinalgError> {
        let n = self.dim();
        if b.len() != n {
            return Err(LinalgError::Dimension { n, len: b.len() });
        }
        let l = &self.l;
        let mut y = b.to_owned();
        for i in 0..n {
            let mut s = y[i];
            for k in 0..i {
                s -= l[[i, k]] * y[k];
            }
            y[i] = s / l[[i, i]];
        }
        for i in (0..n).rev() {
            let mut s = y[i];
            for k in i + 1..n {
                s -= l[[k, i]] * y[k];
            }
            y[i] = s / l[[i, i]];
        }
        Ok(y)
    }

    /// Solve A X = B column by column.
    pub fn solve_mat(&self, b: ArrayView2<f64>) -> Result<Array2<f64>, LinalgError> {
        let mut x = Array2::<f64>::zeros(b.raw_dim());
        for (j, col) in b.columns().into_iter().enumerate() {
            x.column_mut(j).assign(&self.solve(col)?);
        }
        Ok(x)
    }

    /// A⁻¹ (symmetric).
    pub fn inverse(&self) -> Array2<f64> {
        let n = self.dim();
        let eye = Array2::<f64>::eye(n);
        // Cannot fail: the identity has the right shape.
        let mut inv = self.solve_mat(eye.view()).unwrap_or(eye);
        // Symmetrise away rounding.
        for i in 0..n {
            for j in 0..i {
                let v = 0.5 * (inv[[i, j]] + inv[[j, i]]);
                inv[[i, j]] = v;
                inv[[j, i]] = v;
            }
        }
        inv
    }

    /// log det A.
    pub fn log_det(&self) -> f64 {
        2.0 * self.l.diag().iter().map(|d| d.ln()).sum::<f64>()
    }
}

/// Inverse of a symmetric positive definite matrix.
pub fn spd_inverse(a: ArrayView2<f64>) -> Result<Array2<f64>, LinalgError> {
    Ok(Cholesky::new(a)?.inverse())
}

#[cfg(test)]
mod tests {
    use super::*;
    use ndarray::array;

    #[test]
    fn solves_and_inverts() {
        let a = array![[4.0, 2.0, 0.6], [2.0, 5.0, 1.0], [0.6, 1.0, 3.0]];
        let c = Cholesky::new(a.view()).unwrap();
        let b = array![1.0, 2.0, 3.0];
        let x = c.solve(b.view()).unwrap();
        let r = a.dot(&x) - &b;
        assert!(r.iter().all(|v| v.abs() < 1e-12));
        let inv = c.inverse();
        let eye = a.dot(&inv);
        for i in 0..3 {
            for j in 0..3 {
                let e = if i == j { 1.0 } else { 0.0 };
                assert!((eye[[i, j]] - e).abs() < 1e-12);
            }
        }
        let det: f64 = 4.0 * (5.0 * 3.0 - 1.0) - 2.0 * (2.0 * 3.0 - 0.6) + 0.6 * (2.0 - 5.0 * 0.6);
        assert!((c.log_det() - det.ln()).abs() < 1e-12);
    }

    #[test]
    fn rejects_indefinite_and_jitter_rescues_singular() {
        let a = array![[1.0, 2.0], [2.0, 1.0]];
        assert!(matches!(
            Cholesky::new(a.view()),
            Err(LinalgError::NotPositiveDefinite { .. })
        ));
        let s = array![[1.0, 1.0], [1.0, 1.0]];
        let (_, jitter) = Cholesky::with_jitter(s.view(), 1e-10, 1.0).unwrap();
        assert!(jitter > 0.0);
    }
}
