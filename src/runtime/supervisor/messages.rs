//! The supervisor's messages and their handlers. Each handler ends its turn by firing what is
//! ready, rescheduling the race, and stopping the actor once the run has finished.

use kameo::message::{Context, Message};

use super::super::StopReason;
use super::super::action::{ActionDone, Outcome};
use super::super::agent::AgentState;
use super::super::engine::Ready;
use super::super::event::EventKind;
use super::super::handle::AgentInfo;
use super::Supervisor;

/// The next net-timed firing (or the time limit) is due.
#[derive(Debug)]
pub(super) struct Timer {
    pub(super) generation: u64,
    pub(super) at: f64,
    pub(super) limit: bool,
}

/// Play the next batch of the virtual-time fast path.
#[derive(Debug)]
pub(super) struct Continue;

/// Stop the run.
#[derive(Debug)]
pub(crate) struct StopRequest(pub(crate) StopReason);

/// The grace period for cancelled actions is over.
#[derive(Debug)]
pub(super) struct StopDeadline;

/// Ask for the current marking.
#[derive(Debug)]
pub(crate) struct GetMarking;

/// Ask for every live agent.
#[derive(Debug)]
pub(crate) struct GetAgents;

macro_rules! finish_turn {
    ($self:ident, $ctx:ident) => {
        if $self.finished {
            $ctx.stop();
        }
    };
}

impl Message<ActionDone> for Supervisor {
    type Reply = ();

    async fn handle(&mut self, msg: ActionDone, ctx: &mut Context<Self, ()>) {
        if self.action_done(msg) {
            self.settle();
            self.schedule();
        }
        finish_turn!(self, ctx)
    }
}

impl Supervisor {
    /// Records one action's end; true when the caller should fire what is ready and
    /// reschedule (reports arriving together are recorded first, in order, then settled once).
    pub(super) fn action_done(&mut self, msg: ActionDone) -> bool {
        let Some(rec) = self.eng.agent(msg.agent) else {
            return false;
        };
        if rec.ticket != msg.ticket || rec.state != AgentState::Occupied {
            return false;
        }
        let (place, attempt) = (rec.place, rec.attempt);
        self.eng.action_ended();
        self.clock.advance();
        self.set_state(msg.agent, AgentState::Done);
        // A place without an action has no action events.
        let passive = self
            .eng
            .action_index(place)
            .is_some_and(|a| self.setups[a].passive);
        if self.observed() && !passive {
            self.emit(EventKind::ActionEnded {
                agent: msg.agent,
                place,
                outcome: msg.outcome.clone(),
            });
        }
        if self.stopping.is_some() {
            if self.eng.running() == 0 {
                self.finish();
            }
            return false;
        }
        if let Some(u) = self.stop.time_limit
            && self.now() >= u
        {
            self.clock.jump_to(u);
            self.begin_stop(StopReason::TimeLimit);
            return false;
        }
        let pname = || self.eng.net().place(place).name.clone();
        match msg.outcome {
            Outcome::Fire(t) => {
                if self.eng.consumes(place, t) {
                    self.eng.ready(msg.agent, Ready::Fire(t));
                } else {
                    let pname = pname();
                    let tname = self
                        .eng
                        .net()
                        .transitions()
                        .get(t.index())
                        .map_or_else(|| format!("#{}", t.0), |x| x.name.clone());
                    let m = format!(
                        "agent {} in `{pname}` returned transition `{tname}`, which is not an output of `{pname}`",
                        msg.agent.0
                    );
                    self.errors.push(m.clone());
                    self.emit(EventKind::Error { message: m });
                    self.failure(msg.agent, place, attempt);
                }
            }
            Outcome::Decide => self.eng.ready(msg.agent, Ready::Decide),
            Outcome::Failed(r) => {
                let m = format!("agent {} in `{}` failed: {r}", msg.agent.0, pname());
                self.errors.push(m.clone());
                self.emit(EventKind::Error { message: m });
                self.failure(msg.agent, place, attempt);
            }
            Outcome::Cancelled => {
                let m = format!(
                    "agent {} in `{}` cancelled its action",
                    msg.agent.0,
                    pname()
                );
                self.errors.push(m);
                self.failure(msg.agent, place, attempt);
            }
        }
        true
    }
}

impl Message<Timer> for Supervisor {
    type Reply = ();

    async fn handle(&mut self, msg: Timer, ctx: &mut Context<Self, ()>) {
        if self.stopping.is_some() || !self.clock.fired(msg.generation) {
            return;
        }
        self.clock.jump_to(msg.at.max(self.now()));
        if msg.limit {
            self.begin_stop(StopReason::TimeLimit);
        } else {
            if let Some(t) = self.eng.pick_race() {
                self.fire_one(t);
                self.settle();
            }
            self.schedule();
        }
        finish_turn!(self, ctx)
    }
}

impl Message<Continue> for Supervisor {
    type Reply = ();

    async fn handle(&mut self, _: Continue, ctx: &mut Context<Self, ()>) {
        self.continue_pending = false;
        if self.stopping.is_none() {
            if self.clock.is_discrete() {
                self.drive();
            } else if self.clock.is_virtual() && self.eng.running() == 0 {
                self.fast_path();
            } else {
                self.schedule();
            }
        }
        finish_turn!(self, ctx)
    }
}

impl Message<StopRequest> for Supervisor {
    type Reply = ();

    async fn handle(&mut self, msg: StopRequest, ctx: &mut Context<Self, ()>) {
        self.clock.advance();
        self.begin_stop(msg.0);
        finish_turn!(self, ctx)
    }
}

impl Message<StopDeadline> for Supervisor {
    type Reply = ();

    async fn handle(&mut self, _: StopDeadline, ctx: &mut Context<Self, ()>) {
        if !self.finished {
            self.deliver();
        }
        if !self.finished {
            let m = format!(
                "{} action(s) did not end within {:?} of the stop",
                self.eng.running(),
                self.grace
            );
            self.errors.push(m.clone());
            self.emit(EventKind::Error { message: m });
            self.finish();
        }
        finish_turn!(self, ctx)
    }
}

impl Message<GetMarking> for Supervisor {
    type Reply = Vec<u32>;

    async fn handle(&mut self, _: GetMarking, _: &mut Context<Self, Vec<u32>>) -> Vec<u32> {
        self.eng.marking().to_vec()
    }
}

impl Message<GetAgents> for Supervisor {
    type Reply = Vec<AgentInfo>;

    async fn handle(
        &mut self,
        _: GetAgents,
        _: &mut Context<Self, Vec<AgentInfo>>,
    ) -> Vec<AgentInfo> {
        self.eng.mark_waiting();
        let mut v: Vec<AgentInfo> = self
            .eng
            .agents()
            .map(|(&id, r)| AgentInfo {
                id,
                place: r.place,
                state: r.state,
                robot: r.robot.clone(),
            })
            .collect();
        v.sort_by_key(|a| a.id);
        v
    }
}
