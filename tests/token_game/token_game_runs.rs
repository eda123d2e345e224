//! The token game: priorities, weights, policies, server semantics, dead markings, timeless
//! traps, determinism, and Monte-Carlo estimates against exact answers.

use crate::support as common;

use gspn::net::{Net, NetBuilder, PlaceId, Servers, TransitionId};
use gspn::policy::{Pattern, Policy, Rule};
use gspn::sim::{Horizon, MonteCarlo, RunEnd, SimError, Simulator, Step};

/// GreatSPN's cyc3 (fixtures/greatspn/cyc3): P1 (2) → T1 (rate 1) → P2 → t2 (imm) → P3 →
/// T3 (rate 2) → P1.
use common::cyc3;

/// A choice: `p` feeds immediate `a` (weight 1) and `b` (weight 3), each leading to its own
/// place from which an exponential transition returns the token.
fn choice() -> (Net, [TransitionId; 2]) {
    let mut n = NetBuilder::new("choice");
    let p = n.place("p", 1);
    let qa = n.place("qa", 0);
    let qb = n.place("qb", 0);
    let a = n.immediate("a", 1.0, 1);
    let b = n.immediate("b", 3.0, 1);
    let ra = n.exponential("ra", 1.0, Servers::Single);
    let rb = n.exponential("rb", 1.0, Servers::Single);
    n.input(p, a, 1);
    n.output(a, qa, 1);
    n.input(p, b, 1);
    n.output(b, qb, 1);
    n.input(qa, ra, 1);
    n.output(ra, p, 1);
    n.input(qb, rb, 1);
    n.output(rb, p, 1);
    (n.build().unwrap(), [a, b])
}

fn trace(sim: &mut Simulator, n: usize) -> Vec<Step> {
    (0..n).map_while(|_| sim.step().unwrap()).collect()
}

#[test]
fn highest_priority_immediate_fires_first() {
    let mut b = NetBuilder::new("prio");
    let p = b.place("p", 1);
    let low = b.immediate("low", 100.0, 1);
    let high = b.immediate("high", 1.0, 2);
    let exp = b.exponential("exp", 1000.0, Servers::Single);
    for t in [low, high, exp] {
        b.input(p, t, 1);
    }
    let net = b.build().unwrap();
    for seed in 0..200 {
        let mut sim = Simulator::new(net.clone(), seed);
        assert!(sim.is_vanishing());
        let s = sim.step().unwrap().unwrap();
        assert_eq!((s.transition, s.time, s.immediate), (high, 0.0, true));
        assert_eq!(sim.step().unwrap(), None, "p is empty: dead");
        assert!(sim.is_dead());
    }
}

#[test]
fn weights_split_conflicting_immediates() {
    let (net, [a, b]) = choice();
    let mut sim = Simulator::new(net.clone(), 5);
    let steps = trace(&mut sim, 40_000);
    let na = steps.iter().filter(|s| s.transition == a).count() as f64;
    let nb = steps.iter().filter(|s| s.transition == b).count() as f64;
    assert_eq!(na + nb, 20_000.0, "every other firing is a choice");
    // P(b) = 3/4; the sd of the frequency is √(3/16/20000) ≈ 0.0031.
    assert!((nb / (na + nb) - 0.75).abs() < 0.0125, "{}", nb / (na + nb));
}

#[test]
fn policy_overrides_weights_where_a_rule_applies() {
    let (net, [a, b]) = choice();
    let p = net.place_by_name("p").unwrap();
    let policy = Policy::new(
        &net,
        vec![Rule {
            pattern: Pattern::Partial(vec![(p, 1)]),
            choose: vec![(a, 0.9), (b, 0.1)],
        }],
    )
    .unwrap();
    let mut sim = Simulator::new(net.clone(), 5).with_policy(policy.clone());
    let steps = trace(&mut sim, 40_000);
    let na = steps.iter().filter(|s| s.transition == a).count() as f64;
    // P(a) = 0.9 by the policy instead of 1/4 by weight; sd ≈ 0.0021.
    assert!((na / 20_000.0 - 0.9).abs() < 0.009, "{}", na / 20_000.0);

    // A deterministic rule: `b` never fires.
    let always_a = Policy::new(
        &net,
        vec![Rule {
            pattern: Pattern::Partial(vec![(p, 1)]),
            choose: vec![(a, 1.0)],
        }],
    )
    .unwrap();
    let mut sim = Simulator::new(net.clone(), 6).with_policy(always_a.clone());
    assert!(trace(&mut sim, 1000).iter().all(|s| s.transition != b));
}

