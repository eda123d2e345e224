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

mod monitor;
pub mod stats;

pub use monitor::{Drift, Monitor, MonitorOptions};

use std::collections::BTreeMap;
use std::sync::Arc;

use serde::Serialize;

use crate::analysis::measures::SolverOptions;
use crate::analysis::state_space::Options as SpaceOptions;
use crate::net::{Net, NetBuilder, PlaceId, Timing, TransitionId};
use crate::policy::Policy;
use crate::runtime::event::{Event, EventKind};
use crate::sim::{Estimate, SimError, Simulator};

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

/// A recorded run: the marking it started from, its firings and when it ended.
#[derive(Clone, Debug, PartialEq)]
pub struct Trace {
    /// The marking at time 0.
    pub initial: Vec<u32>,
    /// The firings, in order.
    pub steps: Vec<TraceStep>,
    /// The end of the observation (the last event's time).
    pub end: f64,
}

impl Trace {
    /// The firings of a journal's events (see [`crate::runtime::journal::read_events`]). The
    /// initial marking is the one before the first firing (a plan may have scaled the net's,
    /// e.g. with `--robots`), else the net's.
    pub fn from_events(net: &Net, events: &[Event]) -> Trace {
        let mut steps = Vec::new();
        let mut end = 0.0f64;
        for e in events {
            end = end.max(e.time);
            if let EventKind::Fired {
                transition,
                marking,
                ..
            } = &e.kind
            {
                steps.push(TraceStep {
                    seq: e.seq,
                    time: e.time,
                    transition: *transition,
                    marking: marking.as_slice().to_vec(),
                });
            }
        }
        let initial = steps
            .first()
            .and_then(|s| marking_before(net, s.transition, &s.marking))
            .unwrap_or_else(|| net.initial_marking().as_slice().to_vec());
        Trace {
            initial,
            steps,
            end,
        }
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
}

impl Default for Options {
    /// 20 batches, 10 firings, 20 gaps, 5 expected decisions per option.
    fn default() -> Self {
        Options {
            batches: 20,
            min_firings: 10,
            min_gaps: 20,
            min_expected: 5.0,
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
}

/// Reads a trace of `net` (run under `policy`, if any) into observations.
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
    let mut tokens = stats::BatchMeans::new(b, trace.end, np);
    let mut fired = stats::BatchMeans::new(b, trace.end, nt);
    // Places with more than one output transition: (place, [transitions]).
    let mut outs: Vec<Vec<TransitionId>> = vec![Vec::new(); np];
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
    let pair_index: BTreeMap<(usize, usize), usize> = pairs
        .iter()
        .enumerate()
        .map(|(i, (p, t))| ((p.index(), t.index()), i))
        .collect();
    let mut chosen = stats::BatchMeans::new(b, trace.end, pairs.len());
    let mut left = stats::BatchMeans::new(b, trace.end, np);
    let mut exposure: Vec<Option<Exposure>> = net
        .transitions()
        .iter()
        .map(|t| (!t.is_immediate()).then(Exposure::default))
        .collect();
    let mut open_gap = vec![0.0; nt];
    let mut decisions: Vec<Decision> = Vec::new();
    let mut class: BTreeMap<(Vec<TransitionId>, Option<usize>), usize> = BTreeMap::new();
    let mut counts = vec![0u64; nt];
    let mut m = trace.initial.clone();
    let mut mf: Vec<f64> = m.iter().map(|&k| k as f64).collect();
    let mut now = 0.0;
    let active = |m: &[u32], t: TransitionId| active_servers(net, m, t);
    let pass_time = |m: &[u32],
                     mf: &[f64],
                     from: f64,
                     to: f64,
                     tokens: &mut stats::BatchMeans,
                     exposure: &mut [Option<Exposure>],
                     open_gap: &mut [f64]| {
        let to = to.min(trace.end);
        if to <= from {
            return;
        }
        tokens.advance(to, mf);
        for (i, x) in exposure.iter_mut().enumerate() {
            if let Some(x) = x {
                let a = active(m, TransitionId(i as u32));
                if a > 0 {
                    let e = a as f64 * (to - from);
                    x.exposure += e;
                    open_gap[i] += e;
                    x.by_servers.entry(a).or_default().1 += to - from;
                }
            }
        }
    };
    for s in &trace.steps {
        if s.time > trace.end {
            break;
        }
        pass_time(
            &m,
            &mf,
            now,
            s.time,
            &mut tokens,
            &mut exposure,
            &mut open_gap,
        );
        now = now.max(s.time);
        let t = s.transition;
        counts[t.index()] += 1;
        fired.count(s.time, t.index(), 1.0);
        if let Some(x) = &mut exposure[t.index()] {
            let a = active(&m, t);
            x.firings += 1;
            x.by_servers.entry(a).or_default().0 += 1;
            x.gaps.push(std::mem::take(&mut open_gap[t.index()]));
        } else {
            let firable: Vec<TransitionId> = net
                .firable(&m)
                .into_iter()
                .filter(|&u| net.transition(u).is_immediate())
                .collect();
            let rule = policy.and_then(|p| p.rule_for(&m, &firable).map(|(i, _)| i));
            let key = (firable, rule);
            let i = match class.get(&key) {
                Some(&i) => i,
                None => {
                    let dist = match policy {
                        Some(p) => p.distribution_or_weights(net, &m, &key.0),
                        None => Policy::empty().distribution_or_weights(net, &m, &key.0),
                    };
                    let probs = key
                        .0
                        .iter()
                        .map(|u| dist.iter().find(|(v, _)| v == u).map_or(0.0, |d| d.1))
                        .collect();
                    decisions.push(Decision {
                        firable: key.0.clone(),
                        rule,
                        probs,
                        counts: vec![0; key.0.len()],
                        outside: 0,
                    });
                    class.insert(key.clone(), decisions.len() - 1);
                    decisions.len() - 1
                }
            };
            let d = &mut decisions[i];
            match d.firable.iter().position(|&u| u == t) {
                Some(k) => d.counts[k] += 1,
                None => d.outside += 1,
            }
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
    pass_time(
        &m,
        &mf,
        now,
        trace.end,
        &mut tokens,
        &mut exposure,
        &mut open_gap,
    );
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
            .map(|p| stats::estimate(&tokens.batches(p)))
            .collect(),
        throughput: (0..nt)
            .map(|t| stats::estimate(&fired.batches(t)))
            .collect(),
        counts,
        exposure,
        choices,
        decisions,
    })
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
}

impl Predictions {
    /// No analysis (a policy the steady state cannot take into account yet): only the rows
    /// of rates, shapes and decisions get verdicts.
    pub fn none(why: &str) -> Self {
        Predictions {
            source: why.into(),
            mean_tokens: None,
            throughput: None,
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
    })
}

/// What a row compares.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum RowKind {
    /// Time-average tokens of a place.
    MeanTokens,
    /// Firings per unit time of a transition.
    Throughput,
    /// Firings per unit of enabled time of an exponential transition.
    Rate,
    /// Whether the enabled time between firings is exponential.
    Shape,
    /// Share of a place's departures through one transition.
    Choice,
    /// The immediate choices of one decision class.
    Decision,
}

/// The outcome of a row.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Verdict {
    /// p ≥ [`ALPHA`].
    Consistent,
    /// p < [`ALPHA`].
    Diverges,
    /// Fewer observations than [`Options`] asks for.
    TooLittleData,
    /// The model gives no prediction for this row.
    NoPrediction,
}

