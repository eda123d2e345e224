//! Chance, in one place: every random draw of the token game, the runtime, the robot world,
//! ROS 2 robots and the viewer goes through this module, so the same seed gives the same
//! numbers, bit for bit, on every machine.
//!
//! - [`uniform`]: a number in `[0, 1)` with 53 random bits.
//! - [`exponential`]: a delay `−ln(U) / rate`. `f64::ln` calls the platform's libm, whose
//!   last bit may differ between systems; one differing bit in a sampled delay can change
//!   which transition wins a later race. So the logarithm is [`ln`]: the `libm` crate's
//!   software `log` (fdlibm's algorithm from IEEE-754 `+ − × ÷` and bit operations, exactly
//!   rounded everywhere; Rust never fuses them into FMAs on its own).
//! - [`pick_weighted`]: one index drawn ∝ weight from a short list.
//! - `SumTree`: the same draw in `O(log n)` over many weights that change one at a time.
//!
//! Nothing outside this module calls `f64::ln` or draws a weighted choice by hand.

pub(crate) mod fnv;
pub(crate) mod sum_tree;

pub(crate) use sum_tree::SumTree;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;

/// The random number generator every component draws from: seeded, portable, with streams.
pub type Rng = ChaCha8Rng;

/// A uniform number in `[0, 1)` with 53 random bits.
#[inline]
pub fn uniform(rng: &mut Rng) -> f64 {
    rng.random::<f64>()
}

/// An exponential delay with rate `rate` (> 0): `−ln(U) / rate` with `U` in `(0, 1]`.
#[inline]
pub fn exponential(rng: &mut Rng, rate: f64) -> f64 {
    let u = 1.0 - uniform(rng);
    -ln(u) / rate
}

/// Natural logarithm, portable: the `libm` crate's software `log`, measured as fast as the
/// platform's on the sampler's inputs (docs/benchmarks.md, `benches/ln.rs`).
#[inline]
pub fn ln(x: f64) -> f64 {
    libm::log(x)
}

/// Draws one item ∝ its weight with `u` uniform in `[0, 1)`: the item whose cumulative
/// weight first exceeds `u × total`. Items of weight 0 are never drawn while the total is
/// positive (rounding that carries `u × total` past the end gives the last positive item).
/// `None` when no weight is positive.
#[inline]
pub fn pick_weighted_with<T: Copy>(u: f64, items: &[(T, f64)]) -> Option<T> {
    let total: f64 = items.iter().map(|&(_, w)| w).sum();
    if total.is_nan() || total <= 0.0 {
        return None;
    }
    let mut x = u * total;
    let mut last = None;
    for &(t, w) in items {
        if w > 0.0 {
            if x < w {
                return Some(t);
            }
            x -= w;
            last = Some(t);
        }
    }
    last
}

/// Draws one item ∝ its weight (one [`uniform`] draw, also when `items` is short or all
/// weights are 0); `None` when no weight is positive. See [`pick_weighted_with`].
#[inline]
pub fn pick_weighted<T: Copy>(rng: &mut Rng, items: &[(T, f64)]) -> Option<T> {
    pick_weighted_with(uniform(rng), items)
}

/// The hand-written logarithm the sampler used before `libm` (kept to measure against it):
/// `x = m·2^e` with `m ∈ [√½, √2)`; `ln m = 2·atanh(s)`, `s = (m−1)/(m+1)`, `|s| ≤ 0.172`,
/// summed to 12 terms (the next is below 2⁻⁵⁶ relative). For positive, finite, normal `x`.
#[doc(hidden)]
#[inline]
pub fn ln_series(x: f64) -> f64 {
    /// ln 2 split as in fdlibm: the high part has 32 trailing zero bits, so `e · LN2_HI` is
    /// exact.
    const LN2_HI: f64 = f64::from_bits(0x3fe6_2e42_fee0_0000);
    const LN2_LO: f64 = f64::from_bits(0x3dea_39ef_3579_3c76);
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
    fn ln_matches_the_platform_to_a_few_ulps() {
        let mut x = 1e-300_f64;
        while x < 1e300 {
            for y in [
                x,
                x * 1.234_567,
                x * std::f64::consts::SQRT_2 * 0.9999,
                x * std::f64::consts::SQRT_2 * 1.0001,
                x * 1.999,
            ] {
                for a in [ln(y), ln_series(y)] {
                    let b = y.ln();
                    assert!(
                        (a - b).abs() <= 4.0 * f64::EPSILON * b.abs().max(1.0),
                        "{y}: {a} vs {b}"
                    );
                }
            }
            x *= 3.7;
        }
        assert_eq!(ln(1.0), 0.0);
        assert_eq!(ln(2.0), std::f64::consts::LN_2);
        assert!((ln(2f64.powi(-53)) + 53.0 * std::f64::consts::LN_2).abs() < 1e-13);
    }

    #[test]
    fn exponential_has_the_right_mean() {
        let mut rng = Rng::seed_from_u64(7);
        let n = 200_000;
        let mean = (0..n).map(|_| exponential(&mut rng, 4.0)).sum::<f64>() / n as f64;
        // sd of the mean = 0.25 / √n ≈ 5.6e-4
        assert!((mean - 0.25).abs() < 3e-3, "{mean}");
    }

    #[test]
    fn pick_weighted_follows_cumulative_weights_and_skips_zeros() {
        let items = [('a', 1.0), ('b', 0.0), ('c', 3.0)];
        assert_eq!(pick_weighted_with(0.0, &items), Some('a'));
        assert_eq!(pick_weighted_with(0.249, &items), Some('a'));
        assert_eq!(pick_weighted_with(0.25, &items), Some('c'));
        assert_eq!(pick_weighted_with(0.999_999, &items), Some('c'));
        // Past the end by rounding: the last positive item, never a zero one.
        assert_eq!(
            pick_weighted_with(1.0, &[('a', 1.0), ('z', 0.0)]),
            Some('a')
        );
        assert_eq!(pick_weighted_with(0.5, &[('a', 0.0)]), None);
        assert_eq!(pick_weighted_with::<char>(0.5, &[]), None);
    }
}
