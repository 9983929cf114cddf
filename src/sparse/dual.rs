//! The basis step by the Lagrange dual (Lee et al. 2007, Sec. 3).
//!
//! With the codes `A` (N × K) fixed, `min_D ||X − A D||²_F` subject to `||d_j||² ≤ c` has
//! the Lagrangian dual, over one multiplier λ_j ≥ 0 per basis,
//!
//! ```text
//! min_λ≥0 φ(λ) = tr(Pᵀ M(λ)⁻¹ P) + c Σ_j λ_j,   M(λ) = AᵀA + diag(λ),  P = AᵀX
//! ∂φ/∂λ_j = c − ||d_j||²,   ∂²φ/∂λ_i∂λ_j = 2 (D Dᵀ)_ij (M⁻¹)_ij,   D = M⁻¹ P
//! ```
//!
//! (`D Dᵀ = M⁻¹ P Pᵀ M⁻¹`), after which the dictionary is the closed form `D = M⁻¹ P`.
//! We minimise φ by projected Newton (Bertsekas 1982: Newton on the multipliers that are
//! above their bound or have a negative gradient, the others moved to their bound, 0 or,
//! where AᵀA is singular, a small ridge; Armijo backtracking along the projected arc),
//! warm-started from the previous multipliers. It needs only the K × K and K × n
//! sufficient statistics `AᵀA`, `AᵀX`, so its cost does not depend on N.
//! Bases whose codes are all zero have no say in the objective; they are excluded here
//! (the learner re-seeds them).

use ndarray::{Array2, ArrayView2};

use crate::linalg::dense::{self, chol_solve, chol_solve_rows, cholesky};

const MAX_NEWTON: usize = 50;

#[derive(Clone, Debug, Default, PartialEq)]
pub struct DualStats {
    pub newton_steps: usize,
    pub converged: bool,
    /// Largest projected-gradient entry at the end (≈ violation of ||d_j||² ≤ c or of
    /// complementary slackness).
    pub kkt_violation: f64,
}

struct DualWork {
    k: usize,
    m: Vec<f64>,
    l: Vec<f64>,
    minv: Vec<f64>,
    d: Vec<f64>,
}

impl DualWork {
    /// Factor M(λ) and compute D = M⁻¹ P; returns φ(λ) or None if M is not positive definite.
    fn eval(&mut self, ata: &[f64], p: &[f64], n: usize, c: f64, lambda: &[f64]) -> Option<f64> {
        let k = self.k;
        self.m.copy_from_slice(ata);
        for (j, l) in lambda.iter().enumerate() {
            self.m[j * k + j] += l;
        }
        cholesky(k, &self.m, &mut self.l).ok()?;
        // D = M⁻¹ P (P is K × n row-major), all columns at once; φ adds tr(Pᵀ D).
        self.d.copy_from_slice(p);
        chol_solve_rows(k, &self.l, &mut self.d, n);
        let phi = c * lambda.iter().sum::<f64>() + dense::dot(p, &self.d);
        Some(phi)
    }

    fn inverse(&mut self) {
        let k = self.k;
        self.minv.iter_mut().for_each(|v| *v = 0.0);
        for j in 0..k {
            self.minv[j * k + j] = 1.0;
        }
        chol_solve_rows(k, &self.l, &mut self.minv, k);
    }
}

/// Solve the basis step. `ata` = AᵀA (K × K), `atx` = AᵀX (K × n), `c` the squared-norm
/// bound, `lambda` the multipliers (in/out: warm start and result). Returns the new
/// dictionary (K × n) and statistics. Rows `j` with `ata[j][j] == 0` (unused bases) are
/// returned as zero rows with λ_j = 0; the caller decides what to do with them.
pub fn basis_step_dual(
    ata: ArrayView2<f64>,
    atx: ArrayView2<f64>,
    c: f64,
    lambda: &mut [f64],
) -> (Array2<f64>, DualStats) {
    let (k_all, n) = atx.dim();
    assert_eq!(ata.dim(), (k_all, k_all));
    assert_eq!(lambda.len(), k_all);
    let used: Vec<usize> = (0..k_all).filter(|&j| ata[[j, j]] > 0.0).collect();
    let k = used.len();
    let mut out = Array2::<f64>::zeros((k_all, n));
    for j in 0..k_all {
        if ata[[j, j]] <= 0.0 {
            lambda[j] = 0.0;
        }
    }
    if k == 0 {
        return (
            out,
            DualStats {
                newton_steps: 0,
                converged: true,
                kkt_violation: 0.0,
            },
        );
    }
    let (ata_u, p, mut lam) = restrict_to_used(ata, atx, lambda, &used);
    let mut w = DualWork {
        k,
        m: vec![0.0; k * k],
        l: vec![0.0; k * k],
        minv: vec![0.0; k * k],
        d: vec![0.0; k * n],
    };
    // A singular AᵀA (e.g. two bases always used together) makes φ infinite at λ = 0:
    // the multipliers' bound is then a small ridge λ_min instead of 0.
    let lam_min = if cholesky(k, &ata_u, &mut w.l).is_ok() {
        0.0
    } else {
        1e-6 * (0..k).map(|j| ata_u[j * k + j]).sum::<f64>() / k as f64
    };
    lam.iter_mut().for_each(|v| *v = v.max(lam_min));
    let problem = Problem {
        ata: &ata_u,
        p: &p,
        n,
        c,
        lam_min,
    };
    let stats = projected_newton(&mut w, &problem, &mut lam);
    for (a, &i) in used.iter().enumerate() {
        lambda[i] = lam[a];
        let row = &w.d[a * n..(a + 1) * n];
        // Enforce the bound exactly (the dual leaves it satisfied to ~1e-10 relative).
        let nrm2: f64 = row.iter().map(|v| v * v).sum();
        let scale = if nrm2 > c { (c / nrm2).sqrt() } else { 1.0 };
        for col in 0..n {
            out[[i, col]] = row[col] * scale;
        }
    }
    (out, stats)
}

