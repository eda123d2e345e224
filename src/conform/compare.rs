//! Observations beside predictions: one row per measure, with its interval and verdict.

use serde::Serialize;

use super::*;
use crate::net::{Net, Timing, TransitionId};
use crate::stats::Estimate;

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
    /// The mean time agents stayed in an action place before one output transition took
    /// them out.
    Holding,
    /// Whether the agents' stays in an action place follow the predicted exponential.
    HoldingShape,
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
    /// The observation (for `shape` and `holding_shape`: the modified KS statistic; for
    /// `decision`: Pearson's X²).
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
    /// Counts beside expectations (decision rows); why the model predicts nothing (holding
    /// rows with `no_prediction`).
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

/// Sets the observations beside the model: the rows of the module's table, in its order —
/// tokens and throughputs, then [`rate_rows`], [`choice_rows`], [`decision_row`]s and
/// [`holding_rows`].
pub fn compare(net: &Net, obs: &Observations, pred: &Predictions, opts: &Options) -> Report {
    let mut rows = Vec::new();
    for (p, e) in obs.mean_tokens.iter().enumerate() {
        let x = pred.mean_tokens.as_ref().map(|v| v[p]);
        let name = net.places()[p].name.clone();
        rows.push(batch_row(RowKind::MeanTokens, name, e, x, obs.batches));
    }
    for (t, e) in obs.throughput.iter().enumerate() {
        let x = pred.throughput.as_ref().map(|v| v[t]);
        let name = net.transitions()[t].name.clone();
        rows.push(batch_row(RowKind::Throughput, name, e, x, obs.batches));
    }
    rate_rows(net, obs, opts, &mut rows);
    choice_rows(net, obs, pred, &mut rows);
    rows.extend(
        obs.decisions
            .iter()
            .filter(|d| d.firable.len() >= 2 || d.outside > 0)
            .map(|d| decision_row(net, d, opts)),
    );
    holding_rows(net, obs, pred, opts, &mut rows);
    Report {
        net: net.name().to_string(),
        predictions: pred.source.clone(),
        time: obs.end,
        firings: obs.firings,
        batches: obs.batches,
        rows,
    }
}

/// Per exponential transition, its `rate` row (firings over exposure against the net's
/// rate) and its `shape` row (the enabled-time gaps against an exponential law).
fn rate_rows(net: &Net, obs: &Observations, opts: &Options, rows: &mut Vec<Row>) {
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
}

/// Per place with a choice and each of its output transitions, the share of the place's
/// departures against the share of the predicted flows.
fn choice_rows(net: &Net, obs: &Observations, pred: &Predictions, rows: &mut Vec<Row>) {
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
}

/// The `decision` row of one class of immediate choices: the counts against the
/// probabilities (a χ² test where enough are expected; p = 0 for an impossible choice).
fn decision_row(net: &Net, d: &Decision, opts: &Options) -> Row {
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
    } else if min_expected >= opts.min_expected || d.probs.iter().filter(|p| **p > 0.0).count() <= 1
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
    Row {
        kind: RowKind::Decision,
        item,
        observed: x2,
        interval: None,
        predicted: None,
        n: total,
        p_value: p,
        verdict: p.map_or(Verdict::TooLittleData, verdict),
        detail: Some(detail.join(", ")),
    }
}

/// The `holding` rows (per place and exit transition) and the `holding_shape` row (per
/// place) of the agents' stays (see [`super::holding`]): every stay that ended within the
/// run, tested where the model predicts it ([`holding::stay_model`], with the most tokens
/// each place holds in a tangible marking: `pred.bounds`, else the P-invariants' bounds, and
/// never fewer than the run held); elsewhere shown with `no prediction` and why.
fn holding_rows(
    net: &Net,
    obs: &Observations,
    pred: &Predictions,
    opts: &Options,
    rows: &mut Vec<Row>,
) {
    let bounds: Vec<Option<u32>> = match &pred.bounds {
        Some(b) => b.iter().map(|&k| Some(k)).collect(),
        None => crate::analysis::invariants::structural_bounds(net)
            .into_iter()
            .map(|b| b.and_then(|k| u32::try_from(k).ok()))
            .collect(),
    };
    for (p, outs) in holding::by_place(net, &obs.holdings) {
        let seen = obs.most_tokens.get(p.index()).copied().unwrap_or(0);
        let bound = bounds[p.index()].map(|b| b.max(seen));
        let model = holding::stay_model(net, p, bound);
        let (rate, why) = match &model {
            holding::StayModel::Exponential { rate } => (Some(*rate), None),
            holding::StayModel::Unpredicted(u) => (None, Some(u.describe(net))),
        };
        // (duration, horizon): a stay that entered `horizon` before the end was seen ended
        // only because it was shorter.
        let stays = |hs: &[&Holding]| -> Vec<(f64, f64)> {
            hs.iter()
                .map(|h| (h.duration, obs.end - h.entered))
                .collect()
        };
        let mut all = Vec::new();
        for (t, hs) in &outs {
            let xs = stays(hs);
            all.extend_from_slice(&xs);
            let n = xs.len() as u64;
            let durations: Vec<f64> = xs.iter().map(|s| s.0).collect();
            let mean = durations.iter().sum::<f64>() / n.max(1) as f64;
            let p_value = rate
                .filter(|_| n >= opts.min_firings)
                .and_then(|r| stats::stays_mean_test(&xs, r));
            let e = (n >= 2).then(|| stats::estimate(&durations));
            rows.push(Row {
                kind: RowKind::Holding,
                item: format!("{} -> {}", net.place(p).name, net.transition(*t).name),
                observed: mean,
                interval: e.map(|e| [e.lo().max(0.0), e.hi()]),
                predicted: rate.map(|r| 1.0 / r),
                n,
                p_value,
                verdict: match (rate, p_value) {
                    (None, _) => Verdict::NoPrediction,
                    (Some(_), None) => Verdict::TooLittleData,
                    (Some(_), Some(p)) => verdict(p),
                },
                detail: why.clone(),
            });
        }
        // Against the predicted exponential where there is one; otherwise, for information,
        // the Kolmogorov–Smirnov statistic against an exponential of the stays' own mean.
        let ks = (all.len() >= opts.min_gaps)
            .then(|| match rate {
                Some(r) => stats::stays_ks_test(&all, r),
                None => stats::ks_exponential(&all.iter().map(|s| s.0).collect::<Vec<_>>()),
            })
            .flatten();
        rows.push(Row {
            kind: RowKind::HoldingShape,
            item: net.place(p).name.clone(),
            observed: ks.map_or(0.0, |k| k.0),
            interval: None,
            predicted: None,
            n: all.len() as u64,
            p_value: ks.filter(|_| rate.is_some()).map(|k| k.1),
            verdict: match (rate, ks) {
                (None, _) => Verdict::NoPrediction,
                (Some(_), None) => Verdict::TooLittleData,
                (Some(_), Some(k)) => verdict(k.1),
            },
            detail: why,
        });
    }
}
