//! L2-regularised linear SVM by dual coordinate descent (Hsieh et al. 2008, the method of
//! liblinear's `solve_l2r_l1l2_svc`).
//!
//! Primal, with y_i ∈ {−1, +1}, per-sample costs C_i = C · weight(y_i) and the features
//! augmented by a constant `bias` (so the intercept is regularised, as in liblinear and
//! scikit-learn's `LinearSVC` with `intercept_scaling`):
//!
//! ```text
//! hinge:          min_w 0.5 ||w||² + Σ_i C_i max(0, 1 − y_i wᵀx_i)
//! squared hinge:  min_w 0.5 ||w||² + Σ_i C_i max(0, 1 − y_i wᵀx_i)²
//! ```
//!
//! Dual: `min_α 0.5 αᵀ(Q + Dg)α − Σα_i`, `0 ≤ α_i ≤ U_i`, with `Q_ij = y_i y_j x_iᵀx_j`,
//! and (U_i, Dg_ii) = (C_i, 0) for the hinge, (∞, 1/(2C_i)) for the squared hinge; one
//! coordinate at a time in a seeded random order, with liblinear's shrinking, until the
//! projected gradient's spread falls below `tol`. `w = Σ α_i y_i x_i` is kept up to date,
//! so an epoch costs O(nnz). Features are standardised on the training data only
//! (`standardize`), and the same scaling is applied at prediction.

use ndarray::linalg::general_mat_mul;
use ndarray::{Array1, ArrayView1, ArrayView2, ArrayViewMut2, s};
use serde::{Deserialize, Serialize};

use super::SvmError;
use crate::features::Standardizer;
use crate::linalg::dense;
use crate::rng::Rng;

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Loss {
    /// L1-loss SVM (the classic soft margin).
    #[default]
    Hinge,
    /// L2-loss SVM (liblinear's and scikit-learn `LinearSVC`'s default).
    SquaredHinge,
}

/// Per-class multipliers of C.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize, Default)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum ClassWeight {
    /// Every sample costs C.
    Uniform,
    /// weight(class) = N / (2 N_class) (scikit-learn's "balanced"): both classes weigh
    /// the same in total, which is what the weighted success rate rewards.
    #[default]
    Balanced,
    /// Explicit multipliers for the negative (false) and positive (true) class.
    Custom { negative: f64, positive: f64 },
}

/// How the optimisation problem is solved (both give the same optimum).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    /// Primal Newton for the squared hinge, dual coordinate descent for the hinge.
    #[default]
    Auto,
    /// Dual coordinate descent with shrinking (liblinear), either loss.
    DualCoordinateDescent,
    /// Finite Newton on the primal (Keerthi & DeCoste 2005), squared hinge only.
    PrimalNewton,
}

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearSvmParams {
    pub c: f64,
    pub loss: Loss,
    pub class_weight: ClassWeight,
    /// Value of the constant feature that carries the intercept (0: no intercept).
    pub bias: f64,
    /// z-score every feature on the training data (and the same at prediction).
    pub standardize: bool,
    pub solver: Solver,
    /// Dual CD: stop when the projected gradient's max − min is below this (liblinear's
    /// eps). Primal Newton: stop when ||∇||∞ ≤ tol · 1e-3.
    pub tol: f64,
    /// Dual CD: passes over the data; primal Newton: Newton steps.
    pub max_epochs: usize,
    /// Seed of the coordinate order.
    pub seed: u64,
}

impl Default for LinearSvmParams {
    fn default() -> Self {
        LinearSvmParams {
            c: 1.0,
            loss: Loss::Hinge,
            class_weight: ClassWeight::Balanced,
            bias: 1.0,
            standardize: true,
            solver: Solver::Auto,
            tol: 1e-3,
            max_epochs: 1000,
            seed: 0,
        }
    }
}

/// A trained linear SVM. Decision value `weights · x + intercept` on raw inputs (the
/// standardisation is folded in); positive means the positive (true) class.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LinearSvm {
    /// Weights on the raw (un-standardised) features.
    pub weights: Array1<f64>,
    pub intercept: f64,
    /// Weights on the standardised features (what the optimiser solved for), for
    /// comparing feature relevance; the last entry multiplies the bias feature.
    pub weights_standardized: Array1<f64>,
    pub scaler: Option<Standardizer>,
    pub epochs: usize,
    pub converged: bool,
    /// Samples with α > 0.
    pub support_vectors: usize,
    /// Primal and dual objective at the solution (their gap certifies optimality).
    pub primal_objective: f64,
    pub dual_objective: f64,
}

