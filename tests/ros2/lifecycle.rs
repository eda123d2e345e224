//! How ROS 2 processes start and end: the domain's precedence (flag, plan,
//! `GSPN_ROS2_DOMAIN`, `ROS_DOMAIN_ID`, 0), robots leaving when the supervisor's run is
//! over or when its heartbeat stops (`--stay` keeps one), cancelling the goals they still
//! run, virtual time refused with ros2 places.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::path::Path;
use std::process::Stdio;
use std::time::{Duration, Instant};

use support::{
    GOAL_LOG, domain, finish, repo, robot_env, robot_with, supervisor, terminate, wait_for_log,
};

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

/// Bug: a robot that missed the supervisor's "the run is over" served forever, and a robot
/// leaving while a goal ran neither cancelled nor counted it. Now a robot leaves when the
/// supervisor's heartbeat stops for `lost_after` (here the supervisor is killed: it says
/// nothing), cancelling its running goal; a `--stay` robot says so and keeps serving, and
/// cancels its goal when it is stopped.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn robots_leave_when_the_supervisor_dies_and_cancel_their_running_goals() {
    let dir = tempfile::tempdir().unwrap();
    let d = domain(9);
    let plan = Path::new(support::PLAN);
    // 10,000 s per model unit: each robot's first goal runs until it is cancelled.
    let slow = ["--time-scale", "10000"];
    let stay = ["--time-scale", "10000", "--stay"];
    let r1 = robot_env(dir.path(), "r1", plan, d, &slow, &[GOAL_LOG]);
    let r2 = robot_env(dir.path(), "r2", plan, d, &slow, &[GOAL_LOG]);
    let r3 = robot_env(dir.path(), "r3", plan, d, &stay, &[GOAL_LOG]);
    let mut sup = supervisor(dir.path(), d, &[]);
    // Each robot runs a goal and has heard the supervisor's heartbeat (a robot that never
    // heard it, e.g. on a loaded host, waits 5 × lost_after instead).
    for r in [&r1, &r2, &r3] {
        assert!(
            wait_for_log(r, "a supervisor is here", Duration::from_secs(60)).await,
            "{}: {}",
            r.name,
            r.log()
        );
        assert!(
            wait_for_log(r, ") started: ", Duration::from_secs(60)).await,
            "{}: {}\nsupervisor: {}",
            r.name,
            r.log(),
            sup.log()
        );
    }
    sup.child.start_kill().expect("kill the supervisor");
    let killed = Instant::now();
    for r in [r1, r2] {
        let (name, log) = (r.name.clone(), r.log.clone());
        let (code, _) = finish(r, Duration::from_secs(30)).await;
        let after = killed.elapsed();
        let log = std::fs::read_to_string(log).unwrap();
        assert_eq!(code, Some(0), "{name}: {log}");
        assert!(
            log.contains(&format!(
                "robot {name}: the supervisor's heartbeat stopped (none for 1s): leaving"
            )),
            "{name}: {log}"
        );
        assert!(
            log.contains(&format!("robot {name}: 1 goals, 1 cancelled")),
            "{name}: {log}"
        );
        // Not before lost_after (the plan's 1 s) without a heartbeat.
        assert!(
            after >= Duration::from_secs(1),
            "{name} left after {after:?}"
        );
        println!("{name} left {after:?} after the supervisor was killed");
    }
    assert!(
        wait_for_log(
            &r3,
            "robot r3: the supervisor's heartbeat stopped (none for 1s); idle, serving until stopped (--stay)",
            Duration::from_secs(30)
        )
        .await,
        "{}",
        r3.log()
    );
    let mut r3 = r3;
    assert!(r3.child.try_wait().unwrap().is_none(), "{}", r3.log());
    let log = terminate(r3, Duration::from_secs(10)).await;
    assert!(!log.contains("leaving"), "{log}");
    assert!(log.contains("robot r3: 1 goals, 1 cancelled"), "{log}");
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
