//! Any ROS 2 node can be a robot (issue 25): three Cyclone DDS (Python) robots that publish
//! no gspn heartbeat — nothing but an ExecPlace action server, as an rclpy `ActionServer`
//! would be — run the patrol to 100 firings beside a supervisor that finds them through DDS
//! discovery; one is then killed (SIGKILL: no goodbye), the supervisor sees its server leave
//! discovery when its participant's lease (1 s here) ends, and the place's `on_failure`
//! ("stop") ends the run naming it.

use crate::ros2_support as support;

use std::process::Stdio;
use std::time::{Duration, Instant};

use support::{domain, finish, listen, python, repo, supervisor_with, take};

/// The loopback Cyclone configuration with a 1 s participant lease.
fn cyclone_with_short_lease() -> String {
    support::CYCLONE_CONFIG.replace(
        "<Peers>",
        "<LeaseDuration>1s</LeaseDuration><SPDPInterval>0.3s</SPDPInterval><Peers>",
    )
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robots_without_heartbeat_run_the_patrol_and_a_killed_one_is_found_by_discovery() {
    const N: usize = 100;
    let py = python();
    let dir = tempfile::tempdir().unwrap();
    let plan = crate::python_robot::write_cyclone_plan(dir.path());
    let d = domain(17);
    let uri = cyclone_with_short_lease();
    let mut robots = Vec::new();
    for id in ["r1", "r2", "r3"] {
        let log = dir.path().join(format!("{id}.log"));
        let child = tokio::process::Command::new(&py)
            .arg(repo("ros2/examples/python_robot.py"))
            .args(["--id", id, "--domain", &d.to_string(), "--delay", "0.005"])
            .args(["--heartbeat", "0"])
            .env("CYCLONEDDS_URI", &uri)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(std::fs::File::create(&log).unwrap())
            .kill_on_drop(true)
            .spawn()
            .expect("python starts");
        robots.push((child, log));
    }
    let (mut firings, _markings) = listen(d);
    let sup = supervisor_with(
        dir.path(),
        &plan,
        d,
        &["--max-firings", "1000000", "--ros2-wait-subscribers", "1"],
    );
    let logs = |robots: &[(tokio::process::Child, std::path::PathBuf)]| {
        robots
            .iter()
            .map(|(_, l)| std::fs::read_to_string(l).unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n")
    };
    let before = take(&mut firings, N, Duration::from_secs(120)).await;
    assert_eq!(
        before.len(),
        N,
        "supervisor:\n{}\nrobots:\n{}",
        sup.log(),
        logs(&robots)
    );
    let seqs: Vec<u64> = before.iter().map(|f| f.seq).collect();
    assert_eq!(seqs, (1..=N as u64).collect::<Vec<_>>());
    for r in ["r1", "r2", "r3"] {
        let moved = before.iter().filter(|f| f.robots == [r]).count();
        assert!(moved >= 10, "{r} moved {moved} times in {N} firings");
    }
    assert!(
        !sup.log().contains("heartbeat"),
        "no heartbeat is expected of these robots:\n{}",
        sup.log()
    );

    robots[1].0.start_kill().expect("kill r2");
    let killed = Instant::now();
    let sup_log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(30)).await;
    let log = std::fs::read_to_string(&sup_log).unwrap();
    println!(
        "robot r2 (no heartbeat) killed → the run stopped after {:?}",
        killed.elapsed()
    );
    // on_failure = "stop": the run ends as a failure naming r2 and only r2.
    assert_eq!(code, Some(1), "{out}\n{log}");
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "failure");
    let errors: Vec<&str> = summary["errors"]
        .as_array()
        .expect("errors")
        .iter()
        .filter_map(|e| e.as_str())
        .collect();
    assert!(
        errors
            .iter()
            .any(|e| e.contains("robot `r2` lost (its ExecPlace server left DDS discovery)")),
        "{errors:?}"
    );
    assert!(
        !errors
            .iter()
            .any(|e| e.contains("robot `r1` lost") || e.contains("robot `r3` lost")),
        "{errors:?}"
    );
    // The two live robots leave when the supervisor says the run is over.
    for i in [0, 2] {
        let (child, log) = &mut robots[i];
        let status = tokio::time::timeout(Duration::from_secs(20), child.wait())
            .await
            .expect("the robot leaves")
            .unwrap();
        let text = std::fs::read_to_string(log).unwrap();
        assert_eq!(status.code(), Some(0), "{text}");
        assert!(
            text.contains("the supervisor's run is over (failure after"),
            "{text}"
        );
    }
}
