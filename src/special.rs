//! Special functions the models need in double precision: the complementary error function
//! (plain, scaled and in log form) and the log-gamma function.
//!
//! `erfc` and `erfcx` follow W. J. Cody, "Rational Chebyshev approximations for the error
//! function", Math. Comp. 23 (1969) 631–638, with the coefficients of his portable packet
//! CALERF (netlib `specfun/erf`, 1990). `ln_gamma` uses the Lanczos approximation (g = 7,
//! nine terms), with the reflection formula below 1/2.

// Cody's coefficients and the reference values keep their published digits.
#![allow(clippy::excessive_precision)]

use std::f64::consts::PI;

/// 1/√π.
const FRAC_1_SQRT_PI: f64 = 0.564_189_583_547_756_3;

// erf on |x| ≤ 0.46875
const A: [f64; 5] = [
    3.161_123_743_870_565_6,
    1.138_641_541_510_501_6e2,
    3.774_852_376_853_020_2e2,
    3.209_377_589_138_469_5e3,
    1.857_777_061_846_031_5e-1,
];
const B: [f64; 4] = [
    2.360_129_095_234_412e1,
    2.440_246_379_344_441_7e2,
    1.282_616_526_077_372_3e3,
    2.844_236_833_439_170_6e3,
];
// erfcx on 0.46875 < x ≤ 4
const C: [f64; 9] = [
    5.641_884_969_886_701e-1,
    8.883_149_794_388_376,
    6.611_919_063_714_163e1,
    2.986_351_381_974_001_3e2,
    8.819_522_212_417_691e2,
    1.712_047_612_634_070_6e3,
    2.051_078_377_826_071_5e3,
    1.230_339_354_797_997_2e3,
    2.153_115_354_744_038_5e-8,
];
const D: [f64; 8] = [
    1.574_492_611_070_983_5e1,
    1.176_939_508_913_125e2,
    5.371_811_018_620_099e2,
    1.621_389_574_566_690_2e3,
    3.290_799_235_733_459_7e3,
    4.362_619_090_143_247e3,
    3.439_367_674_143_721_6e3,
    1.230_339_354_803_749_4e3,
];
// erfcx on x > 4, in 1/x²
const P: [f64; 6] = [
    3.053_266_349_612_323_4e-1,
    3.603_448_999_498_044_4e-1,
    1.257_817_261_112_292_5e-1,
    1.608_378_514_874_227_7e-2,
    6.587_491_615_298_378e-4,
    1.631_538_713_730_209_8e-2,
];
const Q: [f64; 5] = [
    2.568_520_192_289_822_4,
    1.872_952_849_923_460_4,
    5.279_051_029_514_284e-1,
    6.051_834_131_244_132e-2,
    2.335_204_976_268_691_8e-3,
];
/// Beyond this erfc(x) is below the smallest normal double (Cody's XBIG).
const X_BIG: f64 = 26.543;
/// Beyond this, 1 − 1/(2x²) = 1 in double precision and erfcx(x) = 1/(x√π).
const X_HUGE: f64 = 6.71e7;

/// erf(x) for |x| ≤ 0.46875.
fn erf_small(x: f64) -> f64 {
    let y2 = x * x;
    let mut num = A[4] * y2;
    let mut den = y2;
    for i in 0..3 {
        num = (num + A[i]) * y2;
        den = (den + B[i]) * y2;
    }
    x * (num + A[3]) / (den + B[3])
}

/// erfcx(y) = exp(y²) erfc(y) for y > 0.46875.
fn erfcx_large(y: f64) -> f64 {
    if y <= 4.0 {
        let mut num = C[8] * y;
        let mut den = y;
        for i in 0..7 {
            num = (num + C[i]) * y;
            den = (den + D[i]) * y;
        }
        (num + C[7]) / (den + D[7])
    } else if y >= X_HUGE {
        FRAC_1_SQRT_PI / y
    } else {
        let y2 = 1.0 / (y * y);
        let mut num = P[5] * y2;
        let mut den = y2;
        for i in 0..4 {
            num = (num + P[i]) * y2;
            den = (den + Q[i]) * y2;
        }
        let r = y2 * (num + P[4]) / (den + Q[4]);
        (FRAC_1_SQRT_PI - r) / y
    }
}