/// One line of the comparison.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Row {
    /// What it compares.
    pub kind: RowKind,
    /// The place, transition, `place -> transition` or decision class.
    pub item: String,
    /// The observation (for `shape`: the modified KS statistic; for `decision`: Pearson's X²).
    pub observed: f64,
    /// Its 95% interval, when it has one.
    pub interval: Option<[f64; 2]>,
    /// The model's value, when it has one.
    pub predicted: Option<f64>,
    /// Sample size: batches, firings, gaps, departures or decisions.
    pub n: u64,
    /// The test's p-value.
    pub p_value: Option<f64>,
    /// The verdict at [`ALPHA`].
    pub verdict: Verdict,
    /// Counts beside expectations (decision rows).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub detail: Option<String>,
}

/// The comparison of one run with its model.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The net's name.
    pub net: String,
    /// Where the steady-state predictions come from.
    pub predictions: String,
    /// The observed span.
    pub time: f64,
    /// Firings.
    pub firings: u64,
    /// Batches of batch means.
    pub batches: usize,
    /// The rows.
    pub rows: Vec<Row>,
}

impl Report {
    /// Rows with a verdict of consistent or diverges.
    pub fn tested(&self) -> impl Iterator<Item = &Row> {
        self.rows
            .iter()
            .filter(|r| matches!(r.verdict, Verdict::Consistent | Verdict::Diverges))
    }

