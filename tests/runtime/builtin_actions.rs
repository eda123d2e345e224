//! Built-in actions without a map: `wait [S]`, `log MSG`, `fire T [after S]` run agents in
//! every plan; a malformed one is refused at spawn, naming the place and the text.

use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::{EventKind, Outcome, Runtime, RuntimeError, StopReason};
use gspn::runtime::{FailurePolicy, Role};

/// look → t1 | t2 → rest → back → look
fn loop_net() -> Net {
    let mut b = NetBuilder::new("builtins");
    let look = b.place("look", 1);
    let rest = b.place("rest", 0);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    let t2 = b.exponential("t2", 1.0, Servers::Single);
    let back = b.exponential("back", 2.0, Servers::Single);
    b.input(look, t1, 1);
    b.output(t1, rest, 1);
    b.input(look, t2, 1);
    b.output(t2, rest, 1);
    b.input(rest, back, 1);
    b.output(back, look, 1);
    b.build().unwrap()
}

fn role(name: &str) -> Role {
    Role::Action {
        name: name.into(),
        timeout: None,
        on_failure: FailurePolicy::Stop,
        robot: None,
    }
}

#[tokio::test(start_paused = true)]
async fn fire_after_and_log_run_agents_on_virtual_time() {
    let net = loop_net();
    let (look, rest) = (
        net.place_by_name("look").unwrap(),
        net.place_by_name("rest").unwrap(),
    );
    let t2 = net.transition_by_name("t2").unwrap();
    let mut h = Runtime::builder(net)
        .role(look, role("fire t2 after 3"))
        .role(rest, role("log resting"))
        .max_firings(6)
        .seed(1)
        .spawn()
        .unwrap();
    assert!(h.warnings().is_empty(), "{:?}", h.warnings());
    let events = h.events().collect().await;
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::MaxFirings);
    assert_eq!(s.agents_spawned, 1);
    let fired: Vec<(f64, u32)> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Fired { transition, .. } => Some((e.time, transition.0)),
            _ => None,
        })
        .collect();
    // Every `look` ends with t2 exactly 3 s after it started; `rest` lets the net's rate decide.
    let mut started = 0.0;
    for (i, &(t, tr)) in fired.iter().enumerate() {
        if i % 2 == 0 {
            assert_eq!(tr, t2.0);
            assert!((t - started - 3.0).abs() < 1e-3, "{fired:?}");
        } else {
            assert_eq!(tr, 2);
            started = t;
        }
    }
    let logged = events
        .iter()
        .filter(|e| matches!(&e.kind, EventKind::ActionOutput { line, .. } if line == "resting"))
        .count();
    assert_eq!(logged, 3);
    let ended_with_fire = events
        .iter()
        .filter(|e| {
            matches!(&e.kind, EventKind::ActionEnded { outcome: Outcome::Fire(t), .. } if *t == t2)
        })
        .count();
    assert_eq!(ended_with_fire, 3);
}

#[tokio::test(start_paused = true)]
async fn wait_with_seconds_holds_the_agent_then_the_net_decides() {
    let net = loop_net();
    let look = net.place_by_name("look").unwrap();
    let mut h = Runtime::builder(net)
        .role(look, role("wait 10"))
        .max_firings(1)
        .seed(2)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let first = events
        .iter()
        .find(|e| matches!(e.kind, EventKind::Fired { .. }))
        .unwrap();
    // 10 s of waiting, then the race of t1 and t2 (rate 1 each) from there.
    assert!(first.time > 10.0, "{}", first.time);
    assert_eq!(h.wait().await.agents_spawned, 1);
}

#[tokio::test]
async fn a_malformed_builtin_is_refused_naming_the_place_and_the_text() {
    for (text, why) in [
        (
            "fire t9",
            "place `look`: `fire t9`: `t9` is not an output transition of `look` (outputs: t1, t2)",
        ),
        (
            "fire back",
            "place `look`: `fire back`: `back` is not an output transition of `look` (outputs: t1, t2)",
        ),
        (
            "wait soon",
            "place `look`: `wait soon`: `soon` is not a number of seconds (finite, ≥ 0, ≤ 315576000: 10 years)",
        ),
        (
            "fire t1 after 1e300",
            "place `look`: `fire t1 after 1e300`: `1e300` is not a number of seconds (finite, ≥ 0, ≤ 315576000: 10 years)",
        ),
        (
            "fire t1 later 3",
            "place `look`: `fire t1 later 3`: expected `fire T` or `fire T after S`",
        ),
    ] {
        let net = loop_net();
        let look = net.place_by_name("look").unwrap();
        let err = Runtime::builder(net)
            .role(look, role(text))
            .spawn()
            .unwrap_err();
        assert!(matches!(err, RuntimeError::BadBuiltin { .. }));
        assert_eq!(err.to_string(), why);
    }
}

#[tokio::test(start_paused = true)]
async fn an_action_neither_registered_nor_built_in_is_refused_at_spawn() {
    let net = loop_net();
    let look = net.place_by_name("look").unwrap();
    let e = Runtime::builder(net)
        .role(look, role("inspect"))
        .action(
            "scan",
            gspn::runtime::action_fn(|_| async { Outcome::Decide }),
        )
        .action(
            "dock",
            gspn::runtime::action_fn(|_| async { Outcome::Decide }),
        )
        .spawn()
        .unwrap_err();
    match &e {
        RuntimeError::UnknownAction {
            place,
            action,
            known,
        } => {
            assert_eq!(place, "look");
            assert_eq!(action, "inspect");
            assert_eq!(known, &["dock", "scan"]);
        }
        other => panic!("{other:?}"),
    }
    assert_eq!(
        e.to_string(),
        "place `look`: action `inspect` is not registered and not a built-in (`wait [S]`, `log MSG`, `fire T [after S]`); registered: dock, scan"
    );
}