/// AᵀA and AᵀX restricted to the used bases (row-major, K_used × K_used and K_used × n),
/// and their warm-start multipliers (at least 0).
fn restrict_to_used(
    ata: ArrayView2<f64>,
    atx: ArrayView2<f64>,
    lambda: &[f64],
    used: &[usize],
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let (k, n) = (used.len(), atx.ncols());
    let mut ata_u = vec![0.0; k * k];
    let mut p = vec![0.0; k * n];
    let mut lam = vec![0.0; k];
    for (a, &i) in used.iter().enumerate() {
        for (b, &j) in used.iter().enumerate() {
            ata_u[a * k + b] = ata[[i, j]];
        }
        for col in 0..n {
            p[a * n + col] = atx[[i, col]];
        }
        lam[a] = lambda[i].max(0.0);
    }
    (ata_u, p, lam)
}

/// The dual over the used bases: AᵀA (K × K), P = AᵀX (K × n), the squared-norm bound and
/// the multipliers' lower bound.
struct Problem<'a> {
    ata: &'a [f64],
    p: &'a [f64],
    n: usize,
    c: f64,
    lam_min: f64,
}

impl Problem<'_> {
    /// φ(λ), leaving M(λ)'s factor and D = M⁻¹ P in `w`; None if M is not positive
    /// definite.
    fn eval(&self, w: &mut DualWork, lambda: &[f64]) -> Option<f64> {
        w.eval(self.ata, self.p, self.n, self.c, lambda)
    }
}

/// Projected Newton on φ from `lam` (at or above the bound, with D for it not yet in `w`),
/// leaving the optimum in `lam` and its D in `w`.
fn projected_newton(w: &mut DualWork, problem: &Problem, lam: &mut [f64]) -> DualStats {
    let (k, c) = (w.k, problem.c);
    let mut phi = problem.eval(w, lam).unwrap_or(f64::INFINITY);
    let tol = 1e-10 * c;
    let eps0 = 1e-3 * (0..k).map(|j| problem.ata[j * k + j]).sum::<f64>() / k as f64;
    let mut grad = vec![0.0; k];
    let mut hess = vec![0.0; k * k];
    let mut hl = vec![0.0; k * k];
    let mut dir = vec![0.0; k];
    let mut trial = vec![0.0; k];
    let mut free: Vec<usize> = Vec::with_capacity(k);
    let mut stats = DualStats::default();
    for _ in 0..MAX_NEWTON {
        let viol = gradient(w, problem, lam, &mut grad);
        stats.kkt_violation = viol;
        if viol <= tol {
            stats.converged = true;
            break;
        }
        stats.newton_steps += 1;
        let held_above_bound = free_set(lam, &grad, problem.lam_min, eps0, &mut free);
        w.inverse();
        let Some((rhs, sol)) = newton_on_free(w, problem.n, &free, &grad, &mut hess, &mut hl)
        else {
            break;
        };
        let f = free.len();
        // Newton decrement on the free set: below rounding of φ, λ is optimal to
        // machine precision (the gradient test above can sit at its rounding floor) once
        // the held multipliers are at their bound. Relative to φ (≥ 0), as the gradient
        // test is to c: scaling the codes scales φ, and must not change where it stops.
        let dec: f64 = (0..f).map(|a| rhs[a] * sol[a]).sum();
        if 0.5 * dec <= 1e-14 * phi && !held_above_bound {
            stats.converged = true;
            break;
        }
        // A held multiplier takes Bertsekas' scaled gradient step with the scale
        // (λ_j − λ_min) / ∂φ/∂λ_j, which reaches the bound at t = 1.
        for (d, l) in dir.iter_mut().zip(lam.iter()) {
            *d = problem.lam_min - l;
        }
        for (a, &j) in free.iter().enumerate() {
            dir[j] = -sol[a];
        }
        match armijo(w, problem, lam, &dir, &grad, &mut trial, phi) {
            Some(ft) => phi = ft,
            None => {
                // At the optimum to rounding: restore D for the current λ and stop.
                if let Some(v) = problem.eval(w, lam) {
                    phi = v;
                }
                break;
            }
        }
    }
    let _ = phi;
    stats
}

