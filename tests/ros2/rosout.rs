//! `--ros2-rosout`: the ROS 2 layer's warnings reach `/rosout` (rcl_interfaces/msg/Log) from
//! the process's node, as a ROS 2 node's log does; without the flag nothing is published
//! there. The scenario of `multiprocess::a_killed_robot…`: the supervisor and 3 robots, r2
//! killed (SIGKILL), the supervisor's heartbeat watch warns.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::Path;
use std::time::{Duration, Instant, SystemTime, UNIX_EPOCH};

use futures_util::StreamExt;
use gspn::ros2::DdsConfig;
use gspn::ros2::rosout::qos;
use ros2_client::log::Log;
use ros2_client::{MessageTypeName, Name, Subscription};
use support::{
    PLAN, Proc, assert_leaves, domain, finish, listen, robot, robot_with, supervisor, take,
};
use tokio::sync::mpsc;

const ROBOTS: [&str; 3] = ["r1", "r2", "r3"];

/// An in-process subscriber of `/rosout` on `domain` (rcl's QoS: reliable, transient local):
/// every Log received goes to the channel.
fn rosout(domain: u16) -> mpsc::UnboundedReceiver<Log> {
    let cfg = DdsConfig {
        domain_id: domain,
        ..DdsConfig::default()
    };
    let mut node = cfg
        .node("test_rosout", None)
        .expect("a DDS node on loopback");
    let topic = node
        .create_topic(
            &Name::parse("/rosout").unwrap(),
            MessageTypeName::new("rcl_interfaces", "Log"),
            &qos(),
        )
        .expect("the rosout topic");
    let sub: Subscription<Log> = node
        .create_subscription(&topic, Some(qos()))
        .expect("a rosout subscription");
    let (tx, rx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        let _node = node;
        let logs = sub.async_stream();
        futures_util::pin_mut!(logs);
        while let Some(m) = logs.next().await {
            if let Ok((log, _)) = m
                && tx.send(log).is_err()
            {
                break;
            }
        }
    });
    rx
}

