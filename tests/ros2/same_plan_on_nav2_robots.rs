//! The same plan on simulated robots first and on real Nav2 robots after, unchanged (issue
//! 25, part 3): `plan-runner sim-nav2` serves the temperature patrol's map with 4 simulated
//! robots as a Nav2 fleet in a process of its own (`/<robot>/navigate_to_pose`, poses on
//! `/<robot>/pose`), and a supervisor runs the patrol's own plan file on them with
//! `--nav2`, as it would on robots running Nav2: every `goto L` a `NavigateToPose` goal,
//! nothing simulated on its side, its map a mirror that shows each robot where the goal's
//! feedback says it is.
#![cfg(all(feature = "ros2", feature = "sim"))]

use crate::ros2_support as support;

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::time::Duration;

use support::{domain, finish, supervisor_with, terminate};

const PATROL: &str = "plans/temperature-patrol/plan.toml";

/// The robot poses of a journal's `world` records: per robot, every `(x, y)` in order.
fn recorded_poses(journal: &Path) -> BTreeMap<String, Vec<(f64, f64)>> {
    let mut out: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for line in std::fs::read_to_string(journal).unwrap().lines() {
        let Ok(v) = serde_json::from_str::<serde_json::Value>(line) else {
            continue;
        };
        if v["record"] != "world" {
            continue;
        }
        for r in v["data"].as_array().unwrap() {
            let id = r["id"].as_str().unwrap().to_string();
            let (x, y) = (r["x"].as_f64().unwrap(), r["y"].as_f64().unwrap());
            out.entry(id).or_default().push((x, y));
        }
    }
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_patrol_runs_unchanged_on_a_nav2_fleet_in_another_process() {
    let d = domain(20);
    let dir = tempfile::tempdir().unwrap();
    let fleet = support::plan_runner(
        dir.path(),
        "sim-nav2",
        &[
            "sim-nav2",
            PATROL,
            "--robots",
            "4",
            "--time-scale",
            "0.05",
            "--ros2-domain",
            &d.to_string(),
        ],
    );
    let served = tokio::time::timeout(Duration::from_secs(60), async {
        while !fleet.log().contains("NavigateToPose served for 4") {
            tokio::time::sleep(Duration::from_millis(100)).await;
        }
    })
    .await;
    assert!(served.is_ok(), "sim-nav2 did not start: {}", fleet.log());

    let journal = dir.path().join("run.jsonl");
    let sup = supervisor_with(
        dir.path(),
        Path::new(PATROL),
        d,
        &[
            "--robots",
            "4",
            "--nav2",
            "--time-scale",
            "0.05",
            "--max-firings",
            "60",
            "--journal",
            journal.to_str().unwrap(),
        ],
    );
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    let log = std::fs::read_to_string(&log).unwrap_or_default();
    assert_eq!(code, Some(0), "{out}\n{log}\nsim-nav2: {}", fleet.log());
    let summary: serde_json::Value = serde_json::from_str(&out).expect("a JSON summary");
    assert_eq!(summary["firings"], 60, "{out}");
    assert_eq!(summary["errors"].as_array().map(Vec::len), Some(0), "{out}");
    // The supervisor simulated nothing: it waited for Nav2 on the four robots and counted
    // its own goals.
    assert!(log.contains("Nav2 ready on 4 robot(s)"), "{log}");
    assert!(!log.contains("served for"), "{log}");
    support::assert_nav2_goals(&summary, 4);

    // The mirror showed each robot where Nav2's feedback put it: poses between locations,
    // not only the queue slots it starts in, and every robot ends near a patrol location.
    let patrol = support::patrol_locations();
    let poses = recorded_poses(&journal);
    assert_eq!(
        poses.keys().cloned().collect::<Vec<_>>(),
        ["r1", "r2", "r3", "r4"]
    );
    for (r, p) in &poses {
        let distinct: BTreeSet<(i64, i64)> = p
            .iter()
            .map(|&(x, y)| ((x * 1000.0) as i64, (y * 1000.0) as i64))
            .collect();
        assert!(distinct.len() >= 5, "{r} moved through {distinct:?}");
        let far = p
            .iter()
            .map(|&(x, y)| {
                patrol
                    .iter()
                    .map(|&(px, py)| (px - x).hypot(py - y))
                    .fold(f64::INFINITY, f64::min)
            })
            .fold(0.0, f64::max);
        assert!(far > 1.0, "{r} was never between locations: {p:?}");
    }
    let fleet_log = terminate(fleet, Duration::from_secs(10)).await;
    assert!(fleet_log.contains("sim-nav2: stopped"), "{fleet_log}");
}
