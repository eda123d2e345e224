//! The firing rules of a GSPN, once: what may fire in a marking, the immediate choice, the
//! exponential race and the statistics. Every component that plays a net drives this module
//! with its own chooser (stateright's "one model, many checkers"):
//!
//! - the state-space explorer (`analysis::state_space`) enumerates every move with
//!   [`moves`] — the exhaustive chooser;
//! - the token game ([`crate::sim::Simulator`]) keeps a [`Firable`] up to date with the
//!   net's own enabling and draws from it — the seeded chooser;
//! - the runtime's engine keeps a [`Firable`] up to date with what its agents are ready for
//!   (an agent's action gates its place's transitions) and draws from it the same way — the
//!   agent-readiness-filtered chooser. With no action bound, its rates and candidates are the
//!   net's, so it draws exactly what the token game draws.
//!
//! The rules:
//!
//! - **Enabling** ([`Net::is_enabled`], the rule's one home): every input arc satisfied,
//!   every inhibitor below its threshold, no capacity exceeded.
//! - **Vanishing** markings (an immediate transition enabled): time does not pass; only the
//!   enabled immediate transitions of the highest priority may fire. The [`Policy`], when one
//!   of its rules applies, gives the distribution; otherwise the choice is ∝ weight, and
//!   uniform when every candidate has weight 0 (a decision the net leaves to a policy it was
//!   not given).
//! - **Tangible** markings: the enabled exponential transitions race; `t` fires at
//!   `rate(t) × min(servers, degree(t))` ([`Net::exp_rate`]; the runtime caps the degree by
//!   its ready agents); the delay is exponential with the total
//!   rate and the winner is drawn ∝ its rate.
//! - **Dead** markings: nothing is enabled.

mod statistics;

pub use statistics::Statistics;
pub(crate) use statistics::Tally;

use crate::net::{Net, Servers, Timing, TransitionId};
use crate::policy::Policy;
use crate::sample::{self, Rng, SumTree};

/// The transitions of a net sorted for the rules: immediate ones by decreasing priority (then
/// id), and the exponential ones.
#[derive(Clone, Debug)]
pub(crate) struct Rules {
    /// (transition, weight, priority), highest priority first.
    immediates: Vec<(TransitionId, f64, u32)>,
    exponentials: Vec<TransitionId>,
}

impl Rules {
    /// The rules of `net`.
    /// The exponential transitions, in net order.
    pub(crate) fn exponentials(&self) -> &[TransitionId] {
        &self.exponentials
    }

    pub(crate) fn new(net: &Net) -> Rules {
        let mut immediates = Vec::new();
        let mut exponentials = Vec::new();
        for t in net.transition_ids() {
            match net.transition(t).timing {
                Timing::Immediate { weight, priority } => immediates.push((t, weight, priority)),
                Timing::Exponential { .. } => exponentials.push(t),
            }
        }
        immediates.sort_by_key(|&(t, _, p)| (std::cmp::Reverse(p), t));
        Rules {
            immediates,
            exponentials,
        }
    }
}

/// Every move out of `m`, for the exhaustive chooser: fills `out` with what may fire and its
/// rate (tangible `m`) or its probability (vanishing `m`, by weight, uniform when all weights
/// are 0; no policy); returns whether `m` is tangible. Empty `out`: `m` is dead.
pub(crate) fn moves(
    net: &Net,
    rules: &Rules,
    m: &[u32],
    out: &mut Vec<(TransitionId, f64)>,
) -> bool {
    out.clear();
    let mut level = None;
    for &(t, w, pr) in &rules.immediates {
        if level.is_some_and(|l| pr < l) {
            break;
        }
        if net.is_enabled(m, t) {
            level = Some(pr);
            out.push((t, w));
        }
    }
    if level.is_some() {
        let sum: f64 = out.iter().map(|&(_, w)| w).sum();
        let k = out.len() as f64;
        for (_, w) in out.iter_mut() {
            *w = if sum > 0.0 { *w / sum } else { 1.0 / k };
        }
        return false;
    }
    for &t in &rules.exponentials {
        let r = net.exp_rate(m, t);
        if r > 0.0 {
            out.push((t, r));
        }
    }
    true
}

