//! The policy's lookup order (DESIGN.md): the exact marking through its hash index first,
//! then partial patterns in file order; restricted to the transitions that can fire now and
//! renormalised; no rule → the net's own weights. Rules come from plan text, as a user
//! writes them.

use std::path::Path;

use gspn::net::{Net, NetBuilder, Servers, TransitionId};
use gspn::plan::{Plan, PlanFile};

/// `Decide` (1 token) feeds immediate `a` (weight 1), `b` (weight 3), `c` (weight 0, needs
/// `Key` too); `Busy` and `Key` are side places; `E` is exponential.
fn net() -> Net {
    let mut bld = NetBuilder::new("choice");
    let decide = bld.place("Decide", 1);
    let busy = bld.place("Busy", 0);
    let key = bld.place("Key", 1);
    let a = bld.immediate("a", 1.0, 1);
    let b = bld.immediate("b", 3.0, 1);
    let c = bld.immediate("c", 0.0, 1);
    let e = bld.exponential("E", 1.0, Servers::Single);
    for t in [a, b, c] {
        bld.input(decide, t, 1);
        bld.output(t, busy, 1);
    }
    bld.input(key, c, 1);
    bld.output(c, key, 1);
    bld.input(busy, e, 1);
    bld.output(e, decide, 1);
    bld.build().unwrap()
}

fn plan(rules: &str) -> Plan {
    let text = format!("net = \"n.xml\"\n{rules}");
    let path = Path::new("plan.toml");
    PlanFile::parse(path, &text)
        .and_then(|f| f.resolve(path, &text, net()))
        .unwrap_or_else(|e| panic!("{e}"))
}

const A: TransitionId = TransitionId(0);
const B: TransitionId = TransitionId(1);
const C: TransitionId = TransitionId(2);

fn assert_dist(got: &[(TransitionId, f64)], want: &[(TransitionId, f64)]) {
    assert_eq!(got.len(), want.len(), "{got:?} vs {want:?}");
    for ((t, p), (u, q)) in got.iter().zip(want) {
        assert_eq!(t, u, "{got:?} vs {want:?}");
        assert!((p - q).abs() < 1e-9, "{got:?} vs {want:?}");
    }
}

#[test]
fn an_exact_marking_wins_over_an_earlier_partial_pattern() {
    let p = plan(
        "[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { a = 1.0 }\n\
         [[policy]]\nmarking = { Decide = 1, Key = 1 }\nchoose = { b = 0.25, c = 0.75 }\n",
    );
    // (Decide, Busy, Key) = (1, 0, 1) is the exact rule's marking.
    let d = p.policy.distribution(&[1, 0, 1], &[A, B, C]).unwrap();
    assert_dist(&d, &[(B, 0.25), (C, 0.75)]);
    assert_eq!(p.policy.rule_for(&[1, 0, 1], &[A, B, C]).unwrap().0, 1);
    // One token more in Busy: not the exact marking, the partial rule applies.
    let d = p.policy.distribution(&[1, 1, 1], &[A, B, C]).unwrap();
    assert_dist(&d, &[(A, 1.0)]);
}

#[test]
fn partial_patterns_apply_in_file_order() {
    let p = plan(
        "[[policy]]\nmarking = { Busy = 2 }\npartial = true\nchoose = { b = 1.0 }\n\
         [[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { a = 1.0 }\n\
         [[policy]]\nmarking = { Decide = 1, Busy = 2 }\npartial = true\nchoose = { c = 1.0 }\n",
    );
    // Both the first and the third match (1, 2, 1): the first in file order wins.
    assert_eq!(p.policy.rule_for(&[1, 2, 1], &[A, B, C]).unwrap().0, 0);
    assert_dist(
        &p.policy.distribution(&[1, 2, 1], &[A, B, C]).unwrap(),
        &[(B, 1.0)],
    );
    // Busy = 0: only the second matches.
    assert_dist(
        &p.policy.distribution(&[1, 0, 1], &[A, B, C]).unwrap(),
        &[(A, 1.0)],
    );
}

#[test]
fn probabilities_are_renormalised_over_the_transitions_that_can_fire() {
    let p =
        plan("[[policy]]\nmarking = {}\npartial = true\nchoose = { a = 0.2, b = 0.3, c = 0.5 }\n");
    let net = &p.net;
    // Key = 0: c is not enabled.
    let firable = net.firable(&[1, 0, 0]);
    assert_eq!(firable, vec![A, B]);
    let d = p.policy.distribution(&[1, 0, 0], &firable).unwrap();
    assert_dist(&d, &[(A, 0.4), (B, 0.6)]);
    let total: f64 = d.iter().map(|x| x.1).sum();
    assert!((total - 1.0).abs() < 1e-12);
}

