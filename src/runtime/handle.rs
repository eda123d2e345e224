//! The handle of a running plan and the summary it ends with.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use kameo::actor::ActorRef;
use serde::Serialize;
use tokio::sync::{broadcast, watch};

use super::StopReason;
use super::agent::AgentState;
use super::by_name::InNetOrder;
use super::engine::Engine;
use super::event::{Event, Events};
use super::id::AgentId;
use super::journal::JournalTap;
use super::reward::Earned;
use super::supervisor::{GetAgents, GetMarking, StopRequest, Supervisor};
use crate::net::{Marking, Net, PlaceId};

/// Counters the supervisor updates as it goes (lock-free reads for progress displays).
#[derive(Debug, Default)]
pub struct Progress {
    pub(crate) firings: AtomicU64,
    pub(crate) time: AtomicU64,
    pub(crate) started: AtomicBool,
}

impl Progress {
    /// Firings so far.
    pub fn firings(&self) -> u64 {
        self.firings.load(Ordering::Relaxed)
    }
    /// Model time of the last firing.
    pub fn time(&self) -> f64 {
        f64::from_bits(self.time.load(Ordering::Relaxed))
    }
    /// True once the initial agents exist and their actions were started.
    pub fn started(&self) -> bool {
        self.started.load(Ordering::Acquire)
    }
}

/// One live agent.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct AgentInfo {
    /// Its id.
    pub id: AgentId,
    /// Its place.
    pub place: PlaceId,
    /// Its state.
    pub state: AgentState,
    /// The robot it is bound to, when there is one.
    pub robot: Option<Arc<str>>,
}

/// How a run ended, with its statistics. The JSON form (`plan-runner run --json`) has exactly
/// the keys `stopped, firings, time, agents_spawned, agents_ended, final_marking, mean_tokens,
/// throughput, errors`, plus `rewards` when the plan has `[rewards.NAME]` and `warnings` when
/// there are some.
#[derive(Clone, Debug, Serialize)]
pub struct Summary {
    /// Why the run stopped.
    pub stopped: StopReason,
    /// Transitions fired.
    pub firings: u64,
    /// Model time at the end (seconds).
    pub time: f64,
    /// Agents created (initial ones and forks).
    pub agents_spawned: u64,
    /// Agents ended by joins.
    pub agents_ended: u64,
    /// Tokens per place at the end, by name, in net order.
    pub final_marking: InNetOrder<u32>,
    /// Time-averaged tokens per place, by name, in net order.
    pub mean_tokens: InNetOrder<f64>,
    /// Firings per unit of model time, per transition, by name, in net order.
    pub throughput: InNetOrder<f64>,
    /// Errors seen during the run, in order.
    pub errors: Vec<String>,
    /// What each reward structure earned, by name (with a 95% interval of its rate).
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub rewards: BTreeMap<String, Earned>,
    /// Warnings of the run (each also a [`EventKind::Warning`](super::EventKind::Warning)
    /// event), in order.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub warnings: Vec<String>,
    /// The final marking, by place id.
    #[serde(skip)]
    pub marking: Marking,
}

impl Summary {
    pub(crate) fn new(
        eng: &Engine,
        stopped: StopReason,
        now: f64,
        errors: Vec<String>,
        warnings: Vec<String>,
    ) -> Self {
        let net = eng.net();
        let (agents_spawned, agents_ended) = eng.agent_counts();
        let stats = eng.statistics(now);
        Summary {
            stopped,
            firings: eng.firings(),
            time: now,
            agents_spawned,
            agents_ended,
            final_marking: net
                .places()
                .iter()
                .zip(eng.marking().iter())
                .map(|(p, &k)| (p.name.clone(), k))
                .collect(),
            mean_tokens: net
                .places()
                .iter()
                .zip(stats.mean_tokens)
                .map(|(p, x)| (p.name.clone(), x))
                .collect(),
            throughput: net
                .transitions()
                .iter()
                .zip(stats.throughput)
                .map(|(t, x)| (t.name.clone(), x))
                .collect(),
            errors,
            rewards: eng.rewards(now),
            warnings,
            marking: eng.marking().clone(),
        }
    }

