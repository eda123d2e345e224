//! The supervisor's state machine, without actors or time: the marking, the agents and what
//! they are ready for, firing with agent identity. The firing rules (the immediate choice,
//! the race with server semantics, the statistics) are [`crate::firing`]'s: the engine is its
//! agent-readiness-filtered chooser — an immediate transition is a candidate when its input
//! places' agents are ready for it, an exponential one races with as many servers as agents
//! handed the choice back to the net. With no action bound, that is the net's own rules, and
//! the engine draws exactly what the token game draws from the same seed. The supervisor
//! actor drives it; keeping it synchronous keeps firing cheap.

use std::collections::{BTreeMap, VecDeque};
use std::sync::Arc;

use rustc_hash::FxHashMap;

use super::agent::AgentState;
use super::id::AgentId;
use super::reward::{Earned, Meter};
use crate::analysis::decision::RewardSpec;
use crate::firing::{Firable, Statistics, Tally};
use crate::net::{Marking, Net, PlaceId, Timing, TokenOverflow, TransitionId};
use crate::policy::Policy;
use crate::sample::{self, Rng};

/// The random stream of [`Engine::pick`].
const PICK_STREAM: u64 = 0x7069_636b; // "pick"

/// What an agent's finished action made it ready for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ready {
    Fire(TransitionId),
    Decide,
}

#[derive(Debug)]
pub(crate) struct AgentRec {
    pub(crate) place: PlaceId,
    pub(crate) state: AgentState,
    /// Which start of the action the supervisor waits for (stale reports are ignored).
    pub(crate) ticket: u64,
    pub(crate) attempt: u32,
    /// The robot bound to the agent, kept through firings.
    pub(crate) robot: Option<Arc<str>>,
}

/// Per action place: who is ready for what, in arrival order.
#[derive(Debug)]
pub(crate) struct ActionPlace {
    /// Transitions consuming from the place.
    pub(crate) consumers: Vec<TransitionId>,
    /// Per consumer: agents whose action returned `Fire(consumer)`.
    fire_q: Vec<VecDeque<AgentId>>,
    /// Agents whose action returned `Decide`.
    decide_q: VecDeque<AgentId>,
}

impl ActionPlace {
    fn local(&self, t: TransitionId) -> Option<usize> {
        self.consumers.iter().position(|&u| u == t)
    }
    fn ready_for(&self, t: TransitionId) -> usize {
        self.local(t).map_or(0, |i| self.fire_q[i].len()) + self.decide_q.len()
    }
}

/// The effects of one firing, for events and for starting actions.
#[derive(Debug, Default)]
pub(crate) struct Firing {
    pub(crate) transition: Option<TransitionId>,
    pub(crate) consumed: Vec<AgentId>,
    pub(crate) produced: Vec<AgentId>,
    pub(crate) spawned: Vec<AgentId>,
    pub(crate) ended: Vec<AgentId>,
    /// Robots of the consumed agents, in consumption order (empty without robots).
    pub(crate) robots: Vec<Arc<str>>,
}

#[derive(Debug)]
pub(crate) struct Engine {
    net: Arc<Net>,
    m: Marking,
    policy: Policy,
    rng: Rng,
    /// Which in-service agent a net-timed race takes (its own stream: the race's draws stay
    /// the token game's).
    pick: Rng,
    /// Per place: index into `aps` when it is an action place.
    action_of: Vec<Option<u32>>,
    aps: Vec<ActionPlace>,
    agents: FxHashMap<AgentId, AgentRec>,
    next_agent: u64,
    next_ticket: u64,
    /// Exponential transitions some agent returned `Fire` for, in arrival order.
    pending: Vec<TransitionId>,
    in_pending: Vec<bool>,
    /// What may fire: the net's rules filtered by what the agents are ready for.
    firable: Firable,
    /// Agents with a running action.
    running: usize,
    firings: u64,
    tally: Tally,
    agents_spawned: u64,
    agents_ended: u64,
    /// Some agent is bound to a robot (firings then report the robots they moved).
    has_robots: bool,
    /// The plan's rewards earned so far.
    meter: Meter,
    /// Decisions taken by the net's weights because no policy rule applied, and the first
    /// marking where that happened (not yet reported).
    policy_misses: u64,
    first_miss: Option<Marking>,
}

impl Engine {
    /// The net being executed.
    pub(crate) fn net(&self) -> &Arc<Net> {
        &self.net
    }

    /// The current marking.
    pub(crate) fn marking(&self) -> &Marking {
        &self.m
    }

