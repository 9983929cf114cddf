//! The standard normal distribution where the probit likelihood needs it: the CDF, its log,
//! and the ratio N(z)/Φ(z), all accurate in the far tails (no 0/0 for confident mistakes), through
//! Cody's scaled complementary error function.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use crate::special::erfcx;

/// Standard normal density.
pub fn norm_pdf(z: f64) -> f64 {
    (-0.5 * z * z).exp() / (2.0 * PI).sqrt()
}

/// Φ(z), the standard normal CDF.
pub fn norm_cdf(z: f64) -> f64 {
    let x = -z * FRAC_1_SQRT_2;
    if x >= 0.0 {
        0.5 * (-x * x).exp() * erfcx(x)
    } else {
        1.0 - 0.5 * (-x * x).exp() * erfcx(-x)
    }
}

/// ln Φ(z), finite for every finite z.
pub fn log_norm_cdf(z: f64) -> f64 {
    let x = -z * FRAC_1_SQRT_2;
    if x >= 0.0 {
        (0.5 * erfcx(x)).ln() - x * x
    } else {
        (-0.5 * (-x * x).exp() * erfcx(-x)).ln_1p()
    }
}

/// N(z)/Φ(z) (the inverse Mills ratio of −z), finite for every finite z: for z → −∞ it
/// grows like −z instead of becoming 0/0.
pub fn pdf_over_cdf(z: f64) -> f64 {
    let x = -z * FRAC_1_SQRT_2;
    if x >= 0.0 {
        (2.0 / PI).sqrt() / erfcx(x)
    } else {
        norm_pdf(z) / norm_cdf(z)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn known_values() {
        assert!((norm_cdf(0.0) - 0.5).abs() < 1e-7);
        assert!((norm_cdf(1.959_963_984_540_054) - 0.975).abs() < 1e-7);
        assert!((norm_cdf(-1.0) - 0.158_655_253_931_457_05).abs() < 1e-7);
        // ln Φ(−10) = −53.231285150...; the tail must stay accurate in relative terms.
        assert!((log_norm_cdf(-10.0) + 53.231_285_150_512_95).abs() < 1e-5);
        assert!((log_norm_cdf(3.0) - (0.998_650_101_968_369_9f64).ln()).abs() < 1e-7);
        // For z → −∞, N/Φ ≈ −z + 1/(−z): at z = −30 about 30.0333.
        let r = pdf_over_cdf(-30.0);
        assert!((r - 30.033_2).abs() < 1e-3, "{r}");
        assert!((pdf_over_cdf(0.0) - 2.0 * norm_pdf(0.0)).abs() < 1e-7);
        assert!(pdf_over_cdf(40.0) >= 0.0 && pdf_over_cdf(40.0) < 1e-300);
    }
}