/// Where a transition's rate or weight lives.
#[derive(Clone, Copy, Debug)]
enum Slot {
    /// Index into the exponential sum tree.
    Exp(u32),
    /// Priority level (index into `levels`) and index within it.
    Imm { level: u32, index: u32 },
}

/// The immediate transitions of one priority.
#[derive(Clone, Debug)]
struct Level {
    members: Vec<TransitionId>,
    weights: SumTree,
    /// How many members are candidates.
    on: u32,
}

/// What may fire in the current marking, kept up to date one transition at a time, and the
/// seeded draws from it: the immediate choice and the exponential race, each `O(log n)`.
///
/// The driver says which transitions are candidates: [`Firable::refresh`] applies the
/// net's own rules; [`Firable::set_immediate`] and [`Firable::set_rate`] take a driver's
/// filtered view (the runtime's agents). The draws are the same for both.
#[derive(Clone, Debug)]
pub(crate) struct Firable {
    slots: Vec<Slot>,
    /// Per exponential slot: (transition, rate per server, servers).
    exp_params: Vec<(TransitionId, f64, Servers)>,
    exp: SumTree,
    /// Bumped whenever a race rate changes (a sample of an unchanged race stays valid).
    version: u64,
    /// Immediate priority levels, highest priority first.
    levels: Vec<Level>,
    /// Per transition: a candidate (kept for immediate ones only).
    imm_on: Vec<bool>,
    imm_on_count: u32,
    candidates: Vec<TransitionId>,
    dist: Vec<(TransitionId, f64)>,
    /// The last [`Firable::choose_immediate`] decided outside the policy's table.
    outside_policy: bool,
}

impl Firable {
    /// Nothing may fire yet: the driver refreshes every transition for its first marking.
    pub(crate) fn new(net: &Net) -> Firable {
        let mut slots = Vec::with_capacity(net.transition_count());
        let mut exp_params = Vec::new();
        let mut priorities: Vec<u32> = net
            .transitions()
            .iter()
            .filter_map(|t| match t.timing {
                Timing::Immediate { priority, .. } => Some(priority),
                Timing::Exponential { .. } => None,
            })
            .collect();
        priorities.sort_unstable_by(|a, b| b.cmp(a));
        priorities.dedup();
        let mut members: Vec<Vec<TransitionId>> = vec![Vec::new(); priorities.len()];
        for t in net.transition_ids() {
            match net.transition(t).timing {
                Timing::Exponential { rate, servers } => {
                    slots.push(Slot::Exp(exp_params.len() as u32));
                    exp_params.push((t, rate, servers));
                }
                Timing::Immediate { priority, .. } => {
                    let level = priorities.iter().position(|&p| p == priority).unwrap_or(0);
                    slots.push(Slot::Imm {
                        level: level as u32,
                        index: members[level].len() as u32,
                    });
                    members[level].push(t);
                }
            }
        }
        let levels = members
            .into_iter()
            .map(|m| Level {
                weights: SumTree::new(m.len()),
                members: m,
                on: 0,
            })
            .collect();
        Firable {
            slots,
            exp: SumTree::new(exp_params.len()),
            exp_params,
            version: 0,
            levels,
            imm_on: vec![false; net.transition_count()],
            imm_on_count: 0,
            candidates: Vec::new(),
            dist: Vec::new(),
            outside_policy: false,
        }
    }

    /// Whether the last [`Firable::choose_immediate`] had a non-empty policy without a rule
    /// for its marking, among candidates that all have weight 0 (a decision the policy's
    /// table should have made; taken uniformly). Weighted races are not decisions and never
    /// count.
    pub(crate) fn outside_policy(&self) -> bool {
        self.outside_policy
    }

    /// Re-evaluates `t` in `m` by the net's own rules (the token game).
    #[inline]
    pub(crate) fn refresh(&mut self, net: &Net, m: &[u32], t: TransitionId) {
        match self.slots[t.index()] {
            Slot::Exp(i) => {
                let (_, r, servers) = self.exp_params[i as usize];
                let r = net.race_rate(m, t, (r, servers), u32::MAX);
                self.set_slot_rate(i as usize, r);
            }
            Slot::Imm { .. } => {
                let on = net.is_enabled(m, t);
                self.set_immediate(net, t, on);
            }
        }
    }

