//! The token game: exact GSPN semantics on virtual time, seeded and portable.
//!
//! A [`Simulator`] plays one run of a [`Net`]:
//!
//! - In a **vanishing** marking (an immediate transition is enabled) time does not pass; only
//!   the enabled immediate transitions of the highest priority may fire. The [`Policy`], when
//!   one is given and one of its rules applies, picks among them; otherwise they are chosen
//!   with probability ∝ weight (uniformly when every one of them has weight 0 — a decision
//!   the net leaves to a policy it was not given).
//! - In a **tangible** marking the enabled exponential transitions race: transition `t` fires
//!   at rate `rate(t) × min(servers, degree(t))`; the clock advances by an exponential delay
//!   with the total rate, and the winner is drawn ∝ its rate.
//! - A marking where nothing is enabled is **dead**: the run ends there.
//!
//! Sampling is `O(log n)` in the number of transitions: the rates of the exponential
//! transitions (and the weights of each priority level of immediate ones) sit in sum trees,
//! and after a firing only the transitions in [`Net::affected_by`] are re-evaluated. A firing
//! allocates nothing.
//!
//! The random numbers come from a [`ChaCha8Rng`] seeded with `seed` (stream 0, or the stream
//! given by [`Simulator::with_stream`]), and delays are computed with a portable logarithm,
//! so a seed gives the same trace on every machine.
//!
//! ```
//! use gspn::net::{NetBuilder, Servers};
//! use gspn::sim::Simulator;
//! let mut b = NetBuilder::new("cycle");
//! let p = b.place("p", 1);
//! let q = b.place("q", 0);
//! let go = b.exponential("go", 2.0, Servers::Single);
//! let back = b.immediate("back", 1.0, 1);
//! b.input(p, go, 1);
//! b.output(go, q, 1);
//! b.input(q, back, 1);
//! b.output(back, p, 1);
//! let net = b.build().unwrap();
//!
//! let mut sim = Simulator::new(&net, 42);
//! let step = sim.step().unwrap().unwrap();
//! assert_eq!(step.transition, go);
//! assert!(step.time > 0.0);
//! let step2 = sim.step().unwrap().unwrap();
//! assert_eq!((step2.transition, step2.time), (back, step.time)); // immediate: no time passes
//!
//! sim.run_until(1000.0).unwrap();
//! let stats = sim.statistics();
//! assert!((stats.throughput_of(go) - 2.0).abs() < 0.2); // ≈ 2 firings per unit of time
//! ```

mod monte_carlo;
mod sample;
mod statistics;
pub(crate) mod sum_tree;

pub use monte_carlo::{Estimate, Estimates, Horizon, MonteCarlo, monte_carlo, t_quantile_975};
pub use statistics::Statistics;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use crate::net::{Marking, Net, Servers, Timing, TransitionId};
use crate::policy::Policy;
use sum_tree::SumTree;

/// Immediate firings allowed at one instant before the run is declared a timeless trap.
pub const DEFAULT_MAX_IMMEDIATE: u64 = 1_000_000;

/// Why a run cannot go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SimError {
    /// Immediate transitions kept firing without time passing: a vanishing loop the net
    /// never leaves (a *timeless trap*).
    #[error(
        "timeless trap at time {time}: {firings} immediate firings without time passing (last: `{last}`)"
    )]
    TimelessTrap {
        /// The instant the run is stuck at.
        time: f64,
        /// Immediate firings at that instant.
        firings: u64,
        /// Name of the last transition fired.
        last: String,
    },
    /// A time limit, run count or similar argument out of range.
    #[error("{0}")]
    BadArgument(String),
}

/// One firing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Step {
    /// When it fired (virtual time).
    pub time: f64,
    /// What fired.
    pub transition: TransitionId,
    /// True for an immediate transition (fired in a vanishing marking, no time passed).
    pub immediate: bool,
}

/// How a call to [`Simulator::run_until`] or [`Simulator::run_steps`] ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RunEnd {
    /// The time or step limit was reached.
    Limit,
    /// A dead marking was reached: nothing can ever fire again.
    Dead,
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
    /// How many members are enabled.
    enabled: u32,
}

/// One run of the token game over a net. See the [module docs](self).
#[derive(Clone, Debug)]
pub struct Simulator<'n> {
    net: &'n Net,
    policy: Option<&'n Policy>,
    seed: u64,
    rng: ChaCha8Rng,
    marking: Marking,
    time: f64,
    firings: u64,
    slots: Vec<Slot>,
    /// Per exponential slot: (transition, rate per server, servers).
    exp_params: Vec<(TransitionId, f64, Servers)>,
    exp: SumTree,
    /// Immediate priority levels, highest priority first.
    levels: Vec<Level>,
    /// Per transition: enabled (kept for immediate ones only).
    imm_on: Vec<bool>,
    imm_enabled: u32,
    /// Immediate firings since the clock last advanced.
    instant: u64,
    max_immediate: u64,
    dead: bool,
    /// Some place has a capacity (checked on enabling).
    has_capacity: bool,
    last: Option<TransitionId>,
    tally: statistics::Tally,
    firable: Vec<TransitionId>,
    dist: Vec<(TransitionId, f64)>,
}

