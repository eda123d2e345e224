//! `check`'s structural facts are proofs, not guesses: on random nets, every marking a
//! random walk reaches respects the place bounds and the P-invariants, and no transition
//! reported "can never fire" ever fires. (The walk ignores priorities and timing, so it
//! explores a superset of what a GSPN run can reach.)

use gspn::check::Structure;
use gspn::net::{Net, NetBuilder, Servers};
use proptest::prelude::*;

/// A random net: `np` places with small initial markings, transitions with 1–2 inputs,
/// 0–2 outputs, sometimes an inhibitor.
fn net_strategy() -> impl Strategy<Value = Net> {
    (2usize..6, 1usize..7).prop_flat_map(|(np, nt)| {
        let marking = prop::collection::vec(0u32..3, np);
        let arc = (0..np, 1u32..3);
        let trans = prop::collection::vec(
            (
                prop::collection::vec(arc.clone(), 1..3),
                prop::collection::vec(arc.clone(), 0..3),
                prop::option::weighted(0.3, arc),
                any::<bool>(),
            ),
            nt,
        );
        (marking, trans).prop_map(move |(marking, trans)| {
            let mut b = NetBuilder::new("random");
            let places: Vec<_> = marking
                .iter()
                .enumerate()
                .map(|(i, &k)| b.place(format!("P{i}"), k))
                .collect();
            for (j, (ins, outs, inhib, imm)) in trans.into_iter().enumerate() {
                let t = if imm {
                    b.immediate(format!("t{j}"), 1.0, 1)
                } else {
                    b.exponential(format!("T{j}"), 1.0, Servers::Single)
                };
                let mut used = Vec::new();
                for (p, w) in ins {
                    if !used.contains(&p) {
                        used.push(p);
                        b.input(places[p], t, w);
                    }
                }
                let mut used = Vec::new();
                for (p, w) in outs {
                    if !used.contains(&p) {
                        used.push(p);
                        b.output(t, places[p], w);
                    }
                }
                if let Some((p, w)) = inhib {
                    b.inhibitor(places[p], t, w);
                }
            }
            b.build().expect("valid random net")
        })
    })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn bounds_invariants_and_dead_transitions_hold_on_random_walks(
        net in net_strategy(),
        choices in prop::collection::vec(any::<prop::sample::Index>(), 60),
    ) {
        let s = Structure::of(&net);
        let mut m: Vec<u32> = net.initial_marking().as_slice().to_vec();
        let m0: Vec<u64> = m.iter().map(|&k| k as u64).collect();
        let value = |y: &[u64], m: &[u64]| -> u64 { y.iter().zip(m).map(|(a, b)| a * b).sum() };
        for pick in choices {
            for p in net.place_ids() {
                let k = m[p.index()];
                prop_assert!(s.allows(p, k), "P{} = {k} outside [{}, {:?}]", p.index(), s.lower[p.index()], s.upper[p.index()]);
            }
            let mu: Vec<u64> = m.iter().map(|&k| k as u64).collect();
            for y in &s.invariants {
                prop_assert_eq!(value(y, &mu), value(y, &m0));
            }
            let enabled: Vec<_> = net.transition_ids().filter(|&t| net.is_enabled(&m, t)).collect();
            if enabled.is_empty() {
                break;
            }
            let t = enabled[pick.index(enabled.len())];
            prop_assert!(s.may_fire[t.index()], "`{}` fired but was reported dead", net.transition(t).name);
            net.fire(&mut m, t).unwrap();
            if m.iter().any(|&k| k > 1000) {
                break;
            }
        }
    }
}