impl LinearSvmParams {
    pub fn validate(&self) -> Result<(), SvmError> {
        let bad = |m: String| Err(SvmError::Param(m));
        if !(self.c > 0.0 && self.c.is_finite()) {
            return bad(format!("C must be finite and > 0, got {}", self.c));
        }
        if !(self.bias >= 0.0 && self.bias.is_finite()) {
            return bad(format!("bias must be finite and ≥ 0, got {}", self.bias));
        }
        if self.tol.is_nan() || self.tol <= 0.0 {
            return bad(format!("tol must be > 0, got {}", self.tol));
        }
        if self.max_epochs == 0 {
            return bad("max_epochs must be at least 1".into());
        }
        if let ClassWeight::Custom { negative, positive } = self.class_weight
            && !(negative > 0.0 && positive > 0.0 && negative.is_finite() && positive.is_finite())
        {
            return bad(format!(
                "class weights must be finite and > 0, got {negative}, {positive}"
            ));
        }
        Ok(())
    }

    /// The solver `Auto` stands for with this loss.
    pub fn resolved_solver(&self) -> Solver {
        match (self.solver, self.loss) {
            (Solver::Auto, Loss::SquaredHinge) | (Solver::PrimalNewton, _) => Solver::PrimalNewton,
            _ => Solver::DualCoordinateDescent,
        }
    }

    /// Per-class cost multipliers (negative, positive) for these labels.
    pub fn class_costs(&self, y: &[bool]) -> (f64, f64) {
        match self.class_weight {
            ClassWeight::Uniform => (self.c, self.c),
            ClassWeight::Balanced => {
                let n = y.len() as f64;
                let pos = y.iter().filter(|v| **v).count() as f64;
                let neg = n - pos;
                (self.c * n / (2.0 * neg), self.c * n / (2.0 * pos))
            }
            ClassWeight::Custom { negative, positive } => (self.c * negative, self.c * positive),
        }
    }

    /// Train on the rows of `x` with labels `y` (true = positive class).
    pub fn fit(&self, x: ArrayView2<f64>, y: &[bool]) -> Result<LinearSvm, SvmError> {
        self.fit_from(x, y, None)
    }

    /// Train starting from another model's decision function (used by the primal Newton
    /// solver; cross validation starts every fold from the all-data model, which halves
    /// the Newton steps). The optimum reached is the same as from zero.
    pub fn fit_from(
        &self,
        x: ArrayView2<f64>,
        y: &[bool],
        init: Option<&LinearSvm>,
    ) -> Result<LinearSvm, SvmError> {
        let all: Vec<usize> = (0..x.nrows()).collect();
        self.fit_rows(x, &all, y, init, &mut SvmWorkspace::default())
    }

    /// [`LinearSvmParams::fit_from`] on the rows `rows` of `x` (in that order; `y[r]` is
    /// the label of row `rows[r]`), with the solver's buffers in `ws`: the same model as
    /// fitting the gathered rows, without the copy, and without fresh buffers when `ws`
    /// is reused (cross validation fits many folds of one size).
    pub fn fit_rows(
        &self,
        x: ArrayView2<f64>,
        rows: &[usize],
        y: &[bool],
        init: Option<&LinearSvm>,
        ws: &mut SvmWorkspace,
    ) -> Result<LinearSvm, SvmError> {
        self.validate()?;
        let (n, d) = (rows.len(), x.ncols());
        if n != y.len() {
            return Err(SvmError::Data(format!(
                "{n} samples but {} labels",
                y.len()
            )));
        }
        if n == 0 || d == 0 {
            return Err(SvmError::Data(format!("no training data ({n} × {d})")));
        }
        if let Some(&i) = rows.iter().find(|&&i| i >= x.nrows()) {
            return Err(SvmError::Data(format!(
                "row {i} of {} requested",
                x.nrows()
            )));
        }
        let pos = y.iter().filter(|v| **v).count();
        if pos == 0 || pos == n {
            return Err(SvmError::Data(
                "the training data hold a single class; an SVM needs both".into(),
            ));
        }
        for (r, &i) in rows.iter().enumerate() {
            let row = x.row(i);
            // (A fold without early exit is branch-free; the position only on failure.)
            if !row.fold(true, |ok, v| ok & v.is_finite())
                && let Some(j) = row.iter().position(|v| !v.is_finite())
            {
                return Err(SvmError::Data(format!(
                    "sample {r} feature {j} is not finite"
                )));
            }
        }
        let scaler = self.standardize.then(|| Standardizer::fit_rows(x, rows));
        // Augmented, standardised rows, contiguous with stride d + 1.
        let stride = d + 1;
        let mut xs = std::mem::take(&mut ws.xs);
        xs.resize(n * stride, 0.0);
        for (r, &i) in rows.iter().enumerate() {
            let row = x.row(i);
            let out = &mut xs[r * stride..(r + 1) * stride];
            match &scaler {
                Some(s) => s.transform_into(row, &mut out[..d]),
                None => out[..d]
                    .iter_mut()
                    .zip(row.iter())
                    .for_each(|(o, v)| *o = *v),
            }
            out[d] = self.bias;
        }
        let fit = self.solve(&xs, stride, y, init, scaler, ws);
        ws.xs = xs;
        fit
    }

