//! The tangible chain left after eliminating vanishing markings gives the reference steady
//! state and throughputs (immediate transitions through `immediate_flows`), solved here with
//! a small dense solver so the check does not depend on the CTMC module.

// Dense matrix code reads best with indices.
#![allow(clippy::needless_range_loop)]

use crate::support::fixtures as shared_fixtures;

use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
use shared_fixtures::fixture;

/// π with πQ = 0, Σπ = 1, by Gaussian elimination on Qᵀ with the last equation replaced by
/// the normalisation (fine for the few hundred states used here).
fn steady_state(ss: &StateSpace) -> Vec<f64> {
    let n = ss.tangible_count();
    // a = Qᵀ (n × n) with an extra column for the right-hand side.
    let mut a = vec![vec![0.0f64; n + 1]; n];
    for s in 0..n {
        for m in ss.moves(s) {
            let r = m.rate * m.prob;
            let to = m.to as usize;
            if to != s {
                a[to][s] += r;
                a[s][s] -= r;
            }
        }
    }
    a[n - 1] = vec![1.0; n + 1];
    for col in 0..n {
        let piv = (col..n)
            .max_by(|&x, &y| a[x][col].abs().total_cmp(&a[y][col].abs()))
            .unwrap();
        a.swap(col, piv);
        for r in 0..n {
            if r != col && a[r][col] != 0.0 {
                let f = a[r][col] / a[col][col];
                for j in col..=n {
                    a[r][j] -= f * a[col][j];
                }
            }
        }
    }
    (0..n).map(|i| a[i][n] / a[i][i]).collect()
}

#[test]
fn ergodic_reference_nets_get_their_steady_state_and_throughputs() {
    let text = std::fs::read_to_string(fixture("reference/thesis_nets_reference.json")).unwrap();
    let reference: serde_json::Value = serde_json::from_str(&text).unwrap();
    let mut checked = 0;
    for (rel, r) in reference.as_object().unwrap() {
        if rel == "_about" || r["ergodic"] != true || r["tangible"].as_u64().unwrap() > 400 {
            continue;
        }
        let net = read_net(&fixture(rel), &ReadOptions::default())
            .unwrap()
            .net;
        let ss = StateSpace::build(&net, &Options::default()).unwrap();
        let pi = steady_state(&ss);
        for (s, &p) in pi.iter().enumerate() {
            let key = net.format_marking(&ss.marking(s));
            let want = r["steady_state"][&key].as_f64().unwrap_or(0.0);
            assert!(
                (p - want).abs() < 1e-9,
                "{rel}: π({key}) = {p}, want {want}"
            );
        }
        let mut throughput = vec![0.0f64; net.transition_count()];
        for (s, &p) in pi.iter().enumerate() {
            for m in ss.moves(s) {
                throughput[m.transition.index()] += p * m.rate * m.prob;
            }
        }
        for f in ss.immediate_flows() {
            let s = f.state as usize;
            let rate = net.exp_rate(&ss.marking(s), f.transition);
            throughput[f.immediate.index()] += pi[s] * rate * f.expected;
        }
        for (name, want) in r["throughput"].as_object().unwrap() {
            let t = net.transition_by_name(name).unwrap();
            let got = throughput[t.index()];
            let want = want.as_f64().unwrap();
            assert!(
                (got - want).abs() < 1e-9,
                "{rel}: X({name}) = {got}, want {want}"
            );
        }
        checked += 1;
    }
    assert!(checked >= 9, "checked {checked} nets");
}

/// Issue 27, part 3: loops of vanishing markings above the dense solver's size go through the
/// sparse LU and keep exact answers. N tokens circle a ring of four places through immediate
/// transitions (`examples/gen_vanishing_ring.rs`), so every distribution of the tokens still
/// on the ring is one loop of vanishing markings (N = 12: loops of up to C(15, 3) = 455); at
/// `r3` a token leaves with probability 0.5 / (0.5 + 1.5) = 1/4 at each pass, whatever else is
/// enabled, and `back` (rate 1, the one tangible marking) returns all N. Per return: N
/// leaves, 4N passes through `r3` (3N of them `step3`), so 4N firings of `step0`..`step2`.
#[test]
fn a_ring_of_vanishing_loops_up_to_455_markings_has_exact_throughputs() {
    use gspn::net::{NetBuilder, Servers};
    let n = 12u32;
    let mut b = NetBuilder::new("vanishing_ring");
    let r = [
        b.place("r0", n),
        b.place("r1", 0),
        b.place("r2", 0),
        b.place("r3", 0),
    ];
    let mut steps = Vec::new();
    for (i, w) in [1.0, 2.0, 3.0, 1.5].into_iter().enumerate() {
        let t = b.immediate(format!("step{i}"), w, 1);
        b.moves(r[i], t, r[(i + 1) % 4]);
        steps.push(t);
    }
    let out = b.place("out", 0);
    let leave = b.immediate("leave", 0.5, 1);
    b.moves(r[3], leave, out);
    let back = b.exponential("back", 1.0, Servers::Single);
    b.input(out, back, n);
    b.output(back, r[0], n);
    let net = b.build().unwrap();
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    // Every distribution of 1..=N tokens on the ring: C(N+4, 4) − 1 vanishing markings.
    assert_eq!((ss.tangible_count(), ss.vanishing_count()), (1, 1819));
    let mut throughput = vec![0.0f64; net.transition_count()];
    for f in ss.immediate_flows() {
        let rate = net.exp_rate(&ss.marking(f.state as usize), f.transition);
        throughput[f.immediate.index()] += rate * f.expected;
    }
    let n = f64::from(n);
    for (t, want) in [
        (steps[0], 4.0 * n),
        (steps[1], 4.0 * n),
        (steps[2], 4.0 * n),
        (steps[3], 3.0 * n),
        (leave, n),
    ] {
        let got = throughput[t.index()];
        assert!(
            (got - want).abs() < 1e-9 * want,
            "{}: {got}, want {want}",
            net.transition(t).name
        );
    }
}
