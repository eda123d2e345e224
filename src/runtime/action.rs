//! The [`Action`] trait: what an agent does while its token sits in an action place.
//!
//! An action is async user code. It gets an [`ActionContext`] (the agent, the bound robot,
//! the place, a marking snapshot, a cancellation signal) and ends with an [`Outcome`]. Actions
//! are registered by name on the runtime builder, as closures ([`action_fn`]) or as types
//! implementing [`Action`].

use std::future::Future;
use std::panic::AssertUnwindSafe;
use std::pin::Pin;
use std::sync::Arc;
use std::task::{Context, Poll};
use std::time::Duration;

use serde::{Deserialize, Serialize};
use tokio::sync::{mpsc, watch};

use super::clock::ModelClock;
use super::id::AgentId;
use crate::net::{Marking, Net, PlaceId, TransitionId};

/// A boxed future returned by [`Action::run`].
pub type ActionFuture = Pin<Box<dyn Future<Output = Outcome> + Send + 'static>>;

/// How an action ended.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(tag = "kind", content = "detail", rename_all = "snake_case")]
pub enum Outcome {
    /// This event happened: fire this transition (an output of the place) when it is enabled.
    Fire(TransitionId),
    /// Let the net decide: the policy or the weights among the immediate transitions, else
    /// the race of the place's exponential outputs at the net's rates.
    Decide,
    /// The action failed; the place's failure policy decides what happens next.
    Failed(String),
    /// The action saw the run being stopped and gave up.
    Cancelled,
}

/// Async user code run for each agent that enters an action place.
///
/// ```
/// use gspn::runtime::{Action, ActionContext, ActionFuture, Outcome};
/// struct AlwaysDecide;
/// impl Action for AlwaysDecide {
///     fn run(&self, _ctx: ActionContext) -> ActionFuture {
///         Box::pin(async { Outcome::Decide })
///     }
/// }
/// ```
pub trait Action: Send + Sync + 'static {
    /// Runs the action for one agent. Called once per entry into the place (again on retry).
    fn run(&self, ctx: ActionContext) -> ActionFuture;
}

/// An [`Action`] made from a closure returning a future; see [`action_fn`].
pub struct FnAction<F>(F);

impl<F> std::fmt::Debug for FnAction<F> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("FnAction")
    }
}

/// Wraps `f(ctx) -> impl Future<Output = Outcome>` as an [`Action`].
///
/// ```
/// use gspn::runtime::{action_fn, Outcome};
/// let noop = action_fn(|_ctx| async { Outcome::Decide });
/// # let _ = noop;
/// ```
pub fn action_fn<F, Fut>(f: F) -> FnAction<F>
where
    F: Fn(ActionContext) -> Fut + Send + Sync + 'static,
    Fut: Future<Output = Outcome> + Send + 'static,
{
    FnAction(f)
}

impl<F, Fut> Action for FnAction<F>
where
    F: Fn(ActionContext) -> Fut + Send + Sync + 'static,
    Fut: Future<Output = Outcome> + Send + 'static,
{
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        Box::pin((self.0)(ctx))
    }
}

/// What an action knows when it starts.
#[derive(Clone, Debug)]
pub struct ActionContext {
    /// The agent running the action.
    pub agent: AgentId,
    /// The robot of the agent (plan key `robots`), else the robot of the place, if any.
    pub robot: Option<Arc<str>>,
    /// The action place.
    pub place: PlaceId,
    /// The marking when the action started.
    pub marking: Arc<Marking>,
    /// How many times the action ran before for this entry (0 the first time; retries count up).
    pub attempt: u32,
    /// Fires when the run is being stopped; the action should clean up and return
    /// [`Outcome::Cancelled`].
    pub cancel: CancelToken,
    /// The net, to turn names into ids.
    pub net: Arc<Net>,
    /// The seed of the run (what a program action sees as `GSPN_SEED`).
    pub seed: u64,
    /// Model time (seconds) when the action started.
    pub time: f64,
    /// The run's model time: [`ModelClock::sleep`] waits model seconds — in virtual time
    /// (`time_scale = 0`) the only way an action takes model time.
    pub clock: ModelClock,
    /// Where the action's output lines go ([`EventKind::ActionOutput`](super::EventKind::ActionOutput)
    /// events in the journal and the viewer's log).
    pub output: OutputSink,
}