    /// Solve on the augmented, standardised rows `xs` (stride d + 1).
    fn solve(
        &self,
        xs: &[f64],
        stride: usize,
        y: &[bool],
        init: Option<&LinearSvm>,
        scaler: Option<Standardizer>,
        ws: &mut SvmWorkspace,
    ) -> Result<LinearSvm, SvmError> {
        let (n, d) = (y.len(), stride - 1);
        let (c_neg, c_pos) = self.class_costs(y);
        let cost = |i: usize| if y[i] { c_pos } else { c_neg };
        let (upper, diag): (Vec<f64>, Vec<f64>) = (0..n)
            .map(|i| match self.loss {
                Loss::Hinge => (cost(i), 0.0),
                Loss::SquaredHinge => (f64::INFINITY, 0.5 / cost(i)),
            })
            .unzip();
        let ys: Vec<f64> = y.iter().map(|&v| if v { 1.0 } else { -1.0 }).collect();
        let costs: Vec<f64> = (0..n).map(cost).collect();
        let prob = Problem {
            xs,
            stride,
            ys: &ys,
            costs: &costs,
            diag: &diag,
            upper: &upper,
        };
        let solver = self.resolved_solver();
        if solver == Solver::PrimalNewton && self.loss == Loss::Hinge {
            return Err(SvmError::Param(
                "the primal Newton solver needs the squared hinge (the hinge is not differentiable)"
                    .into(),
            ));
        }
        let (w, alpha, epochs, converged) = match solver {
            Solver::PrimalNewton => {
                let w0 = init.filter(|m| m.weights.len() == d).map(|m| {
                    let mut w0 = vec![0.0; stride];
                    let mut b = m.intercept;
                    for (j, (w0j, wj)) in w0.iter_mut().zip(m.weights.iter()).enumerate() {
                        let (mean, sd) = match &scaler {
                            Some(sc) => (sc.mean[j], sc.sd[j]),
                            None => (0.0, 1.0),
                        };
                        *w0j = wj * sd;
                        b += wj * mean;
                    }
                    if self.bias > 0.0 {
                        w0[d] = b / self.bias;
                    }
                    w0
                });
                primal_newton(&prob, w0, self.tol, self.max_epochs, ws)
            }
            _ => dual_cd(&prob, self.tol, self.max_epochs, self.seed),
        };
        // Objectives (primal over all samples; dual from α).
        let mut primal = 0.5 * dot(&w, &w);
        let mut dual = -0.5 * dot(&w, &w);
        let mut wx = vec![0.0; n];
        for_rows(xs, stride, &mut wx, |rows| sequential_dots(rows, &w));
        for i in 0..n {
            let margin = (1.0 - ys[i] * wx[i]).max(0.0);
            primal += cost(i)
                * match self.loss {
                    Loss::Hinge => margin,
                    Loss::SquaredHinge => margin * margin,
                };
            dual += alpha[i] - 0.5 * diag[i] * alpha[i] * alpha[i];
        }
        let support_vectors = alpha.iter().filter(|a| **a > 0.0).count();
        let w_std = Array1::from_vec(w);
        let (weights, intercept) = match &scaler {
            Some(sc) => {
                let mut wr = Array1::<f64>::zeros(d);
                let mut b = w_std[d] * self.bias;
                for j in 0..d {
                    wr[j] = w_std[j] / sc.sd[j];
                    b -= wr[j] * sc.mean[j];
                }
                (wr, b)
            }
            None => (w_std.slice(s![..d]).to_owned(), w_std[d] * self.bias),
        };
        Ok(LinearSvm {
            weights,
            intercept,
            weights_standardized: w_std,
            scaler,
            epochs,
            converged,
            support_vectors,
            primal_objective: primal,
            dual_objective: dual,
        })
    }
}

