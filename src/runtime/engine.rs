//! The supervisor's state machine, without actors or time: the marking, the agents and what
//! they are ready for, the race of net-timed transitions, firing with agent identity, and the
//! statistics. The supervisor actor drives it; keeping it synchronous keeps firing cheap.

use std::collections::VecDeque;
use std::sync::Arc;

use rand::RngExt;
use rand_chacha::ChaCha8Rng;
use rustc_hash::FxHashMap;

use super::agent::{AgentId, AgentState};
use crate::net::{Marking, Net, PlaceId, Timing, TokenOverflow, TransitionId};
use crate::policy::Policy;
use crate::sim::sum_tree::SumTree;

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
    pub(crate) net: Arc<Net>,
    pub(crate) m: Marking,
    policy: Policy,
    pub(crate) rng: ChaCha8Rng,
    /// Per place: index into `aps` when it is an action place.
    pub(crate) action_of: Vec<Option<u32>>,
    pub(crate) aps: Vec<ActionPlace>,
    pub(crate) agents: FxHashMap<AgentId, AgentRec>,
    next_agent: u64,
    pub(crate) next_ticket: u64,
    /// Exponential transitions some agent returned `Fire` for, in arrival order.
    pending: Vec<TransitionId>,
    in_pending: Vec<bool>,
    pub(crate) race: SumTree,
    /// Bumped whenever a race rate changes (a timer for an unchanged race stays valid).
    pub(crate) race_version: u64,
    /// Immediate transitions, highest priority first.
    immediates: Vec<(u32, TransitionId)>,
    cands: Vec<TransitionId>,
    dist: Vec<(TransitionId, f64)>,
    /// Agents with a running action.
    pub(crate) running: usize,
    // Statistics.
    pub(crate) firings: u64,
    pub(crate) counts: Vec<u64>,
    integral: Vec<f64>,
    last_change: Vec<f64>,
    pub(crate) agents_spawned: u64,
    pub(crate) agents_ended: u64,
    /// Some agent is bound to a robot (firings then report the robots they moved).
    pub(crate) has_robots: bool,
}

