//! Each action's context carries the marking at the moment it started: the marking after the
//! last firing before its `ActionStarted` event (snapshots are reused from a pool, so a stale
//! or overwritten one would show here).

use std::collections::HashMap;
use std::sync::{Arc, Mutex};

use gspn::net::Servers;
use gspn::runtime::{AgentMode, EventKind, Outcome, Runtime, action_fn};

use crate::support as common;

in_both_agent_modes!(every_action_sees_the_marking_of_its_start);

async fn every_action_sees_the_marking_of_its_start(mode: AgentMode) {
    let (net, _) = common::ring(5, |_| 2, |i| 1.0 + i as f64, Servers::Infinite);
    let initial = net.initial_marking().to_vec();
    let seen: Arc<Mutex<HashMap<u64, Vec<Vec<u32>>>>> = Arc::default();
    let log = Arc::clone(&seen);
    let mut rb = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "step",
            action_fn(move |ctx| {
                let log = Arc::clone(&log);
                async move {
                    log.lock()
                        .unwrap()
                        .entry(ctx.agent.0)
                        .or_default()
                        .push(ctx.marking.to_vec());
                    tokio::time::sleep(std::time::Duration::from_millis(ctx.agent.0 * 7 + 1)).await;
                    Outcome::Decide
                }
            }),
        )
        .seed(4)
        .max_firings(300);
    for i in 0..5 {
        rb = rb.bind(format!("p{i}"), "step");
    }
    let mut h = rb.spawn().unwrap();
    let events = h.events();
    assert_eq!(h.wait().await.firings, 300);
    let mut expected: HashMap<u64, Vec<Vec<u32>>> = HashMap::new();
    let mut now = initial;
    for e in events.collect().await {
        match e.kind {
            EventKind::Fired { marking, .. } => now = marking.to_vec(),
            EventKind::ActionStarted { agent, .. } => {
                expected.entry(agent.0).or_default().push(now.clone())
            }
            _ => {}
        }
    }
    let seen = seen.lock().unwrap().clone();
    assert_eq!(seen.len(), 10);
    let mut checked = 0;
    for (agent, got) in &seen {
        let want = &expected[agent];
        assert!(got.len() <= want.len(), "agent {agent}");
        assert_eq!(got[..], want[..got.len()], "agent {agent}");
        checked += got.len();
    }
    assert!(checked >= 300, "{checked} action starts checked");
}
