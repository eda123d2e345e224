//! Regression (issue 14, defect 3): a token count used to wrap at 2³² in `simulate` and
//! `run` (1 + 4294967295 became 0 through an arc weight). Now every driver refuses the
//! firing with a clear error and leaves the marking as it was.

use gspn::net::{MAX_TOKENS, Net, NetBuilder, Servers};
use gspn::sim::{SimError, Simulator};

/// `full` holds the maximum count; `t` moves the one token of `one` into it.
fn overflowing() -> Net {
    let mut b = NetBuilder::new("overflow");
    let full = b.place("full", MAX_TOKENS);
    let one = b.place("one", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.input(one, t, 1);
    b.output(t, full, 1);
    b.build().unwrap()
}

#[test]
fn the_token_game_refuses_a_firing_past_the_maximum_count() {
    let net = overflowing();
    let t = net.transition_by_name("t").unwrap();
    let mut m = net.initial_marking();
    let o = net.fire(&mut m, t).unwrap_err();
    assert_eq!(o.tokens, 4_294_967_296);
    assert_eq!(m.as_slice(), &[MAX_TOKENS, 1], "the marking is unchanged");
    assert_eq!(
        net.describe_overflow(&o),
        "firing `t` would put 4294967296 tokens in place `full`, which exceeds the maximum token count 4294967295"
    );

    let mut sim = Simulator::new(net.clone(), 1);
    match sim.step() {
        Err(SimError::TokenOverflow { message, .. }) => {
            assert!(message.contains("place `full`"), "{message}")
        }
        other => panic!("expected an overflow, got {other:?}"),
    }
    assert_eq!(sim.marking().as_slice(), &[MAX_TOKENS, 1]);
}

#[test]
fn parallel_arcs_that_add_past_the_maximum_are_refused_when_built() {
    let mut b = NetBuilder::new("arcs");
    let p = b.place("p", 0);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.output(t, p, MAX_TOKENS);
    b.output(t, p, 1);
    let e = b.build().unwrap_err();
    assert_eq!(
        e.to_string(),
        "arcs between `p` and `t` add up to more than the maximum token count 4294967295"
    );
}
