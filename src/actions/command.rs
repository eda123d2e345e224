//! Command actions: one program run per action.
//!
//! The argv is a template (`{place}`, `{agent}`, `{robot}`, `{transition_choices}`); the
//! program also gets `GSPN_AGENT`, `GSPN_PLACE`, `GSPN_ROBOT`, `GSPN_SEED`, `GSPN_TIME`,
//! `GSPN_MARKING` (JSON) and `GSPN_OUTPUTS` (the place's output transitions, space-separated).
//! Exit 0 and an answer naming a transition fires it; an empty answer or `decide` lets the
//! net decide. The answer is the last stdout line that starts with `gspn: ` (`gspn: fire T`,
//! `gspn: decide`, `gspn: fire T after 2`), so a program may log freely after it; without
//! such a line it is the last stdout line (the rule of the 2020 framework's functions); `T after S`, `decide after S` or `after S` states a
//! duration: the outcome takes effect S model seconds later (in virtual time, the only way a
//! program's action takes model time — the time the program itself takes never counts); a
//! non-zero exit fails the action with the code and the tail of stderr. Every stdout and stderr line becomes an
//! [`ActionOutput`](crate::runtime::EventKind::ActionOutput) event.

use std::collections::VecDeque;
use std::path::PathBuf;
use std::process::Stdio;
use std::sync::Arc;
use std::time::Duration;

use tokio::io::{AsyncBufReadExt, AsyncRead, BufReader};
use tokio::process::Command;

use super::group::ProcessGroup;
use super::{
    DEFAULT_KILL_GRACE, MAX_OUTPUT_LINES, OutputNames, marking_json, outcome_of_name, split_after,
};
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome, OutputStream};

/// Lines of stderr quoted in a failure.
const STDERR_TAIL: usize = 5;

/// What to run: an argv template, a directory, extra environment, limits.
#[derive(Clone, Debug, PartialEq)]
pub struct CommandSpec {
    /// Program and arguments; `{place}`, `{agent}`, `{robot}` are replaced in each argument,
    /// and an argument that is exactly `{transition_choices}` becomes one argument per output
    /// transition of the place (inside a longer argument: the names joined by `,`).
    pub argv: Vec<String>,
    /// The working directory (default: the current one).
    pub cwd: Option<PathBuf>,
    /// Extra environment variables.
    pub env: Vec<(String, String)>,
    /// Fails the action (and stops the program) after the program ran this long, in tokio
    /// time: wall-clock seconds (scaled like the run's clock in real time) — a guard against
    /// a hung program, also in virtual time, where the program's own time is not model time
    /// (default: none; the place's `timeout`, in model seconds, applies too).
    pub timeout: Option<Duration>,
    /// Between SIGTERM and SIGKILL when the program must stop.
    pub kill_grace: Duration,
}

impl CommandSpec {
    /// A spec running `argv` with the defaults.
    pub fn new<S: Into<String>>(argv: impl IntoIterator<Item = S>) -> Self {
        CommandSpec {
            argv: argv.into_iter().map(Into::into).collect(),
            cwd: None,
            env: Vec::new(),
            timeout: None,
            kill_grace: DEFAULT_KILL_GRACE,
        }
    }
}

/// An [`Action`] that runs a program per action; see the [module docs](self).
///
/// ```no_run
/// use gspn::actions::{CommandAction, CommandSpec};
/// let inspect = CommandAction::new(CommandSpec::new(["python3", "inspect.py", "{place}"]));
/// # let _ = inspect;
/// ```
#[derive(Debug)]
pub struct CommandAction {
    spec: Arc<CommandSpec>,
    outputs: Arc<OutputNames>,
}

impl CommandAction {
    /// The action running `spec`.
    pub fn new(spec: CommandSpec) -> Self {
        CommandAction {
            spec: Arc::new(spec),
            outputs: Arc::default(),
        }
    }
}

impl Action for CommandAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let spec = Arc::clone(&self.spec);
        let outputs = self.outputs.get(&ctx);
        Box::pin(async move { run(&spec, &outputs, ctx).await })
    }
}

fn expand(arg: &str, ctx: &ActionContext, outputs: &[String]) -> String {
    arg.replace("{place}", ctx.place_name())
        .replace("{agent}", &ctx.agent.0.to_string())
        .replace("{robot}", ctx.robot.as_deref().unwrap_or(""))
        .replace("{transition_choices}", &outputs.join(","))
}

