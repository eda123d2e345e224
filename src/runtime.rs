//! The actor runtime: a plan executed by agents.
//!
//! - [`supervisor`]: one kameo actor per running plan; owns the marking, the policy and the
//!   agent registry, serialises every firing, never awaits a user action.
//! - [`agent`]: one agent per token in an action place (stable [`AgentId`]), spawned and
//!   ended with the tokens; optionally a kameo actor each ([`AgentMode`]).
//! - [`place`]: one actor per action place, running each agent's [`Action`] concurrently.
//! - [`action`]: the [`Action`] trait and its [`Outcome`]; [`builtin`]: `wait`, `log`,
//!   `fire`, the actions every plan has.
//! - [`event`]: the broadcast bus of [`Event`]s; [`journal`]: the JSON Lines journal.
//! - [`RuntimeBuilder`] / [`RuntimeHandle`]: embedding in an existing tokio runtime.
//! - [`Role`] and [`FailurePolicy`] (what a place does), [`StopConditions`] (when a run ends).
//! - [`Backend`]: what a run drives besides its actors (robot world, ROS 2, viewer), kept in
//!   [`Backends`].
//!
//! The execution semantics (`docs/execution.md` has them in full):
//!
//! - **Agents**: once a run has an action place, every token outside resource places is an
//!   agent with a stable id; it keeps its identity through places without an action (they
//!   are transparent: their agents are ready at once). Through a firing, consumed agents
//!   continue into the produced tokens in input-arc order; leftovers end (join), extra tokens
//!   are new agents (fork).
//! - **Readiness**: a transition is ready when it is enabled and each input place's agents
//!   that it needs have ended their actions with `Fire(it)` or `Decide`. The supervisor picks
//!   among ready transitions with the one firing core ([`crate::firing`]): the highest
//!   priority first, then the policy or the weights; a lower-priority immediate transition
//!   never fires while a higher-priority one is enabled and ready.
//! - **Time**: with `time_scale = 0` the model clock moves only by the net's delays and the
//!   durations actions state ([`ModelClock::sleep`], `wait S`, a program's `after S`); the
//!   supervisor chooses only when no action that could decide at this instant is still
//!   computing, and applies what arrived in agent order — the same seed gives the same run
//!   with any actions. With `time_scale > 0` actions take the (scaled) time they take.
//! - Places whose agents hand the choice back to the net (`Decide`, a `wait`, no action) are
//!   *net-timed*: the supervisor samples their exponential transitions with the net's rates
//!   and server semantics, so a plan whose actions take no model time is the GSPN's own token
//!   game, firing for firing.
//!
//! ```
//! use gspn::net::{NetBuilder, Servers};
//! use gspn::runtime::{Runtime, Outcome, action_fn, StopReason};
//! # #[tokio::main(flavor = "current_thread")]
//! # async fn main() {
//! let mut b = NetBuilder::new("ping");
//! let idle = b.place("idle", 1);
//! let busy = b.place("busy", 0);
//! let go = b.exponential("go", 1.0, Servers::Single);
//! let back = b.exponential("back", 1.0, Servers::Single);
//! b.input(idle, go, 1);
//! b.output(go, busy, 1);
//! b.input(busy, back, 1);
//! b.output(back, idle, 1);
//! let net = b.build().unwrap();
//! let handle = Runtime::builder(net)
//!     .action("work", action_fn(move |_ctx| async move { Outcome::Fire(back) }))
//!     .bind("busy", "work")
//!     .seed(7)
//!     .max_firings(10)
//!     .spawn()
//!     .unwrap();
//! let summary = handle.wait().await;
//! assert_eq!(summary.firings, 10);
//! assert_eq!(summary.stopped, StopReason::MaxFirings);
//! # }
//! ```

pub(crate) mod action;
pub(crate) mod agent;
mod backend;
mod builder;
pub(crate) mod builtin;
mod by_name;
mod clock;
mod conservation;
mod engine;
pub(crate) mod event;
mod handle;
mod id;
pub mod journal;
pub(crate) mod place;
pub(crate) mod reward;
mod role;
mod sink;
mod snapshot;
mod stop;
pub(crate) mod supervisor;

use std::path::PathBuf;

use serde::{Deserialize, Serialize};

pub use action::{
    Action, ActionContext, ActionFuture, CancelToken, FnAction, MAX_OUTPUT_LINE, Outcome,
    OutputSink, OutputStream, action_fn,
};
pub use agent::{AgentMode, AgentState};
pub use backend::{
    Backend, BackendError, BackendFuture, Backends, RunError, Section, Start, Started,
};
pub use builder::RuntimeBuilder;
pub use builtin::{BUILTIN_WORDS, Builtin, BuiltinError};
pub use by_name::InNetOrder;
pub use clock::ModelClock;
pub use event::{Drift, Event, EventKind, Events, Monitored, Received, Watcher};
pub use handle::{AgentInfo, Progress, RuntimeHandle, Summary};
pub use id::AgentId;
pub use reward::Earned;
pub use role::{FailurePolicy, Role};
pub use stop::StopConditions;

