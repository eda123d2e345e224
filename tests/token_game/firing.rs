//! On random nets, every transition the token game fires may fire under GSPN rules, and the
//! marking it reaches is the firing equation's: `m = m0 + C·σ`.

use gspn::net::{Net, NetBuilder, Servers};
use gspn::sim::{SimError, Simulator};
use proptest::prelude::*;

/// One transition: timing choice and its arcs to each of the (up to 5) places.
#[derive(Clone, Debug)]
struct TSpec {
    /// 0 = immediate, 1 = single server, 2 = two servers, 3 = infinite server.
    kind: u8,
    /// Rate or weight.
    value: f64,
    priority: u32,
    /// Per place: input weight, output weight, inhibitor threshold (0 = no arc).
    arcs: Vec<(u32, u32, u32)>,
}

fn tspec(places: usize) -> impl Strategy<Value = TSpec> {
    (
        0u8..4,
        0.1f64..5.0,
        1u32..4,
        prop::collection::vec(
            (
                prop_oneof![3 => Just(0u32), 2 => 1u32..3],
                prop_oneof![3 => Just(0u32), 2 => 1u32..3],
                prop_oneof![6 => Just(0u32), 1 => 1u32..4],
            ),
            places,
        ),
    )
        .prop_map(|(kind, value, priority, arcs)| TSpec {
            kind,
            value,
            priority,
            arcs,
        })
}

fn net_spec() -> impl Strategy<Value = (Vec<(u32, Option<u32>)>, Vec<TSpec>)> {
    (1usize..6).prop_flat_map(|np| {
        (
            prop::collection::vec(
                (
                    0u32..4,
                    prop_oneof![3 => Just(None), 1 => (4u32..7).prop_map(Some)],
                ),
                np,
            ),
            prop::collection::vec(tspec(np), 1..7),
        )
    })
}

fn build(places: &[(u32, Option<u32>)], ts: &[TSpec]) -> Net {
    let mut b = NetBuilder::new("random");
    let ps: Vec<_> = places
        .iter()
        .enumerate()
        .map(|(i, &(m0, cap))| b.place_with_capacity(format!("p{i}"), m0, cap))
        .collect();
    for (j, t) in ts.iter().enumerate() {
        let name = format!("t{j}");
        let id = match t.kind {
            0 => b.immediate(name, t.value, t.priority),
            1 => b.exponential(name, t.value, Servers::Single),
            2 => b.exponential(name, t.value, Servers::K(2)),
            _ => b.exponential(name, t.value, Servers::Infinite),
        };
        for (i, &(pre, post, inh)) in t.arcs.iter().enumerate() {
            if pre > 0 {
                b.input(ps[i], id, pre);
            }
            if post > 0 {
                b.output(id, ps[i], post);
            }
            if inh > 0 {
                b.inhibitor(ps[i], id, inh);
            }
        }
    }
    b.build().unwrap()
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn every_firing_is_allowed_and_the_marking_obeys_the_firing_equation(
        (places, ts) in net_spec(),
        seed in any::<u64>(),
    ) {
        let net = build(&places, &ts);
        let mut sim = Simulator::new(net.clone(), seed).with_max_immediate(100);
        let mut sigma = vec![0i64; net.transition_count()];
        let mut last_time = 0.0;
        for _ in 0..300 {
            let before = sim.marking().clone();
            let firable = net.firable(&before);
            match sim.step() {
                Ok(Some(step)) => {
                    let t = step.transition;
                    prop_assert!(net.is_enabled(&before, t), "{} fired disabled", net.transition(t).name);
                    prop_assert!(firable.contains(&t), "{} fired but not firable in {:?}", net.transition(t).name, before);
                    prop_assert_eq!(step.immediate, net.transition(t).is_immediate());
                    if step.immediate {
                        prop_assert_eq!(step.time, last_time);
                    } else {
                        prop_assert!(step.time > last_time);
                    }
                    last_time = step.time;
                    sigma[t.index()] += 1;
                }
                Ok(None) => {
                    prop_assert!(firable.is_empty(), "reported dead with {:?} firable", firable);
                    break;
                }
                Err(SimError::TimelessTrap { firings, .. }) => {
                    prop_assert_eq!(firings, 100);
                    prop_assert!(net.is_vanishing(&before));
                    break;
                }
                Err(e) => return Err(TestCaseError::fail(e.to_string())),
            }
        }
        // m = m0 + C·σ, with C from the arcs (not from the net's own delta lists).
        let mut expected: Vec<i64> = places.iter().map(|&(m0, _)| m0 as i64).collect();
        for t in net.transition_ids() {
            for &(p, w) in net.inputs(t) {
                expected[p.index()] -= w as i64 * sigma[t.index()];
            }
            for &(p, w) in net.outputs(t) {
                expected[p.index()] += w as i64 * sigma[t.index()];
            }
        }
        let got: Vec<i64> = sim.marking().iter().map(|&k| k as i64).collect();
        prop_assert_eq!(got, expected);
        let fired: Vec<i64> = sim.statistics().fired.iter().map(|&k| k as i64).collect();
        prop_assert_eq!(fired, sigma);
    }
}
