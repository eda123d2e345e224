//! Property test on random small bounded nets (token-conserving state machines with
//! exponential transitions of every server kind and acyclic immediate ones): the limiting
//! distribution and π(t) sum to 1, the limiting distribution is stationary (‖πQ‖∞ ≤ 1e-10),
//! and the two solvers (sparse LU, Gauss–Seidel) agree on ergodic chains.

use gspn::analysis::ctmc::{Method, SteadyOptions};
use gspn::analysis::measures::{Solver, SolverOptions, TransientOptions};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::net::{Net, NetBuilder, Servers};
use proptest::prelude::*;

#[derive(Clone, Debug)]
struct Spec {
    tokens: Vec<u32>,
    exp: Vec<(usize, usize, f64, u8)>,
    imm: Vec<(usize, usize, f64)>,
}

fn spec() -> impl Strategy<Value = Spec> {
    (2usize..5).prop_flat_map(|places| {
        (
            proptest::collection::vec(0u32..3, places),
            proptest::collection::vec((0..places, 0..places, 0.1f64..5.0, 0u8..3), 1..6),
            proptest::collection::vec((0..places, 0..places, 0.1f64..3.0), 0..3),
        )
            .prop_map(|(tokens, exp, imm)| Spec { tokens, exp, imm })
    })
}

fn build(s: &Spec) -> Net {
    let mut b = NetBuilder::new("random");
    let places: Vec<_> = s
        .tokens
        .iter()
        .enumerate()
        .map(|(i, &k)| b.place(format!("p{i}"), k))
        .collect();
    for (i, &(from, to, rate, servers)) in s.exp.iter().enumerate() {
        let servers = match servers {
            0 => Servers::Single,
            1 => Servers::Infinite,
            _ => Servers::K(2),
        };
        let t = b.exponential(format!("T{i}"), rate, servers);
        b.input(places[from], t, 1);
        b.output(t, places[to], 1);
    }
    for (i, &(a, c, w)) in s.imm.iter().enumerate() {
        // Immediate transitions only move tokens "forward": no timeless loops.
        let (from, to) = (a.min(c), a.max(c));
        if from == to {
            continue;
        }
        let t = b.immediate(format!("i{i}"), w, 1);
        b.input(places[from], t, 1);
        b.output(t, places[to], 1);
    }
    b.build().expect("a valid net")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn limiting_and_transient_distributions_are_probabilities(s in spec()) {
        let net = build(&s);
        let ss = StateSpace::build(&net, &Options::default()).unwrap();
        let solver = Solver::new(&net, &ss);
        let l = solver.steady_state(&SolverOptions::default()).unwrap();
        prop_assert!((l.pi.iter().sum::<f64>() - 1.0).abs() < 1e-12);
        prop_assert!(l.pi.iter().all(|&p| p >= 0.0));
        prop_assert!(solver.chain().residual(&l.pi) <= 1e-10);
        if l.ergodic && ss.tangible_count() > 1 {
            let gs = solver.chain().steady_state(&SteadyOptions {
                method: Method::GaussSeidel,
                ..SteadyOptions::default()
            }).unwrap();
            for (a, b) in gs.iter().zip(&l.pi) {
                prop_assert!((a - b).abs() < 1e-9);
            }
        }
        for pi in solver
            .transient(&[0.3, 2.0], &TransientOptions::default())
            .unwrap()
        {
            prop_assert!((pi.iter().sum::<f64>() - 1.0).abs() < 1e-10);
        }
        let m = solver.measures(&l.pi);
        let total: f64 = m.mean_tokens.iter().sum();
        prop_assert!((total - s.tokens.iter().sum::<u32>() as f64).abs() < 1e-9);
    }
}
