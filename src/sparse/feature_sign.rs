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
//! The Cholesky factor of the active Gram matrix is kept across steps and updated as the
//! active set changes instead of refactorised: an activation appends a row (one forward
//! substitution, the same numbers a new factor would have), a coefficient that reaches
//! zero removes its row and column by Givens rotations. Where an update loses positive
//! definiteness at rounding level, the rows it touched are factorised afresh.
//!
//! All buffers live in the [`FeatureSign`] workspace: after the first call, solving
//! allocates nothing.

use crate::linalg::dense::{chol_append, chol_delete, chol_solve};

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
    /// The active Gram matrix `G[active, active]` (row stride = active set size).
    gs: Vec<f64>,
    /// Cholesky factor of the active Gram matrix (row stride k), valid in its first
    /// `factored` rows (those of `active[..factored]`); the later rows are appended at
    /// the next step.
    l: Vec<f64>,
    factored: usize,
    /// Givens rotations of a deletion.
    rot: Vec<f64>,
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
            factored: 0,
            rot: vec![0.0; 2 * k],
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

        // The warm start's active set without a branch on each coefficient (whether it is
        // zero follows no pattern a predictor learns): every j is written at the next free
        // place, which moves on only when j is kept.
        self.active.resize(k, 0);
        self.theta.resize(k, 0.0);
        self.factored = 0;
        let mut kept = 0;
        for j in 0..k {
            let v = a[j];
            let nonzero = v != 0.0;
            let keep = nonzero & v.is_finite() & (g[j * k + j] > 0.0);
            self.active[kept] = j;
            self.theta[kept] = v.signum();
            kept += usize::from(keep);
            if !keep && v.to_bits() != 0 {
                // Not finite, on a zero basis, or −0: a plain zero.
                a[j] = 0.0;
            }
        }
        self.active.truncate(kept);
        self.theta.truncate(kept);
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
            // violating zero coefficient, and the optimality of the active ones (the
            // non-zero coefficients are exactly the active ones here).
            for (gr, cj) in self.grad.iter_mut().zip(c) {
                *gr = -cj;
            }
            for &i in &self.active {
                let ai = a[i];
                for (gr, gij) in self.grad.iter_mut().zip(&g[i * k..(i + 1) * k]) {
                    *gr += ai * gij;
                }
            }
            let (best, best_j) = most_violating(&self.grad, a, g, k);
            let mut active_violation = 0.0f64;
            for &i in &self.active {
                active_violation =
                    active_violation.max((self.grad[i] + gamma * a[i].signum()).abs());
            }
            if best_j != usize::MAX && best > gamma + act_tol {
                // Activate it with the sign that decreases the objective.
                self.active.push(best_j);
                self.theta.push(-self.grad[best_j].signum());
                continue;
            }
            // The tolerance scales with max(γ, max |c|), needed only when the violation
            // exceeds its smallest value.
            if active_violation > 1e-11 * (1.0 + gamma)
                && active_violation > 1e-11 * (1.0 + c.iter().fold(gamma, |m, cj| m.max(cj.abs())))
            {
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
            self.rhs[p] = c[i] - gamma * self.theta[p];
            self.cur[p] = a[i];
        }
        // Append the rows of the bases activated since the factor was last valid (each
        // needs its row of the active Gram matrix up to the diagonal).
        self.gather_gram(g, self.factored..s, false);
        while self.factored < s {
            let p = self.factored;
            if !chol_append(p, k, &mut self.l, &self.gs[p * s..p * s + p + 1]) {
                self.gather_gram(g, 0..s, true);
                return self.null_step(p, c, gamma, a);
            }
            self.factored += 1;
        }
        chol_solve(s, k, &self.l, &self.rhs[..s], &mut self.z[..s]);
        if (0..s).all(|p| self.z[p] * self.theta[p] > 0.0) {
            for p in 0..s {
                a[self.active[p]] = self.z[p];
            }
            return Step::Full;
        }
        // The line search reads the whole active Gram matrix.
        self.gather_gram(g, 0..s, true);
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

    /// Rows `rows` of the active Gram matrix `G[active, active]` into `gs` (stride: the
    /// active set's size), whole or up to their diagonal.
    fn gather_gram(&mut self, g: &[f64], rows: std::ops::Range<usize>, whole: bool) {
        let (k, s) = (self.k, self.active.len());
        for p in rows {
            let gi = &g[self.active[p] * k..(self.active[p] + 1) * k];
            let width = if whole { s } else { p + 1 };
            for (gpq, &j) in self.gs[p * s..p * s + width].iter_mut().zip(&self.active) {
                *gpq = gi[j];
            }
        }
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
        chol_solve(r, self.k, &self.l, &self.rhs[..r], &mut self.z[..r]);
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

    /// Drop zero coefficients from the active set (and their rows and columns from the
    /// factor) and reset θ to the current signs.
    fn compact(&mut self, a: &[f64]) {
        // Last position first: the earlier ones keep their place in the factor.
        for p in (0..self.factored).rev() {
            if a[self.active[p]] == 0.0 {
                if chol_delete(self.factored, self.k, &mut self.l, p, &mut self.rot) {
                    self.factored -= 1;
                } else {
                    // Lost positive definiteness at rounding level: refactorise the rows
                    // the update touched.
                    self.factored = p;
                }
            }
        }
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
        self.factored = 0;
        for (j, &v) in a.iter().enumerate() {
            if v != 0.0 {
                self.active.push(j);
                self.theta.push(v.signum());
            }
        }
    }
}

