//! Two places served by one robot (issue 17, item 5): their goals reach the robot's one
//! ExecPlace server at the same time and run side by side. ros2-client's service client
//! dropped the responses of concurrent calls, so goals to one server once went one at a
//! time; the supervisor's link now hands each response to its call by request id.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::Path;
use std::time::Duration;

use gspn::io::{Format, write_net};
use gspn::net::{NetBuilder, Servers};
use support::{GOAL_LOG, domain, finish, robot_env, supervisor_with};

/// Places `A` and `B` (one agent each) both bound to robot `r1`; their exponential outputs
/// `a` and `b` take the agents to `DoneA` and `DoneB`, where the run ends.
fn write_two_place_plan(dir: &Path) -> std::path::PathBuf {
    let mut b = NetBuilder::new("two_places_one_robot");
    for (from, t, to) in [("A", "a", "DoneA"), ("B", "b", "DoneB")] {
        let p = b.place(from, 1);
        let q = b.place(to, 0);
        let t = b.exponential(t, 1.0, Servers::Single);
        b.input(p, t, 1);
        b.output(t, q, 1);
    }
    write_net(&b.build().unwrap(), &dir.join("two.pnml"), Format::Pnml).unwrap();
    let plan = dir.join("two.toml");
    std::fs::write(
        &plan,
        "net = \"two.pnml\"\nseed = 11\ntime_scale = 8.0\n\n\
         [places.A]\naction = \"ros2\"\nrobot = \"r1\"\n\n\
         [places.B]\naction = \"ros2\"\nrobot = \"r1\"\n",
    )
    .unwrap();
    plan
}

/// The robot's goal lines in the order it wrote them: (`started`|`ended`, place).
fn goal_events(log: &str) -> Vec<(&'static str, String)> {
    log.lines()
        .filter_map(|l| {
            let rest = l.split("robot r1: goal `").nth(1)?;
            let (place, tail) = rest.split_once('`')?;
            let kind = if tail.contains(") started: ") {
                "started"
            } else if tail.contains(") ended: Succeeded") {
                "ended"
            } else {
                return None;
            };
            Some((kind, place.to_string()))
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_goals_to_one_robot_run_at_the_same_time() {
    let dir = tempfile::tempdir().unwrap();
    let plan = write_two_place_plan(dir.path());
    let d = domain(11);
    let r1 = robot_env(dir.path(), "r1", &plan, d, &[], &[GOAL_LOG]);
    let journal = dir.path().join("journal.jsonl");
    let sup = supervisor_with(
        dir.path(),
        &plan,
        d,
        &["--journal", journal.to_str().unwrap()],
    );
    let sup_log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(90)).await;
    let sup_log = std::fs::read_to_string(sup_log).unwrap();
    assert_eq!(code, Some(0), "{out}\n{sup_log}\nrobot: {}", r1.log());
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["firings"], 2, "{summary}");
    assert_eq!(summary["final_marking"]["DoneA"], 1);
    assert_eq!(summary["final_marking"]["DoneB"], 1);

    let (code, _) = finish(r1, Duration::from_secs(30)).await;
    let log = std::fs::read_to_string(dir.path().join("r1.log")).unwrap();
    assert_eq!(code, Some(0), "{log}");
    assert!(log.contains("robot r1: 2 goals, 0 cancelled"), "{log}");
    // The robot started both goals before it ended either: they overlapped.
    let events = goal_events(&log);
    let kinds: Vec<&str> = events.iter().map(|(k, _)| *k).collect();
    assert_eq!(
        kinds,
        ["started", "started", "ended", "ended"],
        "{events:?}\n{log}"
    );
    let mut started: Vec<&str> = events[..2].iter().map(|(_, p)| p.as_str()).collect();
    started.sort_unstable();
    assert_eq!(started, ["A", "B"]);
    // The supervisor's journal: both actions started before the first firing.
    let kinds: Vec<String> = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter_map(|e| e["event"].as_str().map(str::to_string))
        .filter(|k| k == "action_started" || k == "fired")
        .collect();
    assert_eq!(
        kinds,
        ["action_started", "action_started", "fired", "fired"],
        "{kinds:?}"
    );
}
