//! The viewer's conformance table: what a run's monitor ([`SharedMonitor`]) sees now, item by
//! item — observed beside predicted, with the 95% interval — sent as `"conform"` in every
//! live state frame and drawn by `conform.js`, drifting rows highlighted.

use serde_json::{Value, json};

use crate::conform::{SharedMonitor, Statistic};
use crate::net::Net;
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

/// The table along a recorded run: a [`crate::conform::Monitor`] of `net` (its transitions'
/// rates: a journal does not say which policy ran it, so places, whose prediction depends on
/// it, are left out) fed the recorded firings; `[{time, rows}]` after every firing — at most
/// [`REPLAY_SNAPSHOTS`], evenly spread, and always the last one — from the first firing that
/// has statistics on. `None` when no transition ever has enough firings.
pub(crate) fn replay_rows(net: &Net, frames: &[crate::runtime::journal::Frame]) -> Option<Value> {
    let first = frames.first()?;
    let monitor = SharedMonitor::new(crate::conform::Monitor::new(
        net,
        first.tokens.clone(),
        Default::default(),
    ));
    let mut watcher = monitor.clone();
    let every = frames.len().div_ceil(REPLAY_SNAPSHOTS).max(1);
    let mut out = Vec::new();
    for (i, f) in frames.iter().enumerate().skip(1) {
        let Some(t) = f
            .transition
            .as_deref()
            .and_then(|n| net.transition_by_name(n))
        else {
            continue;
        };
        crate::runtime::Watcher::fired(&mut watcher, f.time, t, &f.tokens);
        if i % every == 0 || i + 1 == frames.len() {
            let rows = rows(net, &monitor);
            if rows.as_array().is_some_and(|r| !r.is_empty()) {
                out.push(json!({ "time": f.time, "rows": rows }));
            }
        }
    }
    (!out.is_empty()).then_some(Value::Array(out))
}
