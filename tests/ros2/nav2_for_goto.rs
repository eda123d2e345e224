//! Nav2 for `goto` (issue 25, part 3): the temperature patrol on 4 simulated robots with
//! `--ros2`, every `goto L` sent as Nav2's `nav2_msgs/action/NavigateToPose` over DDS
//! (loopback) to `/<robot>/navigate_to_pose`, served by the simulated world, and the robots'
//! poses on `/<robot>/pose`. A Cyclone DDS reader (PyPI `cyclonedds`, not ours;
//! tests/ros2/nav2_watcher.py) reads the goals and the poses with Nav2's own IDL and type
//! names: every goal it sees is a location of the plan's map in frame `map`.
//!
//! Needs the Python venv of `./test.sh` (`target/venv-ros2` or `$GSPN_ROS2_VENV`).
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::Path;
use std::process::Stdio;
use std::time::Duration;

use support::{CYCLONE_CONFIG, domain, finish, python, repo, supervisor_with};
use tokio::io::{AsyncBufReadExt, AsyncReadExt, BufReader};

const PATROL: &str = "plans/temperature-patrol/plan.toml";

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_patrol_on_4_simulated_robots_goes_through_navigate_to_pose_over_dds() {
    let d = domain(19);
    let dir = tempfile::tempdir().unwrap();
    let robots = ["r1", "r2", "r3", "r4"];
    let mut watcher = tokio::process::Command::new(python())
        .arg(repo("tests/ros2/nav2_watcher.py"))
        .args([d.to_string(), robots.join(",")])
        .env("CYCLONEDDS_URI", CYCLONE_CONFIG)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("python starts");
    let mut err = BufReader::new(watcher.stderr.take().unwrap()).lines();
    let ready = tokio::time::timeout(Duration::from_secs(60), async {
        let mut seen = String::new();
        while let Ok(Some(l)) = err.next_line().await {
            if l.trim() == "ready" {
                return Ok(());
            }
            seen.push_str(&l);
            seen.push('\n');
        }
        Err(seen)
    })
    .await;
    match ready {
        Ok(Ok(())) => {}
        Ok(Err(e)) => panic!("the Cyclone watcher failed:\n{e}"),
        Err(_) => panic!("the Cyclone watcher did not start within 60 s"),
    }
    let stderr = tokio::spawn(async move {
        let mut rest = String::new();
        while let Ok(Some(l)) = err.next_line().await {
            rest.push_str(&l);
            rest.push('\n');
        }
        rest
    });

    // 20 times faster than real time: DDS and the world are on the wall clock.
    let sup = supervisor_with(
        dir.path(),
        Path::new(PATROL),
        d,
        &[
            "--robots",
            "4",
            "--ros2",
            "--time-scale",
            "0.05",
            "--max-firings",
            "60",
        ],
    );
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    let log = std::fs::read_to_string(&log).unwrap_or_default();
    assert_eq!(code, Some(0), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("a JSON summary");
    assert_eq!(summary["firings"], 60, "{out}");
    assert_eq!(summary["errors"].as_array().map(Vec::len), Some(0), "{out}");
    let goals = support::assert_nav2_goals(&summary, 4);
    assert!(
        log.contains("Nav2 NavigateToPose served for 4 simulated robot(s)"),
        "{log}"
    );

    // The Cyclone side: close its stdin (the run is over), read what it saw.
    drop(watcher.stdin.take());
    let mut stdout = watcher.stdout.take().unwrap();
    let mut seen = String::new();
    tokio::time::timeout(Duration::from_secs(30), stdout.read_to_string(&mut seen))
        .await
        .expect("the watcher ends")
        .unwrap();
    let status = watcher.wait().await.unwrap();
    let stderr = stderr.await.unwrap_or_default();
    assert!(status.success(), "watcher: {seen}\n{stderr}");
    let seen: serde_json::Value = serde_json::from_str(&seen).expect("one JSON object");
    assert_eq!(
        seen["types"]["goal"],
        "nav2_msgs::action::dds_::NavigateToPose_SendGoal_Request_"
    );
    assert_eq!(
        seen["types"]["pose"],
        "geometry_msgs::msg::dds_::PoseStamped_"
    );

    let patrol = support::patrol_locations();
    let mut seen_goals = 0;
    for r in robots {
        let o = &seen["robots"][r];
        let g = o["goals"].as_array().unwrap();
        for goal in g {
            assert_eq!(goal["frame"], "map", "{goal}");
            assert_eq!(goal["w"], 1.0, "{goal}");
            assert_eq!(goal["behavior_tree"], "", "{goal}");
            let (x, y) = (goal["x"].as_f64().unwrap(), goal["y"].as_f64().unwrap());
            assert!(
                patrol
                    .iter()
                    .any(|&(px, py)| (px - x).abs() < 1e-9 && (py - y).abs() < 1e-9),
                "goal ({x}, {y}) of {r} is no patrol location of the map {patrol:?}"
            );
        }
        seen_goals += g.len() as u64;
        // Poses at 10 Hz for the whole run (over a second of wall clock at least).
        assert!(o["poses"].as_u64().unwrap() >= 5, "{r}: {o}");
        assert_eq!(o["pose_frames"], serde_json::json!(["map"]), "{r}: {o}");
    }
    // Every goal the world served went over DDS where a Cyclone reader saw it (the
    // first ones may precede the reader's match with the client's writer).
    assert!(
        seen_goals >= goals.saturating_sub(4) && seen_goals <= goals,
        "Cyclone saw {seen_goals} goals, the world served {goals}"
    );
}
