//! The runtime beside the token game and the exact analysis, on random nets (issue 24): the
//! model is the contract, and every driver keeps it.
//!
//! - **Transparent actions** (`wait`, `log MSG`, no action at all, and async Rust actions
//!   that answer `Decide` after yielding and sleeping a random bit of *wall-clock* time, on a
//!   two-thread runtime so their answers arrive in any order): in virtual time the run is the
//!   token game's run for the same seed, firing for firing and time for time, and no
//!   immediate transition fires while one of higher priority is enabled.
//! - **Timed actions** (`wait S`, `fire T after S`, Rust actions sleeping on the model
//!   clock): the priority rule holds among what is ready at every firing (readiness read
//!   from the run's own events), the live agents are the tokens outside resource places, and
//!   the same seed gives the same run twice.
//! - **Actions that time the net themselves** (a place whose one output is an
//!   infinite-server exponential transition, the action drawing its own exponential delay
//!   and firing it after that many model seconds): the long-run mean tokens of independent
//!   replications contain the exact steady state.

use std::collections::HashMap;
use std::time::Duration;

use gspn::analysis::measures::{Solver, SolverOptions};
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::net::{Net, NetBuilder, PlaceId, Servers, Timing, TransitionId};
use gspn::runtime::{
    AgentId, Event, EventKind, FailurePolicy, Outcome, Received, Role, Runtime, RuntimeBuilder,
    action_fn,
};
use gspn::sim::Simulator;
use proptest::prelude::*;
use rand::SeedableRng;

/// A random transition: immediate (weight, priority) or exponential (rate, servers kind),
/// input arcs (place, weight), output arcs, an optional inhibitor.
#[derive(Clone, Debug)]
struct TSpec {
    immediate: bool,
    weight: f64,
    priority: u32,
    rate: f64,
    servers: u8,
    inputs: Vec<(usize, u32)>,
    outputs: Vec<(usize, u32)>,
    inhibitor: Option<(usize, u32)>,
}

#[derive(Clone, Debug)]
struct Spec {
    tokens: Vec<u32>,
    /// Per place: 0 resource, 1 `wait`, 2 `log`, 3 no action, 4 async instant action;
    /// with timed actions 5 `wait 0.7`, 6 a Rust action sleeping on the model clock.
    roles: Vec<u8>,
    transitions: Vec<TSpec>,
}

fn tspec(places: usize) -> impl Strategy<Value = TSpec> {
    (
        any::<bool>(),
        prop_oneof![Just(0.0), 0.5f64..3.0],
        1u32..4,
        0.2f64..5.0,
        0u8..3,
        proptest::collection::vec((0..places, 1u32..3), 1..3),
        proptest::collection::vec((0..places, 1u32..3), 0..3),
        proptest::option::of((0..places, 1u32..4)),
    )
        .prop_map(
            |(immediate, weight, priority, rate, servers, inputs, outputs, inhibitor)| TSpec {
                immediate,
                weight,
                priority,
                rate,
                servers,
                inputs,
                outputs,
                inhibitor,
            },
        )
}

