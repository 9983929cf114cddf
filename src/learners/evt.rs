//! Extreme-value novelty of a multivariate Gaussian prediction: GU's cluster-creation score
//! (the second paper, eqs. 31–33), after Clifton, Hugueny & Tarassenko (2011), "Novelty
//! detection with multivariate extreme value statistics", J. Signal Process. Syst. 65, eqs.
//! 28–29, as the authors' `OnlineLocalMemOGP` uses it (OIESGP-NOTES Sec. 7).
//!
//! For X ~ N(μ, Σ) in n dimensions the density is f(x) = exp(−r²/2) / C_n with
//! C_n = (2π)^(n/2) |Σ|^(1/2) and r² the squared Mahalanobis radius. Then
//! - G_n(y) = P[f(X) ≤ y], the distribution of densities, for 0 < y ≤ 1/C_n;
//! - c_m = G_n⁻¹(1/m) and α_m = m c_m g_n(c_m), g_n = dG_n/dy, are the Weibull parameters of
//!   the minimum density among m draws;
//! - G_e(y) = 1 − exp(−(y/c_m)^α_m), and the novelty of an observation o is
//!   1 − G_e(f(o)) = exp(−(f(o)/c_m)^α_m).
//!
//! Everything is computed in log space: with n up to 34 and small predictive variances,
//! |Σ|, C_n and the densities leave the range of f64. Writing t = −2 ln(C_n y) (the squared
//! radius at which the density is y, i.e. the log-density measured down from the mode),
//! G_n depends on t alone and f(o)/c_m = exp((t_c − r²)/2): the normaliser cancels.

use serde::{Deserialize, Serialize};

