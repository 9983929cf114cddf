//! Feature-sign search (Lee et al. 2007, Algorithm 1), exact.
//!
//! Solves, for one patch, `min_a 0.5 aᵀ G a − cᵀ a + γ ||a||₁` where `G = D Dᵀ` (K × K) and
//! `c = D x` are precomputed once per dictionary (and per patch); this equals
//! `0.5 ||x − a D||² + γ ||a||₁` up to the constant `0.5 ||x||²`.
//!
//! Unlike the reference MATLAB code there is no cap on the active set: when the active
//! bases are linearly dependent (more active bases than taxels, or a degenerate dictionary)
//! the step moves along the null direction of the active Gram matrix to the first zero
//! crossing, which never increases the objective and shrinks the active set. When a
//! feature-sign step makes no progress (possible only at rounding level) an exact
//! coordinate update is taken instead. The solver stops when the L1 optimality conditions
//! hold — `|∇_j + γ sign(a_j)| ≈ 0` on non-zero coefficients (to rounding: the step solves
//! that linear system exactly) and `|∇_j| ≤ γ (1 + 1e-12)` on zero ones — which the tests
//! check to 1e-8.
//!
//! All buffers live in the [`FeatureSign`] workspace: after the first call, solving
//! allocates nothing.

use super::dense::{chol_solve, cholesky};

/// Outcome of one solve.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FsStats {
    /// Feature-sign steps plus checks of the optimality conditions.
    pub iterations: usize,
    /// The optimality conditions hold (false only if `max_iter` was reached).
    pub converged: bool,
}

/// Reusable workspace of feature-sign search for dictionaries of `k` bases.
#[derive(Clone, Debug)]
pub struct FeatureSign {
    k: usize,
    /// Indices of the active coefficients.
    active: Vec<usize>,
    /// Sign vector θ of the active coefficients (±1), aligned with `active`.
    theta: Vec<f64>,
    gs: Vec<f64>,
    l: Vec<f64>,
    rhs: Vec<f64>,
    z: Vec<f64>,
    cur: Vec<f64>,
    d: Vec<f64>,
    gcur: Vec<f64>,
    gd: Vec<f64>,
    bp: Vec<f64>,
    grad: Vec<f64>,
    /// Iteration cap (feature-sign steps + activations); generous, reached only on
    /// pathological input.
    pub max_iter: usize,
}

enum Step {
    /// The minimiser of the sign-restricted quadratic was consistent: active set optimal.
    Full,
    /// A line search stopped at a zero crossing (the active set shrank).
    Partial,
    /// No candidate decreased the objective.
    Stalled,
}

impl FeatureSign {
    pub fn new(k: usize) -> Self {
        FeatureSign {
            k,
            active: Vec::with_capacity(k),
            theta: Vec::with_capacity(k),
            gs: vec![0.0; k * k],
            l: vec![0.0; k * k],
            rhs: vec![0.0; k],
            z: vec![0.0; k],
            cur: vec![0.0; k],
            d: vec![0.0; k],
            gcur: vec![0.0; k],
            gd: vec![0.0; k],
            bp: vec![0.0; k],
            grad: vec![0.0; k],
            max_iter: 50 * k + 1000,
        }
    }

    pub fn num_bases(&self) -> usize {
        self.k
    }