fn spec(roles: std::ops::Range<u8>) -> impl Strategy<Value = Spec> {
    (2usize..7).prop_flat_map(move |places| {
        (
            proptest::collection::vec(0u32..4, places),
            proptest::collection::vec(roles.clone(), places),
            proptest::collection::vec(tspec(places), 2..8),
        )
            .prop_map(|(tokens, roles, transitions)| Spec {
                tokens,
                roles,
                transitions,
            })
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
    for (i, t) in s.transitions.iter().enumerate() {
        let id = if t.immediate {
            b.immediate(format!("t{i}"), t.weight, t.priority)
        } else {
            let servers = match t.servers {
                0 => Servers::Single,
                1 => Servers::Infinite,
                _ => Servers::K(2),
            };
            b.exponential(format!("t{i}"), t.rate, servers)
        };
        let mut seen = Vec::new();
        for &(p, w) in &t.inputs {
            if !seen.contains(&p) {
                seen.push(p);
                b.input(places[p], id, w);
            }
        }
        let mut seen = Vec::new();
        for &(p, w) in &t.outputs {
            if !seen.contains(&p) {
                seen.push(p);
                b.output(id, places[p], w);
            }
        }
        if let Some((p, w)) = t.inhibitor
            && !t.inputs.iter().any(|&(q, _)| q == p)
        {
            b.inhibitor(places[p], id, w);
        }
    }
    b.build().expect("a valid net")
}

/// An action that answers `Decide` after yielding and sleeping some wall-clock time (which
/// must not count: virtual time moves only by the net and by stated durations).
fn instant_with_wall_time() -> impl gspn::runtime::Action {
    action_fn(|ctx| async move {
        let spin = ctx.agent.0.wrapping_add(ctx.time.to_bits()) % 4;
        for _ in 0..spin {
            tokio::task::yield_now().await;
        }
        tokio::time::sleep(Duration::from_micros(20 * spin)).await;
        Outcome::Decide
    })
}

/// An action that sleeps 0.4 model seconds, then lets the net decide.
fn model_sleep() -> impl gspn::runtime::Action {
    action_fn(|ctx| async move {
        ctx.clock.sleep(0.4).await;
        Outcome::Decide
    })
}

fn runtime_of(s: &Spec, net: Net, seed: u64) -> RuntimeBuilder {
    let mut run = Runtime::builder(net)
        .seed(seed)
        .action("instant", instant_with_wall_time())
        .action("asleep", model_sleep());
    for (i, &r) in s.roles.iter().enumerate() {
        let p = PlaceId(i as u32);
        let action = |name: &str| Role::Action {
            name: name.to_string(),
            timeout: None,
            on_failure: FailurePolicy::Stop,
            robot: None,
        };
        run = match r {
            0 => run.role(p, Role::Resource),
            1 => run.role(p, action("wait")),
            2 => run.role(p, action("log here")),
            4 => run.role(p, action("instant")),
            5 => run.role(p, action("wait 0.7")),
            6 => run.role(p, action("asleep")),
            _ => run,
        };
    }
    run
}

/// Every event of a run, and the live agents at its end.
async fn events_of(run: RuntimeBuilder, firings: u64) -> (Vec<Event>, usize, Vec<u32>) {
    let mut h = run
        .max_firings(firings)
        .event_capacity(1 << 18)
        .spawn()
        .unwrap();
    let mut rx = h.events();
    let mut events = Vec::new();
    while let Some(r) = rx.recv().await {
        match r {
            Received::Event(e) => events.push(e),
            Received::Lagged(n) => panic!("{n} events lost"),
        }
    }
    h.wait().await;
    let agents = events.iter().fold(0i64, |n, e| match e.kind {
        EventKind::AgentSpawned { .. } => n + 1,
        EventKind::AgentEnded { .. } => n - 1,
        _ => n,
    }) as usize;
    let marking = events
        .iter()
        .rev()
        .find_map(|e| match &e.kind {
            EventKind::Fired { marking, .. } => Some(marking.to_vec()),
            _ => None,
        })
        .unwrap_or_default();
    (events, agents, marking)
}

fn fired(events: &[Event]) -> Vec<(TransitionId, f64)> {
    events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Fired { transition, .. } => Some((*transition, e.time)),
            _ => None,
        })
        .collect()
}

fn token_game(net: &Net, seed: u64, firings: usize) -> Vec<(TransitionId, f64)> {
    let mut sim = Simulator::new(net.clone(), seed);
    let mut out = Vec::new();
    while out.len() < firings {
        match sim.step() {
            Ok(Some(step)) => out.push((step.transition, step.time)),
            _ => break,
        }
    }
    out
}

fn priority(net: &Net, t: TransitionId) -> Option<u32> {
    match net.transition(t).timing {
        Timing::Immediate { priority, .. } => Some(priority),
        Timing::Exponential { .. } => None,
    }
}

/// The priority rule checked from a run's events: at each immediate firing, no immediate
/// transition of higher priority is enabled in the marking before it *and ready* — each of
/// its input places that runs actions holds enough agents whose action ended (read from the
/// `action_started` / `action_ended` / `fired` events). Returns the violations.
fn priority_violations(net: &Net, resource: &[bool], events: &[Event]) -> Vec<String> {
    let mut m: Vec<u32> = net.initial_marking().to_vec();
    // Agents with an action running (not ready yet), by place.
    let mut running: HashMap<AgentId, usize> = HashMap::new();
    let mut busy = vec![0u32; net.place_count()];
    let mut bad = Vec::new();
    for e in events {
        match &e.kind {
            EventKind::ActionStarted { agent, place, .. } => {
                running.insert(*agent, place.index());
                busy[place.index()] += 1;
            }
            EventKind::ActionEnded { agent, .. } => {
                if let Some(p) = running.remove(agent) {
                    busy[p] -= 1;
                }
            }
            EventKind::Fired {
                transition,
                marking,
                ..
            } => {
                if let Some(pr) = priority(net, *transition) {
                    for u in net.transition_ids() {
                        let Some(pu) = priority(net, u) else { continue };
                        let ready = net.inputs(u).iter().all(|&(p, w)| {
                            resource[p.index()] || m[p.index()].saturating_sub(busy[p.index()]) >= w
                        });
                        if pu > pr && net.is_enabled(&m, u) && ready {
                            bad.push(format!(
                                "t={}: {} (priority {pr}) fired while {} (priority {pu}) was enabled and ready in {m:?}",
                                e.time,
                                net.transition(*transition).name,
                                net.transition(u).name
                            ));
                        }
                    }
                }
                m = marking.to_vec();
            }
            _ => {}
        }
    }
    bad
}

