//! Conformance: a recorded run checked against its net, and the net learnt back from runs.
//!
//! A [`Trace`] (a journal's firings, or a token-game run) is read once into
//! [`Observations`]; [`compare`] sets them beside the model's predictions row by row, each
//! with a 95% interval for the observation and a verdict (consistent / diverges at the 5%
//! level, with its p-value):
//!
//! | row | observed | predicted | test |
//! |---|---|---|---|
//! | `mean_tokens` (place) | time-average tokens, batch means | steady state | Student t over the batches |
//! | `throughput` (transition) | firings per unit time, batch means | steady state | Student t over the batches |
//! | `rate` (exponential transition) | firings per unit of enabled time | the net's rate | Poisson score test |
//! | `shape` (exponential transition) | Kolmogorov–Smirnov statistic of the enabled-time gaps | exponential | Lilliefors (Stephens) |
//! | `choice` (place → transition) | share of the place's tokens leaving by the transition, ratio batch means | from the steady-state throughputs | Student t over the batches |
//! | `decision` (set of firable immediate transitions, policy rule) | how often each fired | the weights or the policy's rule | Pearson chi-square |
//! | `holding` (place → exit transition) | mean stay of the agents that left by it | `1/Λ` where the model times each agent (see [`holding`]) | gamma, the end of the run taken into account |
//! | `holding_shape` (place) | Kolmogorov–Smirnov statistic of every stay | exponential of rate `Λ` | Kolmogorov |
//!
//! **Enabled time** respects server semantics: while exponential `t` has enabling degree
//! `d`, its exposure grows at `min(servers, d)` per unit of time, so under the model its
//! firings form a Poisson process of rate `λ` in exposure time (the random time change): the
//! maximum-likelihood rate is `firings / exposure`, and the exposure between consecutive
//! firings is exponential with that rate — whatever the place's other transitions do. A
//! deterministic 5 s `goto` gives gaps of about 5 s, which the shape test flags.
//!
//! Batch means cut the run into [`Options::batches`] equal spans of time; the spread of the
//! batch values gives the interval, as the spread of independent runs does for
//! `simulate --runs` ([`crate::sim::MonteCarlo`]).
//!
//! [`fit`] writes the maximum-likelihood parameters back into the net: rates per unit of
//! enabled time and weights from the decisions the net (not a policy) made.

mod compare;
mod fit;
pub mod holding;
mod monitor;
mod observe;
pub(crate) mod stats;

pub use compare::{Report, Row, RowKind, Verdict, compare};
pub use fit::{Fitted, fit};
pub use holding::Holding;

pub use crate::runtime::{Drift, Monitored};
pub use monitor::{Monitor, MonitorOptions, SharedMonitor, Statistic};
pub use observe::{Decision, Exposure, Observations, observe};

use std::sync::Arc;

use crate::analysis::measures::SolverOptions;
use crate::analysis::state_space::Options as SpaceOptions;
use crate::net::{Net, Timing, TransitionId};
use crate::policy::Policy;
use crate::runtime::event::Event;
use crate::sim::{SimError, Simulator};

/// The significance level of every verdict.
pub const ALPHA: f64 = 0.05;

/// Why conformance cannot be checked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum ConformError {
    /// The run has no time span to observe.
    #[error("the run lasts no time (end {0}): nothing to observe")]
    Empty(f64),
    /// The net's steady state could not be computed.
    #[error("no prediction from the net: {0}")]
    Analysis(String),
}

/// One firing of a recorded run.
#[derive(Clone, Debug, PartialEq)]
pub struct TraceStep {
    /// The journal's sequence number of the event (the step's index for a token-game run).
    pub seq: u64,
    /// Model time.
    pub time: f64,
    /// What fired.
    pub transition: TransitionId,
    /// The marking after it.
    pub marking: Vec<u32>,
}

