//! A large chain is solved from its columns alone (`Solver::steady_state` never builds the row
//! form — the Kanban N = 4 memory target): same answers as the sparse LU on the row form, and
//! a non-ergodic chain still goes to the limiting distribution.

use crate::support as common;

use gspn::analysis::ctmc::Method;
use gspn::analysis::measures::{Solver, SolverOptions};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
use gspn::net::{NetBuilder, Servers};

fn solve(net: &gspn::net::Net, method: Method, direct_limit: usize) -> (Vec<f64>, Vec<f64>, bool) {
    let ss = StateSpace::build(net, &Options::default()).unwrap();
    let solver = Solver::new(net, &ss);
    let opts = SolverOptions {
        method,
        tolerance: 1e-14,
        direct_limit,
        ..SolverOptions::default()
    };
    let l = solver.steady_state(&opts).unwrap();
    assert!(solver.residual(&l.pi) <= 1e-12, "{method:?}");
    assert!((l.pi.iter().sum::<f64>() - 1.0).abs() < 1e-12);
    let m = solver.measures(&l.pi);
    (m.mean_tokens, m.throughput, l.ergodic)
}

#[test]
fn kanban_n2_from_columns_equals_the_sparse_lu() {
    let path = common::fixture("kanban/kanban_gspn_N2.pnml");
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    // direct_limit 0: Auto takes the column path for all 4,600 states.
    let (gs_mean, gs_x, gs_ergodic) = solve(&net, Method::Auto, 0);
    let (lu_mean, lu_x, lu_ergodic) = solve(&net, Method::Direct, 0);
    assert!(gs_ergodic && lu_ergodic);
    for (a, b) in gs_mean.iter().zip(&lu_mean).chain(gs_x.iter().zip(&lu_x)) {
        assert!((a - b).abs() <= 1e-9, "{a} vs {b}");
    }
}

#[test]
fn a_chain_with_two_absorbing_ends_gets_its_limiting_distribution() {
    // start → left (rate 1) or right (rate 3), each a two-state loop: not irreducible.
    let mut b = NetBuilder::new("split");
    let start = b.place("start", 1);
    let mut ends = Vec::new();
    for (side, rate) in [("left", 1.0), ("right", 3.0)] {
        let a = b.place(format!("{side}_a"), 0);
        let z = b.place(format!("{side}_b"), 0);
        let go = b.exponential(format!("go_{side}"), rate, Servers::Single);
        b.input(start, go, 1);
        b.output(go, a, 1);
        let there = b.exponential(format!("{side}_ab"), 2.0, Servers::Single);
        b.input(a, there, 1);
        b.output(there, z, 1);
        let back = b.exponential(format!("{side}_ba"), 1.0, Servers::Single);
        b.input(z, back, 1);
        b.output(back, a, 1);
        ends.push((a, z));
    }
    let net = b.build().unwrap();
    let (mean, _, ergodic) = solve(&net, Method::Auto, 0);
    assert!(!ergodic);
    // P(left) = 1/4, P(right) = 3/4; inside a loop, π(a) = 1/3, π(b) = 2/3.
    let (la, lb) = ends[0];
    let (ra, rb) = ends[1];
    for (p, want) in [(la, 0.25 / 3.0), (lb, 0.5 / 3.0), (ra, 0.25), (rb, 0.5)] {
        assert!(
            (mean[p.index()] - want).abs() < 1e-12,
            "{}: {}",
            net.place(p).name,
            mean[p.index()]
        );
    }
    assert_eq!(mean[start.index()], 0.0);
}

#[test]
fn a_raised_cancel_flag_stops_the_solver_with_cancelled() {
    use std::sync::Arc;
    use std::sync::atomic::AtomicBool;

    use gspn::analysis::ctmc::SolveError;

    let path = common::fixture("kanban/kanban_gspn_N2.pnml");
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    let solver = Solver::new(&net, &ss);
    for (method, direct_limit) in [(Method::Auto, 0), (Method::Power, 0)] {
        let opts = SolverOptions {
            method,
            direct_limit,
            cancel: Some(Arc::new(AtomicBool::new(true))),
            ..SolverOptions::default()
        };
        match solver.steady_state(&opts) {
            Err(SolveError::Cancelled { .. }) => {}
            other => panic!("{method:?}: expected Cancelled, got {other:?}"),
        }
    }
}