    /// Solve for `a` (in/out: its value on entry is the warm start; pass zeros for none).
    /// `g` is the K × K Gram matrix `D Dᵀ` in row-major order, `c = D x`.
    pub fn solve(&mut self, g: &[f64], c: &[f64], gamma: f64, a: &mut [f64]) -> FsStats {
        let k = self.k;
        assert_eq!(c.len(), k, "feature-sign: c has the wrong length");
        assert_eq!(a.len(), k, "feature-sign: a has the wrong length");
        assert_eq!(g.len(), k * k, "feature-sign: G has the wrong size");
        let act_tol = 1e-12 * gamma.max(1e-300) + 1e-300;

        self.active.clear();
        self.theta.clear();
        for j in 0..k {
            if a[j] != 0.0 && a[j].is_finite() && g[j * k + j] > 0.0 {
                self.active.push(j);
                self.theta.push(a[j].signum());
            } else {
                a[j] = 0.0;
            }
        }
        let mut iterations = 0usize;
        let mut run_steps = !self.active.is_empty();
        loop {
            if run_steps {
                // Feature-sign steps until the active set is optimal for its sign vector.
                loop {
                    if iterations >= self.max_iter {
                        return FsStats {
                            iterations,
                            converged: false,
                        };
                    }
                    iterations += 1;
                    if self.active.is_empty() {
                        break;
                    }
                    match self.step(g, c, gamma, a) {
                        Step::Full => break,
                        Step::Partial => continue,
                        Step::Stalled => {
                            self.coordinate_pass(g, c, gamma, a);
                            break;
                        }
                    }
                }
            }
            run_steps = true;
            if iterations >= self.max_iter {
                return FsStats {
                    iterations,
                    converged: false,
                };
            }
            iterations += 1;
            // Gradient G a − c as a sum of the active rows of G (symmetric), then the most
            // violating zero coefficient; verify active optimality on the way.
            for (gr, cj) in self.grad.iter_mut().zip(c) {
                *gr = -cj;
            }
            for &i in &self.active {
                let ai = a[i];
                for (gr, gij) in self.grad.iter_mut().zip(&g[i * k..(i + 1) * k]) {
                    *gr += ai * gij;
                }
            }
            let mut best = 0.0;
            let mut best_j = usize::MAX;
            let mut active_violation = 0.0f64;
            let mut scale = gamma;
            for j in 0..k {
                let grad = self.grad[j];
                scale = scale.max(c[j].abs());
                if a[j] == 0.0 {
                    if grad.abs() > best && g[j * k + j] > 0.0 {
                        best = grad.abs();
                        best_j = j;
                    }
                } else {
                    active_violation = active_violation.max((grad + gamma * a[j].signum()).abs());
                }
            }
            if best_j != usize::MAX && best > gamma + act_tol {
                // Activate it with the sign that decreases the objective.
                self.active.push(best_j);
                self.theta.push(-self.grad[best_j].signum());
                continue;
            }
            if active_violation > 1e-11 * (1.0 + scale) {
                // Rounding left the active set slightly off: polish with another step.
                if iterations >= self.max_iter {
                    return FsStats {
                        iterations,
                        converged: false,
                    };
                }
                continue;
            }
            return FsStats {
                iterations,
                converged: true,
            };
        }
    }

    /// One feature-sign step (Step 3 of the algorithm) with its discrete line search.
    fn step(&mut self, g: &[f64], c: &[f64], gamma: f64, a: &mut [f64]) -> Step {
        let k = self.k;
        let s = self.active.len();
        for p in 0..s {
            let i = self.active[p];
            for q in 0..s {
                self.gs[p * s + q] = g[i * k + self.active[q]];
            }
            self.rhs[p] = c[i] - gamma * self.theta[p];
            self.cur[p] = a[i];
        }
        if let Err(r) = cholesky(s, &self.gs, &mut self.l) {
            return self.null_step(r, c, gamma, a);
        }
        chol_solve(s, s, &self.l, &self.rhs[..s], &mut self.z[..s]);
        if (0..s).all(|p| self.z[p] * self.theta[p] > 0.0) {
            for p in 0..s {
                a[self.active[p]] = self.z[p];
            }
            return Step::Full;
        }
        // Discrete line search on the segment cur → z: the objective change
        // Δf(t) = t b + t² q + γ (Σ|cur + t d| − Σ|cur|).
        let mut b = 0.0;
        let mut q = 0.0;
        let mut l1_0 = 0.0;
        for p in 0..s {
            self.d[p] = self.z[p] - self.cur[p];
            l1_0 += self.cur[p].abs();
        }
        for p in 0..s {
            let (mut gc, mut gdp) = (0.0, 0.0);
            let row = &self.gs[p * s..(p + 1) * s];
            for ((g, c), d) in row.iter().zip(&self.cur[..s]).zip(&self.d[..s]) {
                gc += g * c;
                gdp += g * d;
            }
            self.gcur[p] = gc;
            self.gd[p] = gdp;
            b += (gc - self.rhs[p] - gamma * self.theta[p]) * self.d[p];
            q += 0.5 * self.d[p] * gdp;
        }
        let eval = |t: f64, cur: &[f64], d: &[f64]| -> f64 {
            let mut l1 = 0.0;
            for p in 0..s {
                l1 += (cur[p] + t * d[p]).abs();
            }
            t * b + t * t * q + gamma * (l1 - l1_0)
        };
        let mut best_t = 0.0;
        let mut best_f = 0.0;
        let f1 = eval(1.0, &self.cur[..s], &self.d[..s]);
        if f1 < best_f {
            best_f = f1;
            best_t = 1.0;
        }
        for p in 0..s {
            let (cp, zp) = (self.cur[p], self.z[p]);
            self.bp[p] = f64::NAN;
            if cp != 0.0 && cp * zp <= 0.0 {
                let t = cp / (cp - zp);
                if t > 0.0 && t <= 1.0 {
                    self.bp[p] = t;
                    let f = eval(t, &self.cur[..s], &self.d[..s]);
                    if f < best_f || (f == best_f && t > best_t && best_t > 0.0) {
                        best_f = f;
                        best_t = t;
                    }
                }
            }
        }
        if best_t == 0.0 {
            return Step::Stalled;
        }
        for p in 0..s {
            let i = self.active[p];
            a[i] = if self.bp[p] == best_t {
                0.0
            } else {
                self.cur[p] + best_t * self.d[p]
            };
        }
        self.compact(a);
        Step::Partial
    }

