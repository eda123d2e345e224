//! Statistics at the bottom layer: estimates with their 95% intervals (over independent runs
//! or over the batches of one run), batch means, Student t quantiles, and the distribution
//! functions the tests of [`crate::conform`] are built from (normal, Student t, gamma,
//! beta).
//!
//! Everything here is plain arithmetic on numbers: no net, no run. The layers above use it —
//! [`crate::sim::MonteCarlo`] (intervals over runs), `runtime::reward` (intervals over the
//! batches of a running plan) and [`crate::conform`] (its tests) — and it uses nothing of
//! theirs.
//!
//! ```
//! use gspn::stats::{estimate, t_quantile_975};
//! let e = estimate(&[1.0, 2.0, 3.0]);
//! assert_eq!(e.mean, 2.0);
//! // s = 1 over 3 values: half-width t₀.₉₇₅(2)·1/√3.
//! assert!((e.half_width - t_quantile_975(2) / 3f64.sqrt()).abs() < 1e-12);
//! ```

use crate::sample::ln;

/// One estimated quantity: the mean of independent observations (runs, or the batches of one
/// run) and the half-width of its 95% interval.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimate {
    /// Mean of the observations.
    pub mean: f64,
    /// Half-width of the 95% confidence interval; NaN with fewer than 2 observations.
    pub half_width: f64,
}

impl Estimate {
    /// Lower end of the 95% interval.
    pub fn lo(&self) -> f64 {
        self.mean - self.half_width
    }

    /// Upper end of the 95% interval.
    pub fn hi(&self) -> f64 {
        self.mean + self.half_width
    }

    /// True when `x` lies in the 95% interval.
    pub fn contains(&self, x: f64) -> bool {
        self.lo() <= x && x <= self.hi()
    }
}

/// The 0.975 quantile of Student's t with `df` degrees of freedom (≥ 1): exact to 9
/// decimals from a table up to 30, then the Cornish–Fisher expansion (error < 1e-7).
pub fn t_quantile_975(df: u64) -> f64 {
    const TABLE: [f64; 30] = [
        12.706204736,
        4.302652730,
        3.182446305,
        2.776445105,
        2.570581836,
        2.446911851,
        2.364624252,
        2.306004135,
        2.262157163,
        2.228138852,
        2.200985160,
        2.178812830,
        2.160368656,
        2.144786688,
        2.131449546,
        2.119905299,
        2.109815578,
        2.100922040,
        2.093024054,
        2.085963447,
        2.079613845,
        2.073873068,
        2.068657610,
        2.063898562,
        2.059538553,
        2.055529439,
        2.051830516,
        2.048407142,
        2.045229642,
        2.042272456,
    ];
    if df == 0 {
        return f64::NAN;
    }
    if df <= 30 {
        return TABLE[df as usize - 1];
    }
    let z: f64 = 1.959_963_984_540_054;
    let v = df as f64;
    let (z2, z3) = (z * z, z * z * z);
    let (z5, z7, z9) = (z3 * z2, z3 * z2 * z2, z3 * z3 * z3);
    z + (z3 + z) / (4.0 * v)
        + (5.0 * z5 + 16.0 * z3 + 3.0 * z) / (96.0 * v * v)
        + (3.0 * z7 + 19.0 * z5 + 17.0 * z3 - 15.0 * z) / (384.0 * v * v * v)
        + (79.0 * z9 + 776.0 * z7 + 1482.0 * z5 - 1920.0 * z3 - 945.0 * z)
            / (92160.0 * v * v * v * v)
}

/// The standard normal 0.975 quantile.
pub const Z975: f64 = 1.959_963_984_540_054;

/// Batch means over one run: the time axis `[0, end]` cut into `n` batches of equal length;
/// each statistic is a time integral ([`BatchMeans::advance`]) or a count
/// ([`BatchMeans::count`]), divided by the batch length.
#[derive(Clone, Debug)]
pub struct BatchMeans {
    len: f64,
    /// `sums[k][b]`: statistic `k` in batch `b`.
    sums: Vec<Vec<f64>>,
    last: f64,
}

