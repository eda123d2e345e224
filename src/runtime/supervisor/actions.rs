//! The supervisor's side of the agents' actions: spawning agent actors, starting an
//! action in its place (or applying an instant one), recording its output, and what a
//! place's failure policy says when one fails. The firing and stopping stay in the
//! [parent module](super).

use std::sync::Arc;

use kameo::actor::Spawn;
use kameo::mailbox;
use tokio::sync::mpsc;

use super::super::FailurePolicy;
use super::super::StopReason;
use super::super::action::{
    ActionContext, ActionDone, Limit, OutputLine, OutputSink, OutputStream,
};
use super::super::agent::{Agent, AgentMode, AgentState, Run};
use super::super::clock::{Mode, ModelClock};
use super::super::engine::Ready;
use super::super::event::EventKind;
use super::super::id::AgentId;
use super::super::place::Start;
use super::{PARALLEL_SPAWN, Supervisor};
use crate::net::PlaceId;

impl Supervisor {
    pub(super) fn spawn_agent_actor(&mut self, id: AgentId, place: PlaceId) {
        self.spawn_agent_actors(&[(id, place)]);
    }

    /// Spawns the actors of these agents ([`AgentMode::Actor`]). Many at once (the initial
    /// agents) are spawned from two threads on a multi-threaded runtime: a kameo spawn costs
    /// microseconds, and 100k of them are most of a large plan's start-up.
    pub(super) fn spawn_agent_actors(&mut self, agents: &[(AgentId, PlaceId)]) {
        if self.agent_mode != AgentMode::Actor {
            return;
        }
        let reports = &self.reports_tx;
        let spawn = |&(id, place): &(AgentId, PlaceId)| {
            let agent = Agent {
                id,
                place,
                state: AgentState::Free,
                reports: reports.clone(),
            };
            (id, Agent::spawn_with_mailbox(agent, mailbox::unbounded()))
        };
        let runtime = tokio::runtime::Handle::current();
        let parallel = agents.len() >= PARALLEL_SPAWN
            && runtime.runtime_flavor() == tokio::runtime::RuntimeFlavor::MultiThread;
        self.agent_actors.reserve(agents.len());
        if !parallel {
            self.agent_actors.extend(agents.iter().map(spawn));
            return;
        }
        let (first, second) = agents.split_at(agents.len() / 2);
        let spawned = std::thread::scope(|s| {
            let other = s.spawn(|| {
                let _inside = runtime.enter();
                second.iter().map(spawn).collect::<Vec<_>>()
            });
            let mut mine: Vec<_> = first.iter().map(spawn).collect();
            match other.join() {
                Ok(theirs) => mine.extend(theirs),
                // Not expected (spawning does not run user code); never lose an agent.
                Err(_) => mine.extend(second.iter().map(spawn)),
            }
            mine
        });
        self.agent_actors.extend(spawned);
    }

    /// Starts (or restarts) the action of an agent in its place; Inactive when the place has
    /// no output transition. An instant one ends here and now.
    pub(super) fn start_action(&mut self, id: AgentId, attempt: u32) {
        let Some(place) = self.eng.agent(id).map(|r| r.place) else {
            return;
        };
        if !self.eng.has_outputs(place) {
            self.set_state(id, AgentState::Inactive);
            return;
        }
        let a = self.ap(place);
        let ticket = self.eng.start(id, attempt);
        let passive = self.setups[a].passive;
        if let Some((outcome, line)) = self.setups[a].instant.clone() {
            if !passive {
                self.occupied(id, place, attempt);
                if let Some(line) = line {
                    self.action_output(OutputLine {
                        agent: id,
                        place,
                        stream: OutputStream::Stdout,
                        line: line.to_string(),
                    });
                }
            }
            self.action_done(ActionDone {
                agent: id,
                ticket,
                outcome,
            });
            return;
        }
        let robot = self.eng.agent(id).and_then(|r| r.robot.clone());
        let clock = match self.clock.mode() {
            Mode::Virtual => ModelClock::virtual_for(self.sleeps_tx.clone(), id, ticket),
            Mode::Tokio => ModelClock::tokio(1.0),
            Mode::Real(scale) => ModelClock::tokio(scale),
        };
        let ctx = ActionContext {
            agent: id,
            robot: robot.or_else(|| self.setups[a].robot.clone()),
            place,
            marking: self.snapshots.get(self.eng.firings(), self.eng.marking()),
            attempt,
            cancel: self.cancel_token.clone(),
            net: Arc::clone(self.eng.net()),
            seed: self.seed,
            time: self.now(),
            clock,
            output: OutputSink::new(self.output_tx.clone()),
        };
        let timeout = self.setups[a].timeout;
        let limit = match timeout {
            None => Limit::None,
            Some(seconds) if self.clock.is_discrete() => {
                let (abort_tx, abort) = tokio::sync::oneshot::channel();
                self.vt.started(
                    id,
                    ticket,
                    self.setups[a].decides,
                    Some((self.now() + seconds, abort_tx)),
                );
                Limit::Abort { abort, seconds }
            }
            Some(seconds) => Limit::After(self.clock.to_tokio(seconds)),
        };
        if self.clock.is_discrete() && timeout.is_none() {
            self.vt.started(id, ticket, self.setups[a].decides, None);
        }
        match self.agent_actors.get(&id) {
            Some(agent) => {
                let action = Arc::clone(&self.setups[a].action);
                let _ = agent
                    .tell(Run {
                        ctx,
                        ticket,
                        action,
                        limit,
                    })
                    .try_send();
            }
            None => {
                if let Some(p) = &self.places[a] {
                    let _ = p.tell(Start { ctx, ticket, limit }).try_send();
                }
            }
        }
        self.occupied(id, place, attempt);
    }

    /// The agent's action started: it is Occupied, and an `action_started` event says so.
    pub(super) fn occupied(&mut self, id: AgentId, place: PlaceId, attempt: u32) {
        self.set_state(id, AgentState::Occupied);
        if self.observed() {
            self.emit(EventKind::ActionStarted {
                agent: id,
                place,
                attempt,
            });
        }
    }

    /// Records the output lines waiting in the channel (before the reports that follow them,
    /// so a journal shows an action's output before its end).
    pub(super) fn drain_output(&mut self, rx: &mut mpsc::UnboundedReceiver<OutputLine>) {
        while let Ok(o) = rx.try_recv() {
            self.line(o);
        }
    }

    pub(super) fn action_output(&mut self, o: OutputLine) {
        if self.observed() {
            self.emit(EventKind::ActionOutput {
                agent: o.agent,
                place: o.place,
                stream: o.stream,
                line: o.line,
            });
        }
    }

    /// What the place's failure policy says after an agent's action failed (the error is
    /// already recorded).
    pub(super) fn failure(&mut self, id: AgentId, place: PlaceId, attempt: u32) {
        let a = self.ap(place);
        match self.setups[a].on_failure {
            FailurePolicy::Stop => self.begin_stop(StopReason::Failure),
            FailurePolicy::Retry(n) if attempt < n => self.start_action(id, attempt + 1),
            FailurePolicy::Retry(n) => {
                let msg = format!(
                    "agent {} in `{}`: gave up after {n} retries",
                    id.0,
                    self.eng.net().place(place).name
                );
                self.errors.push(msg.clone());
                self.emit(EventKind::Error { message: msg });
                self.begin_stop(StopReason::Failure);
            }
            FailurePolicy::Fire(t) => self.eng.ready(id, Ready::Fire(t)),
        }
    }
}
