//! The tangible reachability graph: counts, vanishing loops and initial markings, errors, and
//! agreement with a plain breadth-first search on random nets.

use crate::support as common;

use std::collections::{HashSet, VecDeque};

use gspn::analysis::state_space::{AnalysisError, Move, Options, StateSpace};
use gspn::net::{Net, NetBuilder, Servers, TransitionId};
use proptest::prelude::*;

fn build(net: &Net) -> StateSpace {
    StateSpace::build(net, &Options::default()).expect("state space")
}

/// The tangible state whose marking is `m`.
fn state(ss: &StateSpace, m: &[u32]) -> u32 {
    (0..ss.tangible_count())
        .find(|&s| ss.marking(s) == m)
        .unwrap_or_else(|| panic!("{m:?} is not a tangible state")) as u32
}

fn cyc3() -> Net {
    common::cyc3(Servers::Single)
}

#[test]
fn cyc3_has_three_tangible_and_two_vanishing_markings() {
    let net = cyc3();
    let ss = build(&net);
    assert_eq!(ss.tangible_count(), 3);
    assert_eq!(ss.vanishing_count(), 2);
    assert_eq!(ss.reachable_count(), 5);
    // Full graph: (2,0,0) T1; (1,1,0) t2; (1,0,1) T1,T3; (0,1,1) t2; (0,0,2) T3.
    assert_eq!(ss.edge_count(), 6);
    assert_eq!(ss.tangible_edge_count(), 4);
    let s200 = state(&ss, &[2, 0, 0]);
    let s101 = state(&ss, &[1, 0, 1]);
    let t1 = net.transition_by_name("T1").unwrap();
    assert_eq!(
        ss.moves(s200 as usize),
        &[Move {
            transition: t1,
            rate: 1.0,
            to: s101,
            prob: 1.0
        }]
    );
    assert_eq!(ss.initial(), &[(s200, 1.0)]);
    assert!(ss.dead_states().is_empty());
    let t2 = net.transition_by_name("t2").unwrap();
    let flows: Vec<_> = ss
        .immediate_flows()
        .iter()
        .map(|f| (f.state, f.transition, f.immediate, f.expected))
        .collect();
    assert!(flows.contains(&(s200, t1, t2, 1.0)));
    assert_eq!(flows.len(), 2);
}

/// a --T--> v1; v1: i1 → v2 | i2 → b; v2: i3 → v1 | i4 → c (equal weights).
fn vanishing_loop() -> Net {
    let mut b = NetBuilder::new("loop");
    let a = b.place("a", 1);
    let v1 = b.place("v1", 0);
    let v2 = b.place("v2", 0);
    let pb = b.place("b", 0);
    let pc = b.place("c", 0);
    let t = b.exponential("T", 2.0, Servers::Single);
    b.input(a, t, 1);
    b.output(t, v1, 1);
    for (name, from, to) in [
        ("i1", v1, v2),
        ("i2", v1, pb),
        ("i3", v2, v1),
        ("i4", v2, pc),
    ] {
        let i = b.immediate(name, 1.0, 1);
        b.input(from, i, 1);
        b.output(i, to, 1);
    }
    b.build().unwrap()
}

#[test]
fn vanishing_loop_is_solved_not_dropped() {
    let net = vanishing_loop();
    let ss = build(&net);
    assert_eq!((ss.tangible_count(), ss.vanishing_count()), (3, 2));
    let a = state(&ss, &[1, 0, 0, 0, 0]) as usize;
    let b = state(&ss, &[0, 0, 0, 1, 0]);
    let c = state(&ss, &[0, 0, 0, 0, 1]);
    let mut moves: Vec<(u32, f64)> = ss.moves(a).iter().map(|m| (m.to, m.prob)).collect();
    moves.sort_by_key(|m| m.0);
    let expect = if b < c {
        vec![(b, 2.0 / 3.0), (c, 1.0 / 3.0)]
    } else {
        vec![(c, 1.0 / 3.0), (b, 2.0 / 3.0)]
    };
    for ((s, p), (s2, p2)) in moves.iter().zip(&expect) {
        assert_eq!(s, s2);
        assert!((p - p2).abs() < 1e-12, "{p} vs {p2}");
    }
    assert!(ss.moves(a).iter().all(|m| m.rate == 2.0));
    // Expected firings per visit to v1: 4/3 visits; i1, i2 2/3 each; i3, i4 1/3 each.
    for (name, want) in [
        ("i1", 2.0 / 3.0),
        ("i2", 2.0 / 3.0),
        ("i3", 1.0 / 3.0),
        ("i4", 1.0 / 3.0),
    ] {
        let i = net.transition_by_name(name).unwrap();
        let got: f64 = ss
            .immediate_flows()
            .iter()
            .filter(|f| f.immediate == i)
            .map(|f| f.expected)
            .sum();
        assert!((got - want).abs() < 1e-12, "{name}: {got} vs {want}");
    }
    assert_eq!(ss.dead_states().len(), 2);
}

