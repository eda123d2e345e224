//! Regression (issue 14, defect 6): Ctrl-C was ignored while the ROS 2 supervisor waited for
//! its robots (the run ended 28 s later with exit code 1). Now a stop signal ends the wait at
//! once with the signal's exit code.

use std::time::{Duration, Instant};

use crate::ros2_support::{domain, supervisor};

async fn interrupted_while_waiting(signal: libc::c_int, code: i32, k: u16) {
    let dir = tempfile::tempdir().unwrap();
    // No robot process: the supervisor waits up to the plan's `startup` (30 s) for them.
    let mut p = supervisor(dir.path(), domain(k), &[]);
    let start = Instant::now();
    while !p.log().contains("waiting for robot(s)") {
        assert!(start.elapsed() < Duration::from_secs(20), "{}", p.log());
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    tokio::time::sleep(Duration::from_millis(300)).await;
    let pid = p.child.id().unwrap();
    // SAFETY: plain kill(2) on our own child's pid.
    unsafe {
        libc::kill(pid as libc::pid_t, signal);
    }
    let sent = Instant::now();
    let status = tokio::time::timeout(Duration::from_secs(2), p.child.wait())
        .await
        .unwrap_or_else(|_| panic!("still waiting 2 s after the signal: {}", p.log()))
        .unwrap();
    assert!(sent.elapsed() < Duration::from_secs(2));
    assert_eq!(status.code(), Some(code), "{}", p.log());
    assert!(
        p.log().contains("waiting for the robots: interrupted by"),
        "{}",
        p.log()
    );
}

#[tokio::test]
async fn ctrl_c_while_waiting_for_the_robots_exits_130_at_once() {
    interrupted_while_waiting(libc::SIGINT, 130, 6).await;
}

#[tokio::test]
async fn sigterm_while_waiting_for_the_robots_exits_143_at_once() {
    interrupted_while_waiting(libc::SIGTERM, 143, 7).await;
}