#[test]
fn zero_weights_without_a_policy_choose_uniformly() {
    let mut n = NetBuilder::new("undecided");
    let p = n.place("p", 1);
    let x = n.immediate("x", 0.0, 1);
    let y = n.immediate("y", 0.0, 1);
    let back = n.exponential("back", 1.0, Servers::Single);
    let q = n.place("q", 0);
    for t in [x, y] {
        n.input(p, t, 1);
        n.output(t, q, 1);
    }
    n.input(q, back, 1);
    n.output(back, p, 1);
    let net = n.build().unwrap();
    let steps = trace(&mut Simulator::new(net.clone(), 9), 20_000);
    let nx = steps.iter().filter(|s| s.transition == x).count() as f64;
    assert!((nx / 10_000.0 - 0.5).abs() < 0.02, "{}", nx / 10_000.0);
}

/// `p` holds 3 tokens; `t` takes one and puts it back at rate 1 per server.
fn self_loop(servers: Servers) -> Net {
    let mut b = NetBuilder::new("servers");
    let p = b.place("p", 3);
    let t = b.exponential("t", 1.0, servers);
    b.input(p, t, 1);
    b.output(t, p, 1);
    b.build().unwrap()
}

#[test]
fn server_semantics_scale_the_rate() {
    for (servers, rate) in [
        (Servers::Single, 1.0),
        (Servers::K(2), 2.0),
        (Servers::Infinite, 3.0),
    ] {
        let net = self_loop(servers);
        let mut sim = Simulator::new(net.clone(), 11);
        assert_eq!(sim.run_until(20_000.0).unwrap(), RunEnd::Limit);
        let x = sim.statistics().throughput[0];
        // Poisson count: sd of the rate estimate = √(rate/T) ≤ 0.0123.
        assert!((x - rate).abs() < 0.05, "{servers:?}: {x}");
        assert_eq!(sim.time(), 20_000.0);
    }
}

