//! The policy picks the immediate transitions it names — including the thesis's wildcard
//! (partial) rules of the temperature patrol (`'-'` = any count). Regression for the
//! predecessor's policies that never matched (`'1'` vs `1`).

use gspn::net::{NetBuilder, PlaceId, Servers};
use gspn::policy::{Pattern, Policy, Rule};
use gspn::runtime::{EventKind, Runtime};

/// The Decide_L1 fragment of the temperature patrol: a robot in `p3:Decide_L1` goes to wait
/// (`t4:Go_Wait_L1`) or checks L2 (`t6:Go_Check_L2`); `p5:Check_Temperature_L2` tells whether
/// another robot is already checking L2. Both branches come back to `p1`.
fn decide_net(l2_busy: u32) -> gspn::net::Net {
    let mut b = NetBuilder::new("decide");
    let p1 = b.place("p1:Check_Temperature_L1", 1);
    let p3 = b.place("p3:Decide_L1", 0);
    let p4 = b.place("p4:Wait_L1", 0);
    let p5 = b.place("p5:Check_Temperature_L2", l2_busy);
    let p6 = b.place("p6:Went_L2", 0);
    let t3 = b.exponential("t3:Temperature_Low_L1", 1.0, Servers::Single);
    let t4 = b.immediate("t4:Go_Wait_L1", 1.0, 1);
    let t5 = b.exponential("t5:Wait_Done_L1", 1.0, Servers::Single);
    let t6 = b.immediate("t6:Go_Check_L2", 1.0, 1);
    let back = b.exponential("back", 1.0, Servers::Single);
    b.input(p1, t3, 1);
    b.output(t3, p3, 1);
    b.input(p3, t4, 1);
    b.output(t4, p4, 1);
    b.input(p4, t5, 1);
    b.output(t5, p1, 1);
    b.input(p3, t6, 1);
    b.output(t6, p6, 1);
    b.input(p6, back, 1);
    b.output(back, p1, 1);
    let _ = p5;
    b.build().unwrap()
}

/// The thesis's two rules for Decide_L1, wildcards everywhere else.
fn thesis_policy(net: &gspn::net::Net) -> Policy {
    let p3 = net.place_by_name("p3:Decide_L1").unwrap();
    let p5 = net.place_by_name("p5:Check_Temperature_L2").unwrap();
    let t4 = net.transition_by_name("t4:Go_Wait_L1").unwrap();
    let t6 = net.transition_by_name("t6:Go_Check_L2").unwrap();
    let rule = |k: u32, t| Rule {
        pattern: Pattern::Partial(vec![(p3, 1), (p5, k)]),
        choose: vec![(t, 1.0)],
    };
    Policy::new(net, vec![rule(0, t6), rule(1, t4)]).unwrap()
}

async fn decisions(l2_busy: u32, with_policy: bool) -> (u64, u64) {
    let net = decide_net(l2_busy);
    let policy = if with_policy {
        thesis_policy(&net)
    } else {
        Policy::empty()
    };
    let t4 = net.transition_by_name("t4:Go_Wait_L1").unwrap();
    let t6 = net.transition_by_name("t6:Go_Check_L2").unwrap();
    let mut h = Runtime::builder(net)
        .policy(policy)
        .seed(11)
        .max_firings(2000)
        .event_capacity(1 << 16)
        .spawn()
        .unwrap();
    let events = h.events();
    h.wait().await;
    let (mut n4, mut n6) = (0, 0);
    for e in events.collect().await {
        if let EventKind::Fired { transition, .. } = e.kind {
            n4 += (transition == t4) as u64;
            n6 += (transition == t6) as u64;
        }
    }
    (n4, n6)
}

#[tokio::test(start_paused = true)]
async fn the_wildcard_rule_sends_the_robot_to_l2_when_nobody_checks_it() {
    let (n4, n6) = decisions(0, true).await;
    assert_eq!(n4, 0);
    assert!(n6 > 100, "t6 fired {n6} times");
}

#[tokio::test(start_paused = true)]
async fn the_wildcard_rule_makes_the_robot_wait_when_l2_is_taken() {
    let (n4, n6) = decisions(1, true).await;
    assert_eq!(n6, 0);
    assert!(n4 > 100, "t4 fired {n4} times");
}

#[tokio::test(start_paused = true)]
async fn without_a_policy_the_weights_decide() {
    let (n4, n6) = decisions(0, false).await;
    assert!(n4 > 100 && n6 > 100, "t4 {n4}, t6 {n6}");
    let _ = PlaceId(0);
}