    /// Rows that diverge.
    pub fn diverging(&self) -> impl Iterator<Item = &Row> {
        self.rows.iter().filter(|r| r.verdict == Verdict::Diverges)
    }
}

fn verdict(p: f64) -> Verdict {
    if p < ALPHA {
        Verdict::Diverges
    } else {
        Verdict::Consistent
    }
}

fn batch_row(
    kind: RowKind,
    item: String,
    e: &Estimate,
    predicted: Option<f64>,
    batches: usize,
) -> Row {
    let p = predicted.map(|x| stats::t_test(e, x, batches as u64 - 1));
    Row {
        kind,
        item,
        observed: e.mean,
        interval: Some([e.lo(), e.hi()]),
        predicted,
        n: batches as u64,
        p_value: p,
        verdict: p.map_or(Verdict::NoPrediction, verdict),
        detail: None,
    }
}

/// Sets the observations beside the model: the rows of the module's table.
pub fn compare(net: &Net, obs: &Observations, pred: &Predictions, opts: &Options) -> Report {
    let mut rows = Vec::new();
    for (p, e) in obs.mean_tokens.iter().enumerate() {
        let x = pred.mean_tokens.as_ref().map(|v| v[p]);
        rows.push(batch_row(
            RowKind::MeanTokens,
            net.places()[p].name.clone(),
            e,
            x,
            obs.batches,
        ));
    }
    for (t, e) in obs.throughput.iter().enumerate() {
        let x = pred.throughput.as_ref().map(|v| v[t]);
        rows.push(batch_row(
            RowKind::Throughput,
            net.transitions()[t].name.clone(),
            e,
            x,
            obs.batches,
        ));
    }
    for (t, x) in obs.exposure.iter().enumerate() {
        let (Some(x), Timing::Exponential { rate, .. }) = (x, net.transitions()[t].timing) else {
            continue;
        };
        let name = &net.transitions()[t].name;
        let enough = x.firings >= opts.min_firings && x.exposure > 0.0;
        let p = enough.then(|| stats::rate_test(x.firings, x.exposure, rate));
        rows.push(Row {
            kind: RowKind::Rate,
            item: name.clone(),
            observed: if x.exposure > 0.0 {
                x.firings as f64 / x.exposure
            } else {
                0.0
            },
            interval: (x.exposure > 0.0).then(|| {
                let (lo, hi) = stats::rate_interval(x.firings, x.exposure);
                [lo, hi]
            }),
            predicted: Some(rate),
            n: x.firings,
            p_value: p,
            verdict: p.map_or(Verdict::TooLittleData, verdict),
            detail: None,
        });
        let ks = (x.gaps.len() >= opts.min_gaps)
            .then(|| stats::ks_exponential(&x.gaps))
            .flatten();
        rows.push(Row {
            kind: RowKind::Shape,
            item: name.clone(),
            observed: ks.map_or(0.0, |k| k.0),
            interval: None,
            predicted: None,
            n: x.gaps.len() as u64,
            p_value: ks.map(|k| k.1),
            verdict: ks.map_or(Verdict::TooLittleData, |k| verdict(k.1)),
            detail: None,
        });
    }
    for &(p, t, e, n) in &obs.choices {
        let predicted = pred.throughput.as_ref().and_then(|thr| {
            let flow = |u: TransitionId| {
                let w = net
                    .inputs(u)
                    .iter()
                    .find(|(q, _)| *q == p)
                    .map_or(0, |a| a.1);
                thr[u.index()] * w as f64
            };
            let total: f64 = net
                .transition_ids()
                .filter(|&u| net.inputs(u).iter().any(|(q, _)| *q == p))
                .map(flow)
                .sum();
            (total > 0.0).then(|| flow(t) / total)
        });
        let mut row = batch_row(
            RowKind::Choice,
            format!("{} -> {}", net.place(p).name, net.transition(t).name),
            &e,
            predicted,
            obs.batches,
        );
        row.n = n;
        if n == 0 || e.mean.is_nan() {
            row.observed = 0.0;
            row.interval = None;
            row.p_value = None;
            row.verdict = Verdict::TooLittleData;
        }
        rows.push(row);
    }
    for d in &obs.decisions {
        if d.firable.len() < 2 && d.outside == 0 {
            continue;
        }
        let total: u64 = d.counts.iter().sum::<u64>() + d.outside;
        let names: Vec<&str> = d
            .firable
            .iter()
            .map(|&t| net.transition(t).name.as_str())
            .collect();
        let item = match d.rule {
            Some(r) => format!("{{{}}} rule {}", names.join(", "), r + 1),
            None => format!("{{{}}}", names.join(", ")),
        };
        let x2: f64 = d
            .counts
            .iter()
            .zip(&d.probs)
            .filter(|(_, p)| **p > 0.0)
            .map(|(&c, &p)| (c as f64 - p * total as f64).powi(2) / (p * total as f64))
            .sum();
        let min_expected = d
            .probs
            .iter()
            .filter(|p| **p > 0.0)
            .map(|p| p * total as f64)
            .fold(f64::INFINITY, f64::min);
        let impossible = d.outside > 0
            || d.counts
                .iter()
                .zip(&d.probs)
                .any(|(&c, &p)| c > 0 && p <= 0.0);
        let p = if impossible {
            Some(0.0)
        } else if min_expected >= opts.min_expected
            || d.probs.iter().filter(|p| **p > 0.0).count() <= 1
        {
            Some(stats::chi_square(&d.counts, &d.probs))
        } else {
            None
        };
        let mut detail: Vec<String> = names
            .iter()
            .zip(d.counts.iter().zip(&d.probs))
            .map(|(n, (&c, &p))| format!("{n} {c} (expected {:.1})", p * total as f64))
            .collect();
        if d.outside > 0 {
            detail.push(format!("{} not firable there", d.outside));
        }
        rows.push(Row {
            kind: RowKind::Decision,
            item,
            observed: x2,
            interval: None,
            predicted: None,
            n: total,
            p_value: p,
            verdict: p.map_or(Verdict::TooLittleData, verdict),
            detail: Some(detail.join(", ")),
        });
    }
    Report {
        net: net.name().to_string(),
        predictions: pred.source.clone(),
        time: obs.end,
        firings: obs.firings,
        batches: obs.batches,
        rows,
    }
}

