//! The statistics of conformance: batch means over one run, Poisson score intervals for rates,
//! the Lilliefors-corrected Kolmogorov–Smirnov test of exponentiality, Pearson's chi-square
//! for choices, and the distribution functions they need (normal, Student t, chi-square).
//!
//! Intervals are the 95% ones `simulate --runs` prints ([`Estimate`], Student t quantiles from
//! [`t_quantile_975`]); here the observations are the batches of one run instead of
//! independent runs.

use crate::sample::ln;
use crate::sim::{Estimate, t_quantile_975};

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
        while from < t {
            let b = self.batch(from);
            let end = if b == n - 1 {
                t
            } else {
                t.min((b + 1) as f64 * self.len)
            };
            for (k, v) in values.iter().enumerate() {
                self.sums[k][b] += v * (end - from);
            }
            from = end;
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

/// Two-sided p-value of `predicted` against batch means `est` with `df` degrees of freedom
/// (the t statistic `(mean − predicted) / (half_width / t₀.₉₇₅)`); a zero-width interval gives
/// 1 when it holds the prediction (to 1e-12 relative) and 0 otherwise.
pub fn t_test(est: &Estimate, predicted: f64, df: u64) -> f64 {
    let se = est.half_width / t_quantile_975(df);
    let d = est.mean - predicted;
    if se.is_nan() || se <= 0.0 {
        return if d.abs() <= 1e-12 * predicted.abs().max(1.0) {
            1.0
        } else {
            0.0
        };
    }
    student_t_two_sided(d.abs() / se, df as f64)
}

/// The 95% score interval of a Poisson rate from `n` events over exposure `e`: the `λ` with
/// `(n − λe)² ≤ z²·λe` (what [`rate_test`] accepts).
pub fn rate_interval(n: u64, e: f64) -> (f64, f64) {
    let (n, z2) = (n as f64, Z975 * Z975);
    let root = Z975 * (4.0 * n + z2).sqrt();
    (
        ((2.0 * n + z2 - root) / (2.0 * e)).max(0.0),
        (2.0 * n + z2 + root) / (2.0 * e),
    )
}

/// Two-sided p-value of rate `lambda` given `n` events over exposure `e` (score test: the
/// counting process minus `λ·exposure` is a martingale of variance `λ·exposure`).
pub fn rate_test(n: u64, e: f64, lambda: f64) -> f64 {
    let mu = lambda * e;
    if mu <= 0.0 {
        return if n == 0 { 1.0 } else { 0.0 };
    }
    let z = (n as f64 - mu) / mu.sqrt();
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// Upper-tail points of the modified statistic `(D − 0.2/n)(√n + 0.26 + 0.5/√n)` of the
/// Kolmogorov–Smirnov test for exponentiality with the mean estimated (Lilliefors' case;
/// Stephens 1974, in D'Agostino & Stephens, *Goodness-of-Fit Techniques*, table 4.11).
const LILLIEFORS_EXP: [(f64, f64); 5] = [
    (0.926, 0.15),
    (0.990, 0.10),
    (1.094, 0.05),
    (1.190, 0.025),
    (1.308, 0.01),
];

/// The Kolmogorov–Smirnov test of exponentiality with the rate estimated from `xs`
/// (Lilliefors' correction, Stephens' modified statistic): the modified statistic and its
/// p-value, interpolated in `ln p` between the tabulated points (extrapolated beyond them,
/// capped at 1: approximate outside 0.01–0.15, exact at the 0.05 decision). `None` for fewer
/// than 2 values or a zero mean.
pub fn ks_exponential(xs: &[f64]) -> Option<(f64, f64)> {
    let n = xs.len();
    if n < 2 {
        return None;
    }
    let mean = xs.iter().sum::<f64>() / n as f64;
    if mean.is_nan() || mean <= 0.0 {
        return None;
    }
    let mut s: Vec<f64> = xs.to_vec();
    s.sort_by(f64::total_cmp);
    let nf = n as f64;
    let mut d = 0.0f64;
    for (i, &x) in s.iter().enumerate() {
        let f = 1.0 - (-x / mean).exp();
        d = d.max((i + 1) as f64 / nf - f).max(f - i as f64 / nf);
    }
    let modified = (d - 0.2 / nf) * (nf.sqrt() + 0.26 + 0.5 / nf.sqrt());
    Some((modified, lilliefors_p(modified)))
}

fn lilliefors_p(x: f64) -> f64 {
    let t = &LILLIEFORS_EXP;
    let seg = if x <= t[0].0 {
        0
    } else {
        t.windows(2)
            .position(|w| x <= w[1].0)
            .unwrap_or(t.len() - 2)
    };
    let ((x0, p0), (x1, p1)) = (t[seg], t[seg + 1]);
    let lp = ln(p0) + (x - x0) * (ln(p1) - ln(p0)) / (x1 - x0);
    lp.exp().min(1.0)
}

/// Pearson's chi-square test of counts against probabilities: the p-value (chi-square with
/// `k − 1` degrees of freedom over the cells of positive probability). A count where the
/// probability is 0 gives 0; one cell gives 1 when nothing fell elsewhere.
pub fn chi_square(counts: &[u64], probs: &[f64]) -> f64 {
    let total: u64 = counts.iter().sum();
    if total == 0 {
        return 1.0;
    }
    let mut x2 = 0.0;
    let mut cells = 0;
    for (&c, &p) in counts.iter().zip(probs) {
        if p <= 0.0 {
            if c > 0 {
                return 0.0;
            }
            continue;
        }
        cells += 1;
        let e = p * total as f64;
        x2 += (c as f64 - e).powi(2) / e;
    }
    if cells <= 1 {
        return 1.0;
    }
    gamma_q((cells - 1) as f64 / 2.0, x2 / 2.0)
}

/// The complementary error function (Numerical Recipes' Chebyshev fit, relative error
/// < 1.2e-7).
pub fn erfc(x: f64) -> f64 {
    let z = x.abs();
    let t = 1.0 / (1.0 + 0.5 * z);
    let r = t
        * (-z * z - 1.265_512_23
            + t * (1.000_023_68
                + t * (0.374_091_96
                    + t * (0.096_784_18
                        + t * (-0.186_288_06
                            + t * (0.278_868_07
                                + t * (-1.135_203_98
                                    + t * (1.488_515_87
                                        + t * (-0.822_152_23 + t * 0.170_872_77)))))))))
            .exp();
    if x >= 0.0 { r } else { 2.0 - r }
}

/// One-way analysis of variance: the p-value of "the groups have one mean" (Fisher's F with
/// `G − 1` and `N − G` degrees of freedom). Groups of no value are left out; fewer than two
/// groups, or no degree of freedom within them, give 1. Without spread within the groups the
/// p-value is 0 when their means differ and 1 when they do not (a sum of squares below
/// `10⁻²⁰·Σx²`, rounding in the times it was computed from, counts as none).
pub fn anova_p(groups: &[&[f64]]) -> f64 {
    let groups: Vec<&[f64]> = groups.iter().copied().filter(|g| !g.is_empty()).collect();
    let n: usize = groups.iter().map(|g| g.len()).sum();
    let k = groups.len();
    if k < 2 || n <= k {
        return 1.0;
    }
    let mean = |g: &[f64]| g.iter().sum::<f64>() / g.len() as f64;
    let all = groups.iter().map(|g| g.iter().sum::<f64>()).sum::<f64>() / n as f64;
    let (mut between, mut within) = (0.0, 0.0);
    for g in &groups {
        let m = mean(g);
        between += g.len() as f64 * (m - all).powi(2);
        within += g.iter().map(|x| (x - m).powi(2)).sum::<f64>();
    }
    let scale: f64 = groups.iter().flat_map(|g| g.iter()).map(|x| x * x).sum();
    let none = |ss: f64| ss <= 1e-20 * scale;
    if none(between) {
        return 1.0;
    }
    let (d1, d2) = ((k - 1) as f64, (n - k) as f64);
    if none(within) {
        return 0.0;
    }
    let f = (between / d1) / (within / d2);
    beta_i(d2 / 2.0, d1 / 2.0, d2 / (d2 + d1 * f))
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

/// The regularised upper incomplete gamma function Q(a, x).
pub fn gamma_q(a: f64, x: f64) -> f64 {
    if x <= 0.0 {
        return 1.0;
    }
    let gln = ln_gamma(a);
    if x < a + 1.0 {
        // Series for P.
        let (mut ap, mut sum) = (a, 1.0 / a);
        let mut del = sum;
        for _ in 0..1000 {
            ap += 1.0;
            del *= x / ap;
            sum += del;
            if del.abs() < sum.abs() * 1e-15 {
                break;
            }
        }
        1.0 - sum * (-x + a * ln(x) - gln).exp()
    } else {
        // Continued fraction for Q (Lentz).
        let tiny = 1e-300;
        let mut b = x + 1.0 - a;
        let mut c = 1.0 / tiny;
        let mut d = 1.0 / b;
        let mut h = d;
        for i in 1..1000 {
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
        (-x + a * ln(x) - gln).exp() * h
    }
}

/// The regularised incomplete beta function I_x(a, b).
fn beta_i(a: f64, b: f64, x: f64) -> f64 {
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

    #[test]
    fn distribution_functions() {
        // Φ(−1.96)·2 = 0.05; the t test at its own quantile; chi-square(2) tail e^{-x/2}.
        assert!((erfc(Z975 / std::f64::consts::SQRT_2) - 0.05).abs() < 1e-7);
        assert!((student_t_two_sided(t_quantile_975(19), 19.0) - 0.05).abs() < 1e-9);
        assert!((student_t_two_sided(t_quantile_975(4), 4.0) - 0.05).abs() < 1e-9);
        assert!((gamma_q(1.0, 3.0) - (-3.0f64).exp()).abs() < 1e-12);
        assert!((gamma_q(2.5, 1.0) - 0.849_145_036_058_179_5).abs() < 1e-9);
        assert!((lilliefors_p(1.094) - 0.05).abs() < 1e-12);
        assert!(lilliefors_p(0.5) <= 1.0 && lilliefors_p(2.0) < 0.01);
    }

    #[test]
    fn score_interval_is_the_test_acceptance_region() {
        let (lo, hi) = rate_interval(40, 20.0);
        assert!((rate_test(40, 20.0, lo) - 0.05).abs() < 1e-6);
        assert!((rate_test(40, 20.0, hi) - 0.05).abs() < 1e-6);
        assert!(lo < 2.0 && 2.0 < hi);
    }

    #[test]
    fn anova_of_two_groups_is_the_pooled_t_test() {
        // Means 2 and 5, within sum of squares 4 on 4 df: F = 13.5 = t² with 4 df.
        let p = anova_p(&[&[1.0, 2.0, 3.0], &[4.0, 5.0, 6.0]]);
        assert!(
            (p - student_t_two_sided(13.5f64.sqrt(), 4.0)).abs() < 1e-12,
            "{p}"
        );
        assert!((0.02..0.025).contains(&p), "{p}");
        assert_eq!(anova_p(&[&[3.0, 3.0], &[3.0, 3.0, 3.0]]), 1.0);
        assert_eq!(anova_p(&[&[3.0, 3.0], &[4.0, 4.0]]), 0.0);
        assert_eq!(anova_p(&[&[1.0, 2.0], &[]]), 1.0);
        // Rounding is no spread.
        let (a, b) = (3.0 + 4e-16, 3.0 - 4e-16);
        assert_eq!(anova_p(&[&[a, a, a], &[b, b]]), 1.0);
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
}
