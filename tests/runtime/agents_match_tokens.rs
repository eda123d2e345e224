//! At every event, the number of live agents equals the tokens in action places — on random
//! nets with forks, joins, weights and immediate transitions (proptest).

use std::collections::BTreeSet;
use std::time::Duration;

use gspn::net::{Net, NetBuilder, PlaceId, Servers};
use gspn::runtime::{AgentId, EventKind, Outcome, Received, Runtime, action_fn};
use proptest::prelude::*;

/// Arcs of one transition: (place index, weight).
type Arcs = Vec<(usize, u32)>;

#[derive(Clone, Debug)]
struct Spec {
    initial: Vec<u32>,
    action: Vec<bool>,
    /// Per transition: immediate?, inputs (place, weight), outputs (place, weight).
    transitions: Vec<(bool, Arcs, Arcs)>,
}

fn spec() -> impl Strategy<Value = Spec> {
    (2usize..6).prop_flat_map(|np| {
        let arcs = prop::collection::vec((0..np, 1u32..3), 0..3);
        (
            prop::collection::vec(0u32..3, np),
            prop::collection::vec(any::<bool>(), np),
            prop::collection::vec((any::<bool>(), arcs.clone(), arcs), 1..6),
        )
            .prop_map(|(initial, action, transitions)| Spec {
                initial,
                action,
                transitions,
            })
    })
}

fn build(s: &Spec) -> Net {
    let mut b = NetBuilder::new("random");
    let places: Vec<PlaceId> = s
        .initial
        .iter()
        .enumerate()
        .map(|(i, &k)| b.place(format!("p{i}"), k))
        .collect();
    for (i, (imm, ins, outs)) in s.transitions.iter().enumerate() {
        let t = if *imm {
            b.immediate(format!("t{i}"), 1.0, 1)
        } else {
            b.exponential(format!("t{i}"), 1.0 + i as f64, Servers::Infinite)
        };
        let mut seen_in = BTreeSet::new();
        for &(p, w) in ins {
            if seen_in.insert(p) {
                b.input(places[p], t, w);
            }
        }
        let mut seen_out = BTreeSet::new();
        for &(p, w) in outs {
            if seen_out.insert(p) {
                b.output(t, places[p], w);
            }
        }
    }
    b.build().unwrap()
}

fn check(s: Spec, seed: u64) -> Result<(), TestCaseError> {
    let net = build(&s);
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .start_paused(true)
        .build()
        .unwrap();
    rt.block_on(async move {
        let action_places: Vec<usize> = (0..s.action.len()).filter(|&i| s.action[i]).collect();
        let mut b = Runtime::builder(net)
            .action(
                "work",
                action_fn(|ctx| async move {
                    // Agents take different times; half decide, half fire their first output.
                    tokio::time::sleep(Duration::from_millis(100 * (ctx.agent.0 % 4))).await;
                    match ctx.outputs().first() {
                        Some(&t) if ctx.agent.0 % 2 == 0 => Outcome::Fire(t),
                        _ => Outcome::Decide,
                    }
                }),
            )
            .seed(seed)
            .max_firings(150)
            .until(500.0)
            .event_capacity(1 << 16);
        for &p in &action_places {
            b = b.bind(format!("p{p}"), "work");
        }
        let mut h = b.spawn().unwrap();
        let mut events = h.events();
        let mut live = BTreeSet::new();
        while let Some(r) = events.recv().await {
            let Received::Event(e) = r else {
                return Err(TestCaseError::fail("subscriber lagged"));
            };
            match e.kind {
                EventKind::AgentSpawned { agent, .. } => {
                    live.insert(agent);
                }
                EventKind::Fired {
                    consumed,
                    produced,
                    marking,
                    ..
                } => {
                    for a in &consumed {
                        prop_assert!(live.remove(a), "consumed a dead agent {a:?}");
                    }
                    for a in &produced {
                        live.insert(*a);
                    }
                    // Once a plan has an action place, every token is an agent (no place
                    // here is a resource): identity is kept through places without actions.
                    let tokens: u32 = if action_places.is_empty() {
                        0
                    } else {
                        marking.as_slice().iter().sum()
                    };
                    prop_assert_eq!(live.len(), tokens as usize, "after seq {}", e.seq);
                }
                EventKind::AgentEnded { agent } => {
                    prop_assert!(!live.contains(&agent), "{agent:?} ended but still live");
                }
                _ => {}
            }
        }
        let s = h.wait().await;
        prop_assert_eq!(s.agents_spawned - s.agents_ended, live.len() as u64);
        let _ = AgentId(0);
        Ok(())
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]
    #[test]
    fn live_agents_equal_tokens_in_action_places(s in spec(), seed in 0u64..1000) {
        check(s, seed)?;
    }
}
