//! Events: every change of a run, numbered and timed, on a broadcast bus.
//!
//! A slow subscriber never slows the supervisor: the bus keeps the last `capacity` events and
//! a subscriber that falls behind is told how many it missed ([`Received::Lagged`]).

use std::sync::Arc;

use serde::{Deserialize, Serialize};
use tokio::sync::broadcast;

use super::StopReason;
use super::action::{Outcome, OutputStream};
use super::id::AgentId;
use crate::net::{Marking, PlaceId, TransitionId};

/// One change of a run.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Event {
    /// Sequence number, from 0, without gaps.
    pub seq: u64,
    /// Model time (seconds).
    pub time: f64,
    /// What happened.
    #[serde(flatten)]
    pub kind: EventKind,
}

/// What happened.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
pub enum EventKind {
    /// A transition fired. `consumed` are the agents taken from action places (arc order),
    /// `produced` the agents now in its output action places (continuing ones first).
    Fired {
        /// The transition.
        transition: TransitionId,
        /// Agents consumed.
        consumed: Vec<AgentId>,
        /// Agents produced (continuing, then new).
        produced: Vec<AgentId>,
        /// The marking after the firing.
        marking: Marking,
        /// Robots of the consumed agents, in the same order (empty when no robot is bound).
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        robots: Vec<Arc<str>>,
    },
    /// A new agent exists (initial token or fork).
    AgentSpawned {
        /// The agent.
        agent: AgentId,
        /// Its place.
        place: PlaceId,
        /// The robot it is bound to, when there is one.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        robot: Option<Arc<str>>,
    },
    /// An agent's action started.
    ActionStarted {
        /// The agent.
        agent: AgentId,
        /// The action place.
        place: PlaceId,
        /// 0 the first time, then retries.
        attempt: u32,
    },
    /// An agent's action ended.
    ActionEnded {
        /// The agent.
        agent: AgentId,
        /// The action place.
        place: PlaceId,
        /// How it ended.
        outcome: Outcome,
    },
    /// A line an agent's action printed (a program's stdout or stderr, a worker's `output`
    /// message), at most [`MAX_OUTPUT_LINE`](super::action::MAX_OUTPUT_LINE) bytes.
    ActionOutput {
        /// The agent.
        agent: AgentId,
        /// The action place.
        place: PlaceId,
        /// Where the line came from.
        stream: OutputStream,
        /// The line, without its newline.
        line: String,
    },
    /// An agent ended (consumed by a join: the thesis's *Void*).
    AgentEnded {
        /// The agent.
        agent: AgentId,
    },
    /// Something went wrong that the user should see (a wrong transition, a failure).
    Error {
        /// What, with names.
        message: String,
    },
    /// Something the user should know that is not an error: a decision outside the policy's
    /// table (taken by the net's weights), reported once per run.
    Warning {
        /// What, with names.
        message: String,
    },
    /// The run stopped.
    Stopped {
        /// Why.
        reason: StopReason,
    },
}

/// What a subscriber receives.
#[derive(Clone, Debug, PartialEq)]
pub enum Received {
    /// The next event.
    Event(Event),
    /// The subscriber fell behind and missed this many events.
    Lagged(u64),
}

/// A subscription to a run's events.
#[derive(Debug)]
pub struct Events(pub(crate) broadcast::Receiver<Event>);

impl Events {
    /// The next event, a lag notice, or `None` once the run is over and every event was read.
    pub async fn recv(&mut self) -> Option<Received> {
        match self.0.recv().await {
            Ok(e) => Some(Received::Event(e)),
            Err(broadcast::error::RecvError::Lagged(n)) => Some(Received::Lagged(n)),
            Err(broadcast::error::RecvError::Closed) => None,
        }
    }

    /// Reads every remaining event until the run is over, ignoring lag notices.
    pub async fn collect(mut self) -> Vec<Event> {
        let mut v = Vec::new();
        while let Some(r) = self.recv().await {
            if let Received::Event(e) = r {
                v.push(e);
            }
        }
        v
    }
}
