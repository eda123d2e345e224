//! Shared by the ROS 2 tests: processes on loopback, one DDS domain per test.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use futures_util::StreamExt;
use gspn::ros2::DdsConfig;
use gspn::ros2::firings::FiringListener;
use gspn::ros2::msgs::{Firing, Marking};
use tokio::process::{Child, Command};
use tokio::sync::mpsc;

/// The plan every ROS 2 test runs: the temperature patrol, 3 robots, every place `ros2`.
pub const PLAN: &str = "plans/temperature_patrol_ros2.toml";

pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A DDS domain for test `k` of this process: tests in parallel (and other test processes
/// on the machine) do not hear each other.
pub fn domain(k: u16) -> u16 {
    10 + (std::process::id() % 20) as u16 * 10 + k
}

/// A process whose stderr goes to a file in `dir`, killed when dropped.
pub struct Proc {
    pub name: String,
    pub child: Child,
    pub log: PathBuf,
}

impl Proc {
    pub fn log(&self) -> String {
        std::fs::read_to_string(&self.log).unwrap_or_default()
    }
}

fn command(dir: &Path, name: &str, args: &[String], stdout: bool) -> Proc {
    let log = dir.join(format!("{name}.log"));
    let err = std::fs::File::create(&log).expect("log file");
    let child = Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env("RUST_LOG", "warn")
        .stdin(Stdio::null())
        .stdout(if stdout {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stderr(err)
        .kill_on_drop(true)
        .spawn()
        .expect("plan-runner starts");
    Proc {
        name: name.to_string(),
        child,
        log,
    }
}

/// `plan-runner robot --id ID --plan PLAN --ros2-domain D`.
pub fn robot(dir: &Path, id: &str, domain: u16) -> Proc {
    robot_with(dir, id, Path::new(PLAN), domain, &[])
}

/// `plan-runner robot --id ID --plan PLAN --ros2-domain D EXTRA…`.
pub fn robot_with(dir: &Path, id: &str, plan: &Path, domain: u16, extra: &[&str]) -> Proc {
    let mut args: Vec<String> = vec![
        "robot".into(),
        "--id".into(),
        id.into(),
        "--plan".into(),
        plan.to_string_lossy().into_owned(),
        "--ros2-domain".into(),
        domain.to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    command(dir, id, &args, false)
}

/// `plan-runner run PLAN --ros2-domain D --json EXTRA…` (stdout piped: the JSON summary).
pub fn supervisor(dir: &Path, domain: u16, extra: &[&str]) -> Proc {
    supervisor_with(dir, Path::new(PLAN), domain, extra)
}

/// `plan-runner run PLAN --ros2-domain D --json EXTRA…` for another plan.
pub fn supervisor_with(dir: &Path, plan: &Path, domain: u16, extra: &[&str]) -> Proc {
    let mut args: Vec<String> = vec![
        "run".into(),
        plan.to_string_lossy().into_owned(),
        "--json".into(),
        "--ros2-domain".into(),
        domain.to_string(),
    ];
    args.extend(extra.iter().map(|s| s.to_string()));
    command(dir, "supervisor", &args, true)
}

/// Asks a process to end (SIGTERM) and waits (at most `limit`) for it; its log.
pub async fn terminate(mut p: Proc, limit: Duration) -> String {
    if let Some(pid) = p.child.id() {
        // SAFETY: plain kill(2) on our own child's pid.
        unsafe {
            libc::kill(pid as libc::pid_t, libc::SIGTERM);
        }
    }
    let _ = tokio::time::timeout(limit, p.child.wait()).await;
    p.log()
}

/// An in-process subscriber of /gspn/firings and /gspn/marking on `domain`: what arrives
/// goes to the two channels.
pub fn listen(
    domain: u16,
) -> (
    mpsc::UnboundedReceiver<Firing>,
    mpsc::UnboundedReceiver<Marking>,
) {
    let cfg = DdsConfig {
        domain_id: domain,
        ..DdsConfig::default()
    };
    let mut node = cfg.node("test_listener").expect("a DDS node on loopback");
    let listener = FiringListener::new(&mut node).expect("subscriptions");
    let (ftx, frx) = mpsc::unbounded_channel();
    let (mtx, mrx) = mpsc::unbounded_channel();
    tokio::spawn(async move {
        let _node = node;
        let firings = listener.firings();
        let markings = listener.markings();
        futures_util::pin_mut!(firings, markings);
        loop {
            tokio::select! {
                Some(f) = firings.next() => { let _ = ftx.send(f); }
                Some(m) = markings.next() => { let _ = mtx.send(m); }
                else => break,
            }
        }
    });
    (frx, mrx)
}

/// Receives until `n` firings arrived or `limit` passed.
pub async fn take(
    rx: &mut mpsc::UnboundedReceiver<Firing>,
    n: usize,
    limit: Duration,
) -> Vec<Firing> {
    let mut got = Vec::new();
    let end = tokio::time::Instant::now() + limit;
    while got.len() < n {
        match tokio::time::timeout_at(end, rx.recv()).await {
            Ok(Some(f)) => got.push(f),
            _ => break,
        }
    }
    got
}

/// Waits (at most `limit`) for the process to end; its exit code and stdout.
pub async fn finish(p: Proc, limit: Duration) -> (Option<i32>, String) {
    let name = p.name.clone();
    let log = p.log.clone();
    match tokio::time::timeout(limit, p.child.wait_with_output()).await {
        Ok(Ok(out)) => (
            out.status.code(),
            String::from_utf8_lossy(&out.stdout).into_owned(),
        ),
        _ => panic!(
            "{name} did not end within {limit:?}; its log:\n{}",
            std::fs::read_to_string(log).unwrap_or_default()
        ),
    }
}