/// The scenario: 3 robots, a supervisor with `extra` flags, r2 killed after 20 firings; waits
/// (≤ 20 s) for the supervisor to say on stderr that r2 is lost. The supervisor (still
/// running: the failure policy is ending its run) and the killed instant.
async fn kill_r2(dir: &std::path::Path, d: u16, extra: &[&str]) -> (Proc, Vec<Proc>, Instant) {
    let (mut firings, _markings) = listen(d);
    let mut robots: Vec<_> = ROBOTS.iter().map(|r| robot(dir, r, d)).collect();
    let mut args = vec!["--max-firings", "1000000", "--ros2-wait-subscribers", "4"];
    args.extend_from_slice(extra);
    let sup = supervisor(dir, d, &args);
    let before = take(&mut firings, 20, Duration::from_secs(90)).await;
    assert_eq!(before.len(), 20, "supervisor log:\n{}", sup.log());
    robots[1].child.start_kill().expect("kill r2");
    let killed = Instant::now();
    while killed.elapsed() < Duration::from_secs(20) && !sup.log().contains("robot `r2` lost") {
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    assert!(
        sup.log().contains(WARNING_ON_STDERR),
        "the supervisor did not warn that r2 is lost:\n{}",
        sup.log()
    );
    (sup, robots, killed)
}

/// The supervisor's stderr line of the heartbeat watch's warning (unchanged by the flag).
const WARNING_ON_STDERR: &str = "WARN gspn::ros2::heartbeat: robot `r2`: no heartbeat for 1s: lost";

/// The warning's message on /rosout.
const WARNING: &str = "robot `r2`: no heartbeat for 1s: lost";

fn now_ns() -> i64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .unwrap()
        .as_nanos() as i64
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_ros2_layer_s_warnings_reach_rosout_only_when_asked() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(14);

    // With --ros2-rosout: the supervisor's node publishes the warning.
    let mut logs = rosout(d);
    let start_ns = now_ns();
    let (sup, robots, _) = kill_r2(dir.path(), d, &["--ros2-rosout"]).await;
    let end = tokio::time::Instant::now() + Duration::from_secs(10);
    let mut got = Vec::new();
    let found = loop {
        match tokio::time::timeout_at(end, logs.recv()).await {
            Ok(Some(l)) if l.msg == WARNING => break Some(l),
            Ok(Some(l)) => got.push(l),
            _ => break None,
        }
    };
    let end_ns = now_ns();
    let (code, _) = finish(sup, Duration::from_secs(20)).await;
    assert_eq!(code, Some(1), "on_failure = \"stop\": the run fails");
    drop(robots);
    let log = found.unwrap_or_else(|| panic!("no `{WARNING}` on /rosout; received: {got:?}"));
    assert_eq!(log.level, Log::WARN);
    assert_eq!(log.name, "gspn.supervisor");
    assert!(log.file.ends_with("src/ros2/heartbeat.rs"), "{log:?}");
    assert_eq!(log.function, "gspn::ros2::heartbeat");
    assert!(log.line > 0, "{log:?}");
    let stamp = log.stamp.to_nanos();
    assert!(
        start_ns <= stamp && stamp <= end_ns,
        "stamp {stamp} outside the run [{start_ns}, {end_ns}]"
    );
    // Whatever else arrived came from the supervisor's ROS 2 layer at WARN or ERROR (the
    // robots were not asked).
    for l in &got {
        assert_eq!(l.name, "gspn.supervisor", "{l:?}");
        assert!(l.level == Log::WARN || l.level == Log::ERROR, "{l:?}");
    }

    // Without the flag, the same scenario publishes nothing on /rosout.
    let d = domain(15);
    let mut logs = rosout(d);
    let (sup, robots, _) = kill_r2(dir.path(), d, &[]).await;
    let quiet = tokio::time::timeout(Duration::from_secs(3), logs.recv()).await;
    let (code, _) = finish(sup, Duration::from_secs(20)).await;
    assert_eq!(code, Some(1));
    drop(robots);
    assert!(
        quiet.is_err(),
        "/rosout without --ros2-rosout received {quiet:?}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_robot_s_warning_reaches_rosout_under_its_own_name() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(16);
    let mut logs = rosout(d);
    let (mut firings, _markings) = listen(d);
    let r1 = robot_with(dir.path(), "r1", Path::new(PLAN), d, &["--ros2-rosout"]);
    let others: Vec<_> = ["r2", "r3"]
        .iter()
        .map(|r| robot(dir.path(), r, d))
        .collect();
    let mut sup = supervisor(
        dir.path(),
        d,
        &["--max-firings", "1000000", "--ros2-wait-subscribers", "4"],
    );
    let before = take(&mut firings, 20, Duration::from_secs(90)).await;
    assert_eq!(before.len(), 20, "supervisor log:\n{}", sup.log());
    // The supervisor killed (SIGKILL): r1's watch of its heartbeat warns, then r1 leaves.
    sup.child.start_kill().expect("kill the supervisor");
    let end = tokio::time::Instant::now() + Duration::from_secs(20);
    let mut got = Vec::new();
    let found = loop {
        match tokio::time::timeout_at(end, logs.recv()).await {
            Ok(Some(l)) if l.msg == "supervisor: no heartbeat for 1s: lost" => break Some(l),
            Ok(Some(l)) => got.push(l),
            _ => break None,
        }
    };
    let log =
        found.unwrap_or_else(|| panic!("no supervisor warning on /rosout; received: {got:?}"));
    assert_eq!(log.level, Log::WARN);
    assert_eq!(log.name, "gspn.robot_r1");
    assert_eq!(log.function, "gspn::ros2::heartbeat");
    for l in &got {
        assert_eq!(l.name, "gspn.robot_r1", "only r1 was asked: {l:?}");
    }
    assert_leaves(
        r1,
        Duration::from_secs(20),
        "the supervisor's heartbeat stopped",
    )
    .await;
    drop(others);
}