use crate::special::{erfc, erfcx, ln_erfc, ln_gamma};

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvtError {
    #[error("invalid parameter `{name}`: {reason}")]
    InvalidParameter { name: &'static str, reason: String },
}

/// ln C_n = (n/2) ln 2π + ½ ln |Σ|.
pub fn ln_normaliser(n: usize, ln_det_sigma: f64) -> f64 {
    0.5 * n as f64 * (2.0 * std::f64::consts::PI).ln() + 0.5 * ln_det_sigma
}

/// ln(a + b) from ln a and ln b.
fn ln_add(ln_a: f64, ln_b: f64) -> f64 {
    let (hi, lo) = if ln_a >= ln_b {
        (ln_a, ln_b)
    } else {
        (ln_b, ln_a)
    };
    if hi == f64::NEG_INFINITY {
        return hi;
    }
    hi + (lo - hi).exp().ln_1p()
}

/// ln G_n at squared radius t ≥ 0, by the closed forms of Clifton et al. (2011), written in
/// x = t/2 (with y = exp(−x)/C_n the notes' prefactors y Ω_n |Σ|^½ reduce to exp(−x)):
/// - n = 2p:     G = exp(−x) Σ_{k<p} x^k / k!
/// - n = 2p + 1: G = erfc(√x) + exp(−x) Σ_{k<p} x^(k+½) / Γ(k + 3/2)   (n = 1: erfc(√x))
///
/// (the regularised upper incomplete gamma Q(n/2, x), i.e. the χ²_n tail at t). All terms
/// are positive, so the sum is accurate even in the far tail; exp(−x) is kept out of it (as
/// erfcx for the odd case) so that nothing underflows.
fn ln_tail(n: usize, t: f64) -> f64 {
    if t <= 0.0 {
        return 0.0;
    }
    if t == f64::INFINITY {
        return f64::NEG_INFINITY;
    }
    let x = 0.5 * t;
    let ln_x = x.ln();
    let p = n / 2;
    let even = n.is_multiple_of(2);
    // the largest term is below x^p, which must not overflow in linear space
    if (p as f64) * ln_x < 600.0 {
        let mut term = if even {
            1.0
        } else {
            x.sqrt() * std::f64::consts::FRAC_2_SQRT_PI
        };
        let mut sum = 0.0;
        for k in 0..p {
            if k > 0 {
                term *= x / if even { k as f64 } else { k as f64 + 0.5 };
            }
            sum += term;
        }
        if even {
            sum.ln() - x
        } else if x.sqrt() <= 0.468_75 {
            (erfc(x.sqrt()) + (-x).exp() * sum).ln()
        } else {
            (erfcx(x.sqrt()) + sum).ln() - x
        }
    } else if even {
        // the same sums in log space, for very large x or n
        let mut term = 0.0;
        let mut acc = f64::NEG_INFINITY;
        for k in 0..p {
            if k > 0 {
                term += ln_x - (k as f64).ln();
            }
            acc = ln_add(acc, term);
        }
        acc - x
    } else {
        let mut acc = ln_erfc(x.sqrt());
        let mut term = 0.5 * ln_x + std::f64::consts::FRAC_2_SQRT_PI.ln();
        for k in 0..p {
            if k > 0 {
                term += ln_x - (k as f64 + 0.5).ln();
            }
            acc = ln_add(acc, term - x);
        }
        acc
    }
}

/// ln of the χ²_n density at t > 0: ln p(t) = (n/2 − 1) ln t − t/2 − (n/2) ln 2 − ln Γ(n/2).
fn ln_chi2_pdf(n: usize, t: f64) -> f64 {
    ln_chi2_pdf_with(n, t, ln_gamma(0.5 * n as f64))
}

/// [`ln_chi2_pdf`] with ln Γ(n/2) given.
fn ln_chi2_pdf_with(n: usize, t: f64, ln_gamma_half_n: f64) -> f64 {
    let h = 0.5 * n as f64;
    (h - 1.0) * t.ln() - 0.5 * t - h * std::f64::consts::LN_2 - ln_gamma_half_n
}

/// G_n(y) = P[N(X | μ, Σ) ≤ y] for X ~ N(μ, Σ) in n ≥ 1 dimensions, from ln y and
/// ln C_n (see [`ln_normaliser`]). 1 for y ≥ 1/C_n (every density is at most the mode's),
/// 0 for y = 0; 0 also for n = 0 (no Gaussian) or a NaN argument.
pub fn density_cdf(n: usize, ln_c_n: f64, ln_y: f64) -> f64 {
    if n == 0 || ln_y.is_nan() || ln_c_n.is_nan() {
        return 0.0;
    }
    let t = -2.0 * (ln_y + ln_c_n);
    if t.is_nan() {
        return 0.0;
    }
    ln_tail(n, t).exp()
}

/// ln g_n(y), the density of densities dG_n/dy (Clifton et al. 2011):
/// g_n(y) = Ω_n |Σ|^½ (−2 ln(C_n y))^((n−2)/2), Ω_n = 2 π^(n/2) / Γ(n/2), for 0 < y < 1/C_n.
pub fn ln_density_pdf(n: usize, ln_det_sigma: f64, ln_y: f64) -> f64 {
    let h = 0.5 * n as f64;
    let ln_omega = std::f64::consts::LN_2 + h * std::f64::consts::PI.ln() - ln_gamma(h);
    let t = -2.0 * (ln_y + ln_normaliser(n, ln_det_sigma));
    ln_omega + 0.5 * ln_det_sigma + (h - 1.0) * t.ln()
}

/// The squared radius t_c with G_n = 1/m, i.e. ln G_n(t_c) = −ln m, for m ≥ 2.
///
/// ln G_n(t) falls strictly from 0 at t = 0, with derivative −p_χ²(t)/G_n(t): a bracket is
/// grown by doubling, then Newton steps are taken inside it, falling back to bisection
/// whenever a step would leave the bracket (a safeguarded Newton method, which always
/// converges on a monotone function).
fn radius_quantile(n: usize, m: usize) -> f64 {
    let target = -(m as f64).ln();
    let f = |t: f64| ln_tail(n, t) - target;
    let ln_gamma_half_n = ln_gamma(0.5 * n as f64);
    let (mut lo, mut hi) = (0.0_f64, (n as f64).max(1.0));
    while f(hi) > 0.0 {
        lo = hi;
        hi *= 2.0;
    }
    let mut t = 0.5 * (lo + hi);
    for _ in 0..200 {
        let ft = f(t);
        if ft == 0.0 {
            return t;
        }
        if ft > 0.0 {
            lo = t;
        } else {
            hi = t;
        }
        // d/dt ln G = −p(t) / G(t)
        let slope = -(ln_chi2_pdf_with(n, t, ln_gamma_half_n) - (ft + target)).exp();
        let newton = t - ft / slope;
        let next = if newton.is_finite() && newton > lo && newton < hi {
            newton
        } else {
            0.5 * (lo + hi)
        };
        if (next - t).abs() <= 1e-15 * t.max(1e-300) || hi - lo <= 1e-15 * hi {
            return next;
        }
        t = next;
    }
    t
}

/// α_m = m c_m g_n(c_m). With c_m = exp(−t_c/2)/C_n this is 2 m p_χ²(t_c), free of |Σ|.
fn weibull_shape(n: usize, m: usize, t_c: f64) -> f64 {
    ((m as f64).ln() + std::f64::consts::LN_2 + ln_chi2_pdf(n, t_c)).exp()
}

/// Weibull (extreme-value) parameters of the minimum density of m draws from an
/// n-dimensional Gaussian with log-determinant `ln_det_sigma`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct EvtWeibull {
    pub n: usize,
    pub m: usize,
    /// ln C_n.
    pub ln_c_n: f64,
    /// t_c = −2 ln(C_n c_m): the squared Mahalanobis radius where the density is c_m.
    pub radius2: f64,
    /// ln c_m, the Weibull scale (a density).
    pub ln_scale: f64,
    /// α_m, the Weibull shape.
    pub shape: f64,
}