/// The zero coefficient to activate: the first j with `a_j = 0` and `G_jj > 0` whose
/// `|∇_j|` is the largest, and that value; `(0, usize::MAX)` when none is positive.
/// One branch-free pass in four lanes, each keeping its largest value and the first index
/// holding it (a maximum does not round, so the lanes' order does not matter); the first
/// index overall is the smallest among the lanes holding the largest value. Only when that
/// index is a zero basis (`G_jj = 0`, rare) is the eligible set scanned coefficient by
/// coefficient. The answer is that of the direct scan in every case.
fn most_violating(grad: &[f64], a: &[f64], g: &[f64], k: usize) -> (f64, usize) {
    let masked = |gr: f64, aj: f64| if aj == 0.0 { gr.abs() } else { 0.0 };
    let mut lanes = [0.0f64; 4];
    let mut at = [usize::MAX; 4];
    let mut take = |l: usize, j: usize, v: f64| {
        let better = v > lanes[l];
        lanes[l] = if better { v } else { lanes[l] };
        at[l] = if better { j } else { at[l] };
    };
    let (gc, ac) = (grad.chunks_exact(4), a.chunks_exact(4));
    let (gr_rest, a_rest) = (gc.remainder(), ac.remainder());
    let whole = grad.len() - gr_rest.len();
    for (c, (gq, aq)) in gc.zip(ac).enumerate() {
        for l in 0..4 {
            take(l, 4 * c + l, masked(gq[l], aq[l]));
        }
    }
    for (l, (gr, aj)) in gr_rest.iter().zip(a_rest).enumerate() {
        take(l, whole + l, masked(*gr, *aj));
    }
    let best = lanes.iter().fold(0.0f64, |m, &v| if v > m { v } else { m });
    if best == 0.0 {
        return (0.0, usize::MAX);
    }
    let first = (0..4)
        .filter(|&l| lanes[l] == best)
        .map(|l| at[l])
        .min()
        .expect("a lane holds the largest value");
    if g[first * k + first] > 0.0 {
        return (best, first);
    }
    let (mut best, mut best_j) = (0.0, usize::MAX);
    for j in 0..k {
        let grad = grad[j].abs();
        if a[j] == 0.0 && grad > best && g[j * k + j] > 0.0 {
            best = grad;
            best_j = j;
        }
    }
    (best, best_j)
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

    /// G = D Dᵀ and c = D x of a random dictionary (K × n, unit rows) and patch.
    fn random_problem(rng: &mut crate::rng::Rng, k: usize, n: usize) -> (Vec<f64>, Vec<f64>) {
        let mut d: Vec<f64> = (0..k * n).map(|_| rng.normal()).collect();
        for row in d.chunks_mut(n) {
            let nrm = row.iter().map(|v| v * v).sum::<f64>().sqrt();
            row.iter_mut().for_each(|v| *v /= nrm);
        }
        let x: Vec<f64> = (0..n).map(|_| 2.0 * rng.normal()).collect();
        let g = (0..k * k)
            .map(|ij| dot(&d[ij / k * n..][..n], &d[ij % k * n..][..n]))
            .collect();
        let c = (0..k).map(|j| dot(&d[j * n..][..n], &x)).collect();
        (g, c)
    }

    /// A new factor of the active Gram matrix of `fs`, at stride k.
    fn fresh_factor(fs: &FeatureSign, g: &[f64]) -> Vec<f64> {
        let (k, act) = (fs.k, &fs.active);
        let mut l = vec![0.0; k * k];
        for p in 0..act.len() {
            let row: Vec<f64> = act[..=p].iter().map(|&q| g[act[p] * k + q]).collect();
            assert!(chol_append(p, k, &mut l, &row));
        }
        l
    }

    use crate::linalg::dense::{chol_append, chol_solve, dot};

    #[test]
    fn the_kept_factor_is_the_factor_of_the_active_set() {
        // Warm starts from the previous patch's code make coefficients leave the active
        // set (updates by rotation) besides entering it (appends). After every solve the
        // kept factor L must be that of the final active Gram matrix A (s × s): L Lᵀ = A
        // to 10 s u ‖A‖_F (backward stability of Cholesky and of Givens updates), and L
        // a new factor to 10 s u κ ‖L‖, κ = ‖A‖_F ‖A⁻¹‖_F ≥ κ₂(A) (the factor's
        // perturbation is at most κ₂ times the relative backward error, Sun 1991).
        let (k, n) = (24, 16);
        let u = f64::EPSILON / 2.0;
        let mut fs = FeatureSign::new(k);
        let mut rng = crate::rng::Rng::new(11);
        let mut a = vec![0.0; k];
        let (mut deletions, mut checked) = (0, 0);
        for _ in 0..200 {
            let (g, c) = random_problem(&mut rng, k, n);
            let before: Vec<bool> = a.iter().map(|v| *v != 0.0).collect();
            assert!(fs.solve(&g, &c, 0.3, &mut a).converged);
            deletions += before
                .iter()
                .zip(&a)
                .filter(|(b, v)| **b && **v == 0.0)
                .count();
            let s = fs.active.len();
            if fs.factored < s {
                continue;
            }
            checked += 1;
            let fresh = fresh_factor(&fs, &g);
            let gs: Vec<f64> = (0..s * s)
                .map(|pq| g[fs.active[pq / s] * k + fs.active[pq % s]])
                .collect();
            let norm_a = dot(&gs, &gs).sqrt();
            let mut norm_inv = 0.0;
            let (mut e_p, mut col) = (vec![0.0; s], vec![0.0; s]);
            for q in 0..s {
                e_p.fill(0.0);
                e_p[q] = 1.0;
                chol_solve(s, k, &fresh, &e_p, &mut col);
                norm_inv += dot(&col, &col);
            }
            let kappa = norm_a * norm_inv.sqrt();
            let backward = 10.0 * s as f64 * u * norm_a;
            let forward = backward / norm_a * kappa * norm_a.sqrt();
            for p in 0..s {
                for q in 0..=p {
                    let lp = &fs.l[p * k..p * k + q + 1];
                    let e = (dot(lp, &fs.l[q * k..q * k + q + 1]) - gs[p * s + q]).abs();
                    assert!(e <= backward, "(L Lᵀ − A)[{p}][{q}] = {e:e}");
                    let e = (fs.l[p * k + q] - fresh[p * k + q]).abs();
                    assert!(e <= forward, "L[{p}][{q}] differs by {e:e} (κ {kappa:e})");
                }
            }
        }
        assert!(
            deletions > 100 && checked > 150,
            "{deletions} deletions, {checked} checked"
        );
    }

    #[test]
    fn a_deletion_that_loses_positive_definiteness_refactorises_the_rows_it_touched() {
        // Bases 0–4 active with a factor whose last row is lost (0): dropping the
        // coefficient at position 1 cannot update it, so the rows from 1 on are appended
        // afresh at the next step, which must then equal a new factor of the remaining
        // active set exactly (the same operations in the same order). c is chosen so that
        // the step's solution is a = 1 on the active set (a full step: the set stays).
        let (k, gamma) = (8, 0.1);
        let (g, _) = random_problem(&mut crate::rng::Rng::new(5), k, 12);
        let mut fs = FeatureSign::new(k);
        let mut a: Vec<f64> = (0..k).map(|j| if j < 5 { 0.5 } else { 0.0 }).collect();
        fs.active.extend(0..5);
        fs.theta.extend([1.0; 5]);
        fs.l = fresh_factor(&fs, &g);
        fs.factored = 5;
        fs.l[4 * k..4 * k + 5].fill(0.0);
        a[1] = 0.0;
        fs.compact(&a);
        assert_eq!((fs.active.clone(), fs.factored), (vec![0, 2, 3, 4], 1));
        let one: Vec<f64> = (0..k)
            .map(|j| f64::from(u8::from(fs.active.contains(&j))))
            .collect();
        let c: Vec<f64> = (0..k)
            .map(|i| dot(&g[i * k..(i + 1) * k], &one) + gamma)
            .collect();
        assert!(matches!(fs.step(&g, &c, gamma, &mut a), Step::Full));
        for (j, v) in a.iter().enumerate() {
            assert!((v - one[j]).abs() < 1e-12, "a[{j}] = {v}");
        }
        assert_eq!(fs.factored, 4);
        let fresh = fresh_factor(&fs, &g);
        for p in 0..4 {
            assert_eq!(
                fs.l[p * k..p * k + p + 1],
                fresh[p * k..p * k + p + 1],
                "row {p}"
            );
        }
    }

    /// The two-pass choice of the coefficient to activate equals the direct scan (the
    /// first eligible maximum of |∇_j| over zero coefficients with G_jj > 0), with tied
    /// gradients, active coefficients holding the largest gradient, zero bases, NaN and
    /// −0 among them, at every length around the four lanes.
    #[test]
    fn the_coefficient_to_activate_is_the_direct_scans() {
        let direct = |grad: &[f64], a: &[f64], g: &[f64], k: usize| {
            let (mut best, mut best_j) = (0.0, usize::MAX);
            for j in 0..k {
                if a[j] == 0.0 {
                    let v = grad[j].abs();
                    if v > best && g[j * k + j] > 0.0 {
                        best = v;
                        best_j = j;
                    }
                }
            }
            (best, best_j)
        };
        let mut rng = crate::rng::Rng::new(11);
        let values = [0.0, -0.0, 0.5, -0.5, 1.5, -1.5, 2.0, f64::NAN];
        let mut differing_from_the_plain_maximum = 0;
        for trial in 0..20_000 {
            let k = 1 + trial % 11;
            let pick = |rng: &mut crate::rng::Rng| values[rng.below(values.len())];
            let grad: Vec<f64> = (0..k).map(|_| pick(&mut rng)).collect();
            let a: Vec<f64> = (0..k)
                .map(|_| {
                    if rng.below(3) == 0 {
                        pick(&mut rng)
                    } else {
                        0.0
                    }
                })
                .collect();
            let mut g = vec![0.0; k * k];
            for j in 0..k {
                g[j * k + j] = if rng.below(4) == 0 { 0.0 } else { 1.0 };
            }
            let want = direct(&grad, &a, &g, k);
            let got = most_violating(&grad, &a, &g, k);
            assert_eq!(got.1, want.1, "grad {grad:?}, a {a:?}, g {g:?}");
            assert_eq!(got.0.to_bits(), want.0.to_bits());
            let plain = grad
                .iter()
                .zip(&a)
                .filter(|(_, aj)| **aj == 0.0)
                .map(|(gr, _)| gr.abs())
                .fold(0.0, f64::max);
            differing_from_the_plain_maximum += (plain != want.0) as usize;
        }
        // The zero bases made the slow path run.
        assert!(differing_from_the_plain_maximum > 100);
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
