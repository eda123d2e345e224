//! A plan's `[map]`: mistakes are refused with the plan's line and column; a robot that
//! cannot get through is reported stuck with its position and the failure policy decides;
//! the world's view is the JSON the viewer draws, at most 20 times per simulated second.
#![cfg(feature = "sim")]

use std::path::{Path, PathBuf};

use gspn::io::ReadOptions;
use gspn::net::{NetBuilder, Servers};
use gspn::plan::read_plan;
use gspn::runtime::{EventKind, Received, StopReason};
use gspn::world::{Fleet, FleetError};
use serde_json::{Value, json};

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A directory with the thesis net and `plan` (`net = "tp.xml"` + `plan`).
fn patrol_dir(plan: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("plans/temperature-patrol/temperature_patrol.xml"),
        dir.path().join("tp.xml"),
    )
    .unwrap();
    let path = dir.path().join("plan.toml");
    std::fs::write(&path, format!("net = \"tp.xml\"\n{plan}")).unwrap();
    (dir, path)
}

fn error_at(plan: &str) -> (u32, u32, String) {
    let (_dir, path) = patrol_dir(plan);
    let e = read_plan(&path, &ReadOptions::default()).unwrap_err();
    let s = e.span.expect("a position");
    (s.line, s.column, e.kind.to_string())
}