/// A [`Trace`] made one event at a time, as a [`JournalReader`] reads them: a journal of
/// any size in the memory of its firings, not of its text and every event
/// ([`Trace::from_events`] for events in memory).
///
/// [`JournalReader`]: crate::runtime::journal::JournalReader
#[derive(Debug)]
pub struct TraceBuilder<'n> {
    net: &'n Net,
    steps: Vec<TraceStep>,
    end: f64,
    stays: holding::Stays,
}

impl<'n> TraceBuilder<'n> {
    /// An empty trace of a run of `net`.
    pub fn new(net: &'n Net) -> TraceBuilder<'n> {
        TraceBuilder {
            net,
            steps: Vec::new(),
            end: 0.0,
            stays: holding::Stays::default(),
        }
    }

    /// Adds the run's next event.
    pub fn push(&mut self, e: &Event) {
        self.end = self.end.max(e.time);
        if let Some(f) = e.firing() {
            self.steps.push(TraceStep {
                seq: f.seq,
                time: f.time,
                transition: f.transition,
                marking: f.marking.as_slice().to_vec(),
            });
        }
        self.stays.see(e);
    }

    /// The trace. The initial marking is the one before the first firing (a plan may have
    /// scaled the net's, e.g. with `--robots`), else the net's.
    pub fn finish(self) -> Trace {
        let net = self.net;
        let initial = self
            .steps
            .first()
            .and_then(|s| marking_before(net, s.transition, &s.marking))
            .unwrap_or_else(|| net.initial_marking().as_slice().to_vec());
        Trace {
            initial,
            steps: self.steps,
            end: self.end,
            holdings: self.stays.into_holdings(),
        }
    }
}

/// A recorded run: the marking it started from, its firings and when it ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// The marking at time 0.
    pub initial: Vec<u32>,
    /// The firings, in order.
    pub steps: Vec<TraceStep>,
    /// The end of the observation (the last event's time).
    pub end: f64,
    /// The agents' stays in action places (empty for a token-game run: its tokens have no
    /// identity), in the order they ended.
    pub holdings: Vec<Holding>,
}

impl Trace {
    /// The firings of a journal's events (see [`crate::runtime::journal::read_events`]). The
    /// initial marking is the one before the first firing (a plan may have scaled the net's,
    /// e.g. with `--robots`), else the net's.
    pub fn from_events(net: &Net, events: &[Event]) -> Trace {
        let mut b = TraceBuilder::new(net);
        for e in events {
            b.push(e);
        }
        b.finish()
    }

    /// A token-game run of `net` (under `policy`) from its initial marking until `until`,
    /// drawing from stream `stream` of `seed`.
    pub fn simulate(
        net: &Arc<Net>,
        policy: Option<&Arc<Policy>>,
        seed: u64,
        stream: u64,
        until: f64,
    ) -> Result<Trace, SimError> {
        let mut sim = Simulator::new(Arc::clone(net), seed).with_stream(stream);
        if let Some(p) = policy {
            sim = sim.with_policy(Arc::clone(p));
        }
        let initial = sim.marking().as_slice().to_vec();
        let mut steps = Vec::new();
        while let Some(s) = sim.step_until(until)? {
            steps.push(TraceStep {
                seq: steps.len() as u64,
                time: s.time,
                transition: s.transition,
                marking: sim.marking().as_slice().to_vec(),
            });
        }
        Ok(Trace {
            initial,
            steps,
            end: until,
            holdings: Vec::new(),
        })
    }

    /// The marking and time after the last firing with sequence number ≤ `seq` (the
    /// initial marking at time 0 when there is none); `None` for the end of the run.
    pub fn at(&self, seq: Option<u64>) -> (Vec<u32>, f64) {
        let last = match seq {
            None => self.steps.last(),
            Some(q) => self.steps.iter().take_while(|s| s.seq <= q).last(),
        };
        match last {
            Some(s) => (s.marking.clone(), s.time),
            None => (self.initial.clone(), 0.0),
        }
    }
}

/// The servers of exponential `t` at work in `m`: `min(servers, enabling degree)` (0 for an
/// immediate transition) — the rate at which its exposure grows.
pub fn active_servers(net: &Net, m: &[u32], t: TransitionId) -> u32 {
    match net.transition(t).timing {
        Timing::Exponential { servers, .. } => servers.active(net.enabled_degree(m, t)),
        Timing::Immediate { .. } => 0,
    }
}

