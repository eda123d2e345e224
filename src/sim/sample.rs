//! Portable sampling: the same seed gives the same numbers, bit for bit, on every machine.
//!
//! `f64::ln` calls the platform's libm, whose last bit may differ between systems; one
//! differing bit in a sampled delay can change which transition wins a later race. So the
//! exponential delays use [`ln`] below, built only from IEEE-754 `+ − × ÷` (exactly rounded
//! everywhere; Rust never fuses them into FMAs on its own).

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// A uniform number in `[0, 1)` with 53 random bits.
#[inline]
pub(crate) fn uniform(rng: &mut ChaCha8Rng) -> f64 {
    rng.random::<f64>()
}

/// An exponential delay with rate `rate` (> 0): `−ln(U) / rate` with `U` in `(0, 1]`.
#[inline]
pub(crate) fn exponential(rng: &mut ChaCha8Rng, rate: f64) -> f64 {
    let u = 1.0 - uniform(rng);
    -ln(u) / rate
}

/// ln 2 split as in fdlibm: the high part has 32 trailing zero bits, so `e · LN2_HI` is exact.
const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);

/// Natural logarithm of a positive, finite, normal `x`, to within a few ulps, from basic
/// arithmetic only. `x = m·2^e` with `m ∈ [√½, √2)`; `ln m = 2·atanh(s)`, `s = (m−1)/(m+1)`,
/// `|s| ≤ 0.172`, summed to 12 terms (the next is below 2⁻⁵⁶ relative).
#[inline]
pub(crate) fn ln(x: f64) -> f64 {
    debug_assert!(x.is_normal() && x > 0.0);
    let bits = x.to_bits();
    let mut e = ((bits >> 52) & 0x7ff) as i64 - 1023;
    let mut m = f64::from_bits((bits & 0x000f_ffff_ffff_ffff) | 0x3ff0_0000_0000_0000);
    if m > std::f64::consts::SQRT_2 {
        m *= 0.5;
        e += 1;
    }
    let s = (m - 1.0) / (m + 1.0);
    let z = s * s;
    // 1 + z/3 + z²/5 + … + z¹¹/23, by Horner.
    let mut p = 1.0 / 23.0;
    for k in (0..11).rev() {
        p = p * z + 1.0 / (2 * k + 1) as f64;
    }
    let ln_m = 2.0 * s * p;
    let e = e as f64;
    e * LN2_HI + (ln_m + e * LN2_LO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;

    #[test]
    fn ln_matches_libm_to_a_few_ulps() {
        let mut x = 1e-300_f64;
        while x < 1e300 {
            for y in [
                x,
                x * 1.234_567,
                x * std::f64::consts::SQRT_2 * 0.9999,
                x * std::f64::consts::SQRT_2 * 1.0001,
                x * 1.999,
            ] {
                let (a, b) = (ln(y), y.ln());
                assert!(
                    (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0),
                    "{y}: {a} vs {b}"
                );
            }
            x *= 3.7;
        }
        assert_eq!(ln(1.0), 0.0);
        assert!((ln(2.0) - std::f64::consts::LN_2).abs() < 1e-16);
        assert!((ln(2f64.powi(-53)) + 53.0 * std::f64::consts::LN_2).abs() < 1e-13);
    }

    #[test]
    fn exponential_has_the_right_mean() {
        let mut rng = ChaCha8Rng::seed_from_u64(7);
        let n = 200_000;
        let mean = (0..n).map(|_| exponential(&mut rng, 4.0)).sum::<f64>() / n as f64;
        // sd of the mean = 0.25 / √n ≈ 5.6e-4
        assert!((mean - 0.25).abs() < 3e-3, "{mean}");
    }
}