    /// Firings so far.
    pub(crate) fn firings(&self) -> u64 {
        self.firings
    }

    /// Agents whose action is running.
    pub(crate) fn running(&self) -> usize {
        self.running
    }

    /// Agents created and ended so far.
    pub(crate) fn agent_counts(&self) -> (u64, u64) {
        (self.agents_spawned, self.agents_ended)
    }

    /// The live agents.
    pub(crate) fn agents(&self) -> impl Iterator<Item = (&AgentId, &AgentRec)> {
        self.agents.iter()
    }

    /// A live agent's record.
    pub(crate) fn agent(&self, id: AgentId) -> Option<&AgentRec> {
        self.agents.get(&id)
    }

    /// Sets a live agent's state; its place, or `None` for an agent that has ended.
    pub(crate) fn set_state(&mut self, id: AgentId, state: AgentState) -> Option<PlaceId> {
        let rec = self.agents.get_mut(&id)?;
        rec.state = state;
        Some(rec.place)
    }

    /// The index of action place `p` among the action places (`None` for other places).
    pub(crate) fn action_index(&self, p: PlaceId) -> Option<usize> {
        self.action_of[p.index()].map(|a| a as usize)
    }

    /// Whether `t` consumes the agents of action place `p`.
    pub(crate) fn consumes(&self, p: PlaceId, t: TransitionId) -> bool {
        self.action_of[p.index()].is_some_and(|a| self.aps[a as usize].consumers.contains(&t))
    }

    pub(crate) fn new(
        net: Arc<Net>,
        action_places: &[PlaceId],
        policy: Policy,
        rewards: Vec<RewardSpec>,
        rng: Rng,
    ) -> Engine {
        let mut action_of = vec![None; net.place_count()];
        let mut aps = Vec::new();
        for &p in action_places {
            action_of[p.index()] = Some(aps.len() as u32);
            let consumers = net.consumers(p).to_vec();
            aps.push(ActionPlace {
                fire_q: vec![VecDeque::new(); consumers.len()],
                consumers,
                decide_q: VecDeque::new(),
            });
        }
        let nt = net.transition_count();
        let mut e = Engine {
            m: net.initial_marking(),
            policy,
            pick: {
                let mut pick = rng.clone();
                pick.set_stream(PICK_STREAM);
                pick
            },
            rng,
            action_of,
            aps,
            agents: FxHashMap::default(),
            next_agent: 0,
            next_ticket: 0,
            pending: Vec::new(),
            in_pending: vec![false; nt],
            firable: Firable::new(&net),
            running: 0,
            firings: 0,
            tally: Tally::new(&net),
            agents_spawned: 0,
            agents_ended: 0,
            has_robots: false,
            meter: Meter::new(&net, rewards, &net.initial_marking()),
            policy_misses: 0,
            first_miss: None,
            net,
        };
        for t in e.net.transition_ids() {
            e.update(t);
        }
        e
    }

    /// Creates an agent in `p` (state Free); the caller starts its action.
    pub(crate) fn new_agent(&mut self, p: PlaceId) -> AgentId {
        let id = AgentId(self.next_agent);
        self.next_agent += 1;
        self.agents_spawned += 1;
        self.agents.insert(
            id,
            AgentRec {
                place: p,
                state: AgentState::Free,
                ticket: 0,
                attempt: 0,
                robot: None,
            },
        );
        id
    }

    /// Binds the initial agents to their robots, in order (none: no robots).
    pub(crate) fn bind_robots(
        &mut self,
        agents: impl Iterator<Item = AgentId>,
        robots: Vec<Arc<str>>,
    ) {
        self.has_robots = !robots.is_empty();
        for (id, robot) in agents.zip(robots) {
            if let Some(rec) = self.agents.get_mut(&id) {
                rec.robot = Some(robot);
            }
        }
    }

    /// An agent's running action ended (its report was accepted).
    pub(crate) fn action_ended(&mut self) {
        self.running -= 1;
    }

    /// True when a place's agents have something to do (an output transition).
    pub(crate) fn has_outputs(&self, p: PlaceId) -> bool {
        self.action_of[p.index()].is_some_and(|a| !self.aps[a as usize].consumers.is_empty())
    }

    /// Marks the agent's action as started; returns its ticket.
    pub(crate) fn start(&mut self, id: AgentId, attempt: u32) -> u64 {
        self.next_ticket += 1;
        let ticket = self.next_ticket;
        if let Some(a) = self.agents.get_mut(&id) {
            a.state = AgentState::Occupied;
            a.ticket = ticket;
            a.attempt = attempt;
            self.running += 1;
        }
        ticket
    }

