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
pub mod stats;

pub use compare::{Report, Row, RowKind, Verdict, compare};
pub use fit::{Fitted, fit};
pub use holding::Holding;

pub use crate::runtime::{Drift, Monitored};
pub use monitor::{Monitor, MonitorOptions, SharedMonitor, Statistic};

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;

use crate::analysis::measures::SolverOptions;
use crate::analysis::state_space::Options as SpaceOptions;
use crate::net::{Net, PlaceId, Timing, TransitionId};
use crate::policy::Policy;
use crate::runtime::event::Event;
use crate::sim::{SimError, Simulator};
use crate::stats::Estimate;

/// The significance level of every verdict.
pub const ALPHA: f64 = 0.05;

/// Why conformance cannot be checked.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
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

/// The firings of one exponential transition, by active servers `min(servers, degree)`.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct Exposure {
    /// Firings.
    pub firings: u64,
    /// Enabled time weighted by active servers.
    pub exposure: f64,
    /// `active servers → (firings, time)`.
    pub by_servers: BTreeMap<u32, (u64, f64)>,
    /// Exposure between consecutive firings (the first from time 0; the open last one left
    /// out).
    #[serde(skip)]
    pub gaps: Vec<f64>,
}

/// The choices made in one decision class: the same firable immediate transitions and the
/// same policy rule (or none).
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// The immediate transitions that could fire, in id order.
    pub firable: Vec<TransitionId>,
    /// The policy rule that chose, `None` for the net's weights.
    pub rule: Option<usize>,
    /// Predicted probability per firable transition.
    pub probs: Vec<f64>,
    /// Observed count per firable transition.
    pub counts: Vec<u64>,
    /// Firings of transitions that were not firable there (a journal against the rules).
    pub outside: u64,
}

/// What one run showed, before any comparison.
#[derive(Clone, Debug)]
pub struct Observations {
    /// The observed span `[0, end]`.
    pub end: f64,
    /// Firings.
    pub firings: u64,
    /// Batches.
    pub batches: usize,
    /// Time-average tokens per place.
    pub mean_tokens: Vec<Estimate>,
    /// Throughput per transition.
    pub throughput: Vec<Estimate>,
    /// Firings per transition.
    pub counts: Vec<u64>,
    /// Per transition (`None` for immediate ones).
    pub exposure: Vec<Option<Exposure>>,
    /// `(place, transition, share of the place's departures, departures)` for places with
    /// more than one output transition.
    pub choices: Vec<(PlaceId, TransitionId, Estimate, u64)>,
    /// Decision classes, in order of first appearance.
    pub decisions: Vec<Decision>,
    /// The agents' stays that ended within the observed span.
    pub holdings: Vec<Holding>,
    /// The most tokens each place held in the run.
    pub most_tokens: Vec<u32>,
}

/// Reads a trace of `net` (run under `policy`, if any) into observations: step by step,
/// time passing between firings ([`Exposures::pass`]), each timed firing's exposure
/// ([`Exposures::fired`]), each immediate firing's decision class ([`DecisionClasses::see`]),
/// and the departures of places with a choice ([`choice_pairs`]).
pub fn observe(
    net: &Net,
    policy: Option<&Policy>,
    trace: &Trace,
    opts: &Options,
) -> Result<Observations, ConformError> {
    if trace.end.is_nan() || trace.end <= 0.0 {
        return Err(ConformError::Empty(trace.end));
    }
    let (np, nt) = (net.place_count(), net.transition_count());
    let b = opts.batches.max(2);
    let mut time = Exposures::new(net, trace.end, b);
    let mut fired = stats::BatchMeans::new(b, trace.end, nt);
    let (pairs, pair_index) = choice_pairs(net);
    let mut chosen = stats::BatchMeans::new(b, trace.end, pairs.len());
    let mut left = stats::BatchMeans::new(b, trace.end, np);
    let mut decisions = DecisionClasses::default();
    let mut counts = vec![0u64; nt];
    let mut m = trace.initial.clone();
    let mut mf: Vec<f64> = m.iter().map(|&k| k as f64).collect();
    let mut now = 0.0;
    for s in &trace.steps {
        if s.time > trace.end {
            break;
        }
        time.pass(&m, &mf, now, s.time);
        now = now.max(s.time);
        let t = s.transition;
        counts[t.index()] += 1;
        fired.count(s.time, t.index(), 1.0);
        if !time.fired(&m, t) {
            decisions.see(net, policy, &m, t);
        }
        for &(p, w) in net.inputs(t) {
            if let Some(&k) = pair_index.get(&(p.index(), t.index())) {
                chosen.count(s.time, k, w as f64);
                left.count(s.time, p.index(), w as f64);
            }
        }
        m.clone_from(&s.marking);
        mf.clear();
        mf.extend(m.iter().map(|&k| k as f64));
    }
    time.pass(&m, &mf, now, trace.end);
    let choices = pairs
        .iter()
        .enumerate()
        .map(|(k, &(p, t))| {
            let n = left.sums(p.index()).iter().sum::<f64>() as u64;
            let e = stats::ratio_estimate(chosen.sums(k), left.sums(p.index()));
            (p, t, e, n)
        })
        .collect();
    Ok(Observations {
        end: trace.end,
        firings: counts.iter().sum(),
        batches: b,
        mean_tokens: (0..np)
            .map(|p| stats::estimate(&time.tokens.batches(p)))
            .collect(),
        throughput: (0..nt)
            .map(|t| stats::estimate(&fired.batches(t)))
            .collect(),
        counts,
        exposure: time.exposure,
        choices,
        decisions: decisions.list,
        holdings: trace
            .holdings
            .iter()
            .filter(|h| h.entered + h.duration <= trace.end)
            .cloned()
            .collect(),
        most_tokens: trace
            .steps
            .iter()
            .fold(trace.initial.clone(), |mut most, s| {
                for (k, &x) in most.iter_mut().zip(&s.marking) {
                    *k = (*k).max(x);
                }
                most
            }),
    })
}

