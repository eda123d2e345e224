//! Worker actions: one long-lived program per [`WorkerSpec`], many requests in flight.
//!
//! The protocol, JSON Lines (one object per line; `docs/actions.md` has a complete worker):
//!
//! - request, on the worker's stdin: `{"id", "action", "agent", "place", "robot", "marking",
//!   "outputs", "attempt", "time", "seed"}`;
//! - cancel, on stdin: `{"cancel": id}` (the run is stopping or the action timed out);
//! - replies, on stdout: `{"id", "fire": "t3"}` | `{"id", "decide": true}` |
//!   `{"id", "error": "…"}`, and any number of `{"id", "output": "a line"}` before them
//!   (recorded as the agent's output); `"after": S` on a `fire` or `decide` reply states a
//!   duration: the outcome takes effect S model seconds later (in virtual time, the only way
//!   a worker's action takes model time).
//!
//! A worker that exits fails its in-flight actions with the reason and is started again on
//! the next request, after a backoff that doubles from 100 ms up to 5 s while it keeps
//! crashing (reset after 10 s of life). Its stderr lines are kept for that reason.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::process::Stdio;
use std::sync::Arc;
use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use rustc_hash::FxHashMap;
use serde::{Deserialize, Serialize};
use tokio::io::{AsyncBufReadExt, AsyncWriteExt, BufReader, BufWriter};
use tokio::process::{Child, ChildStdin, Command};
use tokio::sync::{mpsc, oneshot};
use tokio::time::Instant;

use super::group::ProcessGroup;
use super::{DEFAULT_KILL_GRACE, MarkingMap, OutputNames, outcome_of_name};
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome, OutputStream};

/// First restart delay of a crashed worker.
const BACKOFF_START: Duration = Duration::from_millis(100);
/// Longest restart delay.
const BACKOFF_MAX: Duration = Duration::from_secs(5);
/// A worker that lived this long starts its backoff over.
const HEALTHY: Duration = Duration::from_secs(10);
/// Lines of stderr quoted when a worker dies.
const STDERR_TAIL: usize = 5;
/// How long the end of a dead worker's stderr is awaited.
const STDERR_DRAIN: Duration = Duration::from_secs(1);

/// The program of a worker.
#[derive(Clone, Debug, PartialEq)]
pub struct WorkerSpec {
    /// Program and arguments.
    pub argv: Vec<String>,
    /// The working directory (default: the current one).
    pub cwd: Option<PathBuf>,
    /// Extra environment variables.
    pub env: Vec<(String, String)>,
    /// Between SIGTERM and SIGKILL when the worker must stop.
    pub kill_grace: Duration,
}

impl WorkerSpec {
    /// A spec running `argv` with the defaults.
    pub fn new<S: Into<String>>(argv: impl IntoIterator<Item = S>) -> Self {
        WorkerSpec {
            argv: argv.into_iter().map(Into::into).collect(),
            cwd: None,
            env: Vec::new(),
            kill_grace: DEFAULT_KILL_GRACE,
        }
    }
}

/// A running worker program (started on the first request), shared by the [`WorkerAction`]s
/// that name its actions. Dropping the last handle stops the program.
///
/// ```no_run
/// use gspn::actions::{Worker, WorkerSpec};
/// # #[tokio::main(flavor = "current_thread")]
/// # async fn main() {
/// let worker = Worker::start(WorkerSpec::new(["python3", "robot_actions.py"]));
/// let inspect = worker.action("inspect");
/// # let _ = inspect;
/// # }
/// ```
#[derive(Clone, Debug)]
pub struct Worker {
    tx: mpsc::UnboundedSender<Msg>,
    next_id: Arc<AtomicU64>,
    outputs: Arc<OutputNames>,
    name: Arc<str>,
}

/// An [`Action`] answered by a [`Worker`]: requests name `action`.
#[derive(Clone, Debug)]
pub struct WorkerAction {
    worker: Worker,
    action: Arc<str>,
}

enum Msg {
    Request {
        id: u64,
        line: String,
        ctx: ActionContext,
        reply: oneshot::Sender<Answer>,
    },
    Cancel(u64),
}

#[derive(Serialize)]
struct Request<'a> {
    id: u64,
    action: &'a str,
    agent: u64,
    place: &'a str,
    robot: Option<&'a str>,
    marking: super::MarkingMap<'a>,
    outputs: &'a [String],
    attempt: u32,
    time: f64,
    seed: u64,
}

