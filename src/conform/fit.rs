//! Calibration: maximum-likelihood rates and weights from a run's observations.

use std::collections::BTreeMap;

use serde::Serialize;

use super::*;
use crate::net::{Net, NetBuilder, PlaceId, Timing, TransitionId};

/// One parameter of a fitted net.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fitted {
    /// The transition (the place, for `stages`).
    pub transition: String,
    /// `rate`, `weight`, `stages` (of a place's Erlang holding time) or `stage_rate` (an
    /// output transition's rate out of the last stage).
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
///
/// **Phase-type holding times.** An action place whose agents' stays (see
/// [`super::holding`]) the exponential does not fit — a race place (so the stays are the
/// outputs' business alone) whose `holding_shape` test rejects at [`ALPHA`] — gets an
/// Erlang-`k` holding time by the method of moments: mean `m` and variance `v` of its stays,
/// `k = round(m²/v)` (at most [`Options::max_stages`]; a `k` of 1 keeps the exponential).
/// The net gets `k` stage places `P~1 … P~k` beside `P`: every arc into `P` also puts its
/// tokens in `P~1`, stage transitions `P~1>2 …` (rate `k/m`, infinite servers) move them on,
/// and each output `t` of `P` also takes its token from `P~k`, at rate `q_t·k/m` where `q_t`
/// is the share of the stays that left by `t`. `P` itself keeps its tokens for the whole
/// stay, so a policy or a plan that reads `P` reads the same marking.
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
    let erlang = erlang_fits(net, obs, opts);
    let mut b = NetBuilder::new(net.name());
    for p in net.places() {
        b.add_place(p.clone());
    }
    for e in &erlang {
        for (t, q) in &e.exits {
            if let Timing::Exponential { servers, .. } = timings[t.index()] {
                let rate = q * e.stage_rate();
                timings[t.index()] = Timing::Exponential { rate, servers };
                if let Some(f) = out
                    .iter_mut()
                    .find(|f| f.parameter == "rate" && f.transition == net.transition(*t).name)
                {
                    f.parameter = "stage_rate";
                    f.new = rate;
                    f.interval = None;
                    f.kept = false;
                }
            }
        }
        out.push(Fitted {
            transition: net.place(e.place).name.clone(),
            parameter: "stages",
            old: 1.0,
            new: e.stages as f64,
            interval: None,
            n: e.n,
            kept: false,
        });
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
    for e in &erlang {
        e.add_stages(net, &mut b);
    }
    let fitted = b
        .build()
        .expect("the same net with positive finite rates and weights builds");
    (fitted, out)
}

/// The Erlang holding time fitted to one place.
struct ErlangFit {
    place: PlaceId,
    stages: u32,
    mean: f64,
    /// Share of the stays out by each output transition.
    exits: Vec<(TransitionId, f64)>,
    n: u64,
}

impl ErlangFit {
    fn stage_rate(&self) -> f64 {
        self.stages as f64 / self.mean
    }

    /// The stage places and transitions (see [`fit`]), named after the place, beside it on
    /// the canvas.
    fn add_stages(&self, net: &Net, b: &mut NetBuilder) {
        let p = net.place(self.place);
        let k = self.stages as usize;
        let unique = |b: &NetBuilder, name: String| {
            let mut n = name.clone();
            let mut i = 1;
            while b.find_place(&n).is_some() || b.find_transition(&n).is_some() {
                i += 1;
                n = format!("{name}~{i}");
            }
            n
        };
        let at = |dx: f64, dy: f64| {
            p.position.map(|q| crate::net::Position {
                x: q.x + dx,
                y: q.y + dy,
            })
        };
        let stages: Vec<PlaceId> = (1..=k)
            .map(|j| {
                let name = unique(b, format!("{}~{j}", p.name));
                b.add_place(crate::net::Place {
                    name,
                    initial: if j == 1 { p.initial } else { 0 },
                    capacity: None,
                    position: at(2.0 * j as f64, 3.0),
                })
            })
            .collect();
        for j in 1..k {
            let name = unique(b, format!("{}~{j}>{}", p.name, j + 1));
            let t = b.add_transition(crate::net::Transition {
                name,
                timing: Timing::Exponential {
                    rate: self.stage_rate(),
                    servers: crate::net::Servers::Infinite,
                },
                position: at(2.0 * j as f64 + 1.0, 4.0),
            });
            b.input(stages[j - 1], t, 1);
            b.output(t, stages[j], 1);
        }
        for t in net.transition_ids() {
            if let Some(&(_, w)) = net.outputs(t).iter().find(|(q, _)| *q == self.place) {
                b.output(t, stages[0], w);
            }
        }
        for &(t, _) in &self.exits {
            b.input(stages[k - 1], t, 1);
        }
    }
}

/// The places that get an Erlang holding time (see [`fit`]).
fn erlang_fits(net: &Net, obs: &Observations, opts: &Options) -> Vec<ErlangFit> {
    let mut fits = Vec::new();
    for (p, outs) in holding::by_place(net, &obs.holdings) {
        if holding::race_rate(net, p).is_none() {
            continue;
        }
        let xs: Vec<f64> = outs
            .iter()
            .flat_map(|(_, hs)| hs.iter().map(|h| h.duration))
            .collect();
        let n = xs.len();
        if n < opts.min_gaps.max(2) || outs.iter().any(|(_, hs)| hs.is_empty()) {
            continue;
        }
        match stats::ks_exponential(&xs) {
            Some((_, p_value)) if p_value < ALPHA => {}
            _ => continue,
        }
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        if !(mean > 0.0 && mean.is_finite()) {
            continue;
        }
        let k = if var > 0.0 {
            (mean * mean / var).round().min(opts.max_stages as f64)
        } else {
            opts.max_stages as f64
        }
        .max(1.0) as u32;
        if k < 2 {
            continue;
        }
        fits.push(ErlangFit {
            place: p,
            stages: k,
            mean,
            exits: outs
                .iter()
                .map(|(t, hs)| (*t, hs.len() as f64 / n as f64))
                .collect(),
            n: n as u64,
        });
    }
    fits
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