use crate::net::Net;

/// Entry point: `Runtime::builder(net)` (a plan file gives one with
/// `gspn::plan::Plan::runtime_builder`).
#[derive(Debug)]
pub struct Runtime;

impl Runtime {
    /// A run of `net` where every place is net-timed until roles and actions say otherwise.
    pub fn builder(net: Net) -> RuntimeBuilder {
        RuntimeBuilder::new(net)
    }
}

/// Why a run stopped.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum StopReason {
    /// Nothing can ever fire again.
    Dead,
    /// Agents chose transitions that never became enabled (see the errors).
    Stuck,
    /// The plan's `stop.when` condition holds.
    Condition,
    /// The time limit was reached.
    TimeLimit,
    /// The firing limit was reached.
    MaxFirings,
    /// An action failed and its place's policy said stop.
    Failure,
    /// `handle.stop()`.
    Requested,
    /// Ctrl-C.
    Interrupted,
    /// The journal could not be written (a full disk): the events after it would be lost,
    /// so the run stops (see the errors).
    Journal,
}

impl StopReason {
    /// 0 done, 1 failure, 130 interrupted.
    pub fn exit_code(&self) -> u8 {
        match self {
            StopReason::Dead
            | StopReason::Condition
            | StopReason::TimeLimit
            | StopReason::MaxFirings => 0,
            StopReason::Stuck | StopReason::Failure | StopReason::Journal => 1,
            StopReason::Requested | StopReason::Interrupted => 130,
        }
    }

    /// A sentence for people.
    pub fn describe(&self) -> &'static str {
        match self {
            StopReason::Dead => "nothing can fire any more",
            StopReason::Stuck => "agents wait for transitions that never became enabled",
            StopReason::Condition => "the stop condition holds",
            StopReason::TimeLimit => "time limit reached",
            StopReason::MaxFirings => "firing limit reached",
            StopReason::Failure => "an action failed",
            StopReason::Requested => "stopped by request",
            StopReason::Interrupted => "interrupted",
            StopReason::Journal => "the journal could not be written",
        }
    }
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.describe())
    }
}

/// Why a run could not start.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RuntimeError {
    /// `spawn` was called outside a tokio runtime.
    #[error("the runtime must be spawned inside a tokio runtime")]
    NoTokio,
    /// A time scale that is negative, not finite, or above
    /// [`MAX_SECONDS`](crate::limits::MAX_SECONDS).
    #[error("time scale {0} must be finite, ≥ 0 and ≤ 315576000")]
    BadTimeScale(f64),
    /// In real time, an exponential transition whose mean delay is longer than
    /// [`MAX_SECONDS`](crate::limits::MAX_SECONDS) (10 years): the run would sit still.
    #[error(
        "transition `{transition}`: rate {rate} at time scale {scale} gives a mean delay of {seconds:e} s of real time, more than the maximum 315576000 s (10 years)"
    )]
    DelayTooLong {
        /// The transition.
        transition: String,
        /// Its rate.
        rate: f64,
        /// The time scale.
        scale: f64,
        /// Its mean delay in real seconds.
        seconds: f64,
    },
    /// `bind` named a place the net does not have.
    #[error("no place named `{0}`")]
    UnknownPlace(String),
    /// Robots are bound to places but a transition creates or destroys robot tokens.
    #[error(
        "transition `{transition}` changes the number of robot tokens by {change} (outside resource places): robots cannot appear or vanish"
    )]
    RobotTokens {
        /// The transition.
        transition: String,
        /// Tokens it adds (negative: removes) outside resource places.
        change: i64,
    },
    /// The plan names a different number of robots than there are initial agents.
    #[error(
        "{robots} robot(s) named but the net starts with {agents} agent(s) (initial tokens outside resource places): name one robot per initial agent"
    )]
    RobotCount {
        /// Robots named.
        robots: usize,
        /// Initial tokens outside resource places.
        agents: u64,
    },
    /// A place's action is a built-in (`wait`, `log`, `fire`) written wrongly.
    #[error("place `{place}`: {reason}")]
    BadBuiltin {
        /// The place.
        place: String,
        /// What is wrong, with the action's text.
        #[source]
        reason: builtin::BuiltinError,
    },
    /// A place's action is neither registered nor a built-in.
    #[error(
        "place `{place}`: action `{action}` is not registered and not a built-in (`wait [S]`, `log MSG`, `fire T [after S]`); registered: {}",
        if known.is_empty() { "none".to_string() } else { known.join(", ") }
    )]
    UnknownAction {
        /// The place.
        place: String,
        /// The action's name.
        action: String,
        /// The names registered on the builder, sorted.
        known: Vec<String>,
    },
    /// The journal file could not be created.
    #[error("journal {path}: {source}")]
    Journal {
        /// The file.
        path: PathBuf,
        /// Why, as the system said it.
        source: std::io::Error,
    },
}

/// The net, for callers that built the run from a plan.
pub fn net_of(handle: &RuntimeHandle) -> &Net {
    handle.net()
}
