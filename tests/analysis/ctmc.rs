//! The CTMC solvers on hand-built chains with closed-form answers: steady state (sparse LU,
//! Gauss–Seidel, power iteration), limiting distributions of non-ergodic chains, transient
//! distributions by uniformization.

use gspn::analysis::ctmc::{Ctmc, Method, SteadyOptions, TransientOptions, poisson_weights};

fn eps(eps: f64) -> TransientOptions {
    TransientOptions {
        eps,
        ..TransientOptions::default()
    }
}

fn opts(method: Method) -> SteadyOptions {
    // A residual of 1e-12 leaves an error up to the chain's condition number times that;
    // the closed-form checks ask for a residual near rounding.
    SteadyOptions {
        method,
        tolerance: 1e-15,
        ..SteadyOptions::default()
    }
}

fn close(a: f64, b: f64, tol: f64) -> bool {
    (a - b).abs() <= tol
}

#[test]
fn two_state_chain_has_rate_weighted_steady_state() {
    let c = Ctmc::from_triplets(2, vec![(0, 1, 3.0), (1, 0, 0.5)]);
    for m in [
        Method::Auto,
        Method::Direct,
        Method::GaussSeidel,
        Method::Power,
    ] {
        let pi = c.steady_state(&opts(m)).unwrap();
        assert!(close(pi[0], 0.5 / 3.5, 1e-12), "{m:?}: {pi:?}");
        assert!(close(pi[1], 3.0 / 3.5, 1e-12), "{m:?}: {pi:?}");
    }
}

/// M/M/1/K: π_k ∝ ρ^k.
fn birth_death(k: usize, lambda: f64, mu: f64) -> (Ctmc, Vec<f64>) {
    let mut t = Vec::new();
    for i in 0..k {
        t.push((i as u32, i as u32 + 1, lambda));
        t.push((i as u32 + 1, i as u32, mu));
    }
    let rho = lambda / mu;
    let w: Vec<f64> = (0..=k).map(|i| rho.powi(i as i32)).collect();
    let s: f64 = w.iter().sum();
    (
        Ctmc::from_triplets(k + 1, t),
        w.into_iter().map(|x| x / s).collect(),
    )
}

#[test]
fn birth_death_chain_matches_closed_form_with_every_solver() {
    let (c, exact) = birth_death(60, 0.9, 1.0);
    for m in [Method::Auto, Method::Direct, Method::GaussSeidel] {
        let pi = c.steady_state(&opts(m)).unwrap();
        for (p, e) in pi.iter().zip(&exact) {
            assert!(close(*p, *e, 1e-12), "{m:?}: {p} vs {e}");
        }
        assert!(c.residual(&pi) <= 1e-12);
        assert!(close(pi.iter().sum::<f64>(), 1.0, 1e-14));
    }
}

#[test]
fn chain_above_the_direct_limit_is_solved_iteratively() {
    // Above the direct limit: Gauss–Seidel with the residual check.
    let (c, exact) = birth_death(3_000, 0.5, 1.0);
    let pi = c
        .steady_state(&SteadyOptions {
            direct_limit: 1_000,
            ..opts(Method::Auto)
        })
        .unwrap();
    for (p, e) in pi.iter().zip(&exact) {
        assert!(close(*p, *e, 1e-12), "{p} vs {e}");
    }
    assert!(c.residual(&pi) <= 1e-12);
}

#[test]
fn competing_absorptions_split_by_rates() {
    // 0 → 1 (a, absorbing), 0 → 2 (b); 2 ⇄ 3 (c, d) is a bottom component.
    let (a, b, cr, d) = (1.0, 3.0, 2.0, 5.0);
    let c = Ctmc::from_triplets(4, vec![(0, 1, a), (0, 2, b), (2, 3, cr), (3, 2, d)]);
    let l = c.limiting(&[(0, 1.0)], &SteadyOptions::default()).unwrap();
    assert!(!l.ergodic);
    assert_eq!(l.bottom.len(), 2);
    let pb = b / (a + b);
    let expect = [0.0, a / (a + b), pb * d / (cr + d), pb * cr / (cr + d)];
    for (p, e) in l.pi.iter().zip(expect) {
        assert!(close(*p, e, 1e-12), "{:?}", l.pi);
    }
    // Starting inside the bottom component stays there.
    let l = c.limiting(&[(3, 1.0)], &SteadyOptions::default()).unwrap();
    assert!(close(l.pi[2], d / (cr + d), 1e-12) && l.pi[1] == 0.0);
}