impl EvtWeibull {
    /// Needs n ≥ 1 dimensions, m ≥ 2 draws (G_n⁻¹(1/m) is the mode's density for m = 1)
    /// and a finite log-determinant.
    pub fn new(n: usize, ln_det_sigma: f64, m: usize) -> Result<EvtWeibull, EvtError> {
        if n == 0 {
            return Err(EvtError::InvalidParameter {
                name: "n",
                reason: "the Gaussian needs at least one dimension".into(),
            });
        }
        if m < 2 {
            return Err(EvtError::InvalidParameter {
                name: "m",
                reason: format!("needs at least 2 draws, got {m}"),
            });
        }
        if !ln_det_sigma.is_finite() {
            return Err(EvtError::InvalidParameter {
                name: "ln_det_sigma",
                reason: format!("must be finite, got {ln_det_sigma}"),
            });
        }
        let ln_c_n = ln_normaliser(n, ln_det_sigma);
        let radius2 = radius_quantile(n, m);
        Ok(EvtWeibull {
            n,
            m,
            ln_c_n,
            radius2,
            ln_scale: -0.5 * radius2 - ln_c_n,
            shape: weibull_shape(n, m, radius2),
        })
    }

    /// Novelty 1 − G_e(y) = exp(−(y/c_m)^α_m) of a density y given as ln y: near 0 at
    /// densities well above c_m, exp(−1) at c_m, → 1 as y → 0. NaN in gives 1.
    pub fn novelty(&self, ln_y: f64) -> f64 {
        novelty_from_log_ratio(self.shape, ln_y - self.ln_scale)
    }

    /// Novelty of an observation at squared Mahalanobis radius `r2` (the same as
    /// `novelty(−r2/2 − ln C_n)`, without forming the density).
    pub fn novelty_at_radius2(&self, r2: f64) -> f64 {
        novelty_from_log_ratio(self.shape, 0.5 * (self.radius2 - r2))
    }
}

/// exp(−exp(α ln(y/c))), in [0, 1]; an unscorable (NaN) ratio counts as fully novel.
fn novelty_from_log_ratio(shape: f64, ln_ratio: f64) -> f64 {
    if ln_ratio.is_nan() {
        return 1.0;
    }
    (-(shape * ln_ratio).exp()).exp()
}

