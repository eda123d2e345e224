//! Robots bound to agents (`RuntimeBuilder::robots`, plan key `robots`): each initial agent
//! gets a robot in agent order and keeps it through every firing; the context of its actions
//! and the `robots` of each `Fired` event name it.

use std::sync::{Arc, Mutex};

use gspn::net::{Net, NetBuilder, Servers};
use gspn::plan::PlanFile;
use gspn::runtime::{EventKind, Outcome, Runtime, RuntimeError, action_fn};

/// A three-place ring a → b → c → a with two tokens in `a` and one in `b`.
fn ring() -> Net {
    let mut b = NetBuilder::new("ring");
    let a = b.place("a", 2);
    let bb = b.place("b", 1);
    let c = b.place("c", 0);
    for (name, from, to) in [("ab", a, bb), ("bc", bb, c), ("ca", c, a)] {
        let t = b.exponential(name, 1.0, Servers::Infinite);
        b.input(from, t, 1);
        b.output(t, to, 1);
    }
    b.build().unwrap()
}

#[tokio::test(start_paused = true)]
async fn each_agent_keeps_its_robot_through_every_firing() {
    let seen: Arc<Mutex<Vec<(u64, String, String)>>> = Arc::default();
    let log = Arc::clone(&seen);
    let mut b = Runtime::builder(ring())
        .action(
            "go",
            action_fn(move |ctx| {
                let log = Arc::clone(&log);
                async move {
                    let robot = ctx.robot.as_deref().unwrap_or("-").to_string();
                    log.lock()
                        .unwrap()
                        .push((ctx.agent.0, robot, ctx.place_name().to_string()));
                    Outcome::Decide
                }
            }),
        )
        .robots(["r1", "r2", "r3"])
        .seed(5)
        .max_firings(60);
    for p in ["a", "b", "c"] {
        b = b.bind(p, "go");
    }
    let mut h = b.spawn().unwrap();
    let events = h.events();
    let summary = h.wait().await;
    assert_eq!(summary.firings, 60);
    let seen = seen.lock().unwrap().clone();
    // Agents 0 and 1 start in `a`, agent 2 in `b`: robots in that order.
    for (agent, robot, _) in seen.iter() {
        let expected = ["r1", "r2", "r3"][*agent as usize];
        assert_eq!(robot, expected, "agent {agent}");
    }
    assert!(
        seen.len() >= 60,
        "every firing starts an action: {}",
        seen.len()
    );
    let mut fired = 0;
    for e in events.collect().await {
        match e.kind {
            EventKind::Fired {
                consumed, robots, ..
            } => {
                fired += 1;
                let names: Vec<&str> = robots.iter().map(|r| &**r).collect();
                let expected: Vec<&str> = consumed
                    .iter()
                    .map(|a| ["r1", "r2", "r3"][a.0 as usize])
                    .collect();
                assert_eq!(names, expected);
            }
            EventKind::AgentSpawned { agent, robot, .. } => {
                assert_eq!(robot.as_deref(), Some(["r1", "r2", "r3"][agent.0 as usize]));
            }
            _ => {}
        }
    }
    assert_eq!(fired, 60);
}

#[tokio::test(start_paused = true)]
async fn the_agents_report_their_robots() {
    let mut b = Runtime::builder(ring())
        .action(
            "go",
            action_fn(|ctx| async move {
                ctx.cancel.cancelled().await;
                Outcome::Cancelled
            }),
        )
        .robots(["left", "right", "spare"]);
    for p in ["a", "b", "c"] {
        b = b.bind(p, "go");
    }
    let h = b.spawn().unwrap();
    tokio::time::sleep(std::time::Duration::from_secs(1)).await;
    let agents = h.agents().await;
    let robots: Vec<(u64, &str)> = agents
        .iter()
        .map(|a| (a.id.0, a.robot.as_deref().unwrap_or("-")))
        .collect();
    assert_eq!(robots, [(0, "left"), (1, "right"), (2, "spare")]);
    h.stop();
    h.wait().await;
}

#[tokio::test]
async fn a_robot_count_that_differs_from_the_agents_is_refused() {
    let mut b = Runtime::builder(ring())
        .action("go", action_fn(|_| async { Outcome::Decide }))
        .robots(["r1", "r2"]);
    for p in ["a", "b", "c"] {
        b = b.bind(p, "go");
    }
    match b.spawn().unwrap_err() {
        RuntimeError::RobotCount { robots, agents } => assert_eq!((robots, agents), (2, 3)),
        e => panic!("unexpected {e}"),
    }
}

#[tokio::test]
async fn robots_on_a_net_that_forks_are_refused() {
    let mut nb = NetBuilder::new("fork");
    let p = nb.place("p", 1);
    let q = nb.place("q", 0);
    let t = nb.exponential("split", 1.0, Servers::Single);
    nb.input(p, t, 1);
    nb.output(t, q, 2);
    let err = Runtime::builder(nb.build().unwrap())
        .action("go", action_fn(|_| async { Outcome::Decide }))
        .bind("p", "go")
        .bind("q", "go")
        .robots(["r1"])
        .spawn()
        .unwrap_err();
    assert!(
        matches!(&err, RuntimeError::RobotTokens { transition, change: 1 } if transition == "split"),
        "{err}"
    );
}

#[test]
fn a_plan_naming_a_robot_twice_is_refused_at_its_line_and_column() {
    let text = "net = \"n.xml\"\nrobots = [\"r1\", \"r2\", \"r1\"]\n";
    let file = PlanFile::parse(std::path::Path::new("plan.toml"), text).unwrap();
    let err = file
        .resolve(std::path::Path::new("plan.toml"), text, ring())
        .unwrap_err();
    let msg = err.to_string();
    assert!(msg.starts_with("plan.toml:2:23:"), "{msg}");
    assert!(msg.contains("robot `r1` is listed twice"), "{msg}");
}

#[tokio::test(start_paused = true)]
async fn a_robot_keeps_its_agent_through_a_place_without_an_action() {
    // `c` has no action: it is transparent, and a robot's agent passes through it (issue 24:
    // it used to end there, and the robot's identity was lost).
    let mut h = Runtime::builder(ring())
        .action("go", action_fn(|_| async { Outcome::Decide }))
        .bind("a", "go")
        .bind("b", "go")
        .robots(["r1", "r2", "r3"])
        .seed(3)
        .max_firings(60)
        .spawn()
        .unwrap();
    assert!(h.warnings().is_empty(), "{:?}", h.warnings());
    let mut events = h.events();
    let mut through_c = 0;
    while let Some(gspn::runtime::Received::Event(e)) = events.recv().await {
        if let gspn::runtime::EventKind::Fired {
            transition,
            consumed,
            produced,
            robots,
            ..
        } = &e.kind
        {
            // Every firing moves one robot: one agent in, the same agent out.
            assert_eq!(consumed, produced);
            assert_eq!(robots.len(), 1);
            // `ca` takes a robot out of `c`, the place without an action.
            through_c += usize::from(transition.0 == 2);
        }
    }
    let s = h.wait().await;
    assert_eq!(s.firings, 60);
    assert_eq!((s.agents_spawned, s.agents_ended), (3, 0));
    assert!(
        through_c >= 10,
        "only {through_c} robots came back out of c"
    );
}