    /// Records an agent's readiness after its action ended (the caller checked the ticket and
    /// that a `Fire` names an output of the place).
    pub(crate) fn ready(&mut self, id: AgentId, r: Ready) {
        let Some(rec) = self.agents.get_mut(&id) else {
            return;
        };
        rec.state = AgentState::Done;
        let p = rec.place;
        let Some(a) = self.action_of[p.index()] else {
            return;
        };
        let ap = &mut self.aps[a as usize];
        match r {
            Ready::Fire(t) => {
                if let Some(i) = ap.local(t) {
                    ap.fire_q[i].push_back(id);
                    if self.net.transition(t).is_immediate() {
                        self.update(t);
                    } else if !self.in_pending[t.index()] {
                        self.in_pending[t.index()] = true;
                        self.pending.push(t);
                    }
                }
            }
            Ready::Decide => {
                ap.decide_q.push_back(id);
                self.update_consumers(a as usize);
            }
        }
    }

    fn update_consumers(&mut self, a: usize) {
        for i in 0..self.aps[a].consumers.len() {
            let t = self.aps[a].consumers[i];
            self.update(t);
        }
    }

    /// Re-evaluates `t` for the firing core: an immediate transition is a candidate when it
    /// is ready; an exponential one races with at most as many servers as agents in its
    /// action places handed the choice back to the net (`Decide`).
    fn update(&mut self, t: TransitionId) {
        if self.net.transition(t).is_immediate() {
            let on = self.is_ready(t);
            self.firable.set_immediate(&self.net, t, on);
            return;
        }
        let mut cap = u32::MAX;
        for &(p, w) in self.net.inputs(t) {
            if let Some(a) = self.action_of[p.index()] {
                cap = cap.min((self.aps[a as usize].decide_q.len() as u32) / w);
            }
        }
        self.firable.refresh_capped(&self.net, &self.m, t, cap);
    }

    fn is_ready(&self, t: TransitionId) -> bool {
        self.net.is_enabled(&self.m, t)
            && self.net.inputs(t).iter().all(|&(p, w)| {
                self.action_of[p.index()]
                    .is_none_or(|a| self.aps[a as usize].ready_for(t) >= w as usize)
            })
    }

    fn still_reported(&self, t: TransitionId) -> bool {
        self.net.inputs(t).iter().any(|&(p, _)| {
            self.action_of[p.index()].is_some_and(|a| {
                let ap = &self.aps[a as usize];
                ap.local(t).is_some_and(|i| !ap.fire_q[i].is_empty())
            })
        })
    }

    /// The next transition the supervisor fires at once: a ready immediate one (the firing
    /// core's choice: highest priority, policy else weights), else a reported exponential
    /// one in arrival order.
    #[inline]
    pub(crate) fn next_ready(&mut self) -> Option<TransitionId> {
        if self.firable.is_vanishing() {
            let t = self
                .firable
                .choose_immediate(&self.m, Some(&self.policy), &mut self.rng);
            if self.firable.outside_policy() {
                self.policy_misses += 1;
                if self.policy_misses == 1 {
                    self.first_miss = Some(self.m.clone());
                }
            }
            return Some(t);
        }
        let mut i = 0;
        while i < self.pending.len() {
            let t = self.pending[i];
            if !self.still_reported(t) {
                self.in_pending[t.index()] = false;
                self.pending.remove(i);
                continue;
            }
            if self.is_ready(t) {
                return Some(t);
            }
            i += 1;
        }
        None
    }

    /// The total rate of the net-timed race (0: nothing races).
    pub(crate) fn race_total(&self) -> f64 {
        self.firable.race_total()
    }

    /// Changes whenever a rate of the race changes (a pending sample stays valid until then).
    pub(crate) fn race_version(&self) -> u64 {
        self.firable.race_version()
    }

    /// The delay to the next net-timed firing; `None` when nothing races.
    pub(crate) fn sample_delay(&mut self) -> Option<f64> {
        self.firable.sample_delay(&mut self.rng)
    }

    /// Samples the race: the delay to the next net-timed firing and the transition.
    #[inline]
    pub(crate) fn sample_race(&mut self) -> Option<(f64, TransitionId)> {
        let dt = self.firable.sample_delay(&mut self.rng)?;
        Some((dt, self.firable.pick_race(&mut self.rng)?))
    }

    /// Picks a transition of the race ∝ its rate; `None` when nothing races.
    pub(crate) fn pick_race(&mut self) -> Option<TransitionId> {
        self.firable.pick_race(&mut self.rng)
    }

