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
    let (kind, item) = match s.of {
        Monitored::Transition(t) => ("rate", &net.transition(t).name),
        Monitored::Place(p) => ("mean_tokens", &net.place(p).name),
    };
    json!({
        "kind": kind,
        "item": item,
        "observed": s.observed,
        "predicted": s.predicted,
        "interval": s.interval,
        "n": s.n,
        "p_value": s.p_value,
        "drifting": s.drifting,
    })
}
