//! How ROS 2 processes start and end: the domain's precedence (flag, plan,
//! `GSPN_ROS2_DOMAIN`, `ROS_DOMAIN_ID`, 0), robots leaving when the supervisor's run is
//! over (`--stay` keeps one), virtual time refused with ros2 places, Ctrl-C while the
//! supervisor waits for its robots.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use support::{domain, finish, repo, robot_with, supervisor, terminate, wait_for_log};

/// `plan-runner robot --id r1 --plan PLAN EXTRA…` with environment `env`: the domain its
/// log says it serves.
async fn robot_domain(plan: &Path, env: &[(&str, &str)], extra: &[&str]) -> String {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("robot.log");
    let mut child = tokio::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["robot", "--id", "r1", "--plan"])
        .arg(plan)
        .args(extra)
        .env_remove("ROS_DOMAIN_ID")
        .env_remove("GSPN_ROS2_DOMAIN")
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log).unwrap())
        .kill_on_drop(true)
        .spawn()
        .unwrap();
    let end = Instant::now() + Duration::from_secs(30);
    let text = loop {
        let text = std::fs::read_to_string(&log).unwrap_or_default();
        if text.contains("serving on domain") || Instant::now() > end {
            break text;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    };
    let _ = child.start_kill();
    let _ = child.wait().await;
    let at = text
        .find("serving on domain ")
        .unwrap_or_else(|| panic!("{text}"));
    text[at + "serving on domain ".len()..]
        .split_whitespace()
        .next()
        .unwrap()
        .to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_domain_is_the_flag_then_the_plan_then_gspn_ros2_domain_then_ros_domain_id() {
    let dir = tempfile::tempdir().unwrap();
    let bare = repo(support::PLAN);
    let text = std::fs::read_to_string(&bare).unwrap().replace(
        "net = \"nets/temperature_patrol.xml\"",
        &format!(
            "net = {:?}",
            repo("plans/nets/temperature_patrol.xml").to_string_lossy()
        ),
    );
    let pinned = dir.path().join("pinned.toml");
    std::fs::write(&pinned, text.replace("[ros2]\n", "[ros2]\ndomain_id = 5\n")).unwrap();
    let ros = [("ROS_DOMAIN_ID", "42")];
    let both = [("ROS_DOMAIN_ID", "42"), ("GSPN_ROS2_DOMAIN", "43")];
    assert_eq!(robot_domain(&bare, &[], &[]).await, "0");
    assert_eq!(robot_domain(&bare, &ros, &[]).await, "42");
    assert_eq!(robot_domain(&bare, &both, &[]).await, "43");
    assert_eq!(robot_domain(&pinned, &both, &[]).await, "5");
    assert_eq!(
        robot_domain(&pinned, &both, &["--ros2-domain", "44"]).await,
        "44"
    );
    // A bad ROS_DOMAIN_ID is refused, naming the variable.
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["robot", "--id", "r1", "--plan"])
        .arg(&bare)
        .env("ROS_DOMAIN_ID", "300")
        .env_remove("GSPN_ROS2_DOMAIN")
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("ROS_DOMAIN_ID=`300`: expected a domain id in 0..=232"),
        "{err}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robots_leave_when_the_run_is_over_unless_told_to_stay() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(8);
    let plan = Path::new(support::PLAN);
    let stay = robot_with(dir.path(), "r1", plan, d, &["--stay"]);
    let r2 = robot_with(dir.path(), "r2", plan, d, &[]);
    let r3 = robot_with(dir.path(), "r3", plan, d, &[]);
    let sup = supervisor(dir.path(), d, &["--max-firings", "10"]);
    let (code, out) = finish(sup, Duration::from_secs(90)).await;
    assert_eq!(code, Some(0), "{out}");
    for r in [r2, r3] {
        let name = r.name.clone();
        let log = r.log.clone();
        let (code, _) = finish(r, Duration::from_secs(20)).await;
        let log = std::fs::read_to_string(log).unwrap();
        assert_eq!(code, Some(0), "{name}: {log}");
        assert!(
            log.contains(&format!(
                "robot {name}: the supervisor's run is over (max_firings after 10 firings): leaving"
            )),
            "{name}: {log}"
        );
    }
    // --stay: still serving, and it says it is idle.
    assert!(
        wait_for_log(
            &stay,
            "the supervisor's run is over (max_firings after 10 firings); idle, serving until stopped (--stay)",
            Duration::from_secs(20)
        )
        .await,
        "{}",
        stay.log()
    );
    let mut stay = stay;
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(stay.child.try_wait().unwrap().is_none(), "{}", stay.log());
    let log = terminate(stay, Duration::from_secs(10)).await;
    assert!(!log.contains("leaving"), "{log}");
}

#[test]
fn virtual_time_is_refused_with_ros2_places() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["run", support::PLAN, "--time-scale", "0"])
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains(
            "plans/temperature_patrol_ros2.toml: time scale 0 (virtual time) with ros2 places"
        ),
        "{err}"
    );
    assert!(err.contains("--allow-virtual-time"), "{err}");
}