    /// The process exit code for this end: 0 done, 1 failure, 130 interrupted.
    pub fn exit_code(&self) -> u8 {
        self.stopped.exit_code()
    }
}

/// A running plan: events, a marking snapshot, stop, wait.
#[derive(Debug)]
pub struct RuntimeHandle {
    pub(crate) sup: ActorRef<Supervisor>,
    pub(crate) done: watch::Receiver<Option<Arc<Summary>>>,
    pub(crate) first: Option<Events>,
    pub(crate) bus: broadcast::WeakSender<Event>,
    pub(crate) progress: Arc<Progress>,
    pub(crate) net: Arc<Net>,
    pub(crate) warnings: Vec<String>,
    pub(crate) seed: u64,
    pub(crate) journal_tap: Option<JournalTap>,
}

impl RuntimeHandle {
    /// A tap to add side records to the run's journal (`None` without a journal).
    pub fn journal_tap(&self) -> Option<JournalTap> {
        self.journal_tap.clone()
    }

    /// The run's events. The first call gets every event since the start (as far as the
    /// bus's capacity reaches); later calls get the events from now on.
    pub fn events(&mut self) -> Events {
        if let Some(e) = self.first.take() {
            return e;
        }
        match self.bus.upgrade() {
            Some(tx) => Events(tx.subscribe()),
            None => {
                let (tx, rx) = broadcast::channel(1);
                drop(tx);
                Events(rx)
            }
        }
    }

    /// The current marking (the final one once the run is over).
    pub async fn marking(&self) -> Marking {
        match self.sup.ask(GetMarking).await {
            Ok(m) => Marking::from(m),
            Err(_) => self
                .done
                .borrow()
                .as_ref()
                .map(|s| s.marking.clone())
                .unwrap_or_else(|| self.net.initial_marking()),
        }
    }

    /// Every live agent with its place and state (empty once the run is over).
    pub async fn agents(&self) -> Vec<AgentInfo> {
        self.sup.ask(GetAgents).await.unwrap_or_default()
    }

    /// Asks the run to stop: running actions are cancelled, the journal is flushed, and the
    /// summary says [`StopReason::Requested`].
    pub fn stop(&self) {
        let _ = self.sup.tell(StopRequest(StopReason::Requested)).try_send();
    }

    /// Like [`RuntimeHandle::stop`], reported as an interruption (Ctrl-C, exit code 130).
    pub fn interrupt(&self) {
        let _ = self
            .sup
            .tell(StopRequest(StopReason::Interrupted))
            .try_send();
    }

    /// Live counters (firings, model time).
    pub fn progress(&self) -> Arc<Progress> {
        Arc::clone(&self.progress)
    }

    /// The net being run.
    pub fn net(&self) -> &Arc<Net> {
        &self.net
    }

    /// What the builder accepted but wants to say (e.g. a place whose action is not registered
    /// and so is net-timed).
    pub fn warnings(&self) -> &[String] {
        &self.warnings
    }

    /// The seed of the run.
    pub fn seed(&self) -> u64 {
        self.seed
    }

    /// True once the run is over.
    pub fn is_finished(&self) -> bool {
        self.done.borrow().is_some()
    }

    /// Waits for the run to end and returns its summary.
    pub async fn wait(&self) -> Summary {
        let mut rx = self.done.clone();
        let got = rx.wait_for(|s| s.is_some()).await;
        match got {
            Ok(s) => s.as_ref().map(|s| (**s).clone()).expect("checked"),
            Err(_) => {
                // The supervisor is gone without a summary (it cannot panic on user input;
                // this is a bug): report it rather than hang.
                let last = self.done.borrow().clone();
                last.map(|s| (*s).clone()).unwrap_or_else(|| Summary {
                    stopped: StopReason::Failure,
                    firings: self.progress.firings(),
                    time: self.progress.time(),
                    agents_spawned: 0,
                    agents_ended: 0,
                    final_marking: InNetOrder::default(),
                    mean_tokens: InNetOrder::default(),
                    throughput: InNetOrder::default(),
                    errors: vec!["the supervisor ended without a summary".into()],
                    rewards: BTreeMap::new(),
                    warnings: Vec::new(),
                    marking: self.net.initial_marking(),
                })
            }
        }
    }
}