/// The `(place, transition)` pairs of places with more than one output transition, and
/// each pair's index.
#[allow(clippy::type_complexity)]
fn choice_pairs(
    net: &Net,
) -> (
    Vec<(PlaceId, TransitionId)>,
    BTreeMap<(usize, usize), usize>,
) {
    let mut outs: Vec<Vec<TransitionId>> = vec![Vec::new(); net.place_count()];
    for t in net.transition_ids() {
        for &(p, _) in net.inputs(t) {
            outs[p.index()].push(t);
        }
    }
    let pairs: Vec<(PlaceId, TransitionId)> = net
        .place_ids()
        .filter(|p| outs[p.index()].len() > 1)
        .flat_map(|p| outs[p.index()].iter().map(move |&t| (p, t)))
        .collect();
    let index = pairs
        .iter()
        .enumerate()
        .map(|(i, (p, t))| ((p.index(), t.index()), i))
        .collect();
    (pairs, index)
}

/// Time as it passes in a trace: the tokens' batch means and each exponential transition's
/// exposure (server-time enabled) and the enabled time since its last firing.
struct Exposures<'n> {
    net: &'n Net,
    end: f64,
    tokens: stats::BatchMeans,
    exposure: Vec<Option<Exposure>>,
    open_gap: Vec<f64>,
}

impl<'n> Exposures<'n> {
    fn new(net: &'n Net, end: f64, batches: usize) -> Self {
        Exposures {
            net,
            end,
            tokens: stats::BatchMeans::new(batches, end, net.place_count()),
            exposure: net
                .transitions()
                .iter()
                .map(|t| (!t.is_immediate()).then(Exposure::default))
                .collect(),
            open_gap: vec![0.0; net.transition_count()],
        }
    }

    /// Time from `from` to `to` (cut at the end) in marking `m` (`mf` as numbers).
    fn pass(&mut self, m: &[u32], mf: &[f64], from: f64, to: f64) {
        let to = to.min(self.end);
        if to <= from {
            return;
        }
        self.tokens.advance(to, mf);
        for (i, x) in self.exposure.iter_mut().enumerate() {
            if let Some(x) = x {
                let a = active_servers(self.net, m, TransitionId(i as u32));
                if a > 0 {
                    let e = a as f64 * (to - from);
                    x.exposure += e;
                    self.open_gap[i] += e;
                    x.by_servers.entry(a).or_default().1 += to - from;
                }
            }
        }
    }

    /// `t` fired in marking `m`: counted and its gap closed when it is exponential (true);
    /// false for an immediate one.
    fn fired(&mut self, m: &[u32], t: TransitionId) -> bool {
        let Some(x) = &mut self.exposure[t.index()] else {
            return false;
        };
        let a = active_servers(self.net, m, t);
        x.firings += 1;
        x.by_servers.entry(a).or_default().0 += 1;
        x.gaps.push(std::mem::take(&mut self.open_gap[t.index()]));
        true
    }
}

/// The immediate choices of a trace, by class: the firable immediate transitions and the
/// policy's rule that applies, in order of first appearance.
#[derive(Default)]
struct DecisionClasses {
    list: Vec<Decision>,
    class: BTreeMap<(Vec<TransitionId>, Option<usize>), usize>,
}

impl DecisionClasses {
    /// Immediate `t` fired in marking `m`: counted in its class (made on first sight, with
    /// the probabilities the policy, or the weights, give each option).
    fn see(&mut self, net: &Net, policy: Option<&Policy>, m: &[u32], t: TransitionId) {
        let firable: Vec<TransitionId> = net
            .firable(m)
            .into_iter()
            .filter(|&u| net.transition(u).is_immediate())
            .collect();
        let rule = policy.and_then(|p| p.rule_for(m, &firable).map(|(i, _)| i));
        let key = (firable, rule);
        let i = match self.class.get(&key) {
            Some(&i) => i,
            None => {
                let dist = match policy {
                    Some(p) => p.distribution_or_weights(net, m, &key.0),
                    None => Policy::empty().distribution_or_weights(net, m, &key.0),
                };
                let probs = key
                    .0
                    .iter()
                    .map(|u| dist.iter().find(|(v, _)| v == u).map_or(0.0, |d| d.1))
                    .collect();
                self.list.push(Decision {
                    firable: key.0.clone(),
                    rule,
                    probs,
                    counts: vec![0; key.0.len()],
                    outside: 0,
                });
                self.class.insert(key, self.list.len() - 1);
                self.list.len() - 1
            }
        };
        let d = &mut self.list[i];
        match d.firable.iter().position(|&u| u == t) {
            Some(k) => d.counts[k] += 1,
            None => d.outside += 1,
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
        &crate::analysis::state_space::Monitor::new(),
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