#[test]
fn loop_through_vanishing_back_to_the_same_state_keeps_its_probability() {
    // a --T--> v --i--> a, and a --U--> done: the T move is a self-loop of probability 1.
    let mut b = NetBuilder::new("selfloop");
    let a = b.place("a", 1);
    let v = b.place("v", 0);
    let done = b.place("done", 0);
    let t = b.exponential("T", 1.0, Servers::Single);
    let u = b.exponential("U", 3.0, Servers::Single);
    let i = b.immediate("i", 1.0, 1);
    b.input(a, t, 1);
    b.output(t, v, 1);
    b.input(v, i, 1);
    b.output(i, a, 1);
    b.input(a, u, 1);
    b.output(u, done, 1);
    let net = b.build().unwrap();
    let ss = build(&net);
    let s = state(&ss, &[1, 0, 0]);
    let m: Vec<_> = ss
        .moves(s as usize)
        .iter()
        .map(|m| (m.transition, m.to, m.prob))
        .collect();
    assert_eq!(m[0], (t, s, 1.0));
    assert_eq!(m.len(), 2);
}

#[test]
fn vanishing_initial_marking_is_resolved_by_weights() {
    let mut b = NetBuilder::new("start");
    let p0 = b.place("p0", 1);
    let x = b.place("x", 0);
    let y = b.place("y", 0);
    let i1 = b.immediate("i1", 3.0, 2);
    let i2 = b.immediate("i2", 1.0, 2);
    let low = b.immediate("low", 100.0, 1);
    b.input(p0, i1, 1);
    b.output(i1, x, 1);
    b.input(p0, i2, 1);
    b.output(i2, y, 1);
    b.input(p0, low, 1);
    let net = b.build().unwrap();
    let ss = build(&net);
    assert_eq!((ss.tangible_count(), ss.vanishing_count()), (2, 1));
    let sx = state(&ss, &[0, 1, 0]);
    let sy = state(&ss, &[0, 0, 1]);
    let mut init = ss.initial().to_vec();
    init.sort_by_key(|e| e.0);
    let mut want = vec![(sx, 0.75), (sy, 0.25)];
    want.sort_by_key(|e| e.0);
    assert_eq!(init, want);
    assert_eq!(ss.initial_global(), 2);
    // The low-priority transition never fires.
    assert_eq!(ss.edge_count(), 2);
    assert_eq!(ss.path_to(sx as usize), vec![i1]);
}

#[test]
fn zero_weights_share_equally() {
    let mut b = NetBuilder::new("zero");
    let p0 = b.place("p0", 1);
    let x = b.place("x", 0);
    let y = b.place("y", 0);
    for (n, to) in [("i1", x), ("i2", y)] {
        let i = b.immediate(n, 0.0, 1);
        b.input(p0, i, 1);
        b.output(i, to, 1);
    }
    let net = b.build().unwrap();
    let ss = build(&net);
    assert!(ss.initial().iter().all(|&(_, p)| p == 0.5));
    assert_eq!(ss.initial().len(), 2);
}

