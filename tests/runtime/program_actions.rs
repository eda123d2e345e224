//! Actions as programs: real `sh` and `python3` processes as command actions and workers.
//! Agents keep their identities through fork, join and many→many transitions (the ids the
//! processes print); a hanging program is killed at its timeout and retried; a program
//! naming a transition that is not an output of its place is an error naming it; a crashing
//! worker fails its in-flight actions and is restarted.

use std::path::{Path, PathBuf};
use std::time::Duration;

use gspn::actions::{CommandAction, CommandSpec, Worker, WorkerSpec};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::{Event, EventKind, Outcome, OutputStream, Runtime, StopReason};
use gspn::runtime::{FailurePolicy, Role};

fn sh(script: &str) -> CommandSpec {
    CommandSpec::new(["sh", "-c", script])
}

fn role(name: &str, timeout: Option<f64>, on_failure: FailurePolicy) -> Role {
    Role::Action {
        name: name.into(),
        timeout,
        on_failure,
        robot: None,
    }
}

fn outputs(events: &[Event]) -> Vec<(u64, String, String)> {
    events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::ActionOutput {
                agent,
                place,
                stream: OutputStream::Stdout,
                line,
            } => Some((agent.0, format!("{}", place.0), line.clone())),
            _ => None,
        })
        .collect()
}