/// exp(−y²) without the rounding error of squaring y: y² is split as y0² + (y − y0)(y + y0)
/// with y0 = y rounded down to 1/16, so that y0² is exact (Cody's device).
fn exp_neg_square(y: f64) -> f64 {
    let y0 = (y * 16.0).trunc() / 16.0;
    let rest = (y - y0) * (y + y0);
    (-y0 * y0).exp() * (-rest).exp()
}

/// Complementary error function erfc(x) = (2/√π) ∫_x^∞ exp(−t²) dt, for every real x.
/// Underflows to 0 beyond x ≈ 26.5 (use [`ln_erfc`] there); NaN in, NaN out.
pub fn erfc(x: f64) -> f64 {
    let y = x.abs();
    let upper = if y <= 0.468_75 {
        1.0 - erf_small(y)
    } else if y >= X_BIG {
        0.0
    } else {
        exp_neg_square(y) * erfcx_large(y)
    };
    if x < 0.0 { 2.0 - upper } else { upper }
}

/// Scaled complementary error function erfcx(x) = exp(x²) erfc(x). Finite for every x ≥ 0
/// (about 1/(x√π) for large x); for negative x it grows like 2 exp(x²) and overflows to
/// +∞ below x ≈ −26.6.
pub fn erfcx(x: f64) -> f64 {
    let y = x.abs();
    let upper = if y <= 0.468_75 {
        (y * y).exp() * (1.0 - erf_small(y))
    } else {
        erfcx_large(y)
    };
    if x < 0.0 {
        2.0 * (y * y).exp() - upper
    } else {
        upper
    }
}

/// ln erfc(x), finite for every finite x (erfc itself underflows for x > 26.5).
pub fn ln_erfc(x: f64) -> f64 {
    if x > 0.468_75 {
        erfcx_large(x).ln() - x * x
    } else {
        erfc(x).ln()
    }
}

const LANCZOS_G: f64 = 7.0;
const LANCZOS: [f64; 9] = [
    0.999_999_999_999_809_9,
    676.520_368_121_885_1,
    -1_259.139_216_722_402_8,
    771.323_428_777_653_1,
    -176.615_029_162_140_6,
    12.507_343_278_686_905,
    -0.138_571_095_265_720_12,
    9.984_369_578_019_572e-6,
    1.505_632_735_149_311_6e-7,
];

