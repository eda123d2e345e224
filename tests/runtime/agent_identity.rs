//! Agent identity through firings (DESIGN.md "Execution"): consumed agents continue in arc
//! order, surplus consumed agents end, extra produced tokens are new agents. Regression for
//! the predecessor's crash on many→many synchronisation.

use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::{
    AgentId, AgentMode, AgentState, EventKind, Outcome, Runtime, StopReason, action_fn,
};

in_both_agent_modes!(
    many_to_many_fires_once_keeps_two_agents_and_spawns_a_third,
    a_join_ends_the_surplus_agent,
    an_agent_in_a_place_without_outputs_is_inactive
);

/// {p1, p2} → t1 → outputs, every place an action place.
fn sync_net(outputs: &[&str]) -> Net {
    let mut b = NetBuilder::new("sync");
    let p1 = b.place("p1", 1);
    let p2 = b.place("p2", 1);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    b.input(p1, t1, 1);
    b.input(p2, t1, 1);
    for name in outputs {
        let p = b.place(*name, 0);
        b.output(t1, p, 1);
    }
    b.build().unwrap()
}

async fn many_to_many_fires_once_keeps_two_agents_and_spawns_a_third(mode: AgentMode) {
    let net = sync_net(&["p3", "p4", "p5"]);
    let t1 = net.transition_by_name("t1").unwrap();
    let mut b = Runtime::builder(net)
        .agent_mode(mode)
        .action("sync", action_fn(move |_| async move { Outcome::Fire(t1) }))
        .seed(1);
    for p in ["p1", "p2", "p3", "p4", "p5"] {
        b = b.bind(p, "sync");
    }
    let mut h = b.spawn().unwrap();
    let events = h.events();
    let s = h.wait().await;
    let events = events.collect().await;
    assert_eq!(s.firings, 1);
    assert_eq!(s.stopped, StopReason::Dead);
    assert_eq!(s.agents_spawned, 3);
    assert_eq!(s.agents_ended, 0);
    let fired: Vec<_> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Fired {
                consumed, produced, ..
            } => Some((consumed.clone(), produced.clone())),
            _ => None,
        })
        .collect();
    assert_eq!(
        fired,
        vec![(
            vec![AgentId(0), AgentId(1)],
            vec![AgentId(0), AgentId(1), AgentId(2)]
        )]
    );
    assert_eq!(s.final_marking["p3"], 1);
    assert_eq!(s.final_marking["p5"], 1);
}

async fn a_join_ends_the_surplus_agent(mode: AgentMode) {
    let net = sync_net(&["p3"]);
    let t1 = net.transition_by_name("t1").unwrap();
    let mut h = Runtime::builder(net)
        .agent_mode(mode)
        .action("sync", action_fn(move |_| async move { Outcome::Fire(t1) }))
        .bind("p1", "sync")
        .bind("p2", "sync")
        .bind("p3", "sync")
        .seed(1)
        .spawn()
        .unwrap();
    let events = h.events();
    let s = h.wait().await;
    let events = events.collect().await;
    assert_eq!((s.agents_spawned, s.agents_ended), (2, 1));
    let ended: Vec<_> = events
        .iter()
        .filter_map(|e| match e.kind {
            EventKind::AgentEnded { agent } => Some(agent),
            _ => None,
        })
        .collect();
    assert_eq!(
        ended,
        vec![AgentId(1)],
        "agent 0 continues into p3, agent 1 ends"
    );
}

async fn an_agent_in_a_place_without_outputs_is_inactive(mode: AgentMode) {
    // The sync net plus an independent net-timed loop that keeps the run alive.
    let mut b = NetBuilder::new("sync+loop");
    let p1 = b.place("p1", 1);
    let p2 = b.place("p2", 1);
    let p3 = b.place("p3", 0);
    let q = b.place("q", 1);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    let tick = b.exponential("tick", 1.0, Servers::Single);
    b.input(p1, t1, 1);
    b.input(p2, t1, 1);
    b.output(t1, p3, 1);
    b.input(q, tick, 1);
    b.output(tick, q, 1);
    let net = b.build().unwrap();
    let h = Runtime::builder(net)
        .agent_mode(mode)
        .action(
            "slow",
            action_fn(move |_| async move {
                tokio::time::sleep(std::time::Duration::from_secs(5)).await;
                Outcome::Fire(t1)
            }),
        )
        .bind("p1", "slow")
        .bind("p2", "slow")
        .bind("p3", "slow")
        .seed(1)
        // Scaled real time (on the test's paused clock), so model time follows tokio's clock.
        .time_scale(1.0)
        .until(100.0)
        .spawn()
        .unwrap();
    // q's token is an agent too (a place without an action keeps its agents), always ready.
    let sync = |v: Vec<gspn::runtime::AgentInfo>| -> Vec<gspn::runtime::AgentInfo> {
        v.into_iter().filter(|a| a.place != q).collect()
    };
    assert_eq!(h.agents().await.len(), 3);
    // Before the actions end, both agents are occupied.
    let agents = sync(h.agents().await);
    assert_eq!(agents.len(), 2);
    assert!(agents.iter().all(|a| a.state == AgentState::Occupied));
    tokio::time::sleep(std::time::Duration::from_secs(6)).await;
    let agents = sync(h.agents().await);
    assert_eq!(agents.len(), 1);
    assert_eq!(agents[0].state, AgentState::Inactive);
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::TimeLimit);
    assert_eq!(s.time, 100.0);
    assert_eq!(s.final_marking["p3"], 1);
}