const TWO: &str = "[map]
edges = [[\"L1\", \"L2\"]]
[map.locations.L1]
x = 0.0
y = 0.0
places = [\"p1:Check_Temperature_L1\"]
[map.locations.L2]
x = 5.0
y = 0.0
";

#[test]
fn the_patrol_plan_loads_with_its_map() {
    let plan = read_plan(
        &repo("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let map = plan.map.unwrap();
    let names: Vec<&str> = map.locations.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(names, ["C1", "C2", "C3", "C4", "L1", "L2", "L3", "L4"]);
    assert_eq!(map.edges.len(), 8);
    assert_eq!(map.patrol, [4, 5, 6, 7]);
    assert_eq!(map.obstacles.len(), 9);
    assert_eq!(map.walls.len(), 4);
    let l1 = &map.locations[4];
    assert_eq!((l1.x, l1.y, l1.queue_dir), (1.5, 3.0, [0.0, 1.0]));
    assert_eq!(l1.places.len(), 4);
    assert_eq!(map.robot.radius, 0.15);
    assert_eq!(map.queue.lanes, 4);
    assert_eq!(
        map.program("goto L2; measure"),
        Ok(Some(vec![
            gspn::world::program::Step::Goto(5),
            gspn::world::program::Step::Measure(None),
        ]))
    );
}

#[test]
fn map_mistakes_are_refused_with_line_and_column() {
    let (l, c, m) = error_at(&TWO.replace("[\"L1\", \"L2\"]", "[\"L1\", \"L9\"]"));
    assert_eq!((l, c), (3, 17));
    assert_eq!(m, "location `L9` does not exist");
    let (l, c, m) = error_at(&TWO.replace("p1:Check_Temperature_L1", "p1:Nope"));
    assert_eq!((l, c), (7, 11));
    assert_eq!(m, "place `p1:Nope` does not exist");
    let twice = format!("{TWO}places = [\"p1:Check_Temperature_L1\"]\n");
    let (l, c, m) = error_at(&twice);
    assert_eq!((l, c), (11, 11));
    assert_eq!(
        m,
        "place `p1:Check_Temperature_L1` is already at location `L1`"
    );
    let (l, c, m) = error_at(&format!("{TWO}colour = 3\n"));
    assert_eq!((l, c), (11, 1));
    assert!(m.contains("colour"), "{m}");
    let goto =
        format!("[places.\"p1:Check_Temperature_L1\"]\naction = \"goto L7; measure\"\n{TWO}");
    let (l, c, m) = error_at(&goto);
    assert_eq!((l, c), (3, 10), "at the action's value");
    assert_eq!(
        m,
        "place `p1:Check_Temperature_L1`: `goto L7`: location `L7` does not exist"
    );
    let (l, _, m) = error_at(&TWO.replacen("x = 0.0\n", "x = 0.0\nqueue = [0.0, 0.0]\n", 1));
    assert_eq!(l, 4);
    assert!(m.contains("non-zero"), "{m}");
}

/// A ring A → B → A whose start place `A` holds one token, and a plan whose map puts a wall
/// between the two locations.
fn walled_plan(dir: &Path, on_failure: &str) -> PathBuf {
    let mut b = NetBuilder::new("walled");
    let a = b.place("A", 1);
    let bb = b.place("B", 0);
    let ab = b.exponential("ab", 1.0, Servers::Single);
    let ba = b.exponential("ba", 1.0, Servers::Single);
    b.input(a, ab, 1);
    b.output(ab, bb, 1);
    b.input(bb, ba, 1);
    b.output(ba, a, 1);
    let net = b.build().unwrap();
    std::fs::write(dir.join("walled.pnml"), gspn::io::pnml::write(&net)).unwrap();
    let plan = format!(
        "net = \"walled.pnml\"
seed = 3
[places.A]
action = \"goto B\"
{on_failure}
[places.B]
action = \"wait 1\"
[map]
stuck_after = 5.0
queue = {{ lanes = 1 }}
edges = [[\"A\", \"B\"]]
walls = [[0.0, -3.0, 10.0, -3.0], [10.0, -3.0, 10.0, 3.0], [10.0, 3.0, 0.0, 3.0], [0.0, 3.0, 0.0, -3.0], [5.0, -3.0, 5.0, 3.0]]
[map.locations.A]
x = 2.0
y = 0.0
places = [\"A\"]
[map.locations.B]
x = 8.0
y = 0.0
places = [\"B\"]
"
    );
    let path = dir.join("plan.toml");
    std::fs::write(&path, plan).unwrap();
    path
}

#[tokio::test(start_paused = true)]
async fn a_robot_that_cannot_get_through_is_reported_stuck_where_it_stands() {
    let dir = tempfile::tempdir().unwrap();
    let plan = read_plan(&walled_plan(dir.path(), ""), &ReadOptions::default()).unwrap();
    let fleet = Fleet::new(plan, None).unwrap();
    let mut handle = fleet.builder.spawn().unwrap();
    let mut events = handle.events();
    let summary = handle.wait().await;
    let metrics = fleet.world.metrics().await.unwrap();
    fleet.world.stop();
    assert_eq!(summary.stopped, StopReason::Failure);
    assert_eq!(metrics.stuck_events, 1);
    assert_eq!(metrics.cycles_per_robot, [0]);
    let mut messages = Vec::new();
    while let Some(Received::Event(e)) = events.recv().await {
        if let EventKind::Error { message } = e.kind {
            messages.push((e.time, message));
        }
    }
    assert_eq!(messages.len(), 1, "{messages:?}");
    let (time, msg) = &messages[0];
    // Driving ~3 m to the wall (slowing down as it nears it) takes ~5 s, then 5 s without
    // progress.
    assert!(*time > 8.0 && *time < 13.0, "{time}");
    let at = msg
        .split_once("stuck at (")
        .map(|(_, r)| r.trim_end_matches(')').to_string())
        .expect(msg);
    let xy: Vec<f64> = at.split(", ").map(|v| v.parse().unwrap()).collect();
    assert!(xy[0] > 4.6 && xy[0] < 4.9, "{msg}");
    assert!(xy[1].abs() < 0.05, "{msg}");
    assert!(
        msg.starts_with("agent 0 in `A` failed: stuck at ("),
        "{msg}"
    );
}

#[tokio::test(start_paused = true)]
async fn the_failure_policy_decides_what_a_stuck_robot_does_next() {
    let dir = tempfile::tempdir().unwrap();
    let path = walled_plan(dir.path(), "on_failure = \"retry 2\"");
    let plan = read_plan(&path, &ReadOptions::default()).unwrap();
    let fleet = Fleet::new(plan, None).unwrap();
    let handle = fleet.builder.spawn().unwrap();
    let summary = handle.wait().await;
    let metrics = fleet.world.metrics().await.unwrap();
    fleet.world.stop();
    // Three tries, each 5 s without progress, then the run stops.
    assert_eq!(summary.stopped, StopReason::Failure);
    assert_eq!(metrics.stuck_events, 3);
    assert_eq!(summary.errors.len(), 4, "{:?}", summary.errors);
    assert!(summary.errors[3].contains("gave up after 2 retries"));
}

#[tokio::test(start_paused = true)]
async fn the_world_view_is_the_json_the_viewer_draws() {
    let plan = read_plan(
        &repo("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let fleet = Fleet::new(plan, Some(2)).unwrap();
    let mut view = fleet.world.view();
    let v = serde_json::to_value(&*view.borrow_and_update()).unwrap();
    assert_eq!(v["time"], json!(0.0));
    assert_eq!(
        v["map"]["locations"][4],
        json!({"name": "L1", "x": 1.5, "y": 3.0})
    );
    assert_eq!(v["map"]["edges"][0], json!(["L1", "C1"]));
    assert_eq!(v["map"]["walls"][0], json!([0.0, 0.0, 14.0, 0.0]));
    assert_eq!(
        v["map"]["obstacles"][0],
        json!({"x": 3.0, "y": 3.0, "w": 2.5, "h": 2.5})
    );
    // Two robots scaled from the net's three start tokens: one at L1 (front, first lane) and
    // one at L2 (front, first lane).
    let robots = v["robots"].as_array().unwrap();
    assert_eq!(robots.len(), 2);
    let r1 = &robots[0];
    let keys: Vec<&str> = r1.as_object().unwrap().keys().map(String::as_str).collect();
    assert_eq!(keys, ["agent", "id", "radius", "x", "y"]);
    assert_eq!(r1["id"], json!("r1"));
    assert_eq!(r1["agent"], json!(0));
    assert!((r1["x"].as_f64().unwrap() - 2.25).abs() < 1e-6, "{r1}");
    assert!((r1["y"].as_f64().unwrap() - 3.0).abs() < 1e-6, "{r1}");
    assert!((r1["radius"].as_f64().unwrap() - 0.15).abs() < 1e-6);
    assert_eq!(robots[1]["id"], json!("r2"));
    assert!((robots[1]["x"].as_f64().unwrap() - 11.0).abs() < 1e-6);

    let handle = fleet.builder.subscribe_at_start(false).spawn().unwrap();
    let mut times = Vec::new();
    let mut moved = false;
    while times.last().is_none_or(|&t| t < 60.0) {
        view.changed().await.unwrap();
        let w = view.borrow_and_update().clone();
        moved |= (w.robots[0].x - 2.25).abs() > 0.1 || (w.robots[1].x - 11.0).abs() > 0.1;
        times.push(w.time);
    }
    handle.stop();
    handle.wait().await;
    fleet.world.stop();
    assert!(moved, "a robot drove off");
    assert!(times.len() > 100, "{}", times.len());
    for w in times.windows(2) {
        assert!(w[1] - w[0] >= 0.05 - 1e-9, "views {} s apart", w[1] - w[0]);
    }
    let v: Value = serde_json::to_value(&*view.borrow()).unwrap();
    assert!(v["time"].as_f64().unwrap() >= 60.0);
}

#[tokio::test(start_paused = true)]
async fn nets_that_create_or_destroy_robots_are_refused() {
    let mut b = NetBuilder::new("fork");
    let a = b.place("A", 1);
    let bb = b.place("B", 0);
    let t = b.exponential("split", 1.0, Servers::Single);
    b.input(a, t, 1);
    b.output(t, bb, 2);
    let net = b.build().unwrap();
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("fork.pnml"), gspn::io::pnml::write(&net)).unwrap();
    let path = dir.path().join("plan.toml");
    std::fs::write(
        &path,
        "net = \"fork.pnml\"\n[places.A]\naction = \"wait\"\n[places.B]\naction = \"wait\"\n\
         [map]\n[map.locations.X]\nx = 0.0\ny = 0.0\nplaces = [\"A\", \"B\"]\n",
    )
    .unwrap();
    let plan = read_plan(&path, &ReadOptions::default()).unwrap();
    let e = Fleet::new(plan, Some(4)).unwrap_err();
    assert!(
        matches!(&e, FleetError::RobotTokens { transition, change: 1 } if transition == "split"),
        "{e}"
    );
    assert_eq!(
        e.to_string(),
        "transition `split` changes the number of robots by 1: robots cannot appear or vanish (make the places that count things `role = \"resource\"`)"
    );
}

#[test]
fn robot_tokens_are_scaled_largest_remainder_first() {
    let plan = read_plan(
        &repo("plans/temperature-patrol/plan.toml"),
        &ReadOptions::default(),
    )
    .unwrap();
    let robot: Vec<bool> = vec![true; plan.net.place_count()];
    let m = |n| gspn::world::fleet::scaled_marking(&plan.net, &robot, n);
    // The net starts with one token in each of Check_Temperature_L1, L2, L3 (places 0, 4, 8).
    let at = |m: Vec<u32>| (m[0], m[4], m[8], m.iter().sum::<u32>());
    assert_eq!(at(m(1)), (1, 0, 0, 1));
    assert_eq!(at(m(2)), (1, 1, 0, 2));
    assert_eq!(at(m(4)), (2, 1, 1, 4));
    assert_eq!(at(m(64)), (22, 21, 21, 64));
}