/// Variances at or below this (or not finite) are raised to it: a zero-variance dimension
/// with a non-zero residual makes the observation novel instead of dividing by zero.
const MIN_VARIANCE: f64 = f64::MIN_POSITIVE;

/// GU's novelty ν_G = 1 − G_e(N(o | μ, Σ)) = exp(−(f/c_m)^α_m) of one observation, for
/// Σ = diag(`variance`), `residual` = o − μ and the extreme-value statistics of `m` draws
/// (the reference code passes the training points its model has seen; GU's choice is in
/// `gu.rs`).
///
/// Values: in [0, 1] and never NaN.
/// - m < 2: 1 (with fewer than two draws there is no extreme-value distribution: a model
///   that has seen nothing finds everything novel).
/// - no dimensions: 0 (an empty observation carries no evidence of novelty).
/// - a variance that is zero, negative or NaN is raised to `f64::MIN_POSITIVE`, so a
///   non-zero residual there gives novelty 1; an infinite variance ignores its dimension.
/// - a NaN residual gives 1.
///
/// # Panics
/// If `residual` and `variance` differ in length.
pub fn evt_novelty(residual: &[f64], variance: &[f64], m: usize) -> f64 {
    assert_eq!(
        residual.len(),
        variance.len(),
        "one variance per residual dimension"
    );
    let n = residual.len();
    if n == 0 {
        return 0.0;
    }
    if m < 2 {
        return 1.0;
    }
    let r2: f64 = residual
        .iter()
        .zip(variance)
        .map(|(&e, &v)| scaled_square(e, v))
        .sum();
    let t_c = radius_quantile(n, m);
    novelty_from_log_ratio(weibull_shape(n, m, t_c), 0.5 * (t_c - r2))
}

/// One dimension's term e²/v of the squared Mahalanobis radius that [`evt_novelty`] sums
/// (the variance raised to `f64::MIN_POSITIVE` as there): a radius summed from these terms
/// in the same order is the one [`evt_novelty`] computes, bit for bit.
pub fn scaled_square(e: f64, v: f64) -> f64 {
    let v = if v.is_nan() || v < MIN_VARIANCE {
        MIN_VARIANCE
    } else {
        v
    };
    e * e / v
}

/// [`evt_novelty`] from the squared radius `r2` (a sum of [`scaled_square`] terms) of an
/// observation in `n` dimensions, with the Weibull parameters of each (n, m) computed once
/// and kept: the same value, bit for bit, as [`evt_novelty`] of the residuals behind `r2`.
/// The parameters depend on n and m alone, and their root-finding costs O(n) per step of
/// its iteration, so a caller that scores many observations of one size (GU's per-step
/// novelties), or of the sizes of a growing grasp again and again, pays it once per size.
#[derive(Clone, Debug, Default)]
pub struct EvtQuantiles {
    /// (n, m) → (t_c, α_m).
    kept: std::collections::HashMap<(usize, usize), (f64, f64)>,
}

impl EvtQuantiles {
    /// Sizes kept at most: past them the map starts afresh (a bound on memory).
    const CAP: usize = 1 << 16;

    /// Whether [`EvtQuantiles::novelty`] at (n, m) costs O(1): no root to find.
    pub fn knows(&self, n: usize, m: usize) -> bool {
        n == 0 || m < 2 || self.kept.contains_key(&(n, m))
    }