    /// The rate of exponential `t` in `m` when at most `cap` servers may be busy (the
    /// runtime's agents that handed the choice back to the net), and records it.
    #[inline]
    pub(crate) fn refresh_capped(&mut self, net: &Net, m: &[u32], t: TransitionId, cap: u32) {
        if let Slot::Exp(i) = self.slots[t.index()] {
            let (_, r, servers) = self.exp_params[i as usize];
            let r = net.race_rate(m, t, (r, servers), cap);
            self.set_slot_rate(i as usize, r);
        }
    }

    #[inline]
    fn set_slot_rate(&mut self, i: usize, r: f64) {
        if r != self.exp.get(i) {
            self.exp.set(i, r);
            self.version += 1;
        }
    }

    /// Makes immediate `t` a candidate of the immediate choice or not.
    #[inline]
    pub(crate) fn set_immediate(&mut self, net: &Net, t: TransitionId, on: bool) {
        let Slot::Imm { level, index } = self.slots[t.index()] else {
            return;
        };
        if on == self.imm_on[t.index()] {
            return;
        }
        self.imm_on[t.index()] = on;
        let lv = &mut self.levels[level as usize];
        let w = match net.transition(t).timing {
            Timing::Immediate { weight, .. } if on => weight,
            _ => 0.0,
        };
        lv.weights.set(index as usize, w);
        if on {
            lv.on += 1;
            self.imm_on_count += 1;
        } else {
            lv.on -= 1;
            self.imm_on_count -= 1;
        }
    }

    /// True when an immediate transition is a candidate (the marking is vanishing).
    #[inline]
    pub(crate) fn is_vanishing(&self) -> bool {
        self.imm_on_count > 0
    }

    /// The total rate of the race (0: no exponential transition may fire).
    #[inline]
    pub(crate) fn race_total(&self) -> f64 {
        self.exp.total()
    }

    /// Changes whenever a rate of the race changes.
    #[inline]
    pub(crate) fn race_version(&self) -> u64 {
        self.version
    }

    /// The immediate choice in `m` (call only when [`Firable::is_vanishing`]): among the
    /// candidates of the highest priority, the policy's distribution when one of its rules
    /// applies, else ∝ weight, else uniformly. One uniform draw.
    pub(crate) fn choose_immediate(
        &mut self,
        m: &[u32],
        policy: Option<&Policy>,
        rng: &mut Rng,
    ) -> TransitionId {
        let level = self
            .levels
            .iter()
            .position(|l| l.on > 0)
            .unwrap_or_default();
        let u = sample::uniform(rng);
        self.outside_policy = false;
        if let Some(policy) = policy {
            let lv = &self.levels[level];
            self.candidates.clear();
            self.candidates.extend(
                lv.members
                    .iter()
                    .copied()
                    .filter(|t| self.imm_on[t.index()]),
            );
            if policy.distribution_into(m, &self.candidates, &mut self.dist)
                && let Some(t) = sample::pick_weighted_with(u, &self.dist)
            {
                return t;
            }
        }
        let lv = &self.levels[level];
        let total = lv.weights.total();
        // A policy was given but has no rule here, and every candidate has weight 0: a
        // decision outside the policy's table, taken uniformly ([`Firable::outside_policy`]).
        self.outside_policy = total <= 0.0 && policy.is_some_and(|p| !p.is_empty());
        if total > 0.0 {
            return lv.members[lv.weights.find(u * total)];
        }
        // All weights 0: uniformly among the candidates.
        let k = ((u * lv.on as f64) as usize).min(lv.on as usize - 1);
        lv.members
            .iter()
            .copied()
            .filter(|t| self.imm_on[t.index()])
            .nth(k)
            .unwrap_or(lv.members[0])
    }

    /// The delay to the next exponential firing (one uniform draw); `None` when nothing
    /// races.
    #[inline]
    pub(crate) fn sample_delay(&self, rng: &mut Rng) -> Option<f64> {
        let total = self.exp.total();
        (total > 0.0).then(|| sample::exponential(rng, total))
    }

    /// The winner of the race, ∝ its rate (one uniform draw); `None` when nothing races.
    #[inline]
    pub(crate) fn pick_race(&self, rng: &mut Rng) -> Option<TransitionId> {
        let total = self.exp.total();
        if total <= 0.0 {
            return None;
        }
        let i = self.exp.find(sample::uniform(rng) * total);
        Some(self.exp_params[i].0)
    }
}