/// Which places of a random net are resources (role 0).
fn resources(s: &Spec) -> Vec<bool> {
    s.roles.iter().map(|&r| r == 0).collect()
}

/// Firings that break the net's firing rule: each must be enabled in the marking before it
/// and leave the marking [`Net::fire`] gives.
fn rule_violations(net: &Net, events: &[Event]) -> Vec<String> {
    let mut m: Vec<u32> = net.initial_marking().to_vec();
    let mut bad = Vec::new();
    for e in events {
        let EventKind::Fired {
            transition,
            marking,
            ..
        } = &e.kind
        else {
            continue;
        };
        let name = &net.transition(*transition).name;
        if !net.is_enabled(&m, *transition) {
            bad.push(format!(
                "t={}: {name} fired while not enabled in {m:?}",
                e.time
            ));
        }
        let mut next = m.clone();
        let after = marking.to_vec();
        if net.fire(&mut next, *transition).is_err() || next != after {
            bad.push(format!(
                "t={}: {name} left {after:?}, the net says {next:?}",
                e.time
            ));
        }
        m = after;
    }
    bad
}

/// Actions started after the run's last firing: the firing that ends a run (here
/// `max_firings`) starts none — its output tokens are counted, not put to work.
fn started_after_the_end(events: &[Event]) -> Vec<String> {
    let last = events
        .iter()
        .rposition(|e| matches!(e.kind, EventKind::Fired { .. }))
        .unwrap_or(0);
    events[last..]
        .iter()
        .filter(|e| matches!(e.kind, EventKind::ActionStarted { .. }))
        .map(|e| format!("{} {:?}", e.time, e.kind))
        .collect()
}

fn two_threads() -> tokio::runtime::Runtime {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .unwrap()
}

const FIRINGS: u64 = 300;

proptest! {
    // 96 random nets × action mixes, each against the token game.
    #![proptest_config(ProptestConfig { cases: 96, rng_seed: proptest::test_runner::RngSeed::Fixed(24), ..ProptestConfig::default() })]
    #[test]
    fn transparent_actions_run_the_token_games_run(s in spec(0..5), seed in 0u64..1000) {
        let net = build(&s);
        let game = token_game(&net, seed, FIRINGS as usize);
        let rt = two_threads();
        let (events, agents, marking) = rt.block_on(events_of(runtime_of(&s, net.clone(), seed), FIRINGS));
        let run = fired(&events);
        prop_assert_eq!(&run, &game, "the run left the token game");
        let bad = priority_violations(&net, &resources(&s), &events);
        prop_assert!(bad.is_empty(), "{:?}", bad);
        if run.len() as u64 == FIRINGS {
            let late = started_after_the_end(&events);
            prop_assert!(late.is_empty(), "actions started by the last firing: {:?}", late);
        }
        // Identity: every token outside resource places is a live agent.
        let any_agents = s.roles.iter().any(|&r| r != 0 && r != 3);
        if any_agents && !marking.is_empty() {
            let tokens: u32 = marking.iter().zip(&s.roles).filter(|&(_, &r)| r != 0).map(|(k, _)| k).sum();
            prop_assert_eq!(agents, tokens as usize);
        }
    }
}