    /// The active Gram matrix is singular at pivot `r`: basis `active[r]` is a linear
    /// combination of the earlier active bases. Along the null direction v the smooth part
    /// of the objective is linear, so the objective along ±v is convex piecewise linear
    /// and its minimum over t ≥ 0 lies at a zero crossing: move there and drop that basis.
    fn null_step(&mut self, r: usize, c: &[f64], gamma: f64, a: &mut [f64]) -> Step {
        let s = self.active.len();
        // v = (w, −1, 0…) with G_rr' w = G_r' r (rows/cols 0..r).
        for p in 0..r {
            self.rhs[p] = self.gs[p * s + r];
        }
        chol_solve(r, s, &self.l, &self.rhs[..r], &mut self.z[..r]);
        for p in 0..s {
            self.d[p] = if p < r {
                self.z[p]
            } else if p == r {
                -1.0
            } else {
                0.0
            };
        }
        // Slope of the smooth part along v and curvature (≈ 0).
        let mut slope = 0.0;
        let mut curv = 0.0;
        for p in 0..s {
            let row = &self.gs[p * s..(p + 1) * s];
            let (mut gc, mut gv) = (0.0, 0.0);
            for ((g, c), d) in row.iter().zip(&self.cur[..s]).zip(&self.d[..s]) {
                gc += g * c;
                gv += g * d;
            }
            slope += (gc - c[self.active[p]]) * self.d[p];
            curv += 0.5 * self.d[p] * gv;
        }
        let mut l1_0 = 0.0;
        for p in 0..s {
            l1_0 += self.cur[p].abs();
        }
        let mut best: Option<(f64, f64, usize)> = None; // (Δf, signed t, index)
        for dir in [1.0, -1.0] {
            for p in 0..s {
                let (cp, vp) = (self.cur[p], dir * self.d[p]);
                if cp == 0.0 || vp == 0.0 || cp * vp > 0.0 {
                    continue;
                }
                let t = -cp / vp;
                let st = dir * t;
                let mut l1 = 0.0;
                for q in 0..s {
                    l1 += if q == p {
                        0.0
                    } else {
                        (self.cur[q] + st * self.d[q]).abs()
                    };
                }
                let df = st * slope + st * st * curv + gamma * (l1 - l1_0);
                if best.is_none_or(|(bf, _, _)| df < bf) {
                    best = Some((df, st, p));
                }
            }
        }
        let Some((_, st, zero_p)) = best else {
            // Only the new (zero) coefficient moves along v: drop it.
            a[self.active[r]] = 0.0;
            self.compact(a);
            return Step::Partial;
        };
        for p in 0..s {
            let i = self.active[p];
            a[i] = if p == zero_p {
                0.0
            } else {
                self.cur[p] + st * self.d[p]
            };
        }
        // The coefficient at r may have left its sign; drop it if it is exactly zero.
        self.compact(a);
        Step::Partial
    }