#[test]
fn a_matching_rule_that_names_nothing_firable_is_skipped() {
    let p = plan(
        "[[policy]]\nmarking = { Decide = 1 }\npartial = true\nchoose = { c = 1.0 }\n\
         [[policy]]\nmarking = {}\npartial = true\nchoose = { a = 0.5, b = 0.5 }\n",
    );
    let net = &p.net;
    let firable = net.firable(&[1, 0, 0]);
    // Key = 0: c cannot fire, so the first rule gives nothing firable and the second applies.
    assert_dist(
        &p.policy.distribution(&[1, 0, 0], &firable).unwrap(),
        &[(A, 0.5), (B, 0.5)],
    );
}

#[test]
fn no_matching_rule_falls_back_to_the_net_weights() {
    let p = plan("[[policy]]\nmarking = { Busy = 5 }\npartial = true\nchoose = { a = 1.0 }\n");
    let net = &p.net;
    let m = [1, 0, 1];
    let firable = net.firable(&m);
    assert_eq!(firable, vec![A, B, C]);
    assert_eq!(p.policy.distribution(&m, &firable), None);
    // Weights 1, 3, 0: c (weight 0) is left to a policy, and there is none here.
    assert_dist(
        &p.policy.distribution_or_weights(net, &m, &firable),
        &[(A, 0.25), (B, 0.75)],
    );
    // Only the weight-0 transition can fire: uniform over it.
    assert_dist(
        &p.policy.distribution_or_weights(net, &m, &[C]),
        &[(C, 1.0)],
    );
}

#[test]
fn the_exact_index_scales_to_many_rules() {
    // 2,000 exact rules over (Decide, Busy, Key): lookups go through the hash index.
    let mut text = String::new();
    for busy in 0..2000 {
        let t = if busy % 2 == 0 { "a" } else { "b" };
        text.push_str(&format!(
            "[[policy]]\nmarking = {{ Decide = 1, Busy = {busy}, Key = 1 }}\nchoose = {{ {t} = 1.0 }}\n"
        ));
    }
    let p = plan(&text);
    for busy in [0u32, 1, 1234, 1999] {
        let (i, rule) = p.policy.rule_for(&[1, busy, 1], &[A, B, C]).unwrap();
        assert_eq!(i, busy as usize);
        let want = if busy % 2 == 0 { A } else { B };
        assert_eq!(rule.choose, vec![(want, 1.0)]);
    }
    assert!(p.policy.rule_for(&[1, 2000, 1], &[A, B, C]).is_none());
    assert_eq!(p.rule_spans[1].line, 5);
}

proptest::proptest! {
    /// Whatever the rule's probabilities and whichever transitions can fire, the policy's
    /// distribution is over firable transitions only, positive, and sums to 1.
    #[test]
    fn distributions_sum_to_one_over_firable_transitions(
        raw in proptest::collection::vec(0u32..5, 3),
        firable_mask in 1u8..8,
    ) {
        let total: u32 = raw.iter().sum();
        proptest::prop_assume!(total > 0);
        let probs: Vec<f64> = raw.iter().map(|&r| r as f64 / total as f64).collect();
        let p = plan(&format!(
            "[[policy]]\nmarking = {{}}\npartial = true\nchoose = {{ a = {:?}, b = {:?}, c = {:?} }}\n",
            probs[0], probs[1], probs[2]
        ));
        let firable: Vec<TransitionId> = [A, B, C]
            .into_iter()
            .enumerate()
            .filter(|(i, _)| firable_mask & (1 << i) != 0)
            .map(|(_, t)| t)
            .collect();
        let d = p.policy.distribution_or_weights(&p.net, &[1, 0, 1], &firable);
        let sum: f64 = d.iter().map(|x| x.1).sum();
        proptest::prop_assert!((sum - 1.0).abs() < 1e-9, "{d:?}");
        for (t, q) in &d {
            proptest::prop_assert!(firable.contains(t) && *q > 0.0, "{d:?}");
        }
        // The rule applies exactly when it gives a firable transition positive mass.
        let applies = firable.iter().any(|t| probs[t.index()] > 0.0);
        proptest::prop_assert_eq!(p.policy.distribution(&[1, 0, 1], &firable).is_some(), applies);
    }
}
