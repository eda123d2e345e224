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

/// Held by the tests that start a fleet of processes (the 24-robot fleet, the netns
/// scenarios): run side by side on 2 cores, 40 robot processes starve each other's DDS
/// heartbeats and no robot becomes ready (seen in CI). The rest run in parallel with them.
pub static FLEET: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// The plan every ROS 2 test runs: the temperature patrol, 3 robots, every place `ros2`.
pub const PLAN: &str = "plans/temperature_patrol_ros2.toml";

pub fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A DDS domain for test `k` (< 22) of this process: tests in parallel (and other test
/// processes on the machine) do not hear each other. At most 10 + 9 × 22 + 21 = 229
/// (DDS domains end at 232).
pub fn domain(k: u16) -> u16 {
    assert!(k < 22, "test domain index {k} ≥ 22");
    10 + (std::process::id() % 10) as u16 * 22 + k
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
    command_env(dir, name, args, stdout, &[])
}

fn command_env(
    dir: &Path,
    name: &str,
    args: &[String],
    stdout: bool,
    env: &[(&str, &str)],
) -> Proc {
    spawn(
        dir,
        name,
        args,
        stdout,
        env,
        Command::new(env!("CARGO_BIN_EXE_plan-runner")),
    )
}

/// [`command_env`] on `cmd` (a `plan-runner` command the caller may have prepared).
fn spawn(
    dir: &Path,
    name: &str,
    args: &[String],
    stdout: bool,
    env: &[(&str, &str)],
    mut cmd: Command,
) -> Proc {
    let log = dir.join(format!("{name}.log"));
    let err = std::fs::File::create(&log).expect("log file");
    let child = cmd
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .env_remove("RUST_LOG")
        .envs(env.iter().copied())
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

/// `plan-runner ARGS…`, its stderr in `dir/NAME.log`.
pub fn plan_runner(dir: &Path, name: &str, args: &[&str]) -> Proc {
    let args: Vec<String> = args.iter().map(|s| s.to_string()).collect();
    command(dir, name, &args, false)
}

/// `plan-runner robot --id ID --plan PLAN --ros2-domain D`.
pub fn robot(dir: &Path, id: &str, domain: u16) -> Proc {
    robot_with(dir, id, Path::new(PLAN), domain, &[])
}

/// `plan-runner robot --id ID --plan PLAN --ros2-domain D EXTRA…`.
pub fn robot_with(dir: &Path, id: &str, plan: &Path, domain: u16, extra: &[&str]) -> Proc {
    robot_env(dir, id, plan, domain, extra, &[])
}

/// [`robot`] whose data segment (heap and other private writable memory, `RLIMIT_DATA`) may
/// not exceed `max_bytes`: a robot whose memory runs away fails at once (allocation failure,
/// abort) instead of taking the machine's memory. (`RLIMIT_AS` does not fit: an idle debug
/// robot already reserves ~300 MB of address space, glibc's per-thread malloc arenas, of
/// which ~15 MB are data.)
pub fn robot_with_data_limit(dir: &Path, id: &str, domain: u16, max_bytes: u64) -> Proc {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_plan-runner"));
    let limit = libc::rlimit {
        rlim_cur: max_bytes,
        rlim_max: max_bytes,
    };
    // SAFETY: setrlimit is async-signal-safe; the closure touches nothing else.
    unsafe {
        cmd.pre_exec(move || {
            if libc::setrlimit(libc::RLIMIT_DATA, &limit) == 0 {
                Ok(())
            } else {
                Err(std::io::Error::last_os_error())
            }
        });
    }
    let args = robot_args(id, Path::new(PLAN), domain, &[]);
    spawn(dir, id, &args, false, &[], cmd)
}

/// The robot's debug log on: it says when each goal starts and ends.
pub const GOAL_LOG: (&str, &str) = (
    "RUST_LOG",
    "warn,gspn=debug,rustdds::rtps::writer=error,ros2_client::distributions=error,\
     ros2_client::service::wrappers=error",
);

/// [`robot_with`] with environment variables `env`.
pub fn robot_env(
    dir: &Path,
    id: &str,
    plan: &Path,
    domain: u16,
    extra: &[&str],
    env: &[(&str, &str)],
) -> Proc {
    command_env(dir, id, &robot_args(id, plan, domain, extra), false, env)
}

/// `robot --id ID --plan PLAN --ros2-domain D EXTRA…`.
fn robot_args(id: &str, plan: &Path, domain: u16, extra: &[&str]) -> Vec<String> {
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
    args
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
    let mut node = cfg
        .node("test_listener", None)
        .expect("a DDS node on loopback");
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

/// A UDP socket of a process: its local address, from /proc/net/udp{,6}.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct UdpSocket {
    pub addr: std::net::IpAddr,
    pub port: u16,
}

/// Every UDP socket (IPv4 and IPv6) process `pid` holds: the inodes of its
/// `/proc/<pid>/fd/*` links `socket:[N]` looked up in `/proc/<pid>/net/udp{,6}` (the
/// process's own network namespace).
pub fn udp_sockets(pid: u32) -> Vec<UdpSocket> {
    let mut inodes = std::collections::BTreeSet::new();
    if let Ok(fds) = std::fs::read_dir(format!("/proc/{pid}/fd")) {
        for fd in fds.flatten() {
            if let Ok(l) = std::fs::read_link(fd.path()) {
                let l = l.to_string_lossy().into_owned();
                if let Some(n) = l.strip_prefix("socket:[").and_then(|x| x.strip_suffix(']')) {
                    inodes.insert(n.to_string());
                }
            }
        }
    }
    let mut out = Vec::new();
    for table in ["udp", "udp6"] {
        let text = std::fs::read_to_string(format!("/proc/{pid}/net/{table}")).unwrap_or_default();
        for line in text.lines().skip(1) {
            let f: Vec<&str> = line.split_whitespace().collect();
            if f.len() < 10 || !inodes.contains(f[9]) {
                continue;
            }
            let (ip, port) = f[1].split_once(':').expect("addr:port");
            let port = u16::from_str_radix(port, 16).expect("hex port");
            // The kernel prints the address as 32-bit words in host order (little endian).
            let words: Vec<u32> = (0..ip.len() / 8)
                .map(|k| u32::from_str_radix(&ip[8 * k..8 * k + 8], 16).expect("hex address"))
                .collect();
            let bytes: Vec<u8> = words.iter().flat_map(|w| w.to_le_bytes()).collect();
            let addr = match bytes.len() {
                4 => std::net::IpAddr::from([bytes[0], bytes[1], bytes[2], bytes[3]]),
                _ => {
                    let b: [u8; 16] = bytes.try_into().expect("16 bytes");
                    std::net::IpAddr::from(b)
                }
            };
            out.push(UdpSocket { addr, port });
        }
    }
    out.sort_by_key(|s| s.port);
    out
}

/// The resident set size of process `pid` in bytes (`VmRSS` of /proc/<pid>/status).
pub fn rss(pid: u32) -> u64 {
    try_rss(pid).expect("VmRSS of a running process")
}

/// [`rss`], or `None` when the process has ended (a zombie has no `VmRSS`).
pub fn try_rss(pid: u32) -> Option<u64> {
    let status = std::fs::read_to_string(format!("/proc/{pid}/status")).ok()?;
    let kb = status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next())
        .and_then(|v| v.parse::<u64>().ok())?;
    Some(kb * 1024)
}

/// Waits (at most `limit`) until the process's log contains `what`; false if it never did.
pub async fn wait_for_log(p: &Proc, what: &str, limit: Duration) -> bool {
    let end = tokio::time::Instant::now() + limit;
    while tokio::time::Instant::now() < end {
        if p.log().contains(what) {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    false
}

/// Cyclone on loopback only, unicast discovery of the local participants (the Python peers'
/// `CYCLONEDDS_URI`).
pub const CYCLONE_CONFIG: &str = "<CycloneDDS><Domain id=\"any\"><General><Interfaces>\
<NetworkInterface address=\"127.0.0.1\"/></Interfaces><AllowMulticast>false</AllowMulticast>\
</General><Discovery><ParticipantIndex>auto</ParticipantIndex>\
<MaxAutoParticipantIndex>60</MaxAutoParticipantIndex><Peers><Peer address=\"127.0.0.1\"/>\
</Peers></Discovery></Domain></CycloneDDS>";

/// The Python of the venv `.ci/run` makes (`target/venv-ros2`, or `$GSPN_ROS2_VENV`), with
/// `cyclonedds`; fails, saying how to make it, when it is missing.
pub fn python() -> PathBuf {
    let venv = std::env::var_os("GSPN_ROS2_VENV")
        .map(PathBuf::from)
        .unwrap_or_else(|| repo("target/venv-ros2"));
    let py = venv.join("bin/python");
    assert!(
        py.is_file(),
        "the ROS 2 tests with Python peers need a Python venv with cyclonedds at {} \
         (create it: python3 -m venv {0} && {0}/bin/pip install cyclonedds==11.0.1 \
         mcap==1.6.0 mcap-ros2-support==0.6.0; \
         .ci/run does this; or point GSPN_ROS2_VENV at one)",
        venv.display()
    );
    py
}

/// Waits (at most `limit`) for robot `r` to leave by itself: exit code 0 and `says` in its
/// log.
pub async fn assert_leaves(r: Proc, limit: Duration, says: &str) {
    let (name, log) = (r.name.clone(), r.log.clone());
    let (code, _) = finish(r, limit).await;
    let text = std::fs::read_to_string(log).unwrap_or_default();
    assert_eq!(code, Some(0), "{name}: {text}");
    assert!(text.contains(says), "{name}: {text}");
}

/// Checks a run summary's `nav2` section: at least `robots` goals (every robot drove), none
/// aborted or rejected, the rest succeeded or — still driving when the run stopped —
/// cancelled, one per robot at most. The number of goals.
pub fn assert_nav2_goals(summary: &serde_json::Value, robots: u64) -> u64 {
    let nav2 = &summary["nav2"];
    let goals = nav2["goals"].as_u64().expect("nav2 goals counted");
    assert!(goals >= robots, "every robot drives at least once: {nav2}");
    assert_eq!(
        (&nav2["aborted"], &nav2["rejected"]),
        (&0.into(), &0.into()),
        "{nav2}"
    );
    let (ok, cancelled) = (
        nav2["succeeded"].as_u64().unwrap(),
        nav2["cancelled"].as_u64().unwrap(),
    );
    assert_eq!(ok + cancelled, goals, "{nav2}");
    assert!(cancelled <= robots, "{nav2}");
    goals
}

/// The temperature patrol's (plans/temperature-patrol) locations L1–L4 on its map.
pub fn patrol_locations() -> Vec<(f64, f64)> {
    let path = repo("plans/temperature-patrol/plan.toml");
    let plan = gspn::plan::read_plan(&path, &gspn::io::ReadOptions::default()).unwrap();
    let map = plan.map.expect("the patrol has a map");
    ["L1", "L2", "L3", "L4"]
        .iter()
        .map(|l| {
            let i = map.location(l).unwrap();
            (map.locations[i].x, map.locations[i].y)
        })
        .collect()
}