/// Buffers of a fit, reused across fits (the folds of a cross validation): the
/// augmented, standardised rows, and the primal Newton solver's Hessian, its factor and
/// the scaled violator rows. Each fit writes every value it reads, so a workspace carries
/// no state from one fit to the next, only capacity.
#[derive(Debug, Default)]
pub struct SvmWorkspace {
    xs: Vec<f64>,
    h: Vec<f64>,
    l: Vec<f64>,
    xv: Vec<f64>,
}

/// The training problem on augmented, standardised rows (stride = features + 1).
struct Problem<'a> {
    xs: &'a [f64],
    stride: usize,
    ys: &'a [f64],
    costs: &'a [f64],
    /// Dual diagonal term: 0 (hinge) or 1/(2 C_i) (squared hinge).
    diag: &'a [f64],
    /// Dual upper bound: C_i (hinge) or ∞ (squared hinge).
    upper: &'a [f64],
}

impl Problem<'_> {
    fn row(&self, i: usize) -> &[f64] {
        &self.xs[i * self.stride..(i + 1) * self.stride]
    }

    /// `dense::dot(v, x_i)` of every row into `out`.
    fn dots(&self, v: &[f64], out: &mut [f64]) {
        for_rows(self.xs, self.stride, out, |rows| dense::dot_rows(rows, v));
    }
}

/// `out[i] = f(rows)[i − first]` for the rows of `xs` (stride `stride`), four at a time:
/// their sums are independent, so four run side by side instead of one after the other
/// (each is still the same sum in the same order). The last rows, fewer than four, are
/// passed again among the four and their duplicates dropped.
fn for_rows(
    xs: &[f64],
    stride: usize,
    out: &mut [f64],
    f: impl Fn([&[f64]; dense::ROWS]) -> [f64; dense::ROWS],
) {
    let n = out.len();
    let row = |i: usize| &xs[i * stride..(i + 1) * stride];
    for first in (0..n).step_by(dense::ROWS) {
        let rows = std::array::from_fn(|m| row((first + m).min(n - 1)));
        let sums = f(rows);
        let take = dense::ROWS.min(n - first);
        out[first..first + take].copy_from_slice(&sums[..take]);
    }
}

/// [`dot`] of each of four rows with `v`, summed as [`dot`] sums it (in order, from −0).
#[inline]
fn sequential_dots(rows: [&[f64]; dense::ROWS], v: &[f64]) -> [f64; dense::ROWS] {
    let rows = rows.map(|r| &r[..v.len()]);
    let mut sums = [-0.0f64; dense::ROWS];
    for (t, vt) in v.iter().enumerate() {
        for (s, r) in sums.iter_mut().zip(&rows) {
            *s += r[t] * vt;
        }
    }
    sums
}