/// ln |Γ(x)| for x > 0 (and for negative non-integers by reflection). Returns +∞ at the
/// poles x = 0, −1, −2, … and NaN for NaN.
pub fn ln_gamma(x: f64) -> f64 {
    if x < 0.5 {
        if x == x.floor() {
            return f64::INFINITY;
        }
        // Γ(x) Γ(1 − x) = π / sin(πx)
        return (PI / (PI * x).sin().abs()).ln() - ln_gamma(1.0 - x);
    }
    let z = x - 1.0;
    let mut series = LANCZOS[0];
    for (k, &c) in LANCZOS.iter().enumerate().skip(1) {
        series += c / (z + k as f64);
    }
    let t = z + LANCZOS_G + 0.5;
    0.5 * (2.0 * PI).ln() + (z + 0.5) * t.ln() - t + series.ln()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn rel(a: f64, b: f64) -> f64 {
        if b == 0.0 {
            a.abs()
        } else {
            ((a - b) / b).abs()
        }
    }

    /// Reference values from mpmath at 40 digits.
    #[test]
    fn erfc_known_values() {
        let cases = [
            (-3.0, 1.999_977_909_503_001_4),
            (-1.0, 1.842_700_792_949_714_9),
            (-0.3, 1.328_626_759_459_127_4),
            (0.0, 1.0),
            (1e-10, 0.999_999_999_887_162_1),
            (0.2, 0.777_297_410_789_521_5),
            (0.468_75, 0.507_386_526_782_062),
            (0.5, 0.479_500_122_186_953_46),
            (1.0, 0.157_299_207_050_285_13),
            (2.0, 4.677_734_981_047_265_8e-3),
            (3.9, 3.479_224_859_723_174e-8),
            (4.0, 1.541_725_790_028_002e-8),
            (4.5, 1.966_160_441_542_887_5e-10),
            (6.0, 2.151_973_671_249_891_3e-17),
            (10.0, 2.088_487_583_762_544_8e-45),
            (20.0, 5.395_865_611_607_901e-176),
            (26.0, 5.663_192_408_856_143e-296),
        ];
        for (x, want) in cases {
            let got = erfc(x);
            assert!(rel(got, want) < 1e-13, "erfc({x}) = {got}, want {want}");
        }
        assert_eq!(erfc(f64::INFINITY), 0.0);
        assert_eq!(erfc(f64::NEG_INFINITY), 2.0);
    }

    #[test]
    fn erfcx_and_ln_erfc_known_values() {
        let cases = [
            (0.0, 1.0),
            (0.3, 0.734_599_334_567_655_1),
            (1.0, 0.427_583_576_155_807),
            (3.0, 0.179_001_151_181_389_95),
            (5.0, 0.110_704_637_733_068_63),
            (10.0, 0.056_140_992_743_822_586),
            (30.0, 0.018_795_888_861_416_75),
            (1e5, 5.641_895_835_195_468e-6),
            (1e8, 5.641_895_835_477_563e-9),
        ];
        for (x, want) in cases {
            let got = erfcx(x);
            assert!(rel(got, want) < 1e-13, "erfcx({x}) = {got}, want {want}");
        }
        let logs = [
            (-2.0, 0.690_805_573_646_587_7),
            (0.1, -0.119_304_973_737_395_6),
            (3.0, -10.720_363_041_981_113),
            (30.0, -903.974_117_110_643_9),
            (100.0, -10_005.177_585_122_664),
            (1000.0, -1_000_007.480_120_721_9),
        ];
        for (x, want) in logs {
            let got = ln_erfc(x);
            assert!(rel(got, want) < 1e-13, "ln_erfc({x}) = {got}, want {want}");
        }
    }

    #[test]
    fn ln_gamma_known_values() {
        let cases = [
            (0.1, 2.252_712_651_734_206),
            (0.5, 0.572_364_942_924_700_1),
            (1.5, -0.120_782_237_635_245_22),
            (2.5, 0.284_682_870_472_919_16),
            (3.0, std::f64::consts::LN_2),
            (7.5, 7.534_364_236_758_733),
            (17.0, 30.671_860_106_080_672),
            (33.5, 83.302_425_502_950_05),
            (100.0, 359.134_205_369_575_4),
            (1e4, 82_099.717_496_442_38),
            (1e8, 1_742_068_066.103_834_7),
        ];
        for (x, want) in cases {
            let got = ln_gamma(x);
            assert!(rel(got, want) < 1e-12, "ln_gamma({x}) = {got}, want {want}");
        }
        // Where ln Γ is 0 a relative bound is meaningless: check absolutely.
        assert!(ln_gamma(1.0).abs() < 1e-14);
        assert!(ln_gamma(2.0).abs() < 1e-14);
        // Integer arguments against the log-factorial.
        let mut ln_factorial = 0.0;
        for n in 1..60 {
            ln_factorial += (n as f64).ln();
            assert!(rel(ln_gamma(n as f64 + 1.0), ln_factorial) < 1e-12, "{n}!");
        }
        assert_eq!(ln_gamma(0.0), f64::INFINITY);
        assert_eq!(ln_gamma(-3.0), f64::INFINITY);
    }
}