    /// Drop zero coefficients from the active set and reset θ to the current signs.
    fn compact(&mut self, a: &[f64]) {
        let mut w = 0;
        for p in 0..self.active.len() {
            let i = self.active[p];
            if a[i] != 0.0 {
                self.active[w] = i;
                self.theta[w] = a[i].signum();
                w += 1;
            }
        }
        self.active.truncate(w);
        self.theta.truncate(w);
    }

    /// Exact coordinate minimisation over every coefficient once (the fallback when a
    /// feature-sign step stalls at rounding level); never increases the objective.
    fn coordinate_pass(&mut self, g: &[f64], c: &[f64], gamma: f64, a: &mut [f64]) {
        let k = self.k;
        for j in 0..k {
            let gjj = g[j * k + j];
            if gjj <= 0.0 {
                continue;
            }
            let row = &g[j * k..(j + 1) * k];
            let mut r = c[j];
            for i in 0..k {
                if i != j {
                    r -= row[i] * a[i];
                }
            }
            a[j] = soft_threshold(r, gamma) / gjj;
        }
        self.active.clear();
        self.theta.clear();
        for (j, &v) in a.iter().enumerate() {
            if v != 0.0 {
                self.active.push(j);
                self.theta.push(v.signum());
            }
        }
    }
}

#[inline]
pub(crate) fn soft_threshold(x: f64, t: f64) -> f64 {
    if x > t {
        x - t
    } else if x < -t {
        x + t
    } else {
        0.0
    }
}

/// `0.5 aᵀ G a − cᵀ a + γ ||a||₁` (the patch objective without the constant 0.5 ||x||²).
pub fn l1_objective(g: &[f64], c: &[f64], gamma: f64, a: &[f64]) -> f64 {
    let k = c.len();
    let mut f = 0.0;
    for i in 0..k {
        if a[i] == 0.0 {
            continue;
        }
        let row = &g[i * k..(i + 1) * k];
        let mut gi = 0.0;
        for j in 0..k {
            gi += row[j] * a[j];
        }
        f += 0.5 * a[i] * gi - c[i] * a[i] + gamma * a[i].abs();
    }
    f
}

