//! The token game: exact GSPN semantics on virtual time, seeded and portable.
//!
//! A [`Simulator`] plays one run of a [`Net`] by the rules of [`crate::firing`], drawing
//! every choice from its seed:
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
//! allocates nothing. The simulator shares its net (`Arc<Net>`) and can start from any
//! marking ([`Simulator::from_marking`]), so a service keeps one alive between requests.
//!
//! The random numbers come from a [`crate::sample::Rng`] seeded with `seed` (stream 0, or
//! the stream given by [`Simulator::with_stream`]) through [`crate::sample`]'s portable
//! sampler, so a seed gives the same trace on every machine.
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
//! let mut sim = Simulator::new(net, 42);
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

pub use crate::firing::Statistics;
pub use crate::stats::{Estimate, t_quantile_975};
pub use monte_carlo::{Estimates, Horizon, MonteCarlo, monte_carlo};

use std::sync::Arc;

use rand::SeedableRng;

use crate::firing::{Firable, Tally};
use crate::net::{Marking, Net, TransitionId};
use crate::policy::Policy;
use crate::sample::Rng;

/// Immediate firings allowed at one instant before the run is declared a timeless trap.
pub const DEFAULT_MAX_IMMEDIATE: u64 = 1_000_000;

/// Why a run cannot go on.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
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
    /// A firing would put more tokens in a place than a count can hold
    /// ([`MAX_TOKENS`](crate::net::MAX_TOKENS)); the marking is left as it was.
    #[error("at time {time}: {message}")]
    TokenOverflow {
        /// When.
        time: f64,
        /// Which transition and place, by name.
        message: String,
    },
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

/// One run of the token game over a net. See the [module docs](self).
#[derive(Clone, Debug)]
pub struct Simulator {
    net: Arc<Net>,
    policy: Option<Arc<Policy>>,
    seed: u64,
    rng: Rng,
    marking: Marking,
    time: f64,
    firings: u64,
    firable: Firable,
    /// Immediate firings since the clock last advanced.
    instant: u64,
    max_immediate: u64,
    dead: bool,
    last: Option<TransitionId>,
    tally: Tally,
}

impl Simulator {
    /// A run of `net` from its initial marking at time 0, drawing from `seed` (stream 0).
    /// The simulator shares the net (`Arc`), so it can be kept between requests.
    pub fn new(net: impl Into<Arc<Net>>, seed: u64) -> Simulator {
        let net = net.into();
        let marking = net.initial_marking();
        Simulator::from_marking(net, marking, seed)
    }

    /// A run of `net` from `marking` at time 0, drawing from `seed` (stream 0).
    ///
    /// # Panics
    ///
    /// When `marking` does not have one count per place of `net` (a caller's bug).
    pub fn from_marking(net: impl Into<Arc<Net>>, marking: Marking, seed: u64) -> Simulator {
        let net = net.into();
        assert_eq!(marking.len(), net.place_count(), "one count per place");
        let mut sim = Simulator {
            firable: Firable::new(&net),
            tally: Tally::new(&net),
            policy: None,
            seed,
            rng: Rng::seed_from_u64(seed),
            marking,
            time: 0.0,
            firings: 0,
            instant: 0,
            max_immediate: DEFAULT_MAX_IMMEDIATE,
            dead: false,
            last: None,
            net,
        };
        for t in sim.net.transition_ids() {
            sim.firable.refresh(&sim.net, &sim.marking, t);
        }
        sim
    }

    /// Uses `policy` to choose among immediate transitions where one of its rules applies.
    pub fn with_policy(mut self, policy: impl Into<Arc<Policy>>) -> Self {
        self.policy = Some(policy.into());
        self
    }

    /// Draws from stream `stream` of the seed instead of stream 0: independent runs of one
    /// seed (Monte-Carlo run `i` uses stream `i`). Call before the first step.
    pub fn with_stream(mut self, stream: u64) -> Self {
        self.rng = Rng::seed_from_u64(self.seed);
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
    pub fn net(&self) -> &Arc<Net> {
        &self.net
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
        self.firable.is_vanishing()
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
        if self.firable.is_vanishing() {
            if self.instant >= self.max_immediate {
                return Err(SimError::TimelessTrap {
                    time: self.time,
                    firings: self.instant,
                    last: self.last_name(),
                });
            }
            let t =
                self.firable
                    .choose_immediate(&self.marking, self.policy.as_deref(), &mut self.rng);
            self.instant += 1;
            self.fire(t)?;
            return Ok(Some(Step {
                time: self.time,
                transition: t,
                immediate: true,
            }));
        }
        let Some(delay) = self.firable.sample_delay(&mut self.rng) else {
            self.dead = true;
            return Ok(None);
        };
        let at = self.time + delay;
        if at > limit {
            self.time = self.time.max(limit);
            self.instant = 0;
            return Ok(None);
        }
        let Some(t) = self.firable.pick_race(&mut self.rng) else {
            self.dead = true;
            return Ok(None);
        };
        self.time = at;
        self.instant = 0;
        self.fire(t)?;
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

    #[inline]
    fn fire(&mut self, t: TransitionId) -> Result<(), SimError> {
        let net = &*self.net;
        self.tally
            .fire(net, &mut self.marking, t, self.time)
            .map_err(|o| SimError::TokenOverflow {
                time: self.time,
                message: net.describe_overflow(&o),
            })?;
        self.firings += 1;
        self.last = Some(t);
        for &u in net.affected_by(t) {
            self.firable.refresh(net, &self.marking, u);
        }
        Ok(())
    }
}