#[test]
fn dead_marking_ends_the_run_and_holds_for_ever() {
    let mut b = NetBuilder::new("chain");
    let p1 = b.place("p1", 1);
    let p2 = b.place("p2", 0);
    let p3 = b.place("p3", 0);
    let t1 = b.exponential("t1", 10.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    b.input(p1, t1, 1);
    b.output(t1, p2, 1);
    b.input(p2, t2, 1);
    b.output(t2, p3, 1);
    let net = b.build().unwrap();

    let mut sim = Simulator::new(net.clone(), 3);
    assert_eq!(sim.run_steps(10).unwrap(), RunEnd::Dead);
    assert_eq!(sim.firings(), 2);
    assert_eq!(sim.marking().as_slice(), &[0, 0, 1]);
    let died = sim.time();
    assert_eq!(sim.step().unwrap(), None);
    assert_eq!(sim.time(), died, "the clock does not move on a dead step");

    let mut sim = Simulator::new(net.clone(), 3);
    assert_eq!(sim.run_until(100.0).unwrap(), RunEnd::Dead);
    let s = sim.statistics();
    assert_eq!(s.time, 100.0);
    assert_eq!(s.fired, vec![1, 1]);
    // p1 held its token until t1 fired, p3 from then on.
    assert!((s.mean_tokens[0] - died / 100.0).abs() < 1e-12);
    assert!((s.mean_tokens[2] - (100.0 - died) / 100.0).abs() < 1e-12);
    assert_eq!(
        s.mean_tokens[1], 0.0,
        "p2 is vanishing: no time spent there"
    );
}

#[test]
fn vanishing_initial_marking_resolves_at_time_zero() {
    let mut b = NetBuilder::new("imm-chain");
    let places: Vec<PlaceId> = (0..4)
        .map(|i| b.place(format!("p{i}"), (i == 0) as u32))
        .collect();
    for i in 0..3 {
        let t = b.immediate(format!("t{i}"), 1.0, 1);
        b.input(places[i], t, 1);
        b.output(t, places[i + 1], 1);
    }
    let net = b.build().unwrap();
    let mut sim = Simulator::new(net.clone(), 0);
    let steps = trace(&mut sim, 10);
    assert_eq!(steps.len(), 3);
    assert!(steps.iter().all(|s| s.time == 0.0 && s.immediate));
    assert_eq!(sim.marking().as_slice(), &[0, 0, 0, 1]);
}

#[test]
fn timeless_trap_is_reported_not_looped_for_ever() {
    let mut b = NetBuilder::new("trap");
    let p = b.place("p", 1);
    let q = b.place("q", 0);
    let there = b.immediate("there", 1.0, 1);
    let back = b.immediate("back", 1.0, 1);
    b.input(p, there, 1);
    b.output(there, q, 1);
    b.input(q, back, 1);
    b.output(back, p, 1);
    let net = b.build().unwrap();
    let mut sim = Simulator::new(net.clone(), 0).with_max_immediate(1000);
    let err = sim.run_until(10.0).unwrap_err();
    assert_eq!(
        err,
        SimError::TimelessTrap {
            time: 0.0,
            firings: 1000,
            last: "back".into()
        }
    );
    assert_eq!(sim.firings(), 1000);
}

#[test]
fn same_seed_same_trace_other_seed_other_trace() {
    let net = cyc3(Servers::Single);
    let run = |seed| {
        let mut sim = Simulator::new(net.clone(), seed);
        let steps = trace(&mut sim, 500);
        (steps, sim.marking().clone(), sim.statistics())
    };
    let (a, b, c) = (run(42), run(42), run(43));
    assert_eq!(a, b);
    assert_eq!(a.0.len(), 500);
    assert_ne!(a.0, c.0);
    // Pin the first firing time of seed 42, so a change of RNG or sampling is noticed.
    let mut sim = Simulator::new(net.clone(), 42);
    let first = sim.step().unwrap().unwrap();
    assert_eq!(first.transition, net.transition_by_name("T1").unwrap());
    assert!(first.time > 0.0 && first.time.is_finite());
}

#[test]
fn streams_give_independent_runs_of_one_seed() {
    let net = cyc3(Servers::Single);
    let s0 = trace(&mut Simulator::new(net.clone(), 1), 50);
    let s0_again = trace(&mut Simulator::new(net.clone(), 1).with_stream(0), 50);
    let s1 = trace(&mut Simulator::new(net.clone(), 1).with_stream(1), 50);
    assert_eq!(s0, s0_again);
    assert_ne!(s0, s1);
}

#[test]
fn cyc3_single_server_estimates_contain_the_exact_answers() {
    let net = cyc3(Servers::Single);
    let est = MonteCarlo::new(&net, Horizon::Until(1000.0))
        .runs(200)
        .seed(1)
        .run()
        .unwrap();
    assert_eq!(est.runs, 200);
    assert_eq!(est.dead_runs, 0);
    let p = |n: &str| est.mean_tokens[net.place_by_name(n).unwrap().index()];
    let t = |n: &str| est.throughput[net.transition_by_name(n).unwrap().index()];
    assert!(p("P1").contains(10.0 / 7.0), "{:?}", p("P1"));
    assert!(p("P3").contains(4.0 / 7.0), "{:?}", p("P3"));
    assert_eq!(p("P2").mean, 0.0);
    for name in ["T1", "t2", "T3"] {
        assert!(t(name).contains(6.0 / 7.0), "{name}: {:?}", t(name));
    }
    assert!(p("P1").half_width < 0.01);
}

#[test]
fn cyc3_infinite_server_estimate_contains_four_thirds() {
    let net = cyc3(Servers::Infinite);
    let est = MonteCarlo::new(&net, Horizon::Until(1000.0))
        .runs(200)
        .seed(1)
        .run()
        .unwrap();
    assert!(
        est.mean_tokens[0].contains(4.0 / 3.0),
        "{:?}",
        est.mean_tokens[0]
    );
    assert!(
        est.mean_tokens[2].contains(2.0 / 3.0),
        "{:?}",
        est.mean_tokens[2]
    );
}

#[test]
fn monte_carlo_does_not_depend_on_the_thread_count() {
    let net = cyc3(Servers::Single);
    let mc = MonteCarlo::new(&net, Horizon::Steps(300)).runs(37).seed(8);
    let one = mc.clone().threads(1).run().unwrap();
    let two = mc.clone().threads(2).run().unwrap();
    let five = mc.threads(5).run().unwrap();
    assert_eq!(one, two);
    assert_eq!(one, five);
    assert_eq!(one.firings, 37 * 300);
}

/// Issue 31: the blocks of runs go to rayon's pool; the estimates, rewards included, stay
/// the same bits on 1, 2 and 4 threads and on the global pool.
#[test]
fn monte_carlo_on_rayon_gives_the_same_bits_on_1_2_and_4_threads() {
    use gspn::analysis::decision::{PlaceMode, RewardSpec};
    let net = cyc3(Servers::Single);
    let rewards = [RewardSpec {
        name: "busy".into(),
        places: vec![(PlaceId(0), 1.5, PlaceMode::PerToken)],
        transitions: vec![(TransitionId(1), 0.25)],
    }];
    let mc = MonteCarlo::new(&net, Horizon::Until(40.0))
        .runs(45)
        .seed(31)
        .rewards(&rewards);
    let one = mc.clone().threads(1).run().unwrap();
    let two = mc.clone().threads(2).run().unwrap();
    let four = mc.clone().threads(4).run().unwrap();
    assert_eq!(one, two);
    assert_eq!(one, four);
    assert_eq!(one.runs, 45);
    assert_eq!(one.rewards.len(), 1);
    // The global pool (threads 0) too.
    assert_eq!(one, mc.run().unwrap());
}

#[test]
fn monte_carlo_refuses_bad_arguments() {
    let net = cyc3(Servers::Single);
    assert!(matches!(
        MonteCarlo::new(&net, Horizon::Until(10.0)).runs(0).run(),
        Err(SimError::BadArgument(_))
    ));
    assert!(matches!(
        MonteCarlo::new(&net, Horizon::Until(f64::NAN)).run(),
        Err(SimError::BadArgument(_))
    ));
}
