//! The viewer's conformance table: what a run's monitor ([`SharedMonitor`]) sees now, item by
//! item — observed beside predicted, with the 95% interval — sent as `"conform"` in every
//! live state frame and drawn by `conform.js`, drifting rows highlighted.

use serde_json::value::RawValue;
use serde_json::{Value, json};

use crate::conform::{SharedMonitor, Statistic};
use crate::net::{Net, TransitionId};
use crate::runtime::Monitored;

/// The rows: `[{kind: "rate"|"mean_tokens", item, observed, predicted, interval: [lo, hi],
/// n, p_value, drifting}]`, transitions first (net order), then places.
pub(crate) fn rows(net: &Net, monitor: &SharedMonitor) -> Value {
    Value::Array(monitor.statistics().iter().map(|s| row(net, s)).collect())
}

fn row(net: &Net, s: &Statistic) -> Value {
    let (f, drifting) = (&s.figures, s.drifting);
    let (kind, item) = match f.of {
        Monitored::Transition(t) => ("rate", &net.transition(t).name),
        Monitored::Place(p) => ("mean_tokens", &net.place(p).name),
    };
    json!({
        "kind": kind,
        "item": item,
        "observed": f.observed,
        "predicted": f.predicted,
        "interval": f.interval,
        "n": f.n,
        "p_value": f.p_value,
        "drifting": drifting,
    })
}

/// Most snapshots of a replay's table (a long journal is sampled evenly).
const REPLAY_SNAPSHOTS: usize = 400;

/// The table along a recorded run, built as its firings are read: a
/// [`crate::conform::Monitor`] of `net` (its transitions' rates: a journal does not say which
/// policy ran it, so places, whose prediction depends on it, are left out) fed the recorded
/// firings; `[{time, rows}]` at most [`REPLAY_SNAPSHOTS`] times, evenly spread over the run
/// however long it is (every `every`-th firing; when that makes too many, every other
/// snapshot is dropped and `every` doubles), and always after the last firing — from the
/// first firing that has statistics on.
pub(crate) struct ReplayRows {
    net: Net,
    monitor: SharedMonitor,
    every: usize,
    firings: usize,
    last_time: f64,
    /// The snapshots as their JSON text (a tenth of the memory of `Value`s).
    out: Vec<Box<RawValue>>,
}

impl ReplayRows {
    /// A table of a run of `net` from `initial`.
    pub(crate) fn new(net: &Net, initial: Vec<u32>) -> ReplayRows {
        ReplayRows {
            net: net.clone(),
            monitor: SharedMonitor::new(crate::conform::Monitor::new(
                net,
                initial,
                Default::default(),
            )),
            every: 1,
            firings: 0,
            last_time: 0.0,
            out: Vec::new(),
        }
    }

    /// `t` fired at `time`, leaving `tokens`.
    pub(crate) fn fired(&mut self, time: f64, t: TransitionId, tokens: &[u32]) {
        let mut watcher = self.monitor.clone();
        crate::runtime::Watcher::fired(&mut watcher, time, t, tokens);
        self.firings += 1;
        self.last_time = time;
        if self.firings.is_multiple_of(self.every) {
            self.snapshot();
        }
        if self.out.len() > REPLAY_SNAPSHOTS {
            let mut i = 0;
            self.out.retain(|_| {
                i += 1;
                i % 2 == 0
            });
            self.every *= 2;
        }
    }

    fn snapshot(&mut self) {
        let rows = rows(&self.net, &self.monitor);
        if rows.as_array().is_some_and(|r| !r.is_empty())
            && let Ok(raw) =
                serde_json::value::to_raw_value(&json!({ "time": self.last_time, "rows": rows }))
        {
            self.out.push(raw);
        }
    }

    /// The snapshots, the last firing's included; `None` when no transition ever had
    /// enough firings.
    pub(crate) fn finish(mut self) -> Option<Box<RawValue>> {
        if !self.firings.is_multiple_of(self.every) {
            self.snapshot();
        }
        (!self.out.is_empty())
            .then(|| serde_json::value::to_raw_value(&self.out).ok())
            .flatten()
    }
}

/// [`ReplayRows`] of `frames` (the initial marking, then the marking after each firing).
pub(crate) fn replay_rows(
    net: &Net,
    frames: &[crate::runtime::journal::Frame],
) -> Option<Box<RawValue>> {
    let first = frames.first()?;
    let mut table = ReplayRows::new(net, first.tokens.clone());
    for f in &frames[1..] {
        if let Some(t) = f
            .transition
            .as_deref()
            .and_then(|n| net.transition_by_name(n))
        {
            table.fired(f.time, t, &f.tokens);
        }
    }
    table.finish()
}