/// start(2) → fork → a + b; a → ta → c; b → tb → d; c + d → join → end (no outputs), and a
/// many→many `swap`: c + c → swap → c + c would be ambiguous, so the join is the many→one.
fn fork_join() -> Net {
    let mut b = NetBuilder::new("fork-join");
    let start = b.place("start", 2);
    let pa = b.place("a", 0);
    let pb = b.place("b", 0);
    let pc = b.place("c", 0);
    let pd = b.place("d", 0);
    let pe = b.place("e", 0);
    let pf = b.place("f", 0);
    let end = b.place("end", 0);
    let fork = b.exponential("fork", 1.0, Servers::Single);
    let ta = b.exponential("ta", 1.0, Servers::Single);
    let tb = b.exponential("tb", 1.0, Servers::Single);
    let swap = b.exponential("swap", 1.0, Servers::Single);
    let join = b.exponential("join", 1.0, Servers::Single);
    b.input(start, fork, 1);
    b.output(fork, pa, 1);
    b.output(fork, pb, 1);
    b.input(pa, ta, 1);
    b.output(ta, pc, 1);
    b.input(pb, tb, 1);
    b.output(tb, pd, 1);
    // many → many: both of a pair move on together.
    b.input(pc, swap, 1);
    b.input(pd, swap, 1);
    b.output(swap, pe, 1);
    b.output(swap, pf, 1);
    b.input(pe, join, 1);
    b.input(pf, join, 1);
    b.output(join, end, 1);
    b.build().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn fork_join_and_many_to_many_keep_agent_identities() {
    let net = fork_join();
    let names: Vec<String> = net.places().iter().map(|p| p.name.clone()).collect();
    let mut b = Runtime::builder(net)
        .action(
            "say",
            CommandAction::new(sh(
                "echo \"I am $GSPN_AGENT in $GSPN_PLACE ({agent} {place})\"; echo $GSPN_OUTPUTS",
            )),
        )
        .seed(3);
    for p in ["start", "a", "b", "c", "d", "e", "f", "end"] {
        b = b.bind(p, "say");
    }
    let mut h = b.spawn().unwrap();
    let events = h.events().collect().await;
    let summary = h.wait().await;
    assert_eq!(summary.stopped, StopReason::Dead, "{:?}", summary.errors);
    assert!(summary.errors.is_empty(), "{:?}", summary.errors);
    // Every line names the agent and the place of its event: the process ran for that agent.
    let lines = outputs(&events);
    let said: Vec<_> = lines
        .iter()
        .filter(|(_, _, l)| l.starts_with("I am"))
        .collect();
    // 2 in start, 2 in a, 2 in b, 2 in c, 2 in d, 2 in e, 2 in f; none in `end` (no outputs).
    assert_eq!(said.len(), 14, "{lines:?}");
    for (agent, place, line) in &said {
        let pname = &names[place.parse::<usize>().unwrap()];
        assert_eq!(
            line.as_str(),
            format!("I am {agent} in {pname} ({agent} {pname})"),
            "{lines:?}"
        );
    }
    // The ids follow the tokens: each firing consumed exactly the agents whose actions ran in
    // its input places, and the forks and joins kept the continuing ids.
    let mut spawned = Vec::new();
    for e in &events {
        match &e.kind {
            EventKind::AgentSpawned { agent, .. } => spawned.push(agent.0),
            EventKind::Fired {
                transition,
                consumed,
                produced,
                ..
            } => {
                let ran: Vec<u64> = consumed.iter().map(|a| a.0).collect();
                match transition.0 {
                    // fork: the agent goes on to `a`, a new agent starts in `b`.
                    0 => {
                        assert_eq!(produced[0], consumed[0]);
                        assert_eq!(produced.len(), 2);
                    }
                    // swap (c + d → e + f) keeps both agents; join (e + f → end) keeps one.
                    3 => assert_eq!(produced, consumed),
                    4 => assert_eq!(produced[..], consumed[..1]),
                    _ => assert_eq!(produced, consumed),
                }
                // Every consumed agent had its program run in its place before.
                for a in ran {
                    assert!(said.iter().any(|(x, _, _)| *x == a), "agent {a} never ran");
                }
            }
            _ => {}
        }
    }
    assert_eq!(spawned.len(), 4);
    assert_eq!(summary.agents_spawned, 4);
    assert_eq!(summary.agents_ended, 2);
    assert_eq!(summary.final_marking["end"], 2);
}

fn pids(file: &Path) -> Vec<i32> {
    std::fs::read_to_string(file)
        .unwrap_or_default()
        .lines()
        .map(|l| l.trim().parse().unwrap())
        .collect()
}

/// Alive: the process exists and is not a zombie.
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

async fn gone(pids: &[i32]) -> bool {
    for _ in 0..200 {
        if pids.iter().all(|&p| !alive(p)) {
            return true;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    false
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_hanging_command_is_killed_at_its_timeout_and_retried_once() {
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("pids");
    let mut b = NetBuilder::new("hang");
    let p = b.place("hang", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.input(p, t, 1);
    let net = b.build().unwrap();
    // The shell and its child `sleep` (which ignores nothing) write their pids, then hang.
    let mut spec = sh("sleep 30 & echo $! >> \"$PIDS\"; echo $$ >> \"$PIDS\"; echo started; wait");
    spec.env.push(("PIDS".into(), file.display().to_string()));
    spec.kill_grace = Duration::from_millis(200);
    let mut h = Runtime::builder(net)
        .action("hang", CommandAction::new(spec))
        .role(p, role("hang", Some(0.5), FailurePolicy::Retry(1)))
        .time_scale(1.0)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let summary = h.wait().await;
    assert_eq!(summary.stopped, StopReason::Failure);
    let attempts: Vec<u32> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::ActionStarted { attempt, .. } => Some(*attempt),
            _ => None,
        })
        .collect();
    assert_eq!(attempts, [0, 1]);
    let failed: Vec<String> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::ActionEnded {
                outcome: Outcome::Failed(r),
                ..
            } => Some(r.clone()),
            _ => None,
        })
        .collect();
    assert_eq!(failed.len(), 2, "{failed:?}");
    assert!(
        failed
            .iter()
            .all(|r| r.starts_with("timed out after 500ms"))
    );
    assert_eq!(
        summary.errors,
        [
            "agent 0 in `hang` failed: timed out after 500ms",
            "agent 0 in `hang` failed: timed out after 500ms",
            "agent 0 in `hang`: gave up after 1 retries"
        ]
    );
    assert_eq!(
        outputs(&events).iter().filter(|o| o.2 == "started").count(),
        2
    );
    // Both runs' shells and their children are gone: the whole group was stopped.
    let all = pids(&file);
    assert_eq!(all.len(), 4, "{all:?}");
    assert!(gone(&all).await, "still alive: {all:?}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_command_naming_a_transition_that_is_not_an_output_is_an_error_naming_it() {
    let mut b = NetBuilder::new("wrong");
    let p = b.place("p", 1);
    let q = b.place("q", 0);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    let t2 = b.exponential("t2", 1.0, Servers::Single);
    b.input(p, t1, 1);
    b.output(t1, q, 1);
    b.input(q, t2, 1);
    let net = b.build().unwrap();
    let mut h = Runtime::builder(net)
        .action("say", CommandAction::new(sh("echo looking; echo t2")))
        .bind("p", "say")
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let summary = h.wait().await;
    assert_eq!(summary.stopped, StopReason::Failure);
    let errors: Vec<&str> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Error { message } => Some(message.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(
        errors,
        ["agent 0 in `p` returned transition `t2`, which is not an output of `p`"]
    );
    assert_eq!(outputs(&events)[0].2, "looking");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_failing_command_reports_its_exit_code_and_stderr() {
    let mut b = NetBuilder::new("fail");
    let p = b.place("p", 1);
    let t = b.exponential("t", 1.0, Servers::Single);
    b.input(p, t, 1);
    let net = b.build().unwrap();
    let mut h = Runtime::builder(net)
        .action(
            "bad",
            CommandAction::new(sh("echo one >&2; echo 'no battery' >&2; exit 7")),
        )
        .bind("p", "bad")
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let ended: Vec<&Outcome> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::ActionEnded { outcome, .. } => Some(outcome),
            _ => None,
        })
        .collect();
    assert_eq!(
        ended,
        [&Outcome::Failed(
            "`sh` exited with code 7; stderr: one | no battery".into()
        )]
    );
    let stderr: Vec<&str> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::ActionOutput {
                stream: OutputStream::Stderr,
                line,
                ..
            } => Some(line.as_str()),
            _ => None,
        })
        .collect();
    assert_eq!(stderr, ["one", "no battery"]);
    assert_eq!(h.wait().await.stopped, StopReason::Failure);
}

