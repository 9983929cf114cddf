//! The epsilon-L1 code step (the paper's learning phase, eq. 2) by damped Newton.
//!
//! For one patch: `min_a f(a) = 0.5 aᵀ G a − cᵀ a + β Σ_j sqrt(a_j² + ε)`, smooth and
//! strictly convex (its Hessian `G + β diag(ε / (a_j² + ε)^{3/2})` is positive definite).
//! Newton's direction comes from a Cholesky solve of the Hessian; the step is damped by
//! Armijo backtracking (start at 1, halve; sufficient decrease 1e-4 of the predicted
//! decrease). It stops when the gradient's largest entry falls below
//! `1e-10 · (1 + max |c|)`, i.e. at the optimum to rounding, typically after 3–8 steps
//! from a warm start. (The reference code runs nonlinear conjugate gradient to a 0.005 tolerance
//! for at most 100 iterations; Newton converges quadratically on this small problem.)

use crate::linalg::dense::{self, chol_solve, cholesky};

/// `0.5 aᵀ G a − cᵀ a + β Σ sqrt(a² + ε)`.
pub fn eps_l1_objective(g: &[f64], c: &[f64], beta: f64, epsilon: f64, a: &[f64]) -> f64 {
    let k = c.len();
    let mut f = 0.0;
    for i in 0..k {
        let gi = dense::dot(&g[i * k..(i + 1) * k], a);
        f += 0.5 * a[i] * gi - c[i] * a[i] + beta * (a[i] * a[i] + epsilon).sqrt();
    }
    f
}

/// Reusable workspace of the damped Newton solver for K bases.
#[derive(Clone, Debug)]
pub struct EpsL1Newton {
    k: usize,
    h: Vec<f64>,
    l: Vec<f64>,
    grad: Vec<f64>,
    step: Vec<f64>,
    trial: Vec<f64>,
    pub max_iter: usize,
}

impl EpsL1Newton {
    pub fn new(k: usize) -> Self {
        EpsL1Newton {
            k,
            h: vec![0.0; k * k],
            l: vec![0.0; k * k],
            grad: vec![0.0; k],
            step: vec![0.0; k],
            trial: vec![0.0; k],
            max_iter: 100,
        }
    }

    /// Minimise from the warm start in `a` (in/out). Returns (Newton steps, converged).
    pub fn solve(
        &mut self,
        g: &[f64],
        c: &[f64],
        beta: f64,
        epsilon: f64,
        a: &mut [f64],
    ) -> (usize, bool) {
        let k = self.k;
        let mut f = eps_l1_objective(g, c, beta, epsilon, a);
        let gtol = 1e-10 * (1.0 + c.iter().fold(0.0f64, |m, v| m.max(v.abs())));
        for it in 0..self.max_iter {
            for i in 0..k {
                let row = &g[i * k..(i + 1) * k];
                let r = (a[i] * a[i] + epsilon).sqrt();
                self.grad[i] = dense::dot(row, a) - c[i] + beta * a[i] / r;
            }
            let gmax = self.grad.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            if gmax <= gtol {
                return (it, true);
            }
            self.h.copy_from_slice(g);
            for (i, ai) in a.iter().enumerate() {
                let r2 = ai * ai + epsilon;
                self.h[i * k + i] += beta * epsilon / (r2 * r2.sqrt());
            }
            if cholesky(k, &self.h, &mut self.l).is_err() {
                // With more bases than dimensions G is singular, and where the codes on
                // its null directions are so large that β ε / (a² + ε)^{3/2} falls below
                // the pivot tolerance (1e-10 of the diagonal) the factor fails. A ridge
                // above that tolerance makes it pass (each pivot grows by at least its
                // row's ridge) and keeps the step a descent direction.
                for i in 0..k {
                    self.h[i * k + i] += 1e-9 * (1.0 + self.h[i * k + i]);
                }
                if cholesky(k, &self.h, &mut self.l).is_err() {
                    return (it, false);
                }
            }
            chol_solve(k, k, &self.l, &self.grad, &mut self.step);
            // Newton decrement²: gradᵀ H⁻¹ grad.
            let dec = dense::dot(&self.grad, &self.step);
            if dec <= 1e-12 * (1.0 + f.abs()) {
                // Inside the region of quadratic convergence, where Armijo's test is lost
                // in the rounding of f: take the full step.
                a.iter_mut().zip(&self.step).for_each(|(ai, si)| *ai -= si);
                f = eps_l1_objective(g, c, beta, epsilon, a);
                continue;
            }
            let mut t = 1.0;
            loop {
                for ((tr, ai), si) in self.trial.iter_mut().zip(a.iter()).zip(&self.step) {
                    *tr = ai - t * si;
                }
                let ft = eps_l1_objective(g, c, beta, epsilon, &self.trial);
                if ft <= f - 1e-4 * t * dec {
                    a.copy_from_slice(&self.trial);
                    f = ft;
                    break;
                }
                t *= 0.5;
                if t < 1e-9 {
                    // No decrease left at rounding level of f.
                    return (it, gmax <= 1e3 * gtol);
                }
            }
        }
        (self.max_iter, false)
    }
}