impl BatchMeans {
    /// `stats` statistics over `n` (≥ 2) batches of `[0, end]` (end > 0).
    pub fn new(n: usize, end: f64, stats: usize) -> Self {
        BatchMeans {
            len: end / n as f64,
            sums: vec![vec![0.0; n.max(2)]; stats],
            last: 0.0,
        }
    }

    fn batch(&self, t: f64) -> usize {
        let n = self.sums.first().map_or(1, Vec::len);
        ((t / self.len) as usize).min(n - 1)
    }

    /// Adds `values[k]` (held constant since the last call) integrated up to time `t`.
    pub fn advance(&mut self, t: f64, values: &[f64]) {
        let n = self.sums.first().map_or(1, Vec::len);
        let mut from = self.last;
        // Batch by batch, counting the batch up rather than reading it off `from` again: at
        // a batch's end `(b + 1)·len / len` may round below `b + 1`, and the batch would
        // never be left.
        let mut b = self.batch(from);
        while from < t {
            let end = if b + 1 >= n {
                t
            } else {
                t.min((b + 1) as f64 * self.len)
            };
            if end > from {
                for (k, v) in values.iter().enumerate() {
                    self.sums[k][b] += v * (end - from);
                }
                from = end;
            }
            b += 1;
        }
        self.last = self.last.max(t);
    }

    /// Adds `x` to count statistic `k` at time `t`.
    pub fn count(&mut self, t: f64, k: usize, x: f64) {
        let b = self.batch(t);
        self.sums[k][b] += x;
    }

    /// Statistic `k` per batch, per unit of time.
    pub fn batches(&self, k: usize) -> Vec<f64> {
        self.sums[k].iter().map(|s| s / self.len).collect()
    }

    /// Statistic `k` per batch, as summed.
    pub fn sums(&self, k: usize) -> &[f64] {
        &self.sums[k]
    }
}

/// Mean of the batches and the half-width of its 95% interval (Student t, `n − 1` degrees
/// of freedom), as [`crate::sim::MonteCarlo`] gives over runs.
pub fn estimate(xs: &[f64]) -> Estimate {
    let n = xs.len() as f64;
    let mean = xs.iter().sum::<f64>() / n;
    let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0);
    Estimate {
        mean,
        half_width: t_quantile_975(xs.len() as u64 - 1) * (var.max(0.0) / n).sqrt(),
    }
}

/// The ratio `Σ num / Σ den` of two batched counts with its 95% interval (ratio batch means:
/// the residuals `num_b − r·den_b` give the variance).
pub fn ratio_estimate(num: &[f64], den: &[f64]) -> Estimate {
    let (sn, sd): (f64, f64) = (num.iter().sum(), den.iter().sum());
    let r = sn / sd;
    let b = num.len() as f64;
    let res: Vec<f64> = num.iter().zip(den).map(|(n, d)| n - r * d).collect();
    let var = res.iter().map(|x| x * x).sum::<f64>() / (b - 1.0);
    Estimate {
        mean: r,
        half_width: t_quantile_975(num.len() as u64 - 1) * (var / b).sqrt() / (sd / b),
    }
}

/// The complementary error function: the `libm` crate's `erfc` (fdlibm's rational fits,
/// within an ulp or two over the whole line, far in the tail too), where a Chebyshev fit of
/// a textbook was only good to 1.2e-7 relative — the p-values of a long run's drift test
/// live in that tail.
pub fn erfc(x: f64) -> f64 {
    libm::erfc(x)
}

/// P(|T| ≥ t) for Student's t with `df` degrees of freedom.
pub fn student_t_two_sided(t: f64, df: f64) -> f64 {
    beta_i(df / 2.0, 0.5, df / (df + t * t))
}