fn python_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("python")
}

/// A worker that holds its first two requests, and on the third writes to stderr and exits
/// 3 — the first time it runs. Started again, it answers every request with its output.
const CRASHER: &str = r#"
import json, os, sys
marker = os.environ["MARKER"]
first = not os.path.exists(marker)
with open(marker, "a") as f:
    f.write("%d\n" % os.getpid())
n = 0
for line in sys.stdin:
    req = json.loads(line)
    if "cancel" in req:
        continue
    n += 1
    if first and n == 3:
        print("boom: out of memory", file=sys.stderr, flush=True)
        sys.exit(3)
    if not first:
        print(json.dumps({"id": req["id"], "fire": req["outputs"][0]}), flush=True)
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_crashing_worker_fails_its_in_flight_actions_and_is_restarted() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("crasher.py");
    std::fs::write(&script, CRASHER).unwrap();
    let marker = dir.path().join("started");
    let mut b = NetBuilder::new("crash");
    let p = b.place("work", 3);
    let q = b.place("done", 0);
    let t = b.exponential("finish", 1.0, Servers::Single);
    b.input(p, t, 1);
    b.output(t, q, 1);
    let net = b.build().unwrap();
    let mut spec = WorkerSpec::new(["python3", script.to_str().unwrap()]);
    spec.env
        .push(("MARKER".into(), marker.display().to_string()));
    let worker = Worker::start(spec);
    let mut h = Runtime::builder(net)
        .action("work", worker.action("work"))
        .role(p, role("work", None, FailurePolicy::Retry(1)))
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let summary = h.wait().await;
    assert_eq!(summary.stopped, StopReason::Dead, "{:?}", summary.errors);
    assert_eq!(summary.final_marking["done"], 3);
    let mut failed = Vec::new();
    let mut fired = Vec::new();
    for e in &events {
        if let EventKind::ActionEnded { agent, outcome, .. } = &e.kind {
            match outcome {
                Outcome::Failed(r) => failed.push((agent.0, r.clone())),
                Outcome::Fire(_) => fired.push(agent.0),
                o => panic!("unexpected {o:?}"),
            }
        }
    }
    failed.sort();
    let reason = format!(
        "worker `python3 {}` exited with code 3 while running this action; stderr: boom: out of memory; it is restarted",
        script.display()
    );
    assert_eq!(
        failed,
        [
            (0, reason.clone()),
            (1, reason.clone()),
            (2, reason.clone())
        ]
    );
    fired.sort();
    assert_eq!(fired, [0, 1, 2]);
    // Two incarnations, and neither is left running once the worker is dropped.
    let started = pids(&marker);
    assert_eq!(started.len(), 2);
    assert_ne!(started[0], started[1]);
    drop(h);
    drop(worker);
    assert!(gone(&started).await, "still alive: {started:?}");
}

const HELPER_WORKER: &str = r#"
import sys, time
from gspn.worker import action, run

@action("inspect")
def inspect(ctx):
    print("inspecting", ctx.place, "for agent", ctx.agent)
    return "t1" if ctx.marking["left"] > 0 else None

@action("slow", concurrent=True)
def slow(ctx):
    time.sleep(0.2)
    print("slept", ctx.agent)
    return "t2"