async fn run(spec: &CommandSpec, outputs: &[String], ctx: ActionContext) -> Outcome {
    let Some(program) = spec.argv.first() else {
        return Outcome::Failed("empty command".into());
    };
    let mut cmd = Command::new(expand(program, &ctx, outputs));
    for a in &spec.argv[1..] {
        if a == "{transition_choices}" {
            cmd.args(outputs);
        } else {
            cmd.arg(expand(a, &ctx, outputs));
        }
    }
    if let Some(dir) = &spec.cwd {
        cmd.current_dir(dir);
    }
    cmd.envs(spec.env.iter().map(|(k, v)| (k, v)))
        .env("GSPN_AGENT", ctx.agent.0.to_string())
        .env("GSPN_PLACE", ctx.place_name())
        .env("GSPN_ROBOT", ctx.robot.as_deref().unwrap_or(""))
        .env("GSPN_SEED", ctx.seed.to_string())
        .env("GSPN_TIME", ctx.time.to_string())
        .env("GSPN_MARKING", marking_json(&ctx))
        .env("GSPN_OUTPUTS", outputs.join(" "))
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .process_group(0);
    let mut child = match cmd.spawn() {
        Ok(c) => c,
        Err(e) => return Outcome::Failed(format!("cannot start `{program}`: {e}")),
    };
    let Some(pid) = child.id() else {
        return Outcome::Failed(format!("`{program}` exited before it could be watched"));
    };
    let group = ProcessGroup::new(pid, spec.kill_grace);
    let (Some(stdout), Some(stderr)) = (child.stdout.take(), child.stderr.take()) else {
        return Outcome::Failed(format!("`{program}`: no pipes"));
    };
    let work = async {
        let (out, err, status) = tokio::join!(
            answer(stdout, &ctx),
            capture(stderr, &ctx, OutputStream::Stderr, STDERR_TAIL),
            child.wait(),
        );
        (out, err, status)
    };
    let deadline = async {
        match spec.timeout {
            Some(d) => tokio::time::sleep(d).await,
            None => std::future::pending().await,
        }
    };
    tokio::select! {
        (answer, tail, status) = work => {
            group.finish();
            match status {
                Ok(s) if s.success() => {
                    let (name, after) = split_after(&answer.text);
                    let after = match after {
                        Ok(a) => a,
                        Err(why) => return Outcome::Failed(format!("`{program}`: {why}")),
                    };
                    let outcome = match outcome_of_name(&ctx, &format!("`{program}`"), name) {
                        Outcome::Failed(why) if !answer.tagged => Outcome::Failed(format!(
                            "{why}; the answer was the last stdout line: print `{ANSWER_PREFIX}fire T` \
                             (or `{ANSWER_PREFIX}decide`) to answer whatever is printed after it"
                        )),
                        o => o,
                    };
                    if after > 0.0 && !matches!(outcome, Outcome::Failed(_)) {
                        // The program stated a duration: the outcome takes effect that much
                        // model time later.
                        tokio::select! {
                            biased;
                            () = ctx.cancel.cancelled() => return Outcome::Cancelled,
                            () = ctx.clock.sleep(after) => {}
                        }
                    }
                    outcome
                }
                Ok(s) => Outcome::Failed(failure(program, s, &tail)),
                Err(e) => Outcome::Failed(format!("`{program}`: {e}")),
            }
        }
        () = ctx.cancel.cancelled() => {
            group.terminate().await;
            Outcome::Cancelled
        }
        () = deadline => {
            group.terminate().await;
            Outcome::Failed(format!(
                "`{program}` timed out after {:?}; its process group was stopped",
                spec.timeout.unwrap_or_default()
            ))
        }
    }
}

fn failure(program: &str, status: std::process::ExitStatus, tail: &VecDeque<String>) -> String {
    use std::os::unix::process::ExitStatusExt;
    let how = match (status.code(), status.signal()) {
        (Some(c), _) => format!("exited with code {c}"),
        (None, Some(s)) => format!("was killed by signal {s}"),
        (None, None) => "failed".to_string(),
    };
    if tail.is_empty() {
        format!("`{program}` {how}")
    } else {
        let lines: Vec<&str> = tail.iter().map(String::as_str).collect();
        format!("`{program}` {how}; stderr: {}", lines.join(" | "))
    }
}

/// The prefix of a stdout line that answers for the program, whatever it prints after it.
pub(crate) const ANSWER_PREFIX: &str = "gspn: ";

/// A program's answer: the last `gspn: ` line (`tagged`), else the last stdout line.
#[derive(Debug, Default)]
struct Answer {
    text: String,
    tagged: bool,
}

/// Reads stdout into output events (as [`capture`]) and finds the program's [`Answer`].
async fn answer(r: impl AsyncRead + Unpin, ctx: &ActionContext) -> Answer {
    let mut tagged: Option<String> = None;
    let last = capture_with(r, ctx, OutputStream::Stdout, 1, |line| {
        if let Some(rest) = line.strip_prefix(ANSWER_PREFIX) {
            let rest = rest.trim();
            tagged = Some(rest.strip_prefix("fire ").unwrap_or(rest).to_string());
        }
    })
    .await;
    match tagged {
        Some(text) => Answer { text, tagged: true },
        None => Answer {
            text: last.back().cloned().unwrap_or_default(),
            tagged: false,
        },
    }
}

/// Reads `r` line by line into output events (at most [`MAX_OUTPUT_LINES`], then one line
/// counting the rest); returns the last `keep` lines.
async fn capture(
    r: impl AsyncRead + Unpin,
    ctx: &ActionContext,
    stream: OutputStream,
    keep: usize,
) -> VecDeque<String> {
    capture_with(r, ctx, stream, keep, |_| {}).await
}

/// [`capture`], showing each line to `see` as it is read.
async fn capture_with(
    r: impl AsyncRead + Unpin,
    ctx: &ActionContext,
    stream: OutputStream,
    keep: usize,
    mut see: impl FnMut(&str),
) -> VecDeque<String> {
    let mut lines = BufReader::new(r).lines();
    let mut tail = VecDeque::with_capacity(keep + 1);
    let mut n = 0usize;
    // Not UTF-8, or the pipe failed: what was read is what there is.
    while let Ok(Some(line)) = lines.next_line().await {
        n += 1;
        see(&line);
        if n <= MAX_OUTPUT_LINES {
            ctx.output_line(stream, line.clone());
        }
        tail.push_back(line);
        if tail.len() > keep {
            tail.pop_front();
        }
    }
    if n > MAX_OUTPUT_LINES {
        ctx.output_line(
            stream,
            format!("[gspn: {} more lines not recorded]", n - MAX_OUTPUT_LINES),
        );
    }
    tail
}
