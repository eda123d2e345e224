//! Regressions (issue 14, defects 3, 8, 9): `analyze` memory grew with the token count (one
//! state with 2³¹ tokens asked for 16 GiB) and with the square of the number of places
//! (10,000 isolated places took 703 MB; a 10⁶-place chain 12 GB under `--max-states
//! 100000`). Now per-place tables follow the net and the counts that occur, the search is
//! bounded by `max_states` and by a memory estimate made before it allocates, and counts past
//! the packed range are refused before the search. The memory figures are in
//! docs/benchmarks.md.

use gspn::analysis::invariants::{DEFAULT_CAP, p_invariants};
use gspn::analysis::measures::{Solver, SolverOptions};
use gspn::analysis::state_space::{AnalysisError, Options, StateSpace};
use gspn::net::{MAX_TOKENS, Net, NetBuilder, Servers};

/// `n` places in a line, one token at the start: `p0 → t0 → p1 → … → p(n-1)`.
fn chain(n: usize) -> Net {
    let mut b = NetBuilder::new("chain");
    let mut prev = b.place("p0", 1);
    for i in 1..n {
        let p = b.place(format!("p{i}"), 0);
        let t = b.exponential(format!("t{}", i - 1), 1.0, Servers::Single);
        b.input(prev, t, 1);
        b.output(t, p, 1);
        prev = p;
    }
    b.build().unwrap()
}

#[test]
fn one_state_with_two_to_the_31_tokens_is_measured_without_a_table_per_token() {
    let mut b = NetBuilder::new("heap");
    b.place("big", 1 << 31);
    let net = b.build().unwrap();
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    assert_eq!(ss.tangible_count(), 1);
    let solver = Solver::new(&net, &ss);
    let pi = solver.steady_state(&SolverOptions::default()).unwrap().pi;
    let m = solver.measures(&pi);
    assert_eq!(m.token_distribution[0].get(1 << 31), Some(&1.0));
    assert_eq!(m.token_distribution[0].get(0), None);
    assert_eq!(m.token_distribution[0].iter().count(), 1);
    assert_eq!(m.mean_tokens[0], 2147483648.0);
    assert_eq!(m.prob_nonempty[0], 1.0);
}

#[test]
fn ten_thousand_isolated_places_have_sparse_invariants() {
    let mut b = NetBuilder::new("isolated");
    for i in 0..10_000 {
        b.place(format!("p{i}"), 1);
    }
    let net = b.build().unwrap();
    let inv = p_invariants(&net, 20_000);
    assert!(inv.complete);
    assert_eq!(inv.vectors.len(), 10_000);
    assert_eq!(inv.vectors[0].entries(), &[(9_999, 1)]);
    assert!(inv.covers_all(10_000));
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    assert_eq!(ss.tangible_count(), 1);
    // Past the cap the elimination gives up instead of growing.
    assert!(!p_invariants(&chain(5_000), DEFAULT_CAP).complete);
}

#[test]
fn a_long_chain_is_refused_by_the_memory_estimate_before_it_allocates() {
    // 100,000 places of 4 bits: 50 kB per packed marking.
    let net = chain(100_000);
    let opts = Options {
        max_states: 100_000,
        max_memory: 64 << 20,
        ..Options::default()
    };
    match StateSpace::build(&net, &opts) {
        Err(e @ AnalysisError::TooMuchMemory { .. }) => {
            let AnalysisError::TooMuchMemory {
                limit_mib,
                markings,
                bytes_per_marking,
            } = e
            else {
                unreachable!()
            };
            assert_eq!(limit_mib, 64);
            assert_eq!(bytes_per_marking, 6_250 * 16 + 53);
            // The estimate crossed the limit at the first marking past 64 MiB.
            assert_eq!(markings, (64 << 20) / bytes_per_marking + 1);
            assert_eq!(
                e.to_string(),
                format!(
                    "the state space needs more than 64 MiB: {markings} markings of 100053 bytes each so far (raise --max-memory or lower --max-states)"
                )
            );
        }
        other => panic!(
            "expected a memory refusal, got {:?}",
            other.map(|s| s.tangible_count())
        ),
    }
    // The same chain, short enough, is searched in full: one state per place.
    let ss = StateSpace::build(&chain(2_000), &Options::default()).unwrap();
    assert_eq!(ss.tangible_count(), 2_000);
}

#[test]
fn a_bound_past_the_maximum_token_count_is_refused_before_the_search() {
    let mut b = NetBuilder::new("overflow");
    let full = b.place("full", MAX_TOKENS);
    let one = b.place("one", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    let u = b.exponential("u", 1.0, Servers::Single);
    b.input(one, t, 1);
    b.output(t, full, 1);
    b.input(full, u, 1);
    b.output(u, one, 1);
    let net = b.build().unwrap();
    let e = StateSpace::build(&net, &Options::default()).unwrap_err();
    assert_eq!(
        e,
        AnalysisError::TooManyTokens {
            place: "full".into(),
            tokens: 4_294_967_296
        }
    );
    assert_eq!(
        e.to_string(),
        "place `full` can reach 4294967296 tokens, which exceeds the maximum token count 4294967295"
    );
}