/// The gradient c − ||d_j||² into `grad`; returns the largest projected-gradient entry.
fn gradient(w: &DualWork, problem: &Problem, lam: &[f64], grad: &mut [f64]) -> f64 {
    let (n, c, lam_min) = (problem.n, problem.c, problem.lam_min);
    let mut viol = 0.0f64;
    for j in 0..w.k {
        let nrm: f64 = w.d[j * n..(j + 1) * n].iter().map(|v| v * v).sum();
        grad[j] = c - nrm;
        let pg = if lam[j] > lam_min {
            grad[j].abs()
        } else {
            (-grad[j]).max(0.0)
        };
        viol = viol.max(pg);
    }
    viol
}

/// The free set into `free` (Bertsekas' ε-active rule): a multiplier within ε of its bound
/// whose gradient pushes it down is held out of the Newton step and moved to the bound;
/// ε = min(ε0, ||λ − [λ − ∇φ]₊||). Returns whether a held multiplier is above its bound.
fn free_set(lam: &[f64], grad: &[f64], lam_min: f64, eps0: f64, free: &mut Vec<usize>) -> bool {
    let k = lam.len();
    let wk: f64 = (0..k)
        .map(|j| {
            let r = lam[j] - (lam[j] - grad[j]).max(lam_min);
            r * r
        })
        .sum::<f64>()
        .sqrt();
    let eps = wk.min(eps0);
    free.clear();
    let mut held_above_bound = false;
    for j in 0..k {
        if lam[j] - lam_min <= eps && grad[j] > 0.0 {
            held_above_bound |= lam[j] > lam_min;
        } else {
            free.push(j);
        }
    }
    held_above_bound
}

/// The Newton system on the free set, with M⁻¹ in `w`: the gradient there and the
/// solution of H x = ∇φ (the step is −x). None if the Hessian, even with a ridge, cannot
/// be factored.
fn newton_on_free(
    w: &DualWork,
    n: usize,
    free: &[usize],
    grad: &[f64],
    hess: &mut [f64],
    hl: &mut [f64],
) -> Option<(Vec<f64>, Vec<f64>)> {
    let k = w.k;
    // Hessian on the free set: 2 (D Dᵀ)_ij (M⁻¹)_ij.
    let f = free.len();
    for (a, &i) in free.iter().enumerate() {
        for (b, &j) in free.iter().enumerate().take(a + 1) {
            let ddt: f64 = (0..n).map(|col| w.d[i * n + col] * w.d[j * n + col]).sum();
            let h = 2.0 * ddt * w.minv[i * k + j];
            hess[a * f + b] = h;
            hess[b * f + a] = h;
        }
    }
    let rhs: Vec<f64> = free.iter().map(|&j| grad[j]).collect();
    if cholesky(f, &hess[..f * f], &mut hl[..f * f]).is_err() {
        // Positive semidefinite only: add a ridge proportional to its diagonal.
        let md = (0..f).map(|a| hess[a * f + a]).fold(0.0f64, f64::max);
        for a in 0..f {
            hess[a * f + a] += 1e-10 * md + 1e-300;
        }
        if cholesky(f, &hess[..f * f], &mut hl[..f * f]).is_err() {
            return None;
        }
    }
    let mut sol = vec![0.0; f];
    chol_solve(f, f, hl, &rhs, &mut sol);
    Some((rhs, sol))
}

/// Armijo backtracking along the projected arc λ(t) = max(λ_min, λ + t dir) from t = 1:
/// the first t that lowers φ enough moves `lam` there and returns its φ (D for it left in
/// `w`); None if none of 40 halvings does.
fn armijo(
    w: &mut DualWork,
    problem: &Problem,
    lam: &mut [f64],
    dir: &[f64],
    grad: &[f64],
    trial: &mut [f64],
    phi: f64,
) -> Option<f64> {
    let mut t = 1.0;
    for _ in 0..40 {
        let mut pred = 0.0;
        for j in 0..w.k {
            trial[j] = (lam[j] + t * dir[j]).max(problem.lam_min);
            pred += grad[j] * (trial[j] - lam[j]);
        }
        if let Some(ft) = problem.eval(w, trial)
            && ft < phi
            && ft <= phi + 1e-4 * pred.min(0.0)
        {
            lam.copy_from_slice(trial);
            return Some(ft);
        }
        t *= 0.5;
    }
    None
}