#[derive(Deserialize)]
struct Reply {
    id: u64,
    #[serde(default)]
    fire: Option<String>,
    #[serde(default)]
    decide: Option<bool>,
    #[serde(default)]
    error: Option<String>,
    #[serde(default)]
    output: Option<String>,
    /// Model seconds the outcome takes effect after.
    #[serde(default)]
    after: Option<serde_json::Value>,
}

impl Worker {
    /// Starts the worker's task in the current tokio runtime (the program itself starts on
    /// the first request).
    pub fn start(spec: WorkerSpec) -> Worker {
        let (tx, rx) = mpsc::unbounded_channel();
        let name: Arc<str> = Arc::from(spec.argv.join(" "));
        tokio::spawn(supervise(spec, rx));
        Worker {
            tx,
            next_id: Arc::new(AtomicU64::new(0)),
            outputs: Arc::default(),
            name,
        }
    }

    /// The action of this worker named `action` (what requests carry as `"action"`).
    pub fn action(&self, action: impl Into<String>) -> WorkerAction {
        WorkerAction {
            worker: self.clone(),
            action: Arc::from(action.into()),
        }
    }
}

/// Sends a cancel for a request still in flight when its action future is dropped.
struct InFlight<'a> {
    tx: &'a mpsc::UnboundedSender<Msg>,
    id: u64,
    done: bool,
}

impl Drop for InFlight<'_> {
    fn drop(&mut self) {
        if !self.done {
            let _ = self.tx.send(Msg::Cancel(self.id));
        }
    }
}

impl Action for WorkerAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let w = &self.worker;
        let id = w.next_id.fetch_add(1, Ordering::Relaxed);
        let outputs = w.outputs.get(&ctx);
        let req = Request {
            id,
            action: &self.action,
            agent: ctx.agent.0,
            place: ctx.place_name(),
            robot: ctx.robot.as_deref(),
            marking: MarkingMap(&ctx),
            outputs: &outputs,
            attempt: ctx.attempt,
            time: ctx.time,
            seed: ctx.seed,
        };
        let line = match serde_json::to_string(&req) {
            Ok(l) => l,
            Err(e) => {
                let msg = format!("cannot encode the request: {e}");
                return Box::pin(async move { Outcome::Failed(msg) });
            }
        };
        let tx = w.tx.clone();
        let name = Arc::clone(&w.name);
        Box::pin(async move {
            let cancel = ctx.cancel.clone();
            let clock = ctx.clock.clone();
            let (reply, rx) = oneshot::channel();
            if tx
                .send(Msg::Request {
                    id,
                    line,
                    ctx,
                    reply,
                })
                .is_err()
            {
                return Outcome::Failed(format!("worker `{name}` is gone"));
            }
            let mut guard = InFlight {
                tx: &tx,
                id,
                done: false,
            };
            let (out, after) = tokio::select! {
                r = rx => r.unwrap_or_else(|_| (Outcome::Failed(format!("worker `{name}` is gone")), 0.0)),
                () = cancel.cancelled() => (Outcome::Cancelled, 0.0),
            };
            guard.done = !matches!(out, Outcome::Cancelled);
            drop(guard);
            if after > 0.0 {
                // The reply stated a duration: the outcome takes effect that much model
                // time later.
                tokio::select! {
                    biased;
                    () = cancel.cancelled() => return Outcome::Cancelled,
                    () = clock.sleep(after) => {}
                }
            }
            out
        })
    }
}

struct Pending {
    ctx: ActionContext,
    reply: oneshot::Sender<Answer>,
}

/// A reply: the outcome, and the model seconds it takes effect after (`"after"`, 0 when
/// none).
type Answer = (Outcome, f64);