#[test]
fn immediate_loop_without_exit_is_a_timeless_trap() {
    let mut b = NetBuilder::new("trap");
    let a = b.place("a", 1);
    let v1 = b.place("v1", 0);
    let v2 = b.place("v2", 0);
    let t = b.exponential("T", 1.0, Servers::Single);
    b.input(a, t, 1);
    b.output(t, v1, 1);
    let i1 = b.immediate("i1", 1.0, 1);
    b.input(v1, i1, 1);
    b.output(i1, v2, 1);
    let i2 = b.immediate("i2", 1.0, 1);
    b.input(v2, i2, 1);
    b.output(i2, v1, 1);
    let net = b.build().unwrap();
    match StateSpace::build(&net, &Options::default()) {
        Err(AnalysisError::TimelessTrap { marking }) => {
            assert!(marking == "v1=1" || marking == "v2=1", "{marking}")
        }
        other => panic!("expected a timeless trap, got {other:?}"),
    }
}

/// `k` places in a ring, `n` tokens in the first.
fn ring(k: usize, n: u32) -> Net {
    let mut b = NetBuilder::new("ring");
    let ps: Vec<_> = (0..k)
        .map(|i| b.place(format!("p{i}"), if i == 0 { n } else { 0 }))
        .collect();
    for i in 0..k {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(ps[i], t, 1);
        b.output(t, ps[(i + 1) % k], 1);
    }
    b.build().unwrap()
}

#[test]
fn ring_counts_are_binomial() {
    // C(n + k - 1, k - 1) markings, each with as many arcs as marked places.
    let ss = build(&ring(4, 10));
    assert_eq!(ss.tangible_count(), 286);
    assert_eq!(ss.vanishing_count(), 0);
    let net = ring(4, 10);
    let edges: usize = (0..ss.tangible_count())
        .map(|s| ss.marking(s).iter().filter(|&&k| k > 0).count())
        .sum();
    assert_eq!(ss.edge_count(), edges);
    let _ = net;
}

#[test]
fn too_many_states_is_an_error_not_an_oom() {
    let opts = Options {
        max_states: 100,
        ..Options::default()
    };
    assert_eq!(
        StateSpace::build(&ring(4, 10), &opts).err(),
        Some(AnalysisError::TooManyStates { limit: 100 })
    );
}

#[test]
fn unbounded_place_is_reported_by_name() {
    let mut b = NetBuilder::new("producer");
    let idle = b.place("idle", 1);
    let busy = b.place("busy", 0);
    let made = b.place("made", 0);
    let start = b.exponential("start", 1.0, Servers::Single);
    let finish = b.exponential("finish", 1.0, Servers::Single);
    b.input(idle, start, 1);
    b.output(start, busy, 1);
    b.input(busy, finish, 1);
    b.output(finish, idle, 1);
    b.output(finish, made, 1);
    let net = b.build().unwrap();
    assert_eq!(
        StateSpace::build(&net, &Options::default()).err(),
        Some(AnalysisError::Unbounded {
            places: vec!["made".into()]
        })
    );
}

/// `k` independent two-place cycles with one token each: 2^k markings.
fn switches(k: usize) -> Net {
    let mut b = NetBuilder::new("switches");
    for i in 0..k {
        let on = b.place(format!("on{i}"), 1);
        let off = b.place(format!("off{i}"), 0);
        let t = b.exponential(format!("down{i}"), 1.0 + i as f64, Servers::Single);
        let u = b.exponential(format!("up{i}"), 2.0, Servers::Single);
        b.input(on, t, 1);
        b.output(t, off, 1);
        b.input(off, u, 1);
        b.output(u, on, 1);
    }
    b.build().unwrap()
}