#[test]
fn transient_cycle_before_absorption_is_solved_exactly() {
    // 0 ⇄ 1 is transient (α: 0→1, γ: 1→0), with exits 0→3 (β) and 1→2 (δ).
    let (al, be, ga, de) = (2.0, 1.0, 4.0, 0.5);
    let c = Ctmc::from_triplets(4, vec![(0, 1, al), (0, 3, be), (1, 0, ga), (1, 2, de)]);
    // h0 = β/(α+β) + α/(α+β)·h1, h1 = γ/(γ+δ)·h0 (h = P(absorbed in 3)).
    let p01 = al / (al + be);
    let p10 = ga / (ga + de);
    let h0 = (be / (al + be)) / (1.0 - p01 * p10);
    let l = c
        .limiting(&[(0, 0.25), (1, 0.75)], &SteadyOptions::default())
        .unwrap();
    let h = 0.25 * h0 + 0.75 * p10 * h0;
    assert!(close(l.pi[3], h, 1e-12), "{:?}", l.pi);
    assert!(close(l.pi[2], 1.0 - h, 1e-12));
    assert_eq!((l.pi[0], l.pi[1]), (0.0, 0.0));
}

#[test]
fn transient_two_state_matches_matrix_exponential() {
    let (a, b) = (1.0, 2.0);
    let c = Ctmc::from_triplets(2, vec![(0, 1, a), (1, 0, b)]);
    let times = [0.0, 0.5, 1.0, 5.0, 500.0];
    let pt = c.transient(&[(0, 1.0)], &times, &eps(1e-13)).unwrap();
    for (p, t) in pt.iter().zip(times) {
        let p00 = b / (a + b) + a / (a + b) * (-(a + b) * t).exp();
        assert!(close(p[0], p00, 1e-12), "t={t}: {} vs {p00}", p[0]);
        assert!(close(p[0] + p[1], 1.0, 1e-12));
    }
}

#[test]
fn transient_pure_death_chain_matches_closed_form() {
    // 0 → 1 (a) → 2 (b): p0 = e^{-at}, p1 = a/(b−a)(e^{-at} − e^{-bt}).
    let (a, b) = (1.5, 0.25);
    let c = Ctmc::from_triplets(3, vec![(0, 1, a), (1, 2, b)]);
    let times = [5.0, 0.5, 1.0];
    let pt = c.transient(&[(0, 1.0)], &times, &eps(1e-13)).unwrap();
    for (p, t) in pt.iter().zip(times) {
        let p0 = (-a * t).exp();
        let p1 = a / (b - a) * ((-a * t).exp() - (-b * t).exp());
        assert!(
            close(p[0], p0, 1e-12) && close(p[1], p1, 1e-12),
            "t={t}: {p:?}"
        );
        assert!(close(p[2], 1.0 - p0 - p1, 1e-12));
    }
}

#[test]
fn fox_glynn_weights_match_poisson_probabilities() {
    for qt in [0.3, 4.0, 37.5] {
        let (first, w) = poisson_weights(qt, 1e-14);
        let mut p = (-qt).exp();
        for k in 0..first + w.len() {
            if k >= first {
                assert!(close(w[k - first], p, 1e-13), "qt={qt} k={k}");
            }
            p *= qt / (k as f64 + 1.0);
        }
    }
    // Large rates: nothing underflows, the window is centred on the mode.
    let (first, w) = poisson_weights(1e6, 1e-12);
    assert!(first > 990_000 && first + w.len() < 1_010_000);
    assert!(close(w.iter().sum::<f64>(), 1.0, 1e-12));
}