impl<'n> Simulator<'n> {
    /// A run of `net` from its initial marking at time 0, drawing from `seed` (stream 0).
    pub fn new(net: &'n Net, seed: u64) -> Simulator<'n> {
        let n = net.transition_count();
        let mut slots = Vec::with_capacity(n);
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
                enabled: 0,
            })
            .collect();
        let mut sim = Simulator {
            net,
            policy: None,
            seed,
            rng: ChaCha8Rng::seed_from_u64(seed),
            marking: net.initial_marking(),
            time: 0.0,
            firings: 0,
            slots,
            exp: SumTree::new(exp_params.len()),
            exp_params,
            levels,
            imm_on: vec![false; n],
            imm_enabled: 0,
            instant: 0,
            max_immediate: DEFAULT_MAX_IMMEDIATE,
            dead: false,
            has_capacity: net.places().iter().any(|p| p.capacity.is_some()),
            last: None,
            tally: statistics::Tally::new(net),
            firable: Vec::new(),
            dist: Vec::new(),
        };
        for t in net.transition_ids() {
            sim.refresh(t);
        }
        sim
    }

    /// Uses `policy` to choose among immediate transitions where one of its rules applies.
    pub fn with_policy(mut self, policy: &'n Policy) -> Self {
        self.policy = Some(policy);
        self
    }

    /// Draws from stream `stream` of the seed instead of stream 0: independent runs of one
    /// seed (Monte-Carlo run `i` uses stream `i`). Call before the first step.
    pub fn with_stream(mut self, stream: u64) -> Self {
        self.rng = ChaCha8Rng::seed_from_u64(self.seed);
        self.rng.set_stream(stream);
        self
    }

    /// Immediate firings allowed at one instant before [`SimError::TimelessTrap`]
    /// (default [`DEFAULT_MAX_IMMEDIATE`]).
    pub fn with_max_immediate(mut self, max: u64) -> Self {
        self.max_immediate = max;
        self
    }

    /// The net being played.
    pub fn net(&self) -> &'n Net {
        self.net
    }

    /// The current marking.
    pub fn marking(&self) -> &Marking {
        &self.marking
    }

    /// The clock.
    pub fn time(&self) -> f64 {
        self.time
    }

    /// Firings so far.
    pub fn firings(&self) -> u64 {
        self.firings
    }

    /// True once the run has reached a dead marking.
    pub fn is_dead(&self) -> bool {
        self.dead
    }

    /// True when the current marking is vanishing (an immediate transition is enabled).
    pub fn is_vanishing(&self) -> bool {
        self.imm_enabled > 0
    }

    /// The statistics over `[0, time()]`.
    pub fn statistics(&self) -> Statistics {
        self.tally.read(&self.marking, self.time)
    }

    /// Fires the next transition. `Ok(None)` when the marking is dead (the clock stays).
    pub fn step(&mut self) -> Result<Option<Step>, SimError> {
        self.step_until(f64::INFINITY)
    }

    /// Fires transitions until the next one would fire after `until`, then sets the clock
    /// to `until` (the race is memoryless, so the delay that overshot is simply dropped).
    /// A dead marking also moves the clock to `until` — it holds for ever — and returns
    /// [`RunEnd::Dead`].
    pub fn run_until(&mut self, until: f64) -> Result<RunEnd, SimError> {
        if until.is_nan() {
            return Err(SimError::BadArgument(format!("time limit {until}")));
        }
        if until >= self.time {
            while self.step_until(until)?.is_some() {}
        }
        if self.time < until && until.is_finite() {
            self.time = until;
        }
        Ok(if self.dead {
            RunEnd::Dead
        } else {
            RunEnd::Limit
        })
    }

    /// Fires at most `n` transitions; stops early at a dead marking.
    pub fn run_steps(&mut self, n: u64) -> Result<RunEnd, SimError> {
        for _ in 0..n {
            if self.step()?.is_none() {
                return Ok(RunEnd::Dead);
            }
        }
        Ok(RunEnd::Limit)
    }

    /// Fires the next transition if it fires no later than `limit`. Otherwise returns
    /// `Ok(None)` and moves the clock to `limit` (nothing fires in between; the race is
    /// memoryless, so the delay that overshot is dropped and later steps draw afresh), or
    /// leaves the clock where it is when the marking is dead ([`Simulator::is_dead`]).
    pub fn step_until(&mut self, limit: f64) -> Result<Option<Step>, SimError> {
        if self.imm_enabled > 0 {
            if self.instant >= self.max_immediate {
                return Err(SimError::TimelessTrap {
                    time: self.time,
                    firings: self.instant,
                    last: self.last_name(),
                });
            }
            let t = self.choose_immediate();
            self.instant += 1;
            self.fire(t);
            return Ok(Some(Step {
                time: self.time,
                transition: t,
                immediate: true,
            }));
        }
        let total = self.exp.total();
        if total <= 0.0 {
            self.dead = true;
            return Ok(None);
        }
        let at = self.time + sample::exponential(&mut self.rng, total);
        if at > limit {
            self.time = self.time.max(limit);
            self.instant = 0;
            return Ok(None);
        }
        let i = self.exp.find(sample::uniform(&mut self.rng) * total);
        let t = self.exp_params[i].0;
        self.time = at;
        self.instant = 0;
        self.fire(t);
        Ok(Some(Step {
            time: at,
            transition: t,
            immediate: false,
        }))
    }

    fn last_name(&self) -> String {
        self.last
            .map_or_else(String::new, |t| self.net.transition(t).name.clone())
    }

    /// Picks among the enabled immediate transitions of the highest enabled priority.
    fn choose_immediate(&mut self) -> TransitionId {
        let level = self
            .levels
            .iter()
            .position(|l| l.enabled > 0)
            .unwrap_or_default();
        if let Some(policy) = self.policy {
            self.firable.clear();
            let lv = &self.levels[level];
            self.firable.extend(
                lv.members
                    .iter()
                    .copied()
                    .filter(|t| self.imm_on[t.index()]),
            );
            if policy.distribution_into(self.net, &self.marking, &self.firable, &mut self.dist) {
                let mut u = sample::uniform(&mut self.rng);
                for &(t, p) in &self.dist {
                    if u < p {
                        return t;
                    }
                    u -= p;
                }
                if let Some(&(t, _)) = self.dist.last() {
                    return t;
                }
            }
        }
        let lv = &self.levels[level];
        let total = lv.weights.total();
        let u = sample::uniform(&mut self.rng);
        if total > 0.0 {
            return lv.members[lv.weights.find(u * total)];
        }
        // All weights 0: uniformly among the enabled ones.
        let k = ((u * lv.enabled as f64) as usize).min(lv.enabled as usize - 1);
        lv.members
            .iter()
            .copied()
            .filter(|t| self.imm_on[t.index()])
            .nth(k)
            .unwrap_or(lv.members[0])
    }

    #[inline]
    fn fire(&mut self, t: TransitionId) {
        let net = self.net;
        self.tally.fire(net, &mut self.marking, t, self.time);
        self.firings += 1;
        self.last = Some(t);
        for &u in net.affected_by(t) {
            self.refresh(u);
        }
    }

    /// Re-evaluates the enabling of `t` in the current marking.
    #[inline]
    fn refresh(&mut self, t: TransitionId) {
        match self.slots[t.index()] {
            Slot::Exp(i) => {
                let (_, rate, servers) = self.exp_params[i as usize];
                let r = self.rate(t, rate, servers);
                if r != self.exp.get(i as usize) {
                    self.exp.set(i as usize, r);
                }
            }
            Slot::Imm { level, index } => {
                let on = self.enabled(t);
                if on != self.imm_on[t.index()] {
                    self.imm_on[t.index()] = on;
                    let lv = &mut self.levels[level as usize];
                    let w = match self.net.transition(t).timing {
                        Timing::Immediate { weight, .. } if on => weight,
                        _ => 0.0,
                    };
                    lv.weights.set(index as usize, w);
                    if on {
                        lv.enabled += 1;
                        self.imm_enabled += 1;
                    } else {
                        lv.enabled -= 1;
                        self.imm_enabled -= 1;
                    }
                }
            }
        }
    }

    /// Inhibitors below threshold and no capacity exceeded (the input arcs are checked by
    /// the callers). The same rules as [`Net::is_enabled`], inlined into the hot loop.
    #[inline]
    fn side_conditions(&self, t: TransitionId) -> bool {
        let m: &[u32] = &self.marking;
        for &(p, w) in self.net.inhibitors(t) {
            if m[p.index()] >= w {
                return false;
            }
        }
        if self.has_capacity {
            for &(p, d) in self.net.delta(t) {
                if d > 0 && m[p.index()] as i64 + d > self.net.capacity_of(p) as i64 {
                    return false;
                }
            }
        }
        true
    }

    /// [`Net::is_enabled`] for the current marking.
    #[inline]
    fn enabled(&self, t: TransitionId) -> bool {
        let m: &[u32] = &self.marking;
        self.net.inputs(t).iter().all(|&(p, w)| m[p.index()] >= w) && self.side_conditions(t)
    }

    /// Firing rate of exponential `t` now: `rate × min(servers, degree)`, 0 when disabled.
    #[inline]
    fn rate(&self, t: TransitionId, rate: f64, servers: Servers) -> f64 {
        let m: &[u32] = &self.marking;
        let inputs = self.net.inputs(t);
        let active = if servers == Servers::Single {
            // Enabled is all a single server needs: no divisions.
            if !inputs.iter().all(|&(p, w)| m[p.index()] >= w) {
                return 0.0;
            }
            1
        } else {
            let mut degree = if inputs.is_empty() { 1 } else { u32::MAX };
            for &(p, w) in inputs {
                let k = m[p.index()];
                if k < w {
                    return 0.0;
                }
                degree = degree.min(if w == 1 { k } else { k / w });
            }
            servers.active(degree)
        };
        if !self.side_conditions(t) {
            return 0.0;
        }
        rate * active as f64
    }
}