run()
"#;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_python_helper_runs_decorated_functions_and_records_their_prints() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("robot_actions.py");
    std::fs::write(&script, HELPER_WORKER).unwrap();
    let mut b = NetBuilder::new("helper");
    let p = b.place("look", 1);
    let left = b.place("left", 1);
    let q = b.place("wait", 0);
    let end = b.place("end", 0);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    let t2 = b.exponential("t2", 1.0, Servers::Single);
    b.input(p, t1, 1);
    b.output(t1, q, 1);
    b.output(t1, q, 1);
    b.input(q, t2, 1);
    b.output(t2, end, 1);
    let _ = left;
    let net = b.build().unwrap();
    let mut spec = WorkerSpec::new(["python3", script.to_str().unwrap()]);
    spec.env
        .push(("PYTHONPATH".into(), python_dir().display().to_string()));
    let worker = Worker::start(spec);
    let mut h = Runtime::builder(net)
        .action("inspect", worker.action("inspect"))
        .action("slow", worker.action("slow"))
        .bind("look", "inspect")
        .bind("wait", "slow")
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let summary = h.wait().await;
    assert_eq!(summary.stopped, StopReason::Dead, "{:?}", summary.errors);
    assert_eq!(summary.final_marking["end"], 2);
    let mut lines: Vec<String> = outputs(&events)
        .into_iter()
        .map(|(a, _, l)| format!("{a}: {l}"))
        .collect();
    lines.sort();
    // `left`'s token is agent 1 (a place without an action keeps its agent); t1 forks:
    // agent 0 goes on, agent 2 is new; both slept concurrently.
    assert_eq!(
        lines,
        ["0: inspecting look for agent 0", "0: slept 0", "2: slept 2"]
    );
}

const DURATION_WORKER: &str = r#"
import time
from gspn.worker import action, run

@action("slowly")
def slowly(ctx):
    time.sleep(0.05)          # wall-clock time: never model time
    return "t2", 1.5          # fire t2, 1.5 model seconds from now

run()
"#;

/// Durations stated by programs are the only model time they take (issue 24): a command's
/// `t1 after 2.25` and a worker's `("t2", 1.5)` put the two firings at exactly 2.25 and 3.75,
/// however long the processes ran; a bad duration fails the action, naming it.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn programs_state_the_model_time_their_actions_take() {
    let dir = tempfile::tempdir().unwrap();
    let script = dir.path().join("slowly.py");
    std::fs::write(&script, DURATION_WORKER).unwrap();
    let mut b = NetBuilder::new("durations");
    let a = b.place("a", 1);
    let c = b.place("c", 0);
    let end = b.place("end", 0);
    let t1 = b.exponential("t1", 1.0, Servers::Single);
    let t2 = b.exponential("t2", 1.0, Servers::Single);
    b.input(a, t1, 1);
    b.output(t1, c, 1);
    b.input(c, t2, 1);
    b.output(t2, end, 1);
    let net = b.build().unwrap();
    let mut spec = WorkerSpec::new(["python3", script.to_str().unwrap()]);
    spec.env
        .push(("PYTHONPATH".into(), python_dir().display().to_string()));
    let worker = Worker::start(spec);
    let mut h = Runtime::builder(net.clone())
        .action(
            "cmd",
            CommandAction::new(sh("sleep 0.1; echo 't1 after 2.25'")),
        )
        .action("slowly", worker.action("slowly"))
        .bind("a", "cmd")
        .bind("c", "slowly")
        .seed(1)
        .spawn()
        .unwrap();
    let events = h.events().collect().await;
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Dead, "{:?}", s.errors);
    let fired: Vec<(String, f64)> = events
        .iter()
        .filter_map(|e| match &e.kind {
            EventKind::Fired { transition, .. } => {
                Some((net.transition(*transition).name.clone(), e.time))
            }
            _ => None,
        })
        .collect();
    assert_eq!(fired, [("t1".to_string(), 2.25), ("t2".to_string(), 3.75)]);

    // A duration that is no number of seconds fails the action, naming it.
    let h = Runtime::builder(net)
        .action("cmd", CommandAction::new(sh("echo 't1 after soon'")))
        .bind("a", "cmd")
        .seed(1)
        .spawn()
        .unwrap();
    let s = h.wait().await;
    assert_eq!(s.stopped, StopReason::Failure);
    assert!(
        s.errors[0].contains("`after soon`: not a number of model seconds"),
        "{:?}",
        s.errors
    );
}