    /// Fires `t` at model time `now`, moving agents by the identity rules: consumed agents
    /// continue in input-arc order into the produced tokens of agent places (output-arc
    /// order), surplus ones end (a join), extra tokens are new agents (a fork). (With robots
    /// the net conserves its tokens outside resources, so a robot never ends in a join.)
    ///
    /// A firing that would overflow a place's count changes nothing and is refused.
    #[inline]
    pub(crate) fn fire(
        &mut self,
        t: TransitionId,
        now: f64,
        out: &mut Firing,
    ) -> Result<(), TokenOverflow> {
        if let Some(o) = self.net.overflow(&self.m, t) {
            return Err(o);
        }
        out.transition = Some(t);
        out.consumed.clear();
        out.produced.clear();
        out.spawned.clear();
        out.ended.clear();
        out.robots.clear();
        let net = Arc::clone(&self.net);
        for &(p, w) in net.inputs(t) {
            if let Some(a) = self.action_of[p.index()] {
                let ap = &mut self.aps[a as usize];
                let local = ap.local(t);
                // A net-timed race of a transition with several busy servers: each
                // in-service agent (the first `active` to hand the choice back) is equally
                // likely to be the one that finishes — every token has its own server.
                let serving = match net.transition(t).timing {
                    Timing::Exponential { servers, .. } if w == 1 => {
                        servers.active(ap.decide_q.len() as u32) as usize
                    }
                    _ => 1,
                };
                for _ in 0..w {
                    let from_fire = local.and_then(|i| ap.fire_q[i].pop_front());
                    let id = from_fire.or_else(|| {
                        if serving > 1 && ap.decide_q.len() > 1 {
                            let k = (sample::uniform(&mut self.pick) * serving as f64) as usize;
                            ap.decide_q.remove(k.min(serving - 1))
                        } else {
                            ap.decide_q.pop_front()
                        }
                    });
                    if let Some(id) = id {
                        out.consumed.push(id);
                    }
                }
                // Fewer agents are ready: the place's transitions are re-evaluated.
                self.update_consumers(a as usize);
            }
        }
        if self.has_robots {
            for id in &out.consumed {
                if let Some(r) = self.agents.get(id).and_then(|r| r.robot.clone()) {
                    out.robots.push(r);
                }
            }
        }
        self.tally.fire(&net, &mut self.m, t, now)?;
        self.meter.fired(t, now, &self.m);
        self.firings += 1;
        let mut next = 0;
        for &(p, w) in net.outputs(t) {
            if self.action_of[p.index()].is_none() {
                continue;
            }
            for _ in 0..w {
                let id = if next < out.consumed.len() {
                    next += 1;
                    let id = out.consumed[next - 1];
                    if let Some(rec) = self.agents.get_mut(&id) {
                        rec.place = p;
                        rec.state = AgentState::Free;
                    }
                    id
                } else {
                    let id = self.new_agent(p);
                    out.spawned.push(id);
                    id
                };
                out.produced.push(id);
            }
        }
        for k in next..out.consumed.len() {
            let id = out.consumed[k];
            self.agents.remove(&id);
            self.agents_ended += 1;
            out.ended.push(id);
        }
        for &u in net.affected_by(t) {
            self.update(u);
        }
        Ok(())
    }

    /// Transitions some agent chose that cannot fire now (for the "never enabled" error).
    pub(crate) fn stuck(&self) -> Vec<TransitionId> {
        self.pending
            .iter()
            .copied()
            .filter(|&t| self.still_reported(t))
            .collect()
    }

    /// Agents done but not consumed become Waiting (called when the supervisor goes idle).
    pub(crate) fn mark_waiting(&mut self) {
        for rec in self.agents.values_mut() {
            if rec.state == AgentState::Done {
                rec.state = AgentState::Waiting;
            }
        }
    }

    /// The statistics over [0, now]: time-averaged tokens per place, firings per
    /// transition.
    pub(crate) fn statistics(&self, now: f64) -> Statistics {
        self.tally.read(&self.m, now)
    }

    /// The rewards earned over `[0, now]`, by name.
    pub(crate) fn rewards(&self, now: f64) -> BTreeMap<String, Earned> {
        self.meter.read(now)
    }

    /// Decisions the net's weights took because no policy rule applied.
    pub(crate) fn policy_misses(&self) -> u64 {
        self.policy_misses
    }

    /// The first marking where no policy rule applied, once (then `None`).
    pub(crate) fn take_first_miss(&mut self) -> Option<Marking> {
        self.first_miss.take()
    }
}