fn ln_gamma(x: f64) -> f64 {
    // Lanczos (g = 7, n = 9).
    const C: [f64; 9] = [
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
    if x < 0.5 {
        return ln(std::f64::consts::PI / (std::f64::consts::PI * x).sin()) - ln_gamma(1.0 - x);
    }
    let x = x - 1.0;
    let mut a = C[0];
    let t = x + 7.5;
    for (i, &c) in C.iter().enumerate().skip(1) {
        a += c / (x + i as f64);
    }
    0.5 * ln(2.0 * std::f64::consts::PI) + (x + 0.5) * ln(t) - t + ln(a)
}

/// The regularised upper incomplete gamma function Q(a, x) = P(G ≥ x) for G ~ Gamma(a, 1).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).1
}

/// The regularised lower incomplete gamma function P(a, x) = P(G ≤ x) for G ~ Gamma(a, 1).
pub fn gamma_p(a: f64, x: f64) -> f64 {
    gamma_pq(a, x).0
}

/// `(P(a, x), Q(a, x))`, the one on the side of the series computed directly (so a small
/// tail keeps its relative precision) and the other as its complement.
fn gamma_pq(a: f64, x: f64) -> (f64, f64) {
    if x <= 0.0 {
        return (0.0, 1.0);
    }
    let gln = ln_gamma(a);
    // The series and the fraction take O(√a) terms near the mode.
    const MAX_TERMS: usize = 100_000;
    if x < a + 1.0 {
        // Series for P.
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..MAX_TERMS {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        let p = sum * (-x + a * ln(x) - gln).exp();
        (p, 1.0 - p)
    } else {
        // Continued fraction for Q (Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..MAX_TERMS {
            let an = -(i as f64) * (i as f64 - a);
            b += 2.0;
            d = an * d + b;
            if d.abs() < tiny {
                d = tiny;
            }
            c = b + an / c;
            if c.abs() < tiny {
                c = tiny;
            }
            d = 1.0 / d;
            let del = d * c;
            h *= del;
            if (del - 1.0).abs() < 1e-15 {
                break;
            }
        }
        let q = (-x + a * ln(x) - gln).exp() * h;
        (1.0 - q, q)
    }
}

/// P(K > k) for Kolmogorov's limiting distribution `K = sup |B(t)|` of the Brownian bridge:
/// `2 Σ (−1)^(j−1) exp(−2j²k²)` for large `k`, `1 − √(2π)/k Σ exp(−(2j−1)²π²/(8k²))` for
/// small `k` (each series converges fast on its side of 1.18).
pub fn kolmogorov_q(k: f64) -> f64 {
    if k.is_nan() {
        return f64::NAN;
    }
    if k <= 0.0 {
        return 1.0;
    }
    let mut sum = 0.0;
    if k < 1.18 {
        let w = std::f64::consts::PI * std::f64::consts::PI / (8.0 * k * k);
        for j in 1..=20 {
            let m = (2 * j - 1) as f64;
            sum += (-m * m * w).exp();
        }
        (1.0 - (2.0 * std::f64::consts::PI).sqrt() / k * sum).clamp(0.0, 1.0)
    } else {
        for j in 1..=100 {
            let j = j as f64;
            let term = (-2.0 * j * j * k * k).exp();
            sum += if j as u64 % 2 == 1 { term } else { -term };
            if term < 1e-18 {
                break;
            }
        }
        (2.0 * sum).clamp(0.0, 1.0)
    }
}

/// P(X ≤ k) for X ~ Binomial(n, p): `I_(1−p)(n − k, k + 1)`.
pub fn binomial_cdf(k: u64, n: u64, p: f64) -> f64 {
    if k >= n {
        return 1.0;
    }
    beta_i((n - k) as f64, (k + 1) as f64, 1.0 - p)
}

