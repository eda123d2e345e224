//! A robot that is not gspn (issue 17): `ros2/examples/python_robot.py`, on Eclipse Cyclone
//! DDS through the PyPI `cyclonedds` package, serves ExecPlace — the send-goal, get-result and
//! cancel services and the status and feedback topics of a ROS 2 action, with the request
//! ids in the header `rmw_cyclonedds_cpp` writes (`service_mapping = "cyclone"`) — and the
//! supervisor drives it, beside two gspn robots, through the temperature patrol.
//!
//! Needs the Python venv that `.ci/run` creates (`target/venv-ros2` or `$GSPN_ROS2_VENV`);
//! fails, saying so, without it.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::collections::BTreeSet;
use std::process::Stdio;
use std::time::Duration;

use support::{CYCLONE_CONFIG, domain, finish, python, repo, robot_with, supervisor_with};

/// The patrol plan with the Cyclone service mapping.
pub(crate) fn write_cyclone_plan(dir: &std::path::Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(repo(support::PLAN))
        .unwrap()
        .replace(
            "net = \"nets/temperature_patrol.xml\"",
            &format!(
                "net = {:?}",
                repo("plans/nets/temperature_patrol.xml").to_string_lossy()
            ),
        )
        .replace("[ros2]\n", "[ros2]\nservice_mapping = \"cyclone\"\n");
    let plan = dir.join("patrol_cyclone.toml");
    std::fs::write(&plan, text).unwrap();
    plan
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_python_robot_on_cyclone_dds_completes_a_patrol() {
    const N: u64 = 200;
    let py = python();
    let dir = tempfile::tempdir().unwrap();
    let plan = write_cyclone_plan(dir.path());
    let d = domain(12);
    let py_log = dir.path().join("python_robot.log");
    let mut r1 = tokio::process::Command::new(&py)
        .arg(repo("ros2/examples/python_robot.py"))
        .args(["--id", "r1", "--domain", &d.to_string(), "--delay", "0.01"])
        .env("CYCLONEDDS_URI", CYCLONE_CONFIG)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&py_log).unwrap())
        .kill_on_drop(true)
        .spawn()
        .expect("python starts");
    let _r2 = robot_with(dir.path(), "r2", &plan, d, &[]);
    let _r3 = robot_with(dir.path(), "r3", &plan, d, &[]);
    let journal = dir.path().join("journal.jsonl");
    let sup = supervisor_with(
        dir.path(),
        &plan,
        d,
        &[
            "--max-firings",
            &N.to_string(),
            "--journal",
            journal.to_str().unwrap(),
        ],
    );
    let sup_log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    let py_text = || std::fs::read_to_string(&py_log).unwrap_or_default();
    assert_eq!(
        code,
        Some(0),
        "{out}\n{}\npython robot:\n{}",
        std::fs::read_to_string(&sup_log).unwrap_or_default(),
        py_text()
    );
    let summary: serde_json::Value = serde_json::from_str(&out).expect("JSON summary");
    assert_eq!(summary["stopped"], "max_firings");
    assert_eq!(summary["firings"], N);

    // The Python robot leaves by itself when the supervisor says the run is over.
    let status = tokio::time::timeout(Duration::from_secs(20), r1.wait())
        .await
        .unwrap_or_else(|_| panic!("the python robot did not leave:\n{}", py_text()))
        .unwrap();
    let log = py_text();
    assert_eq!(status.code(), Some(0), "{log}");
    assert!(
        log.contains(&format!(
            "python robot r1: the supervisor's run is over (max_firings after {N} firings): leaving"
        )),
        "{log}"
    );

    // Every goal it finished became one firing of its agent (the last may have ended as
    // the run stopped), and it checked the temperature at all four locations.
    let started: Vec<&str> = log
        .lines()
        .filter_map(|l| {
            l.strip_prefix("python robot r1: goal ")?
                .strip_suffix(": started")
        })
        .collect();
    let succeeded = log.lines().filter(|l| l.ends_with(": succeeded")).count();
    let fired_r1 = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|e| e["event"] == "fired" && e["robots"] == serde_json::json!(["r1"]))
        .count();
    assert!(fired_r1 >= 8, "r1 moved {fired_r1} times:\n{log}");
    assert!(
        succeeded == fired_r1 || succeeded == fired_r1 + 1,
        "{succeeded} goals succeeded, {fired_r1} firings of r1:\n{log}"
    );
    let checked: BTreeSet<&str> = started
        .iter()
        .filter_map(|g| g.split(" agent ").next())
        .filter(|p| p.contains("Check_Temperature"))
        .collect();
    assert_eq!(
        checked,
        BTreeSet::from([
            "p1:Check_Temperature_L1",
            "p5:Check_Temperature_L2",
            "p9:Check_Temperature_L3",
            "p13:Check_Temperature_L4"
        ]),
        "{log}"
    );
    println!(
        "python robot: {} goals, {succeeded} succeeded, {fired_r1} firings of r1",
        started.len()
    );
}