/// The worker's task: starts the program when requests come, routes replies, restarts it
/// after a crash, stops it when every handle is gone.
async fn supervise(spec: WorkerSpec, mut rx: mpsc::UnboundedReceiver<Msg>) {
    let name = spec.argv.join(" ");
    let mut backoff = BACKOFF_START;
    loop {
        // Wait for work before (re)starting the program.
        let Some(msg) = rx.recv().await else {
            return;
        };
        if matches!(msg, Msg::Cancel(_)) {
            continue; // for a request of a worker that is gone
        }
        let started = Instant::now();
        let mut proc = match Proc::spawn(&spec) {
            Ok(p) => p,
            Err(e) => {
                let reason = format!("cannot start worker `{name}`: {e}");
                fail(msg, &reason);
                while let Ok(m) = rx.try_recv() {
                    fail(m, &reason);
                }
                tokio::time::sleep(backoff).await;
                backoff = (backoff * 2).min(BACKOFF_MAX);
                continue;
            }
        };
        let mut pending: FxHashMap<u64, Pending> = FxHashMap::default();
        proc.handle(msg, &mut pending);
        let status = loop {
            tokio::select! {
                m = rx.recv() => match m {
                    Some(m) => proc.handle(m, &mut pending),
                    None => {
                        proc.stop().await;
                        return;
                    }
                },
                line = proc.stdout.next_line() => match line {
                    Ok(Some(line)) => route(&name, &line, &mut pending),
                    Ok(None) | Err(_) => break proc.wait().await,
                },
                line = proc.stderr.next_line(), if !proc.stderr_done => match line {
                    Ok(Some(line)) => proc.keep_stderr(&name, line),
                    Ok(None) | Err(_) => proc.stderr_done = true,
                },
            }
        };
        // Crashed (or closed its stdout): every request in flight fails, with the reason —
        // whose last stderr lines may still be in the pipe when stdout's end is seen first.
        proc.drain_stderr(&name).await;
        let tail: Vec<String> = proc.tail.drain(..).collect();
        let mut reason = format!("worker `{name}` {status} while running this action");
        if !tail.is_empty() {
            reason.push_str(&format!("; stderr: {}", tail.join(" | ")));
        }
        reason.push_str("; it is restarted");
        tracing::warn!("{reason}");
        for (_, p) in pending.drain() {
            let _ = p.reply.send((Outcome::Failed(reason.clone()), 0.0));
        }
        if started.elapsed() >= HEALTHY {
            backoff = BACKOFF_START;
        }
        // Requests that come during the backoff wait in the channel.
        tokio::time::sleep(backoff).await;
        backoff = (backoff * 2).min(BACKOFF_MAX);
    }
}

fn fail(msg: Msg, reason: &str) {
    if let Msg::Request { reply, .. } = msg {
        let _ = reply.send((Outcome::Failed(reason.to_string()), 0.0));
    }
}

fn route(name: &str, line: &str, pending: &mut FxHashMap<u64, Pending>) {
    let reply: Reply = match serde_json::from_str(line) {
        Ok(r) => r,
        Err(e) => {
            tracing::warn!(worker = %name, "not a reply ({e}): {line}");
            return;
        }
    };
    if let Some(text) = reply.output {
        if let Some(p) = pending.get(&reply.id) {
            p.ctx.output_line(OutputStream::Stdout, text);
        }
        if reply.fire.is_none() && reply.decide.is_none() && reply.error.is_none() {
            return;
        }
    }
    let Some(p) = pending.remove(&reply.id) else {
        return; // cancelled meanwhile
    };
    let who = format!("worker `{name}`");
    let after = match reply.after.as_ref().map(super::stated_seconds) {
        None => Ok(0.0),
        Some(Some(s)) => Ok(s),
        Some(None) => Err(format!(
            "{who}: `after` = {} is not a number of model seconds (finite, ≥ 0, ≤ 315576000)",
            reply
                .after
                .as_ref()
                .map_or(String::new(), ToString::to_string)
        )),
    };
    let answer = match (reply.error, after) {
        (Some(e), _) => (Outcome::Failed(format!("{who}: {e}")), 0.0),
        (None, Err(why)) => (Outcome::Failed(why), 0.0),
        (None, Ok(after)) => match reply.fire {
            Some(t) => (outcome_of_name(&p.ctx, &who, &t), after),
            None => (Outcome::Decide, after),
        },
    };
    let _ = p.reply.send(answer);
}

/// One incarnation of the worker program.
struct Proc {
    child: Child,
    group: Option<ProcessGroup>,
    stdin: mpsc::UnboundedSender<String>,
    stdout: tokio::io::Lines<BufReader<tokio::process::ChildStdout>>,
    stderr: tokio::io::Lines<BufReader<tokio::process::ChildStderr>>,
    stderr_done: bool,
    tail: VecDeque<String>,
    kill_grace: Duration,
}