#[test]
fn parallel_search_numbers_states_like_the_sequential_one() {
    let net = switches(13);
    let seq = StateSpace::build(
        &net,
        &Options {
            threads: 1,
            ..Options::default()
        },
    )
    .unwrap();
    let par = StateSpace::build(
        &net,
        &Options {
            threads: 3,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(seq.tangible_count(), 1 << 13);
    assert_eq!(seq.edge_count(), 13 << 13);
    assert_eq!(par.tangible_count(), seq.tangible_count());
    assert_eq!(par.edge_count(), seq.edge_count());
    for s in (0..seq.tangible_count()).step_by(97) {
        assert_eq!(par.marking(s), seq.marking(s));
        assert_eq!(par.moves(s), seq.moves(s));
        assert_eq!(par.path_to(s), seq.path_to(s));
    }
}

/// A plain breadth-first search with `Net::firable`: (markings, arcs).
fn plain_bfs(net: &Net) -> (usize, usize) {
    let m0 = net.initial_marking().into_vec();
    let mut seen = HashSet::from([m0.clone()]);
    let mut queue = VecDeque::from([m0]);
    let mut arcs = 0;
    while let Some(m) = queue.pop_front() {
        for t in net.firable(&m) {
            arcs += 1;
            let mut next = m.clone();
            net.fire(&mut next, t).unwrap();
            if seen.insert(next.clone()) {
                queue.push_back(next);
            }
        }
    }
    (seen.len(), arcs)
}

/// A random small net: places with capacity 3, transitions of random kinds and arcs.
type Spec = (
    Vec<u32>,
    Vec<(bool, u32, Vec<(usize, u32)>, Vec<(usize, u32)>)>,
);

fn net_from(spec: &Spec, reversed: bool) -> Net {
    let (initial, transitions) = spec;
    let mut b = NetBuilder::new("random");
    let ps: Vec<_> = initial
        .iter()
        .enumerate()
        .map(|(i, &k)| b.place_with_capacity(format!("p{i}"), k, Some(3)))
        .collect();
    let order: Vec<usize> = if reversed {
        (0..transitions.len()).rev().collect()
    } else {
        (0..transitions.len()).collect()
    };
    for i in order {
        let (imm, prio, ins, outs) = &transitions[i];
        let t = if *imm {
            b.immediate(format!("t{i}"), 1.0 + i as f64, *prio)
        } else {
            b.exponential(format!("t{i}"), 1.0 + i as f64, Servers::Single)
        };
        for &(p, w) in ins {
            b.input(ps[p % ps.len()], t, w);
        }
        for &(p, w) in outs {
            b.output(t, ps[p % ps.len()], w);
        }
    }
    b.build().unwrap()
}

fn spec() -> impl Strategy<Value = Spec> {
    let arcs = || {
        prop::collection::btree_map(0usize..5, 1u32..3, 0..3)
            .prop_map(|m| m.into_iter().collect::<Vec<_>>())
    };
    (
        prop::collection::vec(0u32..3, 2..5),
        prop::collection::vec((prop::bool::weighted(0.3), 1u32..3, arcs(), arcs()), 1..6),
    )
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]
    #[test]
    fn counts_match_plain_bfs_and_ignore_transition_order(spec in spec()) {
        let net = net_from(&spec, false);
        let rev = net_from(&spec, true);
        let (markings, arcs) = plain_bfs(&net);
        match StateSpace::build(&net, &Options::default()) {
            Ok(ss) => {
                prop_assert_eq!(ss.reachable_count(), markings);
                prop_assert_eq!(ss.edge_count(), arcs);
                let total: f64 = ss.initial().iter().map(|e| e.1).sum();
                prop_assert!((total - 1.0).abs() < 1e-12);
                for s in 0..ss.tangible_count() {
                    let mut by_t: std::collections::BTreeMap<TransitionId, f64> = Default::default();
                    for m in ss.moves(s) {
                        *by_t.entry(m.transition).or_default() += m.prob;
                    }
                    for p in by_t.values() {
                        prop_assert!((p - 1.0).abs() < 1e-9);
                    }
                }
                let r = StateSpace::build(&rev, &Options::default()).unwrap();
                prop_assert_eq!(r.tangible_count(), ss.tangible_count());
                prop_assert_eq!(r.vanishing_count(), ss.vanishing_count());
                prop_assert_eq!(r.edge_count(), ss.edge_count());
                prop_assert_eq!(r.tangible_edge_count(), ss.tangible_edge_count());
                prop_assert_eq!(r.dead_states().len(), ss.dead_states().len());
            }
            Err(AnalysisError::TimelessTrap { .. }) => {
                let r = StateSpace::build(&rev, &Options::default());
                let trapped = matches!(r, Err(AnalysisError::TimelessTrap { .. }));
                prop_assert!(trapped, "reversed order should be trapped too");
            }
            Err(e) => prop_assert!(false, "unexpected {}", e),
        }
    }
}
