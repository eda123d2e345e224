//! Calibration: maximum-likelihood rates and weights from a run's observations.

use std::collections::BTreeMap;

use serde::Serialize;

use super::*;
use crate::net::{Net, NetBuilder, Timing, TransitionId};

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
