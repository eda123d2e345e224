//! Stopping (handle.stop() or Ctrl-C) cancels running actions, waits for them, flushes the
//! journal and says why it stopped: exit code 130.

use std::time::Duration;

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{AgentMode, Outcome, Runtime, StopReason, action_fn};
use serde_json::Value;

in_both_agent_modes!(
    stop_cancels_actions_and_leaves_a_complete_journal,
    actions_that_ignore_the_cancel_are_waited_for_a_bounded_time
);

async fn stop_cancels_actions_and_leaves_a_complete_journal(mode: AgentMode) {
    let mut b = NetBuilder::new("patrol");
    let p = b.place("patrol", 3);
    let q = b.place("counter", 1);
    let t = b.exponential("done", 1.0, Servers::Infinite);
    let tick = b.exponential("tick", 2.0, Servers::Single);
    b.input(p, t, 1);
    b.output(t, p, 1);
    b.input(q, tick, 1);
    b.output(tick, q, 1);
    let net = b.build().unwrap();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.jsonl");
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "patrol",
            action_fn(|ctx| async move {
                tokio::select! {
                    _ = ctx.cancel.cancelled() => Outcome::Cancelled,
                    _ = tokio::time::sleep(Duration::from_secs(3600)) => Outcome::Decide,
                }
            }),
        )
        .bind("patrol", "patrol")
        .seed(99)
        // Real time (on the test's paused clock): the hour-long actions take tokio time while
        // the net-timed tick fires.
        .time_scale(1.0)
        .journal(&path)
        .spawn()
        .unwrap();
    tokio::time::sleep(Duration::from_secs(10)).await;
    h.stop();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Requested);
    assert_eq!(s.exit_code(), 130);
    assert!(s.firings > 0, "the net-timed tick kept firing meanwhile");

    let text = std::fs::read_to_string(&path).unwrap();
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[0]["net"], "patrol");
    assert_eq!(lines[0]["seed"], 99);
    assert_eq!(lines[0]["hash"].as_str().unwrap().len(), 16);
    let events = &lines[1..];
    for (i, e) in events.iter().enumerate() {
        assert_eq!(e["seq"], i as u64, "no gaps");
    }
    let count = |kind: &str| events.iter().filter(|e| e["event"] == kind).count();
    assert_eq!(count("action_started"), 3);
    assert_eq!(count("action_ended"), 3);
    assert_eq!(count("fired"), s.firings as usize);
    let cancelled = events
        .iter()
        .filter(|e| e["event"] == "action_ended" && e["outcome"]["kind"] == "cancelled")
        .count();
    assert_eq!(cancelled, 3);
    let last = events.last().unwrap();
    assert_eq!(last["event"], "stopped");
    assert_eq!(last["reason"], "requested");
}

async fn actions_that_ignore_the_cancel_are_waited_for_a_bounded_time(mode: AgentMode) {
    let mut b = NetBuilder::new("stubborn");
    let p = b.place("p", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.input(p, t, 1);
    b.output(t, p, 1);
    let h = Runtime::builder(b.build().unwrap())
        .agent_mode(mode)
        .action(
            "deaf",
            action_fn(|_| async {
                tokio::time::sleep(Duration::from_secs(3600)).await;
                Outcome::Decide
            }),
        )
        .bind("p", "deaf")
        .grace(Duration::from_secs(2))
        .seed(1)
        .spawn()
        .unwrap();
    tokio::time::sleep(Duration::from_secs(1)).await;
    h.stop();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Requested);
    assert_eq!(
        s.errors,
        vec!["1 action(s) did not end within 2s of the stop".to_string()]
    );
}