impl ActionContext {
    /// The id of the transition named `name`, when the net has one.
    pub fn transition(&self, name: &str) -> Option<TransitionId> {
        self.net.transition_by_name(name)
    }

    /// The name of the action place.
    pub fn place_name(&self) -> &str {
        &self.net.place(self.place).name
    }

    /// The transitions that consume from this place (the ones [`Outcome::Fire`] may name).
    pub fn outputs(&self) -> Vec<TransitionId> {
        self.net
            .transition_ids()
            .filter(|&t| self.net.inputs(t).iter().any(|&(p, _)| p == self.place))
            .collect()
    }

    /// Records one line the action printed, as an
    /// [`ActionOutput`](super::EventKind::ActionOutput) event of this agent and place. Lines
    /// longer than [`MAX_OUTPUT_LINE`] bytes are cut.
    pub fn output_line(&self, stream: OutputStream, line: impl Into<String>) {
        self.output
            .send(self.agent, self.place, stream, line.into());
    }

    /// `Fire(name)`, or `Failed` when the net has no such transition.
    pub fn fire(&self, name: &str) -> Outcome {
        match self.transition(name) {
            Some(t) => Outcome::Fire(t),
            None => Outcome::Failed(format!("no transition named `{name}`")),
        }
    }
}

/// Which output stream a line came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum OutputStream {
    /// Standard output (or a worker's reply of kind `output`).
    Stdout,
    /// Standard error.
    Stderr,
}

/// The longest output line kept in an event, in bytes (longer lines are cut at a character
/// boundary and end with `…`).
pub const MAX_OUTPUT_LINE: usize = 1024;

/// One line of an action's output on its way to the supervisor.
#[derive(Debug)]
pub(crate) struct OutputLine {
    pub(crate) agent: AgentId,
    pub(crate) place: PlaceId,
    pub(crate) stream: OutputStream,
    pub(crate) line: String,
}

/// Where an action's output lines go; see [`ActionContext::output_line`]. A sink made with
/// [`OutputSink::discard`] drops them.
#[derive(Clone, Debug, Default)]
pub struct OutputSink(Option<mpsc::UnboundedSender<OutputLine>>);

impl OutputSink {
    pub(crate) fn new(tx: mpsc::UnboundedSender<OutputLine>) -> Self {
        OutputSink(Some(tx))
    }

    /// A sink that drops every line (for actions run outside a runtime, as in tests).
    pub fn discard() -> Self {
        OutputSink(None)
    }

    fn send(&self, agent: AgentId, place: PlaceId, stream: OutputStream, mut line: String) {
        let Some(tx) = &self.0 else {
            return;
        };
        if line.len() > MAX_OUTPUT_LINE {
            let mut cut = MAX_OUTPUT_LINE;
            while !line.is_char_boundary(cut) {
                cut -= 1;
            }
            line.truncate(cut);
            line.push('…');
        }
        let _ = tx.send(OutputLine {
            agent,
            place,
            stream,
            line,
        });
    }
}

/// A cancellation signal shared by every action of a run.
#[derive(Clone, Debug)]
pub struct CancelToken(watch::Receiver<bool>);

/// The sending side of a [`CancelToken`].
#[derive(Debug)]
pub(crate) struct CancelSource(watch::Sender<bool>);

impl CancelSource {
    pub(crate) fn new() -> (CancelSource, CancelToken) {
        let (tx, rx) = watch::channel(false);
        (CancelSource(tx), CancelToken(rx))
    }

