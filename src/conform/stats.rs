//! The tests of conformance: Student t against batch means, Poisson score intervals for rates,
//! the Lilliefors-corrected Kolmogorov–Smirnov test of exponentiality, Pearson's chi-square
//! for choices, one-way analysis of variance, and the tests of agents' stays against an
//! exponential holding time of known rate ([`stays_mean_test`], [`stays_ks_test`]), which
//! take the end of the run into account: a stay that entered `c` before the end was seen
//! only because it lasted less than `c`.
//!
//! The estimates they read and the distribution functions they are built from live at the
//! bottom layer, [`crate::stats`] (re-exported here, where they used to be); intervals are the
//! 95% ones `simulate --runs` prints, here over the batches of one run instead of
//! independent runs.

pub(crate) use crate::stats::{
    BatchMeans, Estimate, Z975, erfc, estimate, gamma_q, ratio_estimate, student_t_two_sided,
    t_quantile_975,
};

use crate::sample::ln;
use crate::stats::{beta_i, gamma_p, kolmogorov_q};

/// Two-sided p-value of `predicted` against batch means `est` with `df` degrees of freedom
/// (the t statistic `(mean − predicted) / (half_width / t₀.₉₇₅)`); a zero-width interval gives
/// 1 when it holds the prediction (to 1e-12 relative) and 0 otherwise.
pub(crate) fn t_test(est: &Estimate, predicted: f64, df: u64) -> f64 {
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
pub(crate) fn rate_interval(n: u64, e: f64) -> (f64, f64) {
    let (n, z2) = (n as f64, Z975 * Z975);
    let root = Z975 * (4.0 * n + z2).sqrt();
    (
        ((2.0 * n + z2 - root) / (2.0 * e)).max(0.0),
        (2.0 * n + z2 + root) / (2.0 * e),
    )
}

/// Two-sided p-value of rate `lambda` given `n` events over exposure `e` (score test: the
/// counting process minus `λ·exposure` is a martingale of variance `λ·exposure`).
pub(crate) fn rate_test(n: u64, e: f64, lambda: f64) -> f64 {
    let mu = lambda * e;
    if mu <= 0.0 {
        return if n == 0 { 1.0 } else { 0.0 };
    }
    let z = (n as f64 - mu) / mu.sqrt();
    erfc(z.abs() / std::f64::consts::SQRT_2)
}

/// Exact two-sided p-value of rate `lambda` given `n` events over exposure `e`, when the
/// exposure was counted until the `n`-th event: `λ·e` is then Gamma(n, 1) under the model
/// (the sum of `n` unit exponentials), so the p-value is uniform on (0, 1) and a test at
/// level α errs with probability α exactly — what the live monitor's false-alarm design needs
/// far in the tail, where the score test's normal approximation is off.
pub(crate) fn gamma_test(n: u64, e: f64, lambda: f64) -> f64 {
    let x = lambda * e;
    if n == 0 || x.is_nan() || x <= 0.0 {
        return if n == 0 { 1.0 } else { 0.0 };
    }
    let (a, b) = (gamma_p(n as f64, x), gamma_q(n as f64, x));
    (2.0 * a.min(b)).min(1.0)
}

/// Mean and variance of an exponential of rate `rate` conditioned on being at most `c`
/// (`c` = ∞: `1/rate` and `1/rate²`): `1/λ − c·q/(1 − q)` and `1/λ² − c²·q/(1 − q)²` with
/// `q = e^(−λc)`, by their series for small `λc` (where the closed forms cancel).
pub(crate) fn truncated_exponential(rate: f64, c: f64) -> (f64, f64) {
    let a = rate * c;
    if a.is_infinite() {
        return (1.0 / rate, 1.0 / (rate * rate));
    }
    if a < 0.05 {
        // 1/a − 1/(eᵃ − 1) = 1/2 − a/12 + a³/720 − …; its derivative gives the variance.
        let a2 = a * a;
        let mean = c * (0.5 - a / 12.0 + a * a2 / 720.0 - a2 * a2 * a / 30_240.0);
        let var = c * c * (1.0 / 12.0 - a2 / 240.0 + a2 * a2 / 6_048.0);
        return (mean, var);
    }
    let q = (-a).exp();
    let one_minus_q = -(-a).exp_m1();
    let r = q / one_minus_q;
    (
        1.0 / rate - c * r,
        1.0 / (rate * rate) - c * c * r / one_minus_q,
    )
}

/// Two-sided p-value of "these stays are exponential with rate `rate`" from their sum.
/// Each stay is `(duration, horizon)`: it entered `horizon` before the end of the run, so it
/// was seen ended only because `duration ≤ horizon`, and under the model its duration is the
/// exponential truncated at its horizon ([`truncated_exponential`]). The sum is referred to
/// the gamma distribution with the sum's exact mean and variance — exactly the
/// `Gamma(n, 1/rate)` of `n` exponential stays when no horizon cuts (each `≫ 1/rate`).
/// Stays with horizon 0 say nothing and are left out; `None` when none is left.
pub(crate) fn stays_mean_test(stays: &[(f64, f64)], rate: f64) -> Option<f64> {
    let (mut sum, mut mean, mut var) = (0.0, 0.0, 0.0);
    for &(x, c) in stays.iter().filter(|s| s.1 > 0.0) {
        let (m, v) = truncated_exponential(rate, c);
        sum += x;
        mean += m;
        var += v;
    }
    if mean <= 0.0 || var <= 0.0 {
        return None;
    }
    let (shape, scale) = (mean * mean / var, var / mean);
    let lower = gamma_p(shape, sum / scale);
    Some((2.0 * lower.min(1.0 - lower)).min(1.0))
}

/// Kolmogorov–Smirnov test of "these stays are exponential with rate `rate`" (the rate the
/// model gives, not one estimated from them): each stay `(duration, horizon)` becomes
/// `u = F(duration) / F(horizon)`, uniform on [0, 1] under the model whatever its horizon
/// (see [`stays_mean_test`]), and the `u`s are tested against the uniform. Returns Stephens'
/// modified statistic `D·(√n + 0.12 + 0.11/√n)` and its p-value from Kolmogorov's
/// distribution; `None` for fewer than 2 stays.
pub(crate) fn stays_ks_test(stays: &[(f64, f64)], rate: f64) -> Option<(f64, f64)> {
    let cdf = |x: f64| -(-rate * x).exp_m1();
    let mut us: Vec<f64> = stays
        .iter()
        .filter(|s| s.1 > 0.0)
        .map(|&(x, c)| (cdf(x) / cdf(c)).min(1.0))
        .collect();
    let n = us.len();
    if n < 2 {
        return None;
    }
    us.sort_by(f64::total_cmp);
    let nf = n as f64;
    let d = us
        .iter()
        .enumerate()
        .map(|(i, &u)| ((i + 1) as f64 / nf - u).max(u - i as f64 / nf))
        .fold(0.0f64, f64::max);
    let k = d * (nf.sqrt() + 0.12 + 0.11 / nf.sqrt());
    Some((k, kolmogorov_q(k)))
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
pub(crate) fn ks_exponential(xs: &[f64]) -> Option<(f64, f64)> {
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
pub(crate) fn chi_square(counts: &[u64], probs: &[f64]) -> f64 {
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

/// One-way analysis of variance: the p-value of "the groups have one mean" (Fisher's F with
/// `G − 1` and `N − G` degrees of freedom). Groups of no value are left out; fewer than two
/// groups, or no degree of freedom within them, give 1. Without spread within the groups the
/// p-value is 0 when their means differ and 1 when they do not (a sum of squares below
/// `10⁻²⁰·Σx²`, rounding in the times it was computed from, counts as none).
pub(crate) fn anova_p(groups: &[&[f64]]) -> f64 {
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

    /// ∫₀ᶜ f(x)·λe^(−λx) dx by Simpson's rule on 20 000 intervals.
    fn integral(rate: f64, c: f64, f: impl Fn(f64) -> f64) -> f64 {
        let n = 20_000;
        let h = c / n as f64;
        let g = |x: f64| f(x) * rate * (-rate * x).exp();
        let inner: f64 = (1..n)
            .map(|i| if i % 2 == 1 { 4.0 } else { 2.0 } * g(i as f64 * h))
            .sum();
        (g(0.0) + inner + g(c)) * h / 3.0
    }

    #[test]
    fn truncated_exponential_moments_match_their_integrals() {
        for &(rate, c) in &[
            (1.0, 0.01),
            (2.0, 0.024),
            (2.0, 0.026),
            (0.5, 0.3),
            (1.0, 1.0),
            (3.0, 2.0),
            (1.0, 40.0),
        ] {
            let mass = integral(rate, c, |_| 1.0);
            let mean = integral(rate, c, |x| x) / mass;
            let var = integral(rate, c, |x| (x - mean).powi(2)) / mass;
            let (m, v) = truncated_exponential(rate, c);
            assert!((m - mean).abs() < 1e-9 * mean, "{rate} {c}: {m} vs {mean}");
            assert!((v - var).abs() < 1e-9 * var, "{rate} {c}: {v} vs {var}");
        }
        // The series and the closed form meet at λc = 0.05.
        let (a, b) = (
            truncated_exponential(1.0, 0.05 - 1e-13),
            truncated_exponential(1.0, 0.05),
        );
        assert!(
            (a.0 - b.0).abs() < 1e-13 && (a.1 - b.1).abs() < 1e-13,
            "{a:?} {b:?}"
        );
        assert_eq!(truncated_exponential(2.0, f64::INFINITY), (0.5, 0.25));
    }

    #[test]
    fn stays_far_from_the_end_get_the_exact_gamma_test() {
        // One stay: p = 2·min(F, 1 − F) of the exponential.
        for x in [0.05f64, 0.7, 3.0] {
            let f = 1.0 - (-2.0 * x).exp();
            let p = stays_mean_test(&[(x, 1e6)], 2.0).unwrap();
            assert!((p - 2.0 * f.min(1.0 - f)).abs() < 1e-12, "{x}: {p}");
        }
        // Three stays of rate 1: the sum is Gamma(3, 1).
        let stays = [(0.4, 1e6), (1.1, 1e6), (2.0, 1e6)];
        let s = 3.5f64;
        let lower = 1.0 - (-s).exp() * (1.0 + s + s * s / 2.0);
        let p = stays_mean_test(&stays, 1.0).unwrap();
        assert!((p - 2.0 * lower.min(1.0 - lower)).abs() < 1e-12, "{p}");
        // Horizon 0 says nothing.
        assert_eq!(stays_mean_test(&[(0.0, 0.0)], 1.0), None);
    }

    /// Runs of `entries` stays of rate 1 entering uniformly over `[0, end]`, seen only when
    /// they end by `end`: how often each test flags at 5% over `reps` runs, and the naive
    /// gamma test that ignores the end.
    fn cut_runs(reps: u64, entries: usize, end: f64) -> (u64, u64, u64) {
        use rand::SeedableRng;
        let mut rng = crate::sample::Rng::seed_from_u64(24);
        let (mut mean_flags, mut ks_flags, mut naive_flags) = (0, 0, 0);
        for _ in 0..reps {
            let mut stays = Vec::new();
            for _ in 0..entries {
                let entered = crate::sample::uniform(&mut rng) * end;
                let x = crate::sample::exponential(&mut rng, 1.0);
                if entered + x <= end {
                    stays.push((x, end - entered));
                }
            }
            mean_flags += (stays_mean_test(&stays, 1.0).unwrap() < 0.05) as u64;
            ks_flags += (stays_ks_test(&stays, 1.0).unwrap().1 < 0.05) as u64;
            let far: Vec<(f64, f64)> = stays.iter().map(|s| (s.0, f64::INFINITY)).collect();
            naive_flags += (stays_mean_test(&far, 1.0).unwrap() < 0.05) as u64;
        }
        (mean_flags, ks_flags, naive_flags)
    }

    #[test]
    fn stays_cut_by_the_end_of_the_run_keep_the_level() {
        // Runs of 5 mean stays: a stay that entered late was seen only if it was short (about
        // a fifth of the entries are still in the place at the end).
        let reps = 2000;
        let (mean_flags, ks_flags, naive_flags) = cut_runs(reps, 200, 5.0);
        let (lo, hi) = crate::stats::binomial_interval(reps, 0.05, 0.999);
        eprintln!(
            "of {reps} runs, flagged: mean {mean_flags}, ks {ks_flags}, naive {naive_flags} \
             (99.9% interval [{lo}, {hi}])"
        );
        assert!(
            (lo..=hi).contains(&mean_flags),
            "{mean_flags} not in [{lo}, {hi}]"
        );
        assert!(
            (lo..=hi).contains(&ks_flags),
            "{ks_flags} not in [{lo}, {hi}]"
        );
        // Ignoring the end, the seen stays look short.
        assert!(naive_flags > 3 * hi, "{naive_flags} vs {hi}");
    }
}