/// Largest violation of the L1 optimality conditions at `a`:
/// `|∇_j + γ sign(a_j)|` for non-zero `a_j`, `max(0, |∇_j| − γ)` for zero ones,
/// with `∇ = G a − c`.
pub fn l1_optimality_violation(g: &[f64], c: &[f64], gamma: f64, a: &[f64]) -> f64 {
    let k = c.len();
    let mut worst = 0.0f64;
    for j in 0..k {
        let row = &g[j * k..(j + 1) * k];
        let mut grad = -c[j];
        for i in 0..k {
            grad += row[i] * a[i];
        }
        let v = if a[j] != 0.0 {
            (grad + gamma * a[j].signum()).abs()
        } else {
            (grad.abs() - gamma).max(0.0)
        };
        worst = worst.max(v);
    }
    worst
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One feature-sign step from the warm start `a` (its non-zero entries active, with
    /// their signs), as `solve` sets it up: the step's outcome, the new code, the active
    /// set and its signs.
    fn one_step(
        g: &[f64],
        c: &[f64],
        gamma: f64,
        a: &[f64],
    ) -> (bool, Vec<f64>, Vec<usize>, Vec<f64>) {
        let mut fs = FeatureSign::new(c.len());
        for (j, &v) in a.iter().enumerate() {
            if v != 0.0 {
                fs.active.push(j);
                fs.theta.push(v.signum());
            }
        }
        let mut a = a.to_vec();
        let partial = matches!(fs.step(g, c, gamma, &mut a), Step::Partial);
        (partial, a, fs.active.clone(), fs.theta.clone())
    }

    #[test]
    fn the_line_search_keeps_the_best_of_the_segments_breakpoints_and_its_end() {
        // G = I and γ = 1, so the objective is separable, Σ_j h_j(a_j) with
        // h_j(a) = a²/2 − c_j a + |a|, and the sign-restricted minimiser z is c − θ.
        let g = [1.0, 0.0, 0.0, 1.0];
        // c = (3, −1), warm start (1, 1): z = (2, −2) leaves the second sign, so the step
        // searches the segment (1, 1) → (2, −2). F at the start: (0.5 − 3 + 1) + (0.5 + 1 +
        // 1) = 1; at the zero crossing t = 1/3, (4/3, 0): 8/9 − 4 + 4/3 = −16/9; at z:
        // (2 − 6 + 2) + (2 − 2 + 2) = 0. The crossing is best: the second basis leaves.
        let (partial, a, active, theta) = one_step(&g, &[3.0, -1.0], 1.0, &[1.0, 1.0]);
        assert!(partial);
        assert!((a[0] - 4.0 / 3.0).abs() < 1e-15 && a[1] == 0.0, "{a:?}");
        assert_eq!((active, theta), (vec![0], vec![1.0]));
        // c = (3, 0), warm start (10, 1): z = (2, −1), the crossing is at t = 1/2, (6, 0).
        // F at the start: (50 − 30 + 10) + (0.5 + 1) = 31.5; at the crossing 6; at z,
        // (2 − 6 + 2) + (0.5 + 1) = −0.5. The end of the segment is best: both stay, the
        // second with its new sign.
        let (partial, a, active, theta) = one_step(&g, &[3.0, 0.0], 1.0, &[10.0, 1.0]);
        assert!(partial);
        assert_eq!(a, vec![2.0, -1.0]);
        assert_eq!((active, theta), (vec![0, 1], vec![1.0, -1.0]));
    }

    #[test]
    fn a_singular_active_set_moves_along_its_null_direction_to_the_best_crossing() {
        // Atoms e₃, e₁, e₂ and e₁ + e₂ and x = (3, 2, 1): G = [[1, 0, 0, 0], [0, 1, 0, 1],
        // [0, 0, 1, 1], [0, 1, 1, 2]], c = D x = (1, 3, 2, 5). The fourth basis is the sum
        // of the second and third, so the Cholesky factor fails at it and the step moves
        // along v = (0, 1, 1, −1), which keeps a D (and with it the smooth part of F). From
        // (1, 2, 3, 1) (‖a‖₁ = 7) the zero crossings are (1, 3, 4, 0) (t = 1, ‖a‖₁ = 8),
        // (1, 0, 1, 3) (t = −2, 5) and (1, −1, 0, 4) (t = −3, 6): the second is taken. The
        // first basis, which v does not move, stays as it is.
        let g = [
            1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 1.0, 1.0, 2.0,
        ];
        let c = [1.0, 3.0, 2.0, 5.0];
        let (partial, a, active, theta) = one_step(&g, &c, 1.0, &[1.0, 2.0, 3.0, 1.0]);
        assert!(partial);
        assert_eq!(a, vec![1.0, 0.0, 1.0, 3.0]);
        assert_eq!((active, theta), (vec![0, 2, 3], vec![1.0; 3]));
    }

    #[test]
    fn the_coordinate_pass_minimises_each_coefficient_exactly_in_turn() {
        // G = [[2, 1, 0], [1, 2, 0], [0, 0, 1]], c = (4, −3, 0.5), γ = 1, from (1, 1, 0):
        // a₀ = S(4 − 1 · 1) / 2 = 1, then a₁ = S(−3 − 1 · 1) / 2 = −1.5, then a₂ = S(0.5) / 1
        // = 0, with S the soft threshold at γ.
        let g = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 1.0];
        let mut fs = FeatureSign::new(3);
        let mut a = [1.0, 1.0, 0.0];
        fs.coordinate_pass(&g, &[4.0, -3.0, 0.5], 1.0, &mut a);
        assert_eq!(a, [1.0, -1.5, 0.0]);
        assert_eq!((fs.active, fs.theta), (vec![0, 1], vec![1.0, -1.0]));
    }

    #[test]
    fn soft_threshold_shrinks_towards_zero_by_t() {
        for (x, want) in [
            (3.0, 2.0),
            (-3.0, -2.0),
            (0.5, 0.0),
            (-0.5, 0.0),
            (1.0, 0.0),
            (-1.0, 0.0),
        ] {
            assert_eq!(soft_threshold(x, 1.0), want, "S({x})");
        }
    }
}