    pub(crate) fn cancel(&self) {
        let _ = self.0.send(true);
    }
}

impl CancelToken {
    /// True once the run is being stopped.
    pub fn is_cancelled(&self) -> bool {
        *self.0.borrow()
    }

    /// Completes when the run is being stopped.
    pub async fn cancelled(&self) {
        let mut rx = self.0.clone();
        // An error means the sender is gone: the run is over, which is a cancellation too.
        let _ = rx.wait_for(|&c| c).await;
    }
}

/// Polls a future, turning a panic into `Err(Panicked)` so one agent's panic never takes the
/// plan down.
pub(crate) struct CatchUnwind<F>(pub(crate) F);

/// A panic caught by [`CatchUnwind`]: its message, when the payload was a string.
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct Panicked(String);

impl<F: Future + Unpin> Future for CatchUnwind<F> {
    type Output = Result<F::Output, Panicked>;

    fn poll(mut self: Pin<&mut Self>, cx: &mut Context<'_>) -> Poll<Self::Output> {
        let inner = &mut self.0;
        match std::panic::catch_unwind(AssertUnwindSafe(|| Pin::new(inner).poll(cx))) {
            Ok(Poll::Ready(v)) => Poll::Ready(Ok(v)),
            Ok(Poll::Pending) => Poll::Pending,
            Err(payload) => {
                let msg = payload
                    .downcast_ref::<&str>()
                    .map(|s| s.to_string())
                    .or_else(|| payload.downcast_ref::<String>().cloned())
                    .unwrap_or_else(|| "panic".to_string());
                Poll::Ready(Err(Panicked(msg)))
            }
        }
    }
}

/// An action's report: which agent, which start of its action (the supervisor ignores stale
/// reports), and how it ended. Sent by the task that ran it to the supervisor.
#[derive(Debug)]
pub(crate) struct ActionDone {
    pub(crate) agent: AgentId,
    pub(crate) ticket: u64,
    pub(crate) outcome: Outcome,
}

/// How long an action may run: a place's `timeout`.
#[derive(Debug)]
pub(crate) enum Limit {
    /// No limit.
    None,
    /// This much tokio time (real time, or tokio's paused clock).
    After(Duration),
    /// Virtual time: the supervisor sends on `abort` when the run's clock passes the
    /// deadline, `seconds` model seconds after the start.
    Abort {
        abort: tokio::sync::oneshot::Receiver<()>,
        seconds: f64,
    },
}

/// One run of `action` for one agent, as a future that never panics: a panic (when the
/// future is made or polled) becomes `Failed("panicked…")`, and running past its [`Limit`]
/// becomes `Failed("timed out…")`. Place actors spawn it as a task; agent actors
/// ([`AgentMode::Actor`](super::AgentMode::Actor)) await it in their own task.
pub(crate) fn run_action(
    action: &Arc<dyn Action>,
    ctx: ActionContext,
    limit: Limit,
) -> impl std::future::Future<Output = Outcome> + Send + 'static {
    // A panic before the future exists is the agent's failure too, not the place's.
    let fut = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| action.run(ctx)))
        .unwrap_or_else(|_| Box::pin(async { Outcome::Failed("panicked".into()) }));
    async move {
        let caught = CatchUnwind(fut);
        let outcome = match limit {
            Limit::None => caught.await,
            Limit::After(d) => match tokio::time::timeout(d, caught).await {
                Ok(r) => r,
                Err(_) => Ok(Outcome::Failed(format!("timed out after {d:?}"))),
            },
            Limit::Abort { abort, seconds } => {
                tokio::select! {
                    biased;
                    Ok(()) = abort => Ok(Outcome::Failed(format!(
                        "timed out after {seconds} model seconds"
                    ))),
                    r = caught => r,
                }
            }
        };
        outcome.unwrap_or_else(|p| Outcome::Failed(format!("panicked: {p}")))
    }
}