/// One parameter of a fitted net.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fitted {
    /// The transition.
    pub transition: String,
    /// `rate` or `weight`.
    pub parameter: &'static str,
    /// The net's value.
    pub old: f64,
    /// The fitted value (the old one when kept).
    pub new: f64,
    /// 95% interval of the fitted value.
    pub interval: Option<[f64; 2]>,
    /// Firings (rates) or decisions (weights) it rests on.
    pub n: u64,
    /// Too little data: the old value was kept.
    pub kept: bool,
}

/// The net with maximum-likelihood parameters: each exponential transition's rate is
/// `firings / exposure` (per server, see the module), each immediate transition's weight
/// comes from the decisions the net's weights made (not a policy's rules): the weights of a
/// group of transitions that met in decisions are fitted together (Luce's choice model, by
/// minorisation–maximisation) and scaled to keep the group's total. Parameters with fewer
/// than [`Options::min_firings`] firings (or decisions) keep their value and are marked
/// `kept`.
pub fn fit(net: &Net, obs: &Observations, opts: &Options) -> (Net, Vec<Fitted>) {
    let mut timings: Vec<Timing> = net.transitions().iter().map(|t| t.timing).collect();
    let mut out = Vec::new();
    for (i, x) in obs.exposure.iter().enumerate() {
        let (Some(x), Timing::Exponential { rate, servers }) = (x, timings[i]) else {
            continue;
        };
        let kept = x.firings < opts.min_firings || x.exposure.is_nan() || x.exposure <= 0.0;
        let new = if kept {
            rate
        } else {
            x.firings as f64 / x.exposure
        };
        timings[i] = Timing::Exponential { rate: new, servers };
        out.push(Fitted {
            transition: net.transitions()[i].name.clone(),
            parameter: "rate",
            old: rate,
            new,
            interval: (x.exposure > 0.0).then(|| {
                let (lo, hi) = stats::rate_interval(x.firings, x.exposure);
                [lo, hi]
            }),
            n: x.firings,
            kept,
        });
    }
    fit_weights(net, obs, opts, &mut timings, &mut out);
    let mut b = NetBuilder::new(net.name());
    for p in net.places() {
        b.add_place(p.clone());
    }
    for (t, timing) in net.transitions().iter().zip(timings) {
        b.add_transition(crate::net::Transition {
            timing,
            ..t.clone()
        });
    }
    for a in net.arcs() {
        b.arc(a.kind, a.place, a.transition, a.weight, a.points.clone());
    }
    let fitted = b
        .build()
        .expect("the same net with positive finite rates and weights builds");
    (fitted, out)
}

