//! Behavioural properties read off the state space: dead markings with shortest firing
//! sequences, bounds, safety, reversibility, liveness per transition.

use gspn::analysis::properties::{Liveness, Properties};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::net::{Net, NetBuilder, Servers};

fn props(net: &Net) -> Properties {
    let ss = StateSpace::build(net, &Options::default()).expect("state space");
    Properties::compute(net, &ss)
}

#[test]
fn choice_leads_to_two_dead_markings_each_with_a_shortest_path() {
    // p0 → t1 → p1 → t2 → p2, and a shortcut p0 → t3 → p2; p0 → t4 → p3.
    let mut b = NetBuilder::new("choice");
    let p: Vec<_> = (0..4)
        .map(|i| b.place(format!("p{i}"), u32::from(i == 0)))
        .collect();
    let t: Vec<_> = (1..=4)
        .map(|i| b.exponential(format!("t{i}"), 1.0, Servers::Single))
        .collect();
    for (tr, from, to) in [(0, 0, 1), (1, 1, 2), (2, 0, 2), (3, 0, 3)] {
        b.input(p[from], t[tr], 1);
        b.output(t[tr], p[to], 1);
    }
    let net = b.build().unwrap();
    let pr = props(&net);
    assert_eq!(
        (pr.reachable, pr.tangible, pr.vanishing, pr.edges),
        (4, 4, 0, 4)
    );
    let dead: Vec<_> = pr
        .dead_markings
        .iter()
        .map(|d| (d.marking.clone(), d.path.clone()))
        .collect();
    assert_eq!(
        dead,
        vec![
            (vec![0, 0, 1, 0], vec![t[2]]),
            (vec![0, 0, 0, 1], vec![t[3]])
        ]
    );
    assert!(!pr.deadlock_free && !pr.reversible && pr.safe);
    assert_eq!(pr.liveness, vec![Liveness::QuasiLive; 4]);
    assert_eq!(pr.place_bounds, vec![1, 1, 1, 1]);
    assert_eq!(pr.max_tokens_per_marking, 1);
}

#[test]
fn ring_is_live_reversible_and_bounded_by_its_tokens() {
    let mut b = NetBuilder::new("ring");
    let p: Vec<_> = (0..3)
        .map(|i| b.place(format!("p{i}"), if i == 0 { 2 } else { 0 }))
        .collect();
    for i in 0..3 {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(p[i], t, 1);
        b.output(t, p[(i + 1) % 3], 1);
    }
    // Never enabled: its input place is never marked.
    let q = b.place("q", 0);
    let never = b.exponential("never", 1.0, Servers::Single);
    b.input(q, never, 1);
    let net = b.build().unwrap();
    let pr = props(&net);
    assert_eq!(pr.reachable, 6);
    assert_eq!(pr.edges, 9);
    assert!(pr.reversible && pr.deadlock_free && !pr.safe);
    assert_eq!(pr.place_bounds, vec![2, 2, 2, 0]);
    assert_eq!((pr.max_tokens_in_place, pr.max_tokens_per_marking), (2, 2));
    assert_eq!(
        pr.liveness,
        vec![
            Liveness::Live,
            Liveness::Live,
            Liveness::Live,
            Liveness::Dead
        ]
    );
    assert_eq!(pr.dead_transitions().len(), 1);
    assert_eq!(pr.live_transitions().len(), 3);
}

#[test]
fn start_up_transition_is_quasi_live_and_the_net_not_reversible() {
    let mut b = NetBuilder::new("startup");
    let s = b.place("s", 1);
    let a = b.place("a", 0);
    let c = b.place("c", 0);
    let go = b.exponential("go", 1.0, Servers::Single);
    let ab = b.exponential("ab", 1.0, Servers::Single);
    let ba = b.exponential("ba", 1.0, Servers::Single);
    b.input(s, go, 1);
    b.output(go, a, 1);
    b.input(a, ab, 1);
    b.output(ab, c, 1);
    b.input(c, ba, 1);
    b.output(ba, a, 1);
    let net = b.build().unwrap();
    let pr = props(&net);
    assert!(!pr.reversible && pr.deadlock_free);
    assert_eq!(
        pr.liveness,
        vec![Liveness::QuasiLive, Liveness::Live, Liveness::Live]
    );
}

#[test]
fn immediate_transitions_count_in_liveness_and_tangible_arcs_in_edges() {
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, Servers::Single);
    b.input(p1, t1, 1);
    b.output(t1, p2, 1);
    b.input(p2, t2, 1);
    b.output(t2, p3, 1);
    b.input(p3, t3, 1);
    b.output(t3, p1, 1);
    let net = b.build().unwrap();
    let pr = props(&net);
    assert_eq!((pr.reachable, pr.tangible, pr.vanishing), (5, 3, 2));
    assert_eq!(pr.edges, 4);
    assert_eq!(pr.place_bounds, vec![2, 1, 2]);
    assert!(pr.reversible);
    assert_eq!(pr.liveness, vec![Liveness::Live; 3]);
}