proptest! {
    // 64 random nets with actions that take model time: priorities among what is ready,
    // agents as tokens, and one seed one run.
    #![proptest_config(ProptestConfig { cases: 64, rng_seed: proptest::test_runner::RngSeed::Fixed(2024), ..ProptestConfig::default() })]
    #[test]
    fn timed_actions_keep_priorities_and_repeat(s in spec(0..7), seed in 0u64..1000) {
        let net = build(&s);
        let rt = two_threads();
        let (a, agents, marking) = rt.block_on(events_of(runtime_of(&s, net.clone(), seed), FIRINGS));
        let (b, _, _) = rt.block_on(events_of(runtime_of(&s, net.clone(), seed), FIRINGS));
        let broken = rule_violations(&net, &a);
        prop_assert!(broken.is_empty(), "{:?}", broken);
        let bad = priority_violations(&net, &resources(&s), &a);
        prop_assert!(bad.is_empty(), "{:?}", bad);
        if fired(&a).len() as u64 == FIRINGS {
            let late = started_after_the_end(&a);
            prop_assert!(late.is_empty(), "actions started by the last firing: {:?}", late);
        }
        let show = |v: &[Event]| v.iter().map(|e| format!("{} {:?}", e.time, e.kind)).collect::<Vec<_>>();
        let (sa, sb) = (show(&a), show(&b));
        let first = sa.iter().zip(&sb).position(|(x, y)| x != y);
        prop_assert!(
            first.is_none() && sa.len() == sb.len(),
            "the same seed gave two runs: event {:?} of {}/{}: {:?} vs {:?}",
            first, sa.len(), sb.len(),
            first.map(|i| &sa[i.saturating_sub(3)..=i]), first.map(|i| &sb[i.saturating_sub(3)..=i])
        );
        let any_agents = s.roles.iter().any(|&r| r != 0 && r != 3);
        if any_agents && !marking.is_empty() {
            let tokens: u32 = marking.iter().zip(&s.roles).filter(|&(_, &r)| r != 0).map(|(k, _)| k).sum();
            prop_assert_eq!(agents, tokens as usize);
        }
    }
}

/// A token-conserving state machine: `exp` (from, to, rate, infinite server?) and forward
/// immediate moves (from, to, weight).
fn machine(tokens: &[u32], exp: &[(usize, usize, f64, bool)], imm: &[(usize, usize, f64)]) -> Net {
    let mut b = NetBuilder::new("machine");
    let places: Vec<_> = tokens
        .iter()
        .enumerate()
        .map(|(i, &k)| b.place(format!("p{i}"), k))
        .collect();
    for (i, &(from, to, rate, infinite)) in exp.iter().enumerate() {
        let servers = if infinite {
            Servers::Infinite
        } else {
            Servers::Single
        };
        let t = b.exponential(format!("T{i}"), rate, servers);
        b.input(places[from], t, 1);
        b.output(t, places[to], 1);
    }
    for (i, &(a, c, w)) in imm.iter().enumerate() {
        let (from, to) = (a.min(c), a.max(c));
        if from != to {
            let t = b.immediate(format!("i{i}"), w, 1 + (i as u32 % 2));
            b.input(places[from], t, 1);
            b.output(t, places[to], 1);
        }
    }
    b.build().expect("a valid net")
}

/// An action that times its place's one output `t` itself: an exponential delay of the
/// transition's rate, drawn from the run's seed and the agent's entry, slept on the model
/// clock, then `Fire(t)` — in distribution, the infinite-server race the net describes.
fn self_timed(t: TransitionId, rate: f64) -> impl gspn::runtime::Action {
    action_fn(move |ctx| async move {
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(
            ctx.seed ^ ctx.agent.0.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ ctx.time.to_bits(),
        );
        let u: f64 = rng.random::<f64>();
        ctx.clock.sleep(-(1.0 - u).ln() / rate).await;
        Outcome::Fire(t)
    })
}

/// The 99.9% two-sided quantile of Student's t with 7 degrees of freedom.
const T_9995_7: f64 = 5.408;