impl Engine {
    pub(crate) fn new(
        net: Arc<Net>,
        action_places: &[PlaceId],
        policy: Policy,
        rng: ChaCha8Rng,
    ) -> Engine {
        let mut action_of = vec![None; net.place_count()];
        let mut aps = Vec::new();
        for &p in action_places {
            action_of[p.index()] = Some(aps.len() as u32);
            let consumers: Vec<_> = net
                .transition_ids()
                .filter(|&t| net.inputs(t).iter().any(|&(q, _)| q == p))
                .collect();
            aps.push(ActionPlace {
                fire_q: vec![VecDeque::new(); consumers.len()],
                consumers,
                decide_q: VecDeque::new(),
            });
        }
        let mut immediates: Vec<(u32, TransitionId)> = net
            .transition_ids()
            .filter_map(|t| match net.transition(t).timing {
                Timing::Immediate { priority, .. } => Some((priority, t)),
                Timing::Exponential { .. } => None,
            })
            .collect();
        immediates.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
        let (np, nt) = (net.place_count(), net.transition_count());
        let mut e = Engine {
            m: net.initial_marking(),
            policy,
            rng,
            action_of,
            aps,
            agents: FxHashMap::default(),
            next_agent: 0,
            next_ticket: 0,
            pending: Vec::new(),
            in_pending: vec![false; nt],
            race: SumTree::new(nt),
            race_version: 0,
            immediates,
            cands: Vec::new(),
            dist: Vec::new(),
            running: 0,
            firings: 0,
            counts: vec![0; nt],
            integral: vec![0.0; np],
            last_change: vec![0.0; np],
            agents_spawned: 0,
            agents_ended: 0,
            has_robots: false,
            net,
        };
        for t in e.net.transition_ids() {
            e.update_race(t);
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
                    if !self.net.transition(t).is_immediate() && !self.in_pending[t.index()] {
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
            self.update_race(t);
        }
    }

    /// The rate at which the supervisor samples `t`: net-timed exponential transitions, and
    /// event-driven ones as far as `Decide` agents hand them back to the net.
    fn race_rate(&self, t: TransitionId) -> f64 {
        let Timing::Exponential { rate, servers } = self.net.transition(t).timing else {
            return 0.0;
        };
        let mut d = self.net.enabled_degree(&self.m, t);
        if d == 0 {
            return 0.0;
        }
        for &(p, w) in self.net.inputs(t) {
            if let Some(a) = self.action_of[p.index()] {
                d = d.min((self.aps[a as usize].decide_q.len() as u32) / w);
            }
        }
        rate * servers.active(d) as f64
    }

    fn update_race(&mut self, t: TransitionId) {
        let r = self.race_rate(t);
        if self.race.get(t.index()) != r {
            self.race.set(t.index(), r);
            self.race_version += 1;
        }
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

    /// The next transition the supervisor fires at once: a ready immediate one (highest
    /// priority, policy else weights), else a reported exponential one in arrival order.
    pub(crate) fn next_ready(&mut self) -> Option<TransitionId> {
        if !self.immediates.is_empty() {
            self.cands.clear();
            let mut best = 0;
            for k in 0..self.immediates.len() {
                let (prio, t) = self.immediates[k];
                if !self.cands.is_empty() && prio < best {
                    break;
                }
                if self.is_ready(t) {
                    best = prio;
                    self.cands.push(t);
                }
            }
            if !self.cands.is_empty() {
                return Some(self.choose_immediate());
            }
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

    fn choose_immediate(&mut self) -> TransitionId {
        if self.cands.len() == 1 {
            return self.cands[0];
        }
        let mut dist = std::mem::take(&mut self.dist);
        if !self
            .policy
            .distribution_into(&self.net, &self.m, &self.cands, &mut dist)
        {
            dist.clear();
            for &t in &self.cands {
                if let Timing::Immediate { weight, .. } = self.net.transition(t).timing {
                    dist.push((t, weight));
                }
            }
            if dist.iter().all(|&(_, w)| w <= 0.0) {
                // Weight 0 everywhere and no rule: a decision nobody made; choose uniformly.
                dist.iter_mut().for_each(|d| d.1 = 1.0);
            }
        }
        let total: f64 = dist.iter().map(|d| d.1).sum();
        let mut u = self.rng.random::<f64>() * total;
        let mut pick = dist[dist.len() - 1].0;
        for &(t, w) in &dist {
            if u < w {
                pick = t;
                break;
            }
            u -= w;
        }
        self.dist = dist;
        pick
    }

    /// Samples the race: the delay to the next net-timed firing and the transition.
    pub(crate) fn sample_race(&mut self) -> Option<(f64, TransitionId)> {
        let total = self.race.total();
        if total <= 0.0 {
            return None;
        }
        let u: f64 = self.rng.random::<f64>();
        let dt = -(1.0 - u).ln() / total;
        Some((dt, self.pick_race()))
    }

    /// Picks a transition of the race ∝ its rate.
    pub(crate) fn pick_race(&mut self) -> TransitionId {
        let u = self.rng.random::<f64>() * self.race.total();
        TransitionId(self.race.find(u) as u32)
    }

    /// Fires `t` at model time `now`, moving agents by the identity rules: consumed agents
    /// continue in arc order into the produced action-place tokens, surplus ones end, extra
    /// tokens are new agents.
    ///
    /// A firing that would overflow a place's count changes nothing and is refused.
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
                let mut decided = false;
                for _ in 0..w {
                    let id = local.and_then(|i| ap.fire_q[i].pop_front()).or_else(|| {
                        decided = true;
                        ap.decide_q.pop_front()
                    });
                    if let Some(id) = id {
                        out.consumed.push(id);
                    }
                }
                if decided {
                    self.update_consumers(a as usize);
                }
            }
        }
        if self.has_robots {
            for id in &out.consumed {
                if let Some(r) = self.agents.get(id).and_then(|r| r.robot.clone()) {
                    out.robots.push(r);
                }
            }
        }
        for &(p, _) in net.delta(t) {
            let i = p.index();
            self.integral[i] += self.m.as_slice()[i] as f64 * (now - self.last_change[i]);
            self.last_change[i] = now;
        }
        net.fire(&mut self.m, t)?;
        self.firings += 1;
        self.counts[t.index()] += 1;
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
            self.update_race(u);
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

    /// Time-averaged tokens per place over [0, now].
    pub(crate) fn mean_tokens(&self, now: f64) -> Vec<f64> {
        (0..self.m.len())
            .map(|i| {
                let total =
                    self.integral[i] + self.m.as_slice()[i] as f64 * (now - self.last_change[i]);
                if now > 0.0 {
                    total / now
                } else {
                    self.m.as_slice()[i] as f64
                }
            })
            .collect()
    }
}