/// Dual coordinate descent with shrinking (liblinear's solve_l2r_l1l2_svc).
/// Returns (w, α, epochs, converged).
fn dual_cd(
    p: &Problem,
    tol: f64,
    max_epochs: usize,
    seed: u64,
) -> (Vec<f64>, Vec<f64>, usize, bool) {
    let n = p.ys.len();
    let stride = p.stride;
    let (xs, ys, diag, upper) = (p.xs, p.ys, p.diag, p.upper);
    let qd: Vec<f64> = (0..n).map(|i| diag[i] + dot(p.row(i), p.row(i))).collect();
    let mut alpha = vec![0.0; n];
    let mut w = vec![0.0; stride];
    let mut index: Vec<usize> = (0..n).collect();
    let mut active = n;
    let mut rng = Rng::stream(seed, 0x5_7A);
    let (mut pg_max_old, mut pg_min_old) = (f64::INFINITY, f64::NEG_INFINITY);
    let mut epochs = 0;
    let mut converged = false;
    while epochs < max_epochs {
        epochs += 1;
        let (mut pg_max, mut pg_min) = (f64::NEG_INFINITY, f64::INFINITY);
        rng.shuffle(&mut index[..active]);
        let mut s = 0;
        while s < active {
            let i = index[s];
            let xi = &xs[i * stride..(i + 1) * stride];
            let g = ys[i] * dot(&w, xi) - 1.0 + alpha[i] * diag[i];
            let mut pg = 0.0;
            if alpha[i] == 0.0 {
                if g > pg_max_old {
                    active -= 1;
                    index.swap(s, active);
                    continue;
                } else if g < 0.0 {
                    pg = g;
                }
            } else if alpha[i] == upper[i] {
                if g < pg_min_old {
                    active -= 1;
                    index.swap(s, active);
                    continue;
                } else if g > 0.0 {
                    pg = g;
                }
            } else {
                pg = g;
            }
            pg_max = pg_max.max(pg);
            pg_min = pg_min.min(pg);
            if pg.abs() > 1e-12 {
                let old = alpha[i];
                alpha[i] = (old - g / qd[i]).max(0.0).min(upper[i]);
                let step = (alpha[i] - old) * ys[i];
                for (wj, xj) in w.iter_mut().zip(xi) {
                    *wj += step * xj;
                }
            }
            s += 1;
        }
        if pg_max - pg_min <= tol {
            if active == n {
                converged = true;
                break;
            }
            // Shrunk samples may have been wrong: one more pass over everything.
            active = n;
            pg_max_old = f64::INFINITY;
            pg_min_old = f64::NEG_INFINITY;
            continue;
        }
        pg_max_old = if pg_max <= 0.0 { f64::INFINITY } else { pg_max };
        pg_min_old = if pg_min >= 0.0 {
            f64::NEG_INFINITY
        } else {
            pg_min
        };
    }
    (w, alpha, epochs, converged)
}

/// Columns per block of the Hessian's product (a multiple of the product kernel's widths).
const GRAM_BLOCK: usize = 32;