/// The marking before `t` fired into `after` (`None` when a count would be negative).
pub fn marking_before(net: &Net, t: TransitionId, after: &[u32]) -> Option<Vec<u32>> {
    let mut m: Vec<i64> = after.iter().map(|&k| k as i64).collect();
    for &(p, d) in net.delta(t) {
        m[p.index()] -= d;
    }
    m.iter().map(|&k| u32::try_from(k).ok()).collect()
}

/// Thresholds of the comparison.
#[derive(Clone, Debug, PartialEq)]
pub struct Options {
    /// Batches of batch means (≥ 2).
    pub batches: usize,
    /// Fewest firings for a rate row or a fitted parameter.
    pub min_firings: u64,
    /// Fewest enabled-time gaps for a shape row.
    pub min_gaps: usize,
    /// Fewest expected decisions per option for a decision row.
    pub min_expected: f64,
    /// Most exponential stages of a phase-type (Erlang) fit of a place's holding time (see
    /// [`fit`]); 1 fits rates only.
    pub max_stages: u32,
}

impl Default for Options {
    /// 20 batches, 10 firings, 20 gaps, 5 expected decisions per option, Erlang fits of up
    /// to 20 stages.
    fn default() -> Self {
        Options {
            batches: 20,
            min_firings: 10,
            min_gaps: 20,
            min_expected: 5.0,
            max_stages: 20,
        }
    }
}

/// What the model predicts for the rows that need an analysis (the rest come from the net's
/// parameters and the policy).
#[derive(Clone, Debug, PartialEq)]
pub struct Predictions {
    /// Where they come from (shown in the report).
    pub source: String,
    /// Steady-state mean tokens per place.
    pub mean_tokens: Option<Vec<f64>>,
    /// Steady-state throughput per transition.
    pub throughput: Option<Vec<f64>>,
    /// The most tokens each place holds in a reachable tangible marking (under the policy):
    /// whether every token of a place has a server, for the `holding` rows.
    pub bounds: Option<Vec<u32>>,
}

impl Predictions {
    /// No analysis (a policy the steady state cannot take into account yet): only the rows
    /// of rates, shapes and decisions get verdicts.
    pub fn none(why: &str) -> Self {
        Predictions {
            source: why.into(),
            mean_tokens: None,
            throughput: None,
            bounds: None,
        }
    }
}

/// The steady state (limiting distribution from the initial marking) of the bare net.
pub fn steady_predictions(
    net: &Net,
    policy: Option<&Policy>,
    max_states: usize,
) -> Result<Predictions, ConformError> {
    let opts = SpaceOptions {
        max_states,
        ..SpaceOptions::default()
    };
    let analysis = crate::analysis::under_policy::analyse(
        net,
        policy.unwrap_or(&Policy::empty()),
        &[],
        &opts,
        &SolverOptions::default(),
    )
    .map_err(|e| ConformError::Analysis(e.to_string()))?;
    let what = if policy.is_some() {
        "the net under the plan's policy"
    } else {
        "the net"
    };
    Ok(Predictions {
        source: if analysis.limiting.ergodic {
            format!("steady state of {what}")
        } else {
            format!("limiting distribution of {what} (not ergodic)")
        },
        mean_tokens: Some(analysis.measures.mean_tokens),
        throughput: Some(analysis.measures.throughput),
        bounds: Some(tangible_bounds(net, &analysis.space)),
    })
}

/// The most tokens each place holds in a tangible marking of `space`.
fn tangible_bounds(net: &Net, space: &crate::analysis::state_space::StateSpace) -> Vec<u32> {
    let mut bounds = vec![0u32; net.place_count()];
    let mut m = vec![0u32; net.place_count()];
    for s in 0..space.tangible_count() {
        space.marking_into(s, &mut m);
        for (b, &k) in bounds.iter_mut().zip(&m) {
            *b = (*b).max(k);
        }
    }
    bounds
}