impl Proc {
    /// Keeps a stderr line for the crash reason (the last `STDERR_TAIL` lines).
    fn keep_stderr(&mut self, name: &str, line: String) {
        tracing::debug!(worker = %name, "{line}");
        self.tail.push_back(line);
        if self.tail.len() > STDERR_TAIL {
            self.tail.pop_front();
        }
    }

    /// Reads what is left on stderr after the program ended, until its end — or for at most
    /// `STDERR_DRAIN`, in case a child of the worker still holds the pipe open.
    async fn drain_stderr(&mut self, name: &str) {
        let deadline = tokio::time::sleep(STDERR_DRAIN);
        tokio::pin!(deadline);
        while !self.stderr_done {
            tokio::select! {
                line = self.stderr.next_line() => match line {
                    Ok(Some(line)) => self.keep_stderr(name, line),
                    Ok(None) | Err(_) => self.stderr_done = true,
                },
                () = &mut deadline => return,
            }
        }
    }

    fn spawn(spec: &WorkerSpec) -> std::io::Result<Proc> {
        let Some(program) = spec.argv.first() else {
            return Err(std::io::Error::other("empty command"));
        };
        let mut cmd = Command::new(program);
        cmd.args(&spec.argv[1..]);
        if let Some(dir) = &spec.cwd {
            cmd.current_dir(dir);
        }
        cmd.envs(spec.env.iter().map(|(k, v)| (k, v)))
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .process_group(0);
        let mut child = cmd.spawn()?;
        let pid = child
            .id()
            .ok_or_else(|| std::io::Error::other("exited at once"))?;
        let group = ProcessGroup::new(pid, spec.kill_grace);
        let (Some(stdin), Some(stdout), Some(stderr)) =
            (child.stdin.take(), child.stdout.take(), child.stderr.take())
        else {
            return Err(std::io::Error::other("no pipes"));
        };
        // A writer task of its own: a worker that does not read its stdin must not keep
        // the replies of others from being read.
        let (tx, lines) = mpsc::unbounded_channel();
        tokio::spawn(write_lines(stdin, lines));
        Ok(Proc {
            child,
            group: Some(group),
            stdin: tx,
            stdout: BufReader::new(stdout).lines(),
            stderr: BufReader::new(stderr).lines(),
            stderr_done: false,
            tail: VecDeque::new(),
            kill_grace: spec.kill_grace,
        })
    }

    fn handle(&mut self, msg: Msg, pending: &mut FxHashMap<u64, Pending>) {
        match msg {
            Msg::Request {
                id,
                line,
                ctx,
                reply,
            } => {
                pending.insert(id, Pending { ctx, reply });
                let _ = self.stdin.send(line);
            }
            Msg::Cancel(id) => {
                if pending.remove(&id).is_some() {
                    let _ = self.stdin.send(format!("{{\"cancel\":{id}}}"));
                }
            }
        }
    }

    /// How the program ended (it closed its stdout: it is ending or has ended).
    async fn wait(&mut self) -> String {
        let status = tokio::time::timeout(self.kill_grace, self.child.wait()).await;
        if let Some(g) = self.group.take() {
            g.finish();
        }
        match status {
            Ok(Ok(s)) => match s.code() {
                Some(c) => format!("exited with code {c}"),
                None => format!("was killed ({s})"),
            },
            Ok(Err(e)) => format!("failed ({e})"),
            Err(_) => "closed its stdout".to_string(),
        }
    }

    /// Closes stdin (a worker's cue to exit), then SIGTERM and SIGKILL to its group.
    async fn stop(mut self) {
        drop(std::mem::replace(
            &mut self.stdin,
            mpsc::unbounded_channel().0,
        ));
        if tokio::time::timeout(self.kill_grace, self.child.wait())
            .await
            .is_ok()
        {
            if let Some(g) = self.group.take() {
                g.finish();
            }
        } else if let Some(g) = self.group.take() {
            g.terminate().await;
        }
    }
}

async fn write_lines(stdin: ChildStdin, mut lines: mpsc::UnboundedReceiver<String>) {
    let mut w = BufWriter::new(stdin);
    while let Some(first) = lines.recv().await {
        let mut next = Some(first);
        // Everything queued goes out in one write.
        while let Some(l) = next {
            if w.write_all(l.as_bytes()).await.is_err() || w.write_all(b"\n").await.is_err() {
                return;
            }
            next = lines.try_recv().ok();
        }
        if w.flush().await.is_err() {
            return;
        }
    }
}