    pub fn novelty(&mut self, n: usize, m: usize, r2: f64) -> f64 {
        if n == 0 {
            return 0.0;
        }
        if m < 2 {
            return 1.0;
        }
        if self.kept.len() >= Self::CAP {
            self.kept.clear();
        }
        let (t_c, shape) = *self.kept.entry((n, m)).or_insert_with(|| {
            let t_c = radius_quantile(n, m);
            (t_c, weibull_shape(n, m, t_c))
        });
        novelty_from_log_ratio(shape, 0.5 * (t_c - r2))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// G_n against the fraction of Gaussian draws whose density is at most y, for random
    /// diagonal covariances spanning several orders of magnitude.
    #[test]
    fn density_cdf_matches_monte_carlo() {
        let draws = 60_000;
        for (i, n) in [1usize, 2, 3, 10, 34].into_iter().enumerate() {
            let mut rng = Rng::stream(11, i as u64);
            let var: Vec<f64> = (0..n).map(|_| rng.range(-6.0, 6.0).exp()).collect();
            let mean: Vec<f64> = (0..n).map(|_| rng.range(-10.0, 10.0)).collect();
            let ln_det: f64 = var.iter().map(|v| v.ln()).sum();
            let ln_c_n = ln_normaliser(n, ln_det);
            let ln_f: Vec<f64> = (0..draws)
                .map(|_| {
                    let r2: f64 = (0..n)
                        .map(|d| {
                            let x = mean[d] + var[d].sqrt() * rng.normal();
                            (x - mean[d]).powi(2) / var[d]
                        })
                        .sum();
                    -0.5 * r2 - ln_c_n
                })
                .collect();
            // densities from near the mode to the far tail
            for q in [0.2, 0.6, 1.0, 1.6, 2.5] {
                let ln_y = -0.5 * q * n as f64 - ln_c_n;
                let want = ln_f.iter().filter(|&&l| l <= ln_y).count() as f64 / draws as f64;
                let got = density_cdf(n, ln_c_n, ln_y);
                let tol = 4.0 * (want * (1.0 - want) / draws as f64).sqrt() + 1e-3;
                assert!((got - want).abs() < tol, "n {n}, q {q}: G {got}, MC {want}");
            }
        }
    }

    /// G_n against numerical integration of the χ²_n density over [t, ∞) (Simpson's rule on
    /// a change of variable s = t + u², which removes the n = 1 singularity at 0).
    #[test]
    fn density_cdf_matches_quadrature() {
        // n = 400, 401 at t ≥ 40 take the log-space branch; so do n = 1000, 1001, and at t
        // = 1600 there a term x^k/k! of the linear-space sum (x = 800, k = 499) overflows
        let cases = [1usize, 2, 3, 4, 5, 10, 33, 34]
            .iter()
            .flat_map(|&n| [0.01, 0.5, 2.0, 7.0, 30.0, 80.0].map(|t| (n, t)))
            .chain(
                [400usize, 401]
                    .iter()
                    .flat_map(|&n| [10.0, 300.0, 400.0, 450.0].map(|t| (n, t))),
            )
            .chain(
                [1000usize, 1001]
                    .iter()
                    .flat_map(|&n| [1000.0, 1600.0].map(|t| (n, t))),
            );
        for (n, t) in cases {
            let f = |u: f64| 2.0 * u * ln_chi2_pdf(n, t + u * u).exp();
            let (a, b, steps) = (0.0, 40.0, 40_000);
            let h = (b - a) / steps as f64;
            let mut s = f(a) + f(b);
            for k in 1..steps {
                s += f(a + k as f64 * h) * if k % 2 == 1 { 4.0 } else { 2.0 };
            }
            let want = s * h / 3.0;
            let got = ln_tail(n, t).exp();
            assert!(
                (got - want).abs() <= 1e-9 * want.max(1e-300) + 1e-300,
                "n {n}, t {t}: {got} vs {want}"
            );
        }
    }

    /// Far in the tail (x = t/2 = 800), where erfc(√x) and exp(−x) underflow, ln G_n against
    /// the closed forms G_1 = erfc(√x) and G_3 = erfc(√x) + 2 √(x/π) exp(−x), with erfc from
    /// its asymptotic series (Abramowitz & Stegun 7.1.23): erfc(z) exp(z²) = (1 − 1/(2z²) +
    /// 3/(4z⁴) − 15/(8z⁶) + …)/(z √π), whose next term is below 2e-11 here.
    #[test]
    fn the_far_tail_is_the_asymptotic_erfc_series() {
        let x: f64 = 800.0;
        let series = 1.0 - 1.0 / (2.0 * x) + 3.0 / (4.0 * x * x) - 15.0 / (8.0 * x.powi(3));
        let erfc_scaled = series / (x.sqrt() * std::f64::consts::PI.sqrt());
        let want1 = erfc_scaled.ln() - x;
        let want3 = (erfc_scaled + 2.0 * (x / std::f64::consts::PI).sqrt()).ln() - x;
        for (n, want) in [(1, want1), (3, want3)] {
            let got = ln_tail(n, 2.0 * x);
            assert!((got - want).abs() < 1e-9, "n {n}: {got} vs {want}");
        }
    }

    /// The n = 1 closed form of the notes, erfc(√(−ln(C_1 y))), evaluated directly.
    #[test]
    fn one_dimension_is_the_erfc_formula() {
        let ln_det = (0.3f64).ln();
        let ln_c = ln_normaliser(1, ln_det);
        for ln_y_rel in [-0.001, -0.1, -1.0, -5.0, -20.0, -300.0] {
            let ln_y = ln_y_rel - ln_c;
            let want = erfc((-(ln_c + ln_y)).sqrt());
            let got = density_cdf(1, ln_c, ln_y);
            assert!(
                (got - want).abs() <= 1e-13 * want,
                "{ln_y_rel}: {got} vs {want}"
            );
        }
        // and P[|Z| ≥ 1] = erfc(1/√2) = 0.3173105078629141 (the one-sigma two-sided tail)
        let ln_y_one_sigma = -0.5 - ln_c;
        assert!((density_cdf(1, ln_c, ln_y_one_sigma) - 0.317_310_507_862_914_1).abs() < 1e-14);
    }

    #[test]
    fn density_cdf_is_monotone_and_bounded() {
        for n in [1usize, 2, 3, 10, 34] {
            let ln_c = ln_normaliser(n, -40.0);
            let mut prev = 0.0;
            for k in 0..400 {
                let ln_y = -ln_c - 0.5 * (400 - k) as f64;
                let g = density_cdf(n, ln_c, ln_y);
                assert!((0.0..=1.0).contains(&g));
                assert!(g >= prev, "n {n}: not monotone at {k}");
                prev = g;
            }
            assert_eq!(density_cdf(n, ln_c, -ln_c + 1.0), 1.0);
            assert_eq!(density_cdf(n, ln_c, f64::NEG_INFINITY), 0.0);
        }
        // no dimensions, or a NaN argument: 0, also at the mode (t = 0)
        assert_eq!(density_cdf(0, 0.0, 0.0), 0.0);
        assert_eq!(density_cdf(2, f64::NAN, 0.0), 0.0);
        assert_eq!(density_cdf(2, 0.0, f64::NAN), 0.0);
    }

    /// c_m solves G_n(c_m) = 1/m; exact for n = 2 (t_c = 2 ln m, α_m = 1).
    #[test]
    fn weibull_parameters() {
        for n in [1usize, 2, 3, 10, 34] {
            for m in [2usize, 10, 100, 10_000, 1_000_000_000] {
                let w = EvtWeibull::new(n, 12.5, m).unwrap();
                let g = density_cdf(n, w.ln_c_n, w.ln_scale);
                assert!(
                    (g * m as f64 - 1.0).abs() < 1e-10,
                    "n {n}, m {m}: G(c_m) = {g}"
                );
                assert!(w.shape.is_finite() && w.shape > 0.0);
                // the notes' form m c_m g_n(c_m) agrees with the simplified 2 m p(t_c)
                let notes =
                    ((m as f64).ln() + w.ln_scale + ln_density_pdf(n, 12.5, w.ln_scale)).exp();
                assert!((notes - w.shape).abs() < 1e-9 * w.shape, "n {n}, m {m}");
                // the novelty at the scale itself is exp(−1)
                assert!((w.novelty(w.ln_scale) - (-1f64).exp()).abs() < 1e-12);
            }
        }
        for m in [2usize, 20, 500] {
            let w = EvtWeibull::new(2, 0.0, m).unwrap();
            assert!((w.radius2 - 2.0 * (m as f64).ln()).abs() < 1e-12 * w.radius2);
            assert!((w.shape - 1.0).abs() < 1e-12);
        }
        assert!(EvtWeibull::new(0, 0.0, 10).is_err());
        assert!(EvtWeibull::new(3, 0.0, 1).is_err());
        assert!(EvtWeibull::new(3, f64::INFINITY, 10).is_err());
    }

    #[test]
    fn novelty_is_low_at_the_mean_and_high_far_away() {
        for n in [1usize, 3, 34] {
            let var: Vec<f64> = (0..n).map(|i| 1e-4 * (1 + i) as f64).collect();
            let at_mean = evt_novelty(&vec![0.0; n], &var, 300);
            assert!(at_mean < 1e-6, "n {n}: {at_mean}");
            let far: Vec<f64> = var.iter().map(|v| 50.0 * v.sqrt()).collect();
            let novel = evt_novelty(&far, &var, 300);
            assert!(novel > 1.0 - 1e-12, "n {n}: {novel}");
            // monotone in the distance from the mean
            let mut prev = 0.0;
            for k in 0..60 {
                let e: Vec<f64> = var.iter().map(|v| 0.1 * k as f64 * v.sqrt()).collect();
                let nu = evt_novelty(&e, &var, 300);
                assert!(nu >= prev && (0.0..=1.0).contains(&nu));
                prev = nu;
            }
        }
    }

    /// The novelty depends on the Mahalanobis radius only: rescaling a dimension's
    /// residual and standard deviation together leaves it unchanged.
    #[test]
    fn novelty_is_scale_free() {
        let e = [0.3, -1.2, 2.0];
        let v = [0.5, 1.0, 2.0];
        let a = evt_novelty(&e, &v, 40);
        let e2 = [0.3e-6, -1.2e4, 2.0];
        let v2 = [0.5e-12, 1.0e8, 2.0];
        let b = evt_novelty(&e2, &v2, 40);
        assert!((a - b).abs() < 1e-12, "{a} vs {b}");
        // and matches the Weibull form evaluated through the density
        let ln_det: f64 = v.iter().map(|x: &f64| x.ln()).sum();
        let w = EvtWeibull::new(3, ln_det, 40).unwrap();
        let r2: f64 = e.iter().zip(&v).map(|(e, v)| e * e / v).sum();
        assert!((w.novelty(-0.5 * r2 - w.ln_c_n) - a).abs() < 1e-12);
        assert!((w.novelty_at_radius2(r2) - a).abs() < 1e-12);
    }

    #[test]
    fn degenerate_inputs_give_defined_values() {
        assert_eq!(evt_novelty(&[], &[], 50), 0.0);
        assert_eq!(evt_novelty(&[0.1], &[1.0], 0), 1.0);
        assert_eq!(evt_novelty(&[0.1], &[1.0], 1), 1.0);
        // a zero residual adds nothing, whatever its variance
        assert_eq!(
            evt_novelty(&[1.0, 0.0], &[1.0, 0.0], 50),
            evt_novelty(&[1.0, 0.0], &[1.0, 1.0], 50)
        );
        assert_eq!(evt_novelty(&[0.0, 0.5], &[1.0, 0.0], 50), 1.0);
        assert_eq!(evt_novelty(&[0.0, 0.5], &[1.0, -2.0], 50), 1.0);
        assert_eq!(evt_novelty(&[0.0, 0.5], &[1.0, f64::NAN], 50), 1.0);
        assert_eq!(evt_novelty(&[f64::NAN, 0.5], &[1.0, 1.0], 50), 1.0);
        assert_eq!(evt_novelty(&[f64::INFINITY], &[1.0], 50), 1.0);
        let ignored = evt_novelty(&[0.0, 7.0], &[1.0, f64::INFINITY], 50);
        assert!(ignored.is_finite() && ignored < 1e-3);
        for m in [2, 3, 1 << 40] {
            for r in [0.0, 1.0, 1e3, 1e300] {
                let nu = evt_novelty(&[r; 34], &[1e-300; 34], m);
                assert!((0.0..=1.0).contains(&nu), "m {m}, r {r}: {nu}");
            }
        }
    }
}
