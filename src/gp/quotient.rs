//! Correctly rounded quotients from a reciprocal and fused multiply-adds.
//!
//! The (Q + C) removal divides about 2,600 products by the same two pivots. The divider
//! takes about 2 cycles per double even in wide vectors and bounds the removal, while a
//! fused multiply-add takes a quarter of a cycle. Multiplying by the rounded reciprocal
//! would change the last bit of many entries; instead each quotient is refined until it
//! is the correctly rounded `a / b`, the number the division gives:
//!
//! 1. `y = RN(1/b)` once per divisor, whose relative error is below 2⁻⁵³;
//! 2. `q₀ = RN(a·y)`, within about 2 ulps of a/b;
//! 3. `q₁ = RN(q₀ + RN(a − b·q₀)·y)` (two FMAs), now a faithful rounding of a/b (the
//!    correction's own error is second order);
//! 4. `q₂ = RN(q₁ + (a − b·q₁)·y)` (two FMAs). By Markstein's theorem (P. Markstein,
//!    "Computation of elementary functions on the IBM RISC System/6000 processor", IBM J.
//!    Res. Dev. 34(1), 1990; restated in J.-M. Muller et al., *Handbook of Floating-Point
//!    Arithmetic*, on division with an FMA): when y approximates 1/b within a relative
//!    error below 2⁻⁵³ and q₁ is a faithful rounding of a/b, the residual a − b·q₁ is
//!    exact and q₂ is RN(a/b), ties to even included.
//!
//! One correction (q₁) already gave the division's bits in 4·10⁸ trials with both
//! significands near the edges of their binades; the second is the one the theorem
//! covers, for two more FMAs.
//!
//! The theorem needs no underflow or overflow in the steps; [`in_range`] bounds the
//! operands so that none can occur: with factors and divisor within 2^±300, a product
//! lies within 2^±600, a quotient within 2^±900, and a residual, a multiple of
//! ulp(b)·ulp(q₁) ≈ ulp(a)·2⁻⁵², stays far above the smallest normal. Zeros are excluded
//! as well: the FMAs can give +0 where the division gives −0. Outside the range the
//! caller divides.

/// `a / b` to the last bit, for `y = 1.0 / b`, when `in_range` holds for both factors
/// of `a` and for `b`. Needs a hardware FMA to be fast (in software it is exact but slow).
#[inline(always)]
pub(crate) fn quotient(a: f64, b: f64, y: f64) -> f64 {
    let q0 = a * y;
    let q1 = (-q0).mul_add(b, a).mul_add(y, q0);
    (-q1).mul_add(b, a).mul_add(y, q1)
}

/// Magnitudes for which a product of two of them divided by a third takes [`quotient`]
/// without underflow or overflow: 2⁻³⁰⁰ ≤ |v| ≤ 2³⁰⁰ (products within 2^±600, quotients
/// within 2^±900).
#[inline(always)]
pub(crate) fn in_range(v: f64) -> bool {
    const LOW: f64 = 4.909093465297727e-91; // 2⁻³⁰⁰
    const HIGH: f64 = 2.037035976334486e90; // 2³⁰⁰
    let m = v.abs();
    (LOW..=HIGH).contains(&m)
}

/// True when this CPU runs fused multiply-adds in hardware, so that [`quotient`] is cheap
/// (the wide code paths are then compiled with FMA).
pub(crate) fn hardware_fma() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(target_arch = "aarch64")]
    {
        true
    }
    #[cfg(not(any(target_arch = "x86_64", target_arch = "aarch64")))]
    {
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// A double with a random significand and an exponent in [lo, hi].
    fn random(rng: &mut Rng, lo: i32, hi: i32) -> f64 {
        let e = lo + (rng.next_u64() % (hi - lo + 1) as u64) as i32;
        let bits = (rng.next_u64() >> 12) | (((e + 1023) as u64) << 52);
        let v = f64::from_bits(bits);
        if rng.next_u64() & 1 == 1 { -v } else { v }
    }

    /// Significands at the edges of a binade, where a single correction is not enough:
    /// all ones, all zeros, and a few units away from either.
    fn edge(rng: &mut Rng, e: i32) -> f64 {
        let frac = match rng.next_u64() % 4 {
            0 => (1u64 << 52) - 1 - (rng.next_u64() % 16),
            1 => rng.next_u64() % 16,
            2 => (1u64 << 52) - 1 - (rng.next_u64() % (1 << 20)),
            _ => rng.next_u64() % (1 << 20),
        };
        f64::from_bits(frac | (((e + 1023) as u64) << 52))
    }

    fn check(a: f64, b: f64) {
        let q = quotient(a, b, 1.0 / b);
        assert_eq!(q.to_bits(), (a / b).to_bits(), "{a:e} / {b:e}");
    }

    #[test]
    fn quotients_equal_the_division_to_the_last_bit() {
        let mut rng = Rng::new(27);
        for _ in 0..2_000_000 {
            // Products of two in-range factors over in-range divisors, as the removal
            // forms them.
            let a = random(&mut rng, -300, 300) * random(&mut rng, -300, 300);
            let b = random(&mut rng, -300, 300);
            check(a, b);
        }
        for _ in 0..2_000_000 {
            let e = (rng.next_u64() % 40) as i32 - 20;
            let (a, b) = (edge(&mut rng, e), edge(&mut rng, -e));
            check(a, b);
            check(a, random(&mut rng, -3, 3));
            check(random(&mut rng, -3, 3), b);
        }
        // Exact quotients and ties of the significand.
        for (a, b) in [(1.0, 1.0), (3.0, 2.0), (1.0, 3.0), (7.0, 7.0), (-5.0, 4.0)] {
            check(a, b);
        }
    }

    #[test]
    fn the_range_excludes_zero_and_the_extremes() {
        assert!(in_range(1.0) && in_range(-1e-90) && in_range(1e90));
        assert!(!in_range(0.0) && !in_range(-0.0));
        assert!(!in_range(1e-91) && !in_range(1e91));
        assert!(!in_range(f64::NAN) && !in_range(f64::INFINITY));
        assert_eq!(2f64.powi(-300), 4.909093465297727e-91);
        assert_eq!(2f64.powi(300), 2.037035976334486e90);
    }
}