/// Finite Newton on the primal of the squared-hinge SVM: with the set of margin
/// violators fixed the objective is quadratic, so each step solves
/// `(I + 2 Σ_viol C_i x_i x_iᵀ) p = −∇f` and an exact line search along p (the objective
/// is a convex piecewise quadratic in the step) picks the next point. It terminates when
/// the violator set stops changing, typically in 5–15 steps whatever the conditioning.
/// The Hessian is updated by rank-one terms for the samples entering or leaving the
/// violator set. Returns (w, α with α_i = 2 C_i max(0, 1 − y_i wᵀx_i), steps, converged).
fn primal_newton(
    p: &Problem,
    w0: Option<Vec<f64>>,
    tol: f64,
    max_steps: usize,
    ws: &mut SvmWorkspace,
) -> (Vec<f64>, Vec<f64>, usize, bool) {
    let n = p.ys.len();
    let d = p.stride;
    let mut w = w0.unwrap_or_else(|| vec![0.0; d]);
    let mut o = vec![0.0; n];
    p.dots(&w, &mut o);
    for (oi, yi) in o.iter_mut().zip(p.ys) {
        *oi *= yi;
    }
    let mut delta = vec![0.0; n];
    let mut steps = 0;
    let mut converged = false;
    let gtol = 1e-3 * tol;
    // H = I + 2 Σ_{i ∈ in_h} C_i x_i x_iᵀ, lower triangle (the first step builds it whole,
    // so nothing of an earlier problem in `ws` is read).
    let SvmWorkspace { h, l, xv, .. } = ws;
    h.resize(d * d, 0.0);
    l.resize(d * d, 0.0);
    let mut in_h = vec![false; n];
    let mut built = false;
    let mut dir = vec![0.0; d];
    let mut g = vec![0.0; d];
    while steps < max_steps {
        // Gradient w − 2 Σ_viol C_i (1 − o_i) y_i x_i.
        g.copy_from_slice(&w);
        let mut changes = 0;
        let mut viol = 0;
        for i in 0..n {
            let v = o[i] < 1.0;
            if v {
                viol += 1;
                let f = -2.0 * p.costs[i] * (1.0 - o[i]) * p.ys[i];
                for (gj, xj) in g.iter_mut().zip(p.row(i)) {
                    *gj += f * xj;
                }
            }
            changes += (v != in_h[i]) as usize;
        }
        let gmax = g.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        if gmax <= gtol {
            converged = true;
            break;
        }
        steps += 1;
        if !built || 2 * changes > viol {
            // Rebuild: I + 2 X_Vᵀ diag(C) X_V by a matrix product (into H whole; only its
            // lower triangle is kept up to date and read).
            xv.resize(viol * d, 0.0);
            let mut r = 0;
            for i in 0..n {
                in_h[i] = o[i] < 1.0;
                if in_h[i] {
                    let s = (2.0 * p.costs[i]).sqrt();
                    for (o2, v) in xv[r * d..(r + 1) * d].iter_mut().zip(p.row(i)) {
                        *o2 = s * v;
                    }
                    r += 1;
                }
            }
            let xv = ArrayView2::from_shape((viol, d), &xv[..viol * d]).expect("viol × d");
            let mut full = ArrayViewMut2::from_shape((d, d), &mut h[..]).expect("d × d");
            // By blocks of columns, each from its diagonal down: about 60 % of the whole
            // product's work. Every entry is the same sum in the same order as in one
            // product of the whole (the blocking splits the output, not the sum).
            for j0 in (0..d).step_by(GRAM_BLOCK) {
                let cols = j0..(j0 + GRAM_BLOCK).min(d);
                general_mat_mul(
                    1.0,
                    &xv.slice(s![.., j0..]).t(),
                    &xv.slice(s![.., cols.clone()]),
                    0.0,
                    &mut full.slice_mut(s![j0.., cols]),
                );
            }
            for a in 0..d {
                for b in 0..=a {
                    h[a * d + b] += if a == b { 1.0 } else { 0.0 };
                }
            }
            built = true;
        } else {
            for i in 0..n {
                let v = o[i] < 1.0;
                if v != in_h[i] {
                    in_h[i] = v;
                    let s = if v {
                        2.0 * p.costs[i]
                    } else {
                        -2.0 * p.costs[i]
                    };
                    let x = p.row(i);
                    for a in 0..d {
                        let f = s * x[a];
                        for (hb, xb) in h[a * d..a * d + a + 1].iter_mut().zip(&x[..=a]) {
                            *hb += f * xb;
                        }
                    }
                }
            }
        }
        // (The factorisation reads the lower triangle only.)
        if dense::cholesky(d, h, l).is_err() {
            break;
        }
        g.iter_mut().for_each(|v| *v = -*v);
        dense::chol_solve(d, d, l, &g, &mut dir);
        // Exact line search: φ'(t) = wᵀp + t pᵀp − 2 Σ C_i max(0, 1 − o_i − t δ_i) δ_i.
        let wp = dense::dot(&w, &dir);
        let pp = dense::dot(&dir, &dir);
        p.dots(&dir, &mut delta);
        for (di, yi) in delta.iter_mut().zip(p.ys) {
            *di *= yi;
        }
        let dphi = |t: f64| -> (f64, f64) {
            let (mut d1, mut d2) = (wp + t * pp, pp);
            for i in 0..n {
                let m = 1.0 - o[i] - t * delta[i];
                if m > 0.0 {
                    d1 -= 2.0 * p.costs[i] * m * delta[i];
                    d2 += 2.0 * p.costs[i] * delta[i] * delta[i];
                }
            }
            (d1, d2)
        };
        let mut t = 1.0;
        for _ in 0..50 {
            let (d1, d2) = dphi(t);
            if d1.abs() <= 1e-13 * (1.0 + wp.abs()) || d2 <= 0.0 {
                break;
            }
            let nt = (t - d1 / d2).max(0.0);
            let done = (nt - t).abs() <= 1e-15 * t.abs().max(1.0);
            t = nt;
            if done {
                break;
            }
        }
        for (wj, pj) in w.iter_mut().zip(&dir) {
            *wj += t * pj;
        }
        for i in 0..n {
            o[i] += t * delta[i];
        }
    }
    let mut alpha = vec![0.0; n];
    p.dots(&w, &mut alpha);
    for ((ai, yi), ci) in alpha.iter_mut().zip(p.ys).zip(p.costs) {
        let oi = yi * *ai;
        *ai = 2.0 * ci * (1.0 - oi).max(0.0);
    }
    (w, alpha, steps, converged)
}

#[inline]
fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl LinearSvm {
    /// Decision value of one sample (positive: the positive class).
    pub fn decision(&self, x: ArrayView1<f64>) -> f64 {
        x.dot(&self.weights) + self.intercept
    }

    pub fn predict(&self, x: ArrayView1<f64>) -> bool {
        self.decision(x) > 0.0
    }

    /// Predictions for every row.
    pub fn predict_all(&self, x: ArrayView2<f64>) -> Vec<bool> {
        x.rows().into_iter().map(|r| self.predict(r)).collect()
    }
}
