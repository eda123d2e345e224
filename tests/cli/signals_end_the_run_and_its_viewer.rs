//! Regression (issue 24, item 5): with `plan-runner run PLAN --web ADDR`, SIGTERM ended the
//! run but the viewer kept serving and a second SIGTERM was ignored; only Ctrl-C ended the
//! process, so under systemd or `ros2 launch` it never ended. Now SIGTERM and SIGINT end a
//! run and its viewer together — journal closed by its `stopped` line, server stopped, exit
//! 143 / 130 within 5 s — and a second signal ends a shutdown that is held up (an action
//! ignoring its cancellation) at once. `serve` and `replay --web` end on SIGTERM with 143.
#![cfg(feature = "web")]

use std::io::{BufRead, BufReader, Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::{Path, PathBuf};
use std::process::{Child, Command, ExitStatus, Stdio};
use std::sync::mpsc::{Receiver, RecvTimeoutError, channel};
use std::time::{Duration, Instant};

use serde_json::Value;

/// The bound: a signalled process is gone within 5 s.
const WITHIN: Duration = Duration::from_secs(5);
/// How long a test waits for something that should happen (a run firing, a line printed)
/// before it gives up: generous, for a loaded machine.
const PATIENCE: Duration = Duration::from_secs(60);

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A `plan-runner` child whose stdout and stderr are read line by line on threads, killed
/// when the test ends, even on a failed assertion.
struct Running {
    child: Child,
    stdout: Receiver<String>,
    stderr: Receiver<String>,
    /// Every stderr line read so far.
    err: Vec<String>,
}

impl Running {
    fn spawn(args: &[&str]) -> Running {
        let mut child = Command::new(env!("CARGO_BIN_EXE_plan-runner"))
            .args(args)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        Running {
            stdout: lines(child.stdout.take().unwrap()),
            stderr: lines(child.stderr.take().unwrap()),
            child,
            err: Vec::new(),
        }
    }

    fn signal(&self, name: &str) {
        let status = Command::new("kill")
            .args([&format!("-{name}"), &self.child.id().to_string()])
            .status()
            .unwrap();
        assert!(status.success());
    }

    /// The first stderr line starting with `prefix`, waiting for it.
    fn stderr_line(&mut self, prefix: &str) -> String {
        let deadline = Instant::now() + PATIENCE;
        loop {
            if let Some(l) = self.err.iter().find(|l| l.starts_with(prefix)) {
                return l.clone();
            }
            match self
                .stderr
                .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            {
                Ok(l) => self.err.push(l),
                Err(e) => panic!("no stderr line `{prefix}…` ({e:?}); stderr: {:?}", self.err),
            }
        }
    }

    /// The first stdout line starting with `prefix`, waiting for it.
    fn stdout_line(&self, prefix: &str) -> String {
        let deadline = Instant::now() + PATIENCE;
        loop {
            match self
                .stdout
                .recv_timeout(deadline.saturating_duration_since(Instant::now()))
            {
                Ok(l) if l.starts_with(prefix) => return l,
                Ok(_) => {}
                Err(e) => panic!("no stdout line `{prefix}…` ({e:?})"),
            }
        }
    }

    /// The exit status, when the process ends within `bound`; polled, never slept on.
    fn exits_within(&mut self, bound: Duration) -> Option<ExitStatus> {
        let deadline = Instant::now() + bound;
        loop {
            if let Some(status) = self.child.try_wait().unwrap() {
                return Some(status);
            }
            if Instant::now() >= deadline {
                return None;
            }
            std::thread::sleep(Duration::from_millis(10));
        }
    }

    /// Everything the process printed on stdout (after it exited) and its stderr so far.
    fn finish(mut self) -> (String, Vec<String>) {
        let mut out = String::new();
        loop {
            match self.stdout.recv_timeout(PATIENCE) {
                Ok(l) => {
                    out.push_str(&l);
                    out.push('\n');
                }
                Err(RecvTimeoutError::Disconnected) => break,
                Err(RecvTimeoutError::Timeout) => panic!("stdout never closed"),
            }
        }
        while let Ok(l) = self.stderr.recv_timeout(Duration::from_millis(200)) {
            self.err.push(l);
        }
        (out, std::mem::take(&mut self.err))
    }
}

impl Drop for Running {
    fn drop(&mut self) {
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

fn lines(r: impl Read + Send + 'static) -> Receiver<String> {
    let (tx, rx) = channel();
    std::thread::spawn(move || {
        for l in BufReader::new(r).lines() {
            let Ok(l) = l else { break };
            if tx.send(l).is_err() {
                break;
            }
        }
    });
    rx
}

/// The status line of `GET /` from the viewer at `addr`, or the connection's error.
fn get_page(addr: SocketAddr) -> std::io::Result<String> {
    let mut s = TcpStream::connect_timeout(&addr, Duration::from_secs(5))?;
    s.set_read_timeout(Some(Duration::from_secs(10)))?;
    write!(
        s,
        "GET / HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n"
    )?;
    let mut first = String::new();
    BufReader::new(s).read_line(&mut first)?;
    Ok(first.trim_end().to_string())
}

fn addr_after(line: &str, prefix: &str) -> SocketAddr {
    let rest = &line[line.find(prefix).unwrap() + prefix.len()..];
    rest.trim_end_matches('/').parse().unwrap()
}

/// The journal's events (its header line skipped).
fn events(path: &Path) -> Vec<Value> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.lines()
        .skip(1)
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

/// Waits until the journal holds a `fired` event: the run is under way.
fn wait_for_a_firing(path: &Path) {
    let deadline = Instant::now() + PATIENCE;
    while Instant::now() < deadline {
        if events(path).iter().any(|e| e["event"] == "fired") {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("the run never fired");
}

/// The quickstart in real time with the viewer: still running for minutes.
fn start_web_run(journal: &Path) -> (Running, SocketAddr) {
    let plan = repo("plans/quickstart.toml");
    let mut run = Running::spawn(&[
        "run",
        plan.to_str().unwrap(),
        "--time-scale",
        "1",
        "--web",
        "127.0.0.1:0",
        "--json",
        "--journal",
        journal.to_str().unwrap(),
    ]);
    let line = run.stderr_line("watch the run at http://");
    let addr = addr_after(&line, "http://");
    wait_for_a_firing(journal);
    assert_eq!(get_page(addr).unwrap(), "HTTP/1.1 200 OK");
    (run, addr)
}

fn a_signal_ends_a_web_run_and_its_viewer(signal: &str, code: i32) {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let (mut run, addr) = start_web_run(&journal);
    run.signal(signal);
    let status = run.exits_within(WITHIN);
    assert!(
        status.is_some(),
        "still running {WITHIN:?} after SIG{signal}: {:?}",
        run.err
    );
    assert_eq!(status.unwrap().code(), Some(code));
    let (stdout, stderr) = run.finish();
    assert!(
        stderr.contains(&format!(
            "SIG{signal}: stopping the run (a second signal ends plan-runner at once)"
        )),
        "{stderr:?}"
    );
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(summary["stopped"], "interrupted");
    // The journal is closed: whole lines, the last one the `stopped` event.
    let text = std::fs::read_to_string(&journal).unwrap();
    assert!(text.ends_with('\n'));
    let events = events(&journal);
    let last = events.last().unwrap();
    assert_eq!(last["event"], "stopped");
    assert_eq!(last["reason"], "interrupted");
    let fired = events.iter().filter(|e| e["event"] == "fired").count() as u64;
    assert_eq!(fired, summary["firings"].as_u64().unwrap());
    // The viewer is gone with the process.
    assert!(get_page(addr).is_err());
}

#[test]
fn sigterm_ends_a_web_run_and_its_viewer_with_exit_143() {
    a_signal_ends_a_web_run_and_its_viewer("TERM", 143);
}

#[test]
fn sigint_ends_a_web_run_and_its_viewer_with_exit_130() {
    a_signal_ends_a_web_run_and_its_viewer("INT", 130);
}

fn alive(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(s) => !s
            .rsplit(')')
            .next()
            .unwrap_or("")
            .trim_start()
            .starts_with('Z'),
        Err(_) => false,
    }
}

#[test]
fn a_second_sigterm_ends_a_held_up_shutdown_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let pids = dir.path().join("pids");
    // Both patrols run a program that ignores SIGTERM and is given 60 s before its SIGKILL:
    // the first signal's shutdown waits for it until the runtime's grace (5 s) is over.
    let command = format!("echo $$ >> {}; trap '' TERM; sleep 60", pids.display());
    let net = repo("plans/nets/two_robot_patrol.xml");
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {net:?}\nseed = 4\ntime_scale = 1\n\n\
             [places.Patrol_A]\naction = {{ command = [\"sh\", \"-c\", {command:?}], kill_grace = 60.0 }}\n\
             [places.Patrol_B]\naction = {{ command = [\"sh\", \"-c\", {command:?}], kill_grace = 60.0 }}\n\
             [places.Decide]\naction = \"wait\"\n[places.Charging]\naction = \"wait\"\n\
             [places.Charger]\nrole = \"resource\"\n",
            net = net.display().to_string()
        ),
    )
    .unwrap();
    let journal = dir.path().join("run.jsonl");
    let mut run = Running::spawn(&[
        "run",
        plan.to_str().unwrap(),
        "--web",
        "127.0.0.1:0",
        "--json",
        "--journal",
        journal.to_str().unwrap(),
    ]);
    run.stderr_line("watch the run at http://");
    // Both actions' programs are running.
    let deadline = Instant::now() + PATIENCE;
    let mut programs: Vec<i32> = Vec::new();
    while programs.len() < 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
        programs = std::fs::read_to_string(&pids)
            .unwrap_or_default()
            .lines()
            .filter_map(|l| l.trim().parse().ok())
            .collect();
    }
    assert_eq!(programs.len(), 2, "both patrols' programs started");
    // And the journal has said so (it is written every 100 ms; the forced exit below keeps
    // what was written).
    while events(&journal)
        .iter()
        .filter(|e| e["event"] == "action_started")
        .count()
        < 2
    {
        assert!(
            Instant::now() < deadline,
            "no action_started in the journal"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    run.signal("TERM");
    run.stderr_line("SIGTERM: stopping the run");
    assert!(
        run.child.try_wait().unwrap().is_none(),
        "held up by the actions"
    );
    run.signal("TERM");
    let sent = Instant::now();
    let status = run.exits_within(WITHIN);
    let took = sent.elapsed();
    assert!(
        status.is_some(),
        "still running {WITHIN:?} after the second SIGTERM"
    );
    assert_eq!(status.unwrap().code(), Some(143));
    let (stdout, stderr) = run.finish();
    assert!(
        stderr.contains(&"SIGTERM: a second signal, ending at once (exit 143)".to_string()),
        "{stderr:?}"
    );
    // It ended before the shutdown did: no summary, no `stopped` event, no "did not end
    // within the grace" error (which the first signal's shutdown would have ended with).
    assert_eq!(stdout, "", "ended after {took:?}");
    let events = events(&journal);
    let started = events.iter().filter(|e| e["event"] == "action_started");
    assert_eq!(started.count(), 2);
    assert!(
        !events.iter().any(|e| e["event"] == "stopped"),
        "{events:?}"
    );
    assert!(!events.iter().any(|e| e["event"] == "error"), "{events:?}");
    // The programs that ignored SIGTERM did not outlive plan-runner.
    let deadline = Instant::now() + PATIENCE;
    let mut left = programs.clone();
    while !left.is_empty() && Instant::now() < deadline {
        left.retain(|&p| alive(p));
        std::thread::sleep(Duration::from_millis(20));
    }
    assert!(left.is_empty(), "still alive: {left:?} of {programs:?}");
}

#[test]
fn after_a_run_that_ended_the_viewer_stays_until_sigterm_with_the_run_s_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let plan = repo("plans/quickstart.toml");
    // Virtual time, 500 firings: over in a moment.
    let mut run = Running::spawn(&[
        "run",
        plan.to_str().unwrap(),
        "--web",
        "127.0.0.1:0",
        "--json",
        "--journal",
        journal.to_str().unwrap(),
    ]);
    let addr = addr_after(&run.stderr_line("watch the run at http://"), "http://");
    let over = run.stderr_line("run over (");
    assert!(over.ends_with("until Ctrl-C or SIGTERM"), "{over}");
    assert!(run.child.try_wait().unwrap().is_none());
    assert_eq!(get_page(addr).unwrap(), "HTTP/1.1 200 OK");
    run.signal("TERM");
    let status = run.exits_within(WITHIN).expect("gone within 5 s");
    // The run itself finished; the signal ended only the viewer.
    assert_eq!(status.code(), Some(0));
    let (stdout, _) = run.finish();
    let summary: Value = serde_json::from_str(&stdout).unwrap();
    assert_eq!(summary["stopped"], "max_firings");
    let last = events(&journal).pop().unwrap();
    assert_eq!(last["event"], "stopped");
    assert_eq!(last["reason"], "max_firings");
}

#[test]
fn serve_ends_on_sigterm_with_exit_143() {
    let plan = repo("plans/quickstart.toml");
    let mut serve = Running::spawn(&["serve", plan.to_str().unwrap(), "--addr", "127.0.0.1:0"]);
    let addr = addr_after(&serve.stdout_line("viewer for "), " at http://");
    assert_eq!(get_page(addr).unwrap(), "HTTP/1.1 200 OK");
    serve.signal("TERM");
    let status = serve.exits_within(WITHIN).expect("gone within 5 s");
    assert_eq!(status.code(), Some(143));
    assert!(get_page(addr).is_err());
}

#[test]
fn replay_web_ends_on_sigterm_with_exit_143() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let plan = repo("plans/quickstart.toml");
    let out = Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["run", plan.to_str().unwrap(), "--quiet", "--journal"])
        .arg(&journal)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let mut replay = Running::spawn(&[
        "replay",
        journal.to_str().unwrap(),
        "--net",
        plan.to_str().unwrap(),
        "--web",
        "127.0.0.1:0",
    ]);
    let addr = addr_after(&replay.stdout_line("replay of "), " at http://");
    assert_eq!(get_page(addr).unwrap(), "HTTP/1.1 200 OK");
    replay.signal("TERM");
    let status = replay.exits_within(WITHIN).expect("gone within 5 s");
    assert_eq!(status.code(), Some(143));
    assert!(get_page(addr).is_err());
}