#[test]
fn self_timed_actions_match_the_exact_steady_state() {
    // Eight random state machines (seeded), eight replications each to model time 400: for
    // every place, the replications' mean tokens give a 99.9% t-interval that must contain
    // the exact E[tokens]. Places whose one output is an infinite-server exponential
    // transition are timed by their action; the others `wait` for the net's race.
    let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(424242);
    let rt = two_threads();
    let (mut checked, mut timed) = (0, 0);
    for net_no in 0..8 {
        let places = rng.random_range(2..5usize);
        let tokens: Vec<u32> = (0..places).map(|_| rng.random_range(0..3u32)).collect();
        let tokens = if tokens.iter().all(|&k| k == 0) {
            vec![2; places]
        } else {
            tokens
        };
        // Every place gets an exponential way out (so the chain never dies), some a second
        // one or an immediate one.
        let mut exp: Vec<(usize, usize, f64, bool)> = (0..places)
            .map(|p| {
                (
                    p,
                    rng.random_range(0..places),
                    rng.random_range(0.3..3.0),
                    rng.random_bool(0.6),
                )
            })
            .collect();
        for _ in 0..rng.random_range(0..2usize) {
            exp.push((
                rng.random_range(0..places),
                rng.random_range(0..places),
                rng.random_range(0.3..3.0),
                rng.random_bool(0.5),
            ));
        }
        let imm: Vec<(usize, usize, f64)> = (0..rng.random_range(0..2usize))
            .map(|_| {
                (
                    rng.random_range(0..places),
                    rng.random_range(0..places),
                    rng.random_range(0.5..2.0),
                )
            })
            .collect();
        let net = machine(&tokens, &exp, &imm);
        let ss = StateSpace::build(&net, &Options::default()).unwrap();
        let solver = Solver::new(&net, &ss);
        let exact = solver
            .measures(&solver.steady_state(&SolverOptions::default()).unwrap().pi)
            .mean_tokens;
        let mut reps: Vec<Vec<f64>> = Vec::new();
        for rep in 0..8u64 {
            let mut run = Runtime::builder(net.clone()).seed(1000 * net_no + rep);
            for p in net.place_ids() {
                let outs = net.consumers(p);
                let action = match outs {
                    [t] => match net.transition(*t).timing {
                        Timing::Exponential {
                            rate,
                            servers: Servers::Infinite,
                        } => {
                            let name = format!("timed_{}", p.index());
                            run = run.action(name.clone(), self_timed(*t, rate));
                            timed += 1;
                            name
                        }
                        _ => "wait".to_string(),
                    },
                    _ => "wait".to_string(),
                };
                run = run.role(
                    p,
                    Role::Action {
                        name: action,
                        timeout: None,
                        on_failure: FailurePolicy::Stop,
                        robot: None,
                    },
                );
            }
            let summary = rt.block_on(async {
                let h = run.until(400.0).subscribe_at_start(false).spawn().unwrap();
                h.wait().await
            });
            reps.push(
                net.places()
                    .iter()
                    .map(|p| summary.mean_tokens[&p.name])
                    .collect(),
            );
        }
        for p in 0..places {
            let xs: Vec<f64> = reps.iter().map(|r| r[p]).collect();
            let n = xs.len() as f64;
            let mean = xs.iter().sum::<f64>() / n;
            let sd = (xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let half = T_9995_7 * sd / n.sqrt();
            assert!(
                (mean - exact[p]).abs() <= half.max(1e-9),
                "net {net_no} place p{p}: {mean} ± {half} misses the exact {} (tokens {tokens:?}, exp {exp:?}, imm {imm:?})",
                exact[p]
            );
            checked += 1;
        }
    }
    assert!(checked >= 16, "{checked} places checked");
    assert!(timed >= 8, "{timed} self-timed places in all replications");
}

/// a --t1--> c --t2--> d, one token in `a`, immediate transitions: only actions take time.
fn two_steps() -> Net {
    let mut b = NetBuilder::new("two steps");
    let a = b.place("a", 1);
    let c = b.place("c", 0);
    let d = b.place("d", 0);
    let t1 = b.immediate("t1", 1.0, 1);
    let t2 = b.immediate("t2", 1.0, 1);
    b.input(a, t1, 1);
    b.output(t1, c, 1);
    b.input(c, t2, 1);
    b.output(t2, d, 1);
    b.build().unwrap()
}

#[test]
fn durations_stated_by_actions_are_the_only_time_they_take() {
    // One agent, `wait 2.5` then a Rust action that burns wall-clock time and sleeps 1.25
    // model seconds: the run ends at exactly 3.75 after two firings.
    let net = two_steps();
    let rt = two_threads();
    let summary = rt.block_on(async {
        let h = Runtime::builder(net)
            .seed(1)
            .action(
                "slow",
                action_fn(|ctx| async move {
                    std::thread::sleep(Duration::from_millis(30));
                    ctx.clock.sleep(1.25).await;
                    Outcome::Decide
                }),
            )
            .bind("a", "wait 2.5")
            .bind("c", "slow")
            .spawn()
            .unwrap();
        h.wait().await
    });
    assert_eq!(summary.firings, 2);
    assert_eq!(summary.time, 3.75);
}

#[test]
fn place_timeouts_are_model_seconds_in_virtual_time() {
    // `a`: a Rust action that burns 300 ms of wall-clock time under a 0.2-model-second
    // timeout — it takes no model time, so it does not time out. `c`: `wait 3` under a
    // 2-second timeout fails at model time 2 exactly, however loaded the machine is.
    let net = two_steps();
    let (a, c) = (PlaceId(0), PlaceId(1));
    let role = |name: &str, timeout: f64| Role::Action {
        name: name.to_string(),
        timeout: Some(timeout),
        on_failure: FailurePolicy::Stop,
        robot: None,
    };
    let rt = two_threads();
    let summary = rt.block_on(async {
        let h = Runtime::builder(net)
            .seed(2)
            .action(
                "busy",
                action_fn(|_| async {
                    std::thread::sleep(Duration::from_millis(300));
                    Outcome::Decide
                }),
            )
            .role(a, role("busy", 0.2))
            .role(c, role("wait 3", 2.0))
            .spawn()
            .unwrap();
        h.wait().await
    });
    assert_eq!(summary.firings, 1, "{summary:?}");
    assert_eq!(summary.time, 2.0);
    assert_eq!(
        summary.errors,
        ["agent 0 in `c` failed: timed out after 2 model seconds"]
    );
}

/// Robots that drive themselves (`run --nav2`: a mirror world whose robots arrive when the
/// robot says so, here a navigator whose legs take 1–8 model seconds drawn from the seed):
/// the temperature patrol's built-in actions on 1–4 such robots keep the firing rule at every
/// firing, the priority rule among what is ready, and the same seed gives the same run.
#[cfg(feature = "sim")]
mod self_driving {
    use super::*;
    use gspn::world::{DriveError, Fleet, Navigator, WorldHandle};
    use std::pin::Pin;
    use std::sync::{Arc, Mutex};

    #[derive(Debug)]
    struct Legs {
        world: WorldHandle,
        state: Mutex<u64>,
    }

    impl Navigator for Legs {
        fn goto(
            &self,
            robot: Arc<str>,
            location: usize,
        ) -> Pin<Box<dyn std::future::Future<Output = Result<(), DriveError>> + Send>> {
            let secs = {
                let mut x = self.state.lock().unwrap();
                *x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                1 + (*x >> 33) % 8
            };
            let world = self.world.clone();
            Box::pin(async move {
                let drive = async {
                    tokio::time::sleep(Duration::from_secs(secs)).await;
                    Ok(())
                };
                world.mirror_goto(robot, location, drive).await
            })
        }
    }

    fn mirrored(robots: usize, seed: u64) -> (Net, Vec<bool>, Vec<Event>) {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build()
            .unwrap();
        rt.block_on(async {
            let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
                .join("plans/temperature-patrol/plan.toml");
            let mut plan = gspn::plan::read_plan(&path, &Default::default()).unwrap();
            plan.seed = Some(seed);
            let fleet = Fleet::mirror(plan, Some(robots)).unwrap();
            let legs = Legs {
                world: fleet.world.clone(),
                state: Mutex::new(seed),
            };
            let fleet = fleet.navigate_with(Arc::new(legs));
            let net = fleet.builder.net().clone();
            let resource = net
                .place_ids()
                .map(|p| matches!(fleet.builder.role_of(p), Some(Role::Resource)))
                .collect();
            let (events, _, _) = events_of(fleet.builder, 150).await;
            fleet.world.stop();
            (net, resource, events)
        })
    }

    proptest! {
        #![proptest_config(ProptestConfig { cases: 12, rng_seed: proptest::test_runner::RngSeed::Fixed(25), ..ProptestConfig::default() })]
        #[test]
        fn robots_that_drive_themselves_keep_the_firing_rule(robots in 1usize..5, seed in 0u64..1000) {
            let (net, resource, a) = mirrored(robots, seed);
            prop_assert_eq!(fired(&a).len(), 150);
            let broken = rule_violations(&net, &a);
            prop_assert!(broken.is_empty(), "{:?}", broken);
            let bad = priority_violations(&net, &resource, &a);
            prop_assert!(bad.is_empty(), "{:?}", bad);
            let late = started_after_the_end(&a);
            prop_assert!(late.is_empty(), "actions started by the last firing: {:?}", late);
            let (_, _, b) = mirrored(robots, seed);
            prop_assert_eq!(fired(&a), fired(&b), "the same seed gave two runs");
        }
    }
}
