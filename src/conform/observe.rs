//! What a trace shows before any comparison ([`observe`]): time-average tokens and
//! throughputs in batches, each exponential transition's exposure, the immediate choices by
//! decision class, the departures of places with a choice, and the agents' stays.

use std::collections::BTreeMap;

use serde::Serialize;

use super::holding::Holding;
use super::{ConformError, Options, Trace, active_servers, stats};
use crate::net::{Net, PlaceId, TransitionId};
use crate::policy::Policy;
use crate::stats::Estimate;

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
