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

impl Event {
    /// The firing this event records, if it records one: what every replay of a run
    /// (a journal's frames, a conformance trace) steps through, read in one place.
    pub fn firing(&self) -> Option<Firing<'_>> {
        match &self.kind {
            EventKind::Fired {
                transition,
                marking,
                ..
            } => Some(Firing {
                seq: self.seq,
                time: self.time,
                transition: *transition,
                marking,
            }),
            _ => None,
        }
    }
}

/// A transition's firing, as [`Event::firing`] reads it from an event.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Firing<'a> {
    /// The event's sequence number.
    pub seq: u64,
    /// Model time.
    pub time: f64,
    /// What fired.
    pub transition: TransitionId,
    /// The marking after the firing.
    pub marking: &'a Marking,
}

/// What happened.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "event", rename_all = "snake_case")]
#[non_exhaustive]
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
    /// A monitored statistic left the model's prediction (emitted right after the firing
    /// that showed it, by the run's [`Watcher`]: `plan-runner run --monitor`).
    Drift(Drift),
}

/// What a [`Drift`] is about.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Monitored {
    /// A transition's rate: firings per unit of enabled time.
    Transition(TransitionId),
    /// A place's time-average tokens.
    Place(PlaceId),
}

/// A transition's recent rate, or a place's recent mean tokens, outside the model's
/// prediction (see `gspn::conform::Monitor`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Drift {
    /// The transition or place.
    pub of: Monitored,
    /// The observation over the monitor's window.
    pub observed: f64,
    /// The model's value.
    pub predicted: f64,
    /// The 95% interval of the observation.
    pub interval: [f64; 2],
    /// Its sample size: firings (a rate) or batches (mean tokens) in the window.
    pub n: u64,
    /// The test's p-value.
    pub p_value: f64,
}

impl Drift {
    /// One line for people: what drifted, by how much, and the model's value.
    pub fn describe(&self, net: &crate::net::Net) -> String {
        let (what, unit) = match self.of {
            Monitored::Transition(t) => (
                net.transition(t).name.as_str(),
                "firings per unit of enabled time over the last",
            ),
            Monitored::Place(p) => (net.place(p).name.as_str(), "mean tokens over the last"),
        };
        let window = match self.of {
            Monitored::Transition(_) => "firings",
            Monitored::Place(_) => "batches",
        };
        format!(
            "{what}: {:.4} {unit} {} {window}, 95% [{:.4}, {:.4}]; the net says {:.4} (p {:.1e})",
            self.observed, self.n, self.interval[0], self.interval[1], self.predicted, self.p_value
        )
    }
}

/// Follows every firing as the supervisor makes it and reports drifts, which the supervisor
/// emits as [`EventKind::Drift`] events right after the firing, into the journal and onto the
/// bus (`gspn::conform::Monitor` is one). It runs inside the supervisor's turn: keep it cheap.
pub trait Watcher: Send + 'static {
    /// `t` fired at model time `time`, leaving `marking`: the drifts found now.
    fn fired(&mut self, time: f64, t: TransitionId, marking: &[u32]) -> Vec<Drift>;
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
