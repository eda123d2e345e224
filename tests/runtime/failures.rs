//! Failures stay with the agent that failed: a panicking action, a wrong transition, a
//! transition that never becomes enabled — each is an error event naming it, and the place's
//! failure policy decides (stop, retry N, fire T).

use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};

use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::{AgentMode, EventKind, Outcome, Runtime, StopReason, action_fn};
use gspn::runtime::{FailurePolicy, Role};

in_both_agent_modes!(
    a_panicking_action_does_not_take_the_plan_down,
    failure_policy_stop_ends_the_run_with_exit_code_1,
    failure_policy_fire_takes_the_named_transition,
    a_transition_that_is_not_an_output_is_an_error_naming_it,
    a_transition_that_never_becomes_enabled_is_an_error_not_a_hang,
    an_action_past_its_place_timeout_fails_and_is_retried
);

/// Two independent loops a → A → a and b → B → b, one agent each, plus a dead end `x`.
fn two_loops() -> Net {
    let mut b = NetBuilder::new("loops");
    let pa = b.place("a", 1);
    let pb = b.place("b", 1);
    let px = b.place("x", 0);
    let ta = b.exponential("A", 1.0, Servers::Single);
    let tb = b.exponential("B", 1.0, Servers::Single);
    let tx = b.exponential("X", 1.0, Servers::Single);
    b.input(pa, ta, 1);
    b.output(ta, pa, 1);
    b.input(pb, tb, 1);
    b.output(tb, pb, 1);
    b.input(px, tx, 1);
    b.input(pb, tx, 1);
    b.output(tx, pb, 1);
    b.build().unwrap()
}

fn role(on_failure: FailurePolicy, name: &str) -> Role {
    Role::Action {
        name: name.into(),
        timeout: None,
        on_failure,
        robot: None,
    }
}

async fn a_panicking_action_does_not_take_the_plan_down(mode: AgentMode) {
    let net = two_loops();
    let (pa, pb) = (
        net.place_by_name("a").unwrap(),
        net.place_by_name("b").unwrap(),
    );
    let ta = net.transition_by_name("A").unwrap();
    let calls = Arc::new(AtomicU32::new(0));
    let c = Arc::clone(&calls);
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action("ok", action_fn(move |_| async move { Outcome::Fire(ta) }))
        .action(
            "boom",
            action_fn(move |_| {
                let c = Arc::clone(&c);
                async move {
                    if c.fetch_add(1, Ordering::SeqCst) < 2 {
                        panic!("sensor exploded");
                    }
                    Outcome::Decide
                }
            }),
        )
        .role(pa, role(FailurePolicy::Stop, "ok"))
        .role(pb, role(FailurePolicy::Retry(3), "boom"))
        .seed(3)
        .max_firings(50)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::MaxFirings);
    assert_eq!(s.firings, 50);
    assert!(calls.load(Ordering::SeqCst) >= 3);
    assert_eq!(s.errors.len(), 2, "{:?}", s.errors);
    assert!(
        s.errors[0].contains("panicked: sensor exploded"),
        "{}",
        s.errors[0]
    );
}

async fn failure_policy_stop_ends_the_run_with_exit_code_1(mode: AgentMode) {
    let net = two_loops();
    let pa = net.place_by_name("a").unwrap();
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "fail",
            action_fn(|_| async { Outcome::Failed("battery low".into()) }),
        )
        .role(pa, role(FailurePolicy::Stop, "fail"))
        .seed(3)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Failure);
    assert_eq!(s.exit_code(), 1);
    assert_eq!(
        s.errors,
        vec!["agent 0 in `a` failed: battery low".to_string()]
    );
}

async fn failure_policy_fire_takes_the_named_transition(mode: AgentMode) {
    let net = two_loops();
    let pa = net.place_by_name("a").unwrap();
    let ta = net.transition_by_name("A").unwrap();
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "fail",
            action_fn(|_| async { Outcome::Failed("no".into()) }),
        )
        .role(pa, role(FailurePolicy::Fire(ta), "fail"))
        .seed(3)
        .max_firings(20)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::MaxFirings);
    // Each failure fires A at once (zero time), so all 20 firings are A, at time 0. The
    // 20th firing ends the run and starts no action (issue 30: the run used to wait for
    // that action, up to its timeout), so 20 failures.
    assert_eq!(s.errors.len(), 20);
    assert!(s.errors.iter().all(|e| e == "agent 0 in `a` failed: no"));
    assert_eq!(s.time, 0.0);
}

async fn a_transition_that_is_not_an_output_is_an_error_naming_it(mode: AgentMode) {
    let net = two_loops();
    let pa = net.place_by_name("a").unwrap();
    let tb = net.transition_by_name("B").unwrap();
    let mut h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "wrong",
            action_fn(move |_| async move { Outcome::Fire(tb) }),
        )
        .role(pa, role(FailurePolicy::Stop, "wrong"))
        .seed(3)
        .spawn()
        .unwrap();
    let events = h.events();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Failure);
    let errors: Vec<String> = events
        .collect()
        .await
        .into_iter()
        .filter_map(|e| match e.kind {
            EventKind::Error { message } => Some(message),
            _ => None,
        })
        .collect();
    assert_eq!(
        errors,
        vec!["agent 0 in `a` returned transition `B`, which is not an output of `a`".to_string()]
    );
}

async fn a_transition_that_never_becomes_enabled_is_an_error_not_a_hang(mode: AgentMode) {
    // b → X needs a token in x as well: there never is one, and nothing else can happen.
    let mut nb = NetBuilder::new("stuck");
    let pb = nb.place("b", 1);
    let px = nb.place("x", 0);
    let tb = nb.exponential("B", 1.0, Servers::Single);
    let tx = nb.exponential("X", 1.0, Servers::Single);
    nb.input(pb, tb, 1);
    nb.output(tb, pb, 1);
    nb.input(pb, tx, 1);
    nb.input(px, tx, 1);
    let net = nb.build().unwrap();
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action("x", action_fn(move |_| async move { Outcome::Fire(tx) }))
        .role(pb, role(FailurePolicy::Stop, "x"))
        .seed(3)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Stuck);
    assert_eq!(s.exit_code(), 1);
    assert_eq!(
        s.errors,
        vec!["transition `X` was chosen by an action but never became enabled".to_string()]
    );
}

async fn an_action_past_its_place_timeout_fails_and_is_retried(mode: AgentMode) {
    let net = two_loops();
    let pa = net.place_by_name("a").unwrap();
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "slow",
            action_fn(|_| async {
                tokio::time::sleep(std::time::Duration::from_secs(10)).await;
                Outcome::Decide
            }),
        )
        .role(
            pa,
            Role::Action {
                name: "slow".into(),
                timeout: Some(1.0),
                on_failure: FailurePolicy::Retry(2),
                robot: None,
            },
        )
        .time_scale(1.0)
        .seed(3)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Failure);
    // First run and two retries time out, then the place gives up.
    assert_eq!(
        s.errors,
        vec![
            "agent 0 in `a` failed: timed out after 1s".to_string(),
            "agent 0 in `a` failed: timed out after 1s".to_string(),
            "agent 0 in `a` failed: timed out after 1s".to_string(),
            "agent 0 in `a`: gave up after 2 retries".to_string(),
        ]
    );
    assert!(
        (s.time - 3.0).abs() < 0.01,
        "three timeouts of 1 s, got {}",
        s.time
    );
}