fn fit_weights(
    net: &Net,
    obs: &Observations,
    opts: &Options,
    timings: &mut [Timing],
    out: &mut Vec<Fitted>,
) {
    let classes: Vec<&Decision> = obs
        .decisions
        .iter()
        .filter(|d| d.rule.is_none() && d.firable.len() > 1)
        .collect();
    let nt = net.transition_count();
    let weight = |t: TransitionId| match net.transition(t).timing {
        Timing::Immediate { weight, .. } => weight,
        Timing::Exponential { .. } => 0.0,
    };
    // Groups: transitions linked by appearing in one class (union–find).
    let mut parent: Vec<usize> = (0..nt).collect();
    fn root(parent: &mut [usize], mut i: usize) -> usize {
        while parent[i] != i {
            parent[i] = parent[parent[i]];
            i = parent[i];
        }
        i
    }
    for d in &classes {
        for w in d.firable.windows(2) {
            let (a, b) = (
                root(&mut parent, w[0].index()),
                root(&mut parent, w[1].index()),
            );
            parent[a] = b;
        }
    }
    let mut wins = vec![0u64; nt];
    let mut decided = vec![0u64; nt];
    for d in &classes {
        let total: u64 = d.counts.iter().sum();
        for (&t, &c) in d.firable.iter().zip(&d.counts) {
            wins[t.index()] += c;
            decided[t.index()] += total;
        }
    }
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for d in &classes {
        for &t in &d.firable {
            let r = root(&mut parent, t.index());
            let g = groups.entry(r).or_default();
            if !g.contains(&t.index()) {
                g.push(t.index());
            }
        }
    }
    for members in groups.values() {
        let enough = members
            .iter()
            .all(|&t| decided[t] >= opts.min_firings && wins[t] > 0);
        let old_total: f64 = members
            .iter()
            .map(|&t| weight(TransitionId(t as u32)))
            .sum();
        let mut w: Vec<f64> = vec![1.0; nt];
        if enough {
            // Minorisation–maximisation for Luce's model (Hunter 2004).
            for _ in 0..500 {
                let mut denom = vec![0.0; nt];
                for d in &classes {
                    if root(&mut parent, d.firable[0].index()) != root(&mut parent, members[0]) {
                        continue;
                    }
                    let total: u64 = d.counts.iter().sum();
                    let s: f64 = d.firable.iter().map(|t| w[t.index()]).sum();
                    for t in &d.firable {
                        denom[t.index()] += total as f64 / s;
                    }
                }
                for &t in members {
                    w[t] = wins[t] as f64 / denom[t];
                }
            }
            let sum: f64 = members.iter().map(|&t| w[t]).sum();
            let scale = if old_total > 0.0 {
                old_total / sum
            } else {
                members.len() as f64 / sum
            };
            for &t in members {
                w[t] *= scale;
            }
        }
        for &t in members {
            let id = TransitionId(t as u32);
            let old = weight(id);
            let new = if enough { w[t] } else { old };
            if let Timing::Immediate { priority, .. } = timings[t] {
                timings[t] = Timing::Immediate {
                    weight: new,
                    priority,
                };
            }
            // The interval: the share in the class where it was decided most, as a weight
            // against the others' fitted weights there (Wilson score interval).
            let interval = enough
                .then(|| {
                    let d = classes
                        .iter()
                        .filter(|d| d.firable.contains(&id))
                        .max_by_key(|d| d.counts.iter().sum::<u64>())?;
                    let k = d.firable.iter().position(|&u| u == id)?;
                    let n: u64 = d.counts.iter().sum();
                    let others: f64 = d
                        .firable
                        .iter()
                        .filter(|&&u| u != id)
                        .map(|u| w[u.index()])
                        .sum();
                    let (lo, hi) = wilson(d.counts[k], n);
                    let odds = |p: f64| {
                        if p >= 1.0 {
                            f64::INFINITY
                        } else {
                            p / (1.0 - p) * others
                        }
                    };
                    Some([odds(lo), odds(hi)])
                })
                .flatten()
                .filter(|[_, hi]| hi.is_finite());
            out.push(Fitted {
                transition: net.transition(id).name.clone(),
                parameter: "weight",
                old,
                new,
                interval,
                n: wins[t],
                kept: !enough,
            });
        }
    }
}

/// The 95% Wilson score interval of a proportion `k / n`.
fn wilson(k: u64, n: u64) -> (f64, f64) {
    let (k, n, z) = (k as f64, n as f64, stats::Z975);
    let p = k / n;
    let c = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let h = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((c - h).max(0.0), (c + h).min(1.0))
}