/// The central `level` interval `[lo, hi]` of Binomial(n, p): the fewest `lo` and `hi` with
/// `P(X < lo) ≤ (1 − level)/2` and `P(X > hi) ≤ (1 − level)/2` — where the count of `n`
/// independent tests at level `p` falls with probability at least `level`.
pub fn binomial_interval(n: u64, p: f64, level: f64) -> (u64, u64) {
    let tail = (1.0 - level) / 2.0;
    let lo = (0..=n).find(|&k| binomial_cdf(k, n, p) > tail).unwrap_or(n);
    let hi = (lo..=n)
        .find(|&k| binomial_cdf(k, n, p) >= 1.0 - tail)
        .unwrap_or(n);
    (lo, hi)
}

/// The regularised incomplete beta function I_x(a, b).
pub fn beta_i(a: f64, b: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 0.0;
    }
    if x >= 1.0 {
        return 1.0;
    }
    let front = (ln_gamma(a + b) - ln_gamma(a) - ln_gamma(b) + a * ln(x) + b * ln(1.0 - x)).exp();
    if x < (a + 1.0) / (a + b + 2.0) {
        front * beta_cf(a, b, x) / a
    } else {
        1.0 - front * beta_cf(b, a, 1.0 - x) / b
    }
}

fn beta_cf(a: f64, b: f64, x: f64) -> f64 {
    let tiny = 1e-300;
    let (qab, qap, qam) = (a + b, a + 1.0, a - 1.0);
    let mut c = 1.0;
    let mut d = 1.0 - qab * x / qap;
    if d.abs() < tiny {
        d = tiny;
    }
    d = 1.0 / d;
    let mut h = d;
    // One step of the modified Lentz recurrence with coefficient `aa`.
    let step = |aa: f64, c: &mut f64, d: &mut f64| -> f64 {
        *d = 1.0 + aa * *d;
        if d.abs() < tiny {
            *d = tiny;
        }
        *c = 1.0 + aa / *c;
        if c.abs() < tiny {
            *c = tiny;
        }
        *d = 1.0 / *d;
        *d * *c
    };
    for m in 1..1000 {
        let m = m as f64;
        let m2 = 2.0 * m;
        h *= step(m * (b - m) * x / ((qam + m2) * (a + m2)), &mut c, &mut d);
        let del = step(
            -(a + m) * (qab + m) * x / ((a + m2) * (qap + m2)),
            &mut c,
            &mut d,
        );
        h *= del;
        if (del - 1.0).abs() < 1e-15 {
            break;
        }
    }
    h
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `erfc` against 40-digit values (mpmath, rounded to the nearest double), to 1e-15 relative: the textbook fit it
    /// replaced was off in the seventh digit, and by orders of magnitude past x = 5.
    #[test]
    fn erfc_matches_known_values_to_1e_15() {
        let known = [
            (0.0, 1.0),
            (0.5, 0.479_500_122_186_953_5),
            (1.0, 0.157_299_207_050_285_13),
            (2.0, 0.004_677_734_981_047_266),
            (3.0, 2.209_049_699_858_544e-5),
            (5.0, 1.537_459_794_428_035e-12),
            (-1.0, 1.842_700_792_949_714_8),
            (10.0, 2.088_487_583_762_545e-45),
        ];
        for (x, want) in known {
            let got = erfc(x);
            assert!(
                ((got - want) / want).abs() < 1e-15,
                "erfc({x}) = {got:e}, want {want:e}"
            );
        }
    }

    #[test]
    fn t_quantiles() {
        assert_eq!(t_quantile_975(1), 12.706204736);
        assert!((t_quantile_975(31) - 2.039513446).abs() < 1e-7);
        assert!((t_quantile_975(199) - 1.971956544).abs() < 1e-8);
        let z = 1.959_963_984_540_054;
        assert!(t_quantile_975(1_000_000) > z && t_quantile_975(1_000_000) - z < 2.5e-6);
        assert!(t_quantile_975(0).is_nan());
    }

    #[test]
    fn batches_split_integrals_at_batch_ends() {
        let mut b = BatchMeans::new(4, 8.0, 1);
        b.advance(3.0, &[1.0]);
        b.advance(8.0, &[2.0]);
        assert_eq!(b.sums(0), &[2.0, 3.0, 4.0, 4.0]);
        let e = estimate(&b.batches(0));
        assert!((e.mean - 1.625).abs() < 1e-12);
    }

    /// Regression: a run that ended at 600.0000611410001 (real time leaking into virtual
    /// time) hung `conform`: at 90.00000917115, the end of batch 2, `t / len` rounds to
    /// 2.9999999999999996 and `advance` never left batch 2.
    #[test]
    fn a_batch_end_that_rounds_down_is_left() {
        let end = 600.000_061_141_000_1;
        let mut b = BatchMeans::new(20, end, 1);
        let edge = 3.0 * (end / 20.0);
        assert!(
            ((edge / (end / 20.0)) as usize) < 3,
            "the rounding this test is about"
        );
        b.advance(edge, &[1.0]);
        b.advance(end, &[2.0]);
        let sums = b.sums(0);
        let len = end / 20.0;
        for (i, s) in sums.iter().enumerate() {
            let want = if i < 3 { len } else { 2.0 * len };
            assert!((s - want).abs() < 1e-9, "batch {i}: {s} vs {want}");
        }
    }

    #[test]
    fn gamma_tails_are_complements_and_exact_for_integer_shapes() {
        for &(a, x) in &[
            (1.0, 0.3),
            (3.0, 1.0),
            (3.0, 7.5),
            (40.0, 38.0),
            (5000.0, 5100.0),
        ] {
            assert!(
                (gamma_p(a, x) + gamma_q(a, x) - 1.0).abs() < 1e-12,
                "{a} {x}"
            );
        }
        // Gamma(3, 1): P(G ≤ x) = 1 − e^(−x)(1 + x + x²/2).
        for x in [0.2f64, 1.0, 2.5, 9.0] {
            let exact = 1.0 - (-x).exp() * (1.0 + x + x * x / 2.0);
            assert!((gamma_p(3.0, x) - exact).abs() < 1e-12, "{x}");
        }
        // The small lower tail keeps its relative precision.
        let x = 1e-3f64;
        let exact = x * x * x / 6.0 * (1.0 - 3.0 * x / 4.0);
        assert!((gamma_p(3.0, x) / exact - 1.0).abs() < 1e-5);
    }

    #[test]
    fn kolmogorov_tail_at_its_tabulated_quantiles() {
        // Upper 5% and 1% points of Kolmogorov's distribution (Smirnov 1948's table).
        assert!((kolmogorov_q(1.358_098_6) - 0.05).abs() < 1e-7);
        assert!((kolmogorov_q(1.627_623_6) - 0.01).abs() < 1e-7);
        // The two series agree where they meet.
        let (below, above) = (kolmogorov_q(1.18 - 1e-12), kolmogorov_q(1.18));
        assert!((below - above).abs() < 1e-10, "{below} {above}");
        assert_eq!(kolmogorov_q(0.0), 1.0);
        assert!(kolmogorov_q(0.2) > 1.0 - 1e-12);
    }

    #[test]
    fn binomial_cdf_and_interval() {
        // Against the sum of the probabilities.
        let (n, p) = (30u64, 0.05f64);
        let mut choose = 1.0f64;
        let mut sum = 0.0;
        for k in 0..=n {
            if k > 0 {
                choose *= (n - k + 1) as f64 / k as f64;
            }
            sum += choose * p.powi(k as i32) * (1.0 - p).powi((n - k) as i32);
            assert!((binomial_cdf(k, n, p) - sum).abs() < 1e-12, "{k}");
        }
        let (lo, hi) = binomial_interval(1000, 0.05, 0.999);
        assert!(binomial_cdf(lo - 1, 1000, 0.05) <= 0.0005);
        assert!(binomial_cdf(lo, 1000, 0.05) > 0.0005);
        assert!(binomial_cdf(hi, 1000, 0.05) >= 0.9995);
        assert!(binomial_cdf(hi - 1, 1000, 0.05) < 0.9995);
        assert_eq!(binomial_interval(10, 0.0, 0.999), (0, 0));
    }
}
