//! Many agent actors at once: the initial agents of a large plan are spawned from two threads
//! (`AgentMode::Actor`, multi-threaded runtime, ≥ 20,000 agents); none is lost, each runs its
//! own actions, and the run is the same token game.

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{AgentMode, AgentState, Outcome, Runtime, StopReason, action_fn};

use crate::support as common;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn twenty_five_thousand_agent_actors_start_and_run() {
    let n = 25_000u32;
    let (net, ts) = common::ring(4, |_| n / 4, |_| 1.0, Servers::Infinite);
    let mut rb = Runtime::builder(net)
        .agent_mode(AgentMode::Actor)
        .seed(9)
        .max_firings(5_000);
    for (i, t) in ts.iter().copied().enumerate() {
        let name = format!("step{i}");
        rb = rb
            .action(
                name.clone(),
                action_fn(move |_| async move { Outcome::Fire(t) }),
            )
            .bind(format!("p{i}"), name);
    }
    let h = rb.subscribe_at_start(false).spawn().unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::MaxFirings);
    assert_eq!(s.firings, 5_000);
    assert_eq!(s.agents_spawned, u64::from(n));
    assert_eq!(s.agents_ended, 0);
    assert_eq!(s.final_marking.values().sum::<u32>(), n);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_agent_actor_reports_while_waiting() {
    // Actions that wait for the stop: every one of the 24,000 agents is Occupied, then each
    // sees the cancel and the run ends with every agent accounted for.
    let n = 24_000u32;
    let mut b = NetBuilder::new("wait");
    let p = b.place("p", n);
    let q = b.place("q", 0);
    let t = b.exponential("t", 1.0, Servers::Infinite);
    b.input(p, t, 1);
    b.output(t, q, 1);
    let h = Runtime::builder(b.build().unwrap())
        .agent_mode(AgentMode::Actor)
        .action(
            "wait",
            action_fn(|ctx| async move {
                ctx.cancel.cancelled().await;
                Outcome::Cancelled
            }),
        )
        .bind("p", "wait")
        .subscribe_at_start(false)
        .spawn()
        .unwrap();
    while !h.progress().started() {
        tokio::task::yield_now().await;
    }
    let agents = h.agents().await;
    assert_eq!(agents.len(), n as usize);
    let ids: Vec<u64> = agents.iter().map(|a| a.id.0).collect();
    assert_eq!(ids, (0..u64::from(n)).collect::<Vec<_>>());
    assert!(agents.iter().all(|a| a.state == AgentState::Occupied));
    h.stop();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Requested);
    assert_eq!(s.firings, 0);
}
