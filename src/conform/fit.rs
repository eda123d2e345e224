//! Calibration: maximum-likelihood rates and weights from a run's observations.

use std::collections::BTreeMap;

use serde::Serialize;

use super::*;
use crate::net::{Net, NetBuilder, PlaceId, Timing, TransitionId};

/// One parameter of a fitted net.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Fitted {
    /// The transition; for `stages` and `mean` the place (`P`) or the place's chain for one
    /// way in (`P from T`, `P from other`).
    pub transition: String,
    /// `rate`, `weight`, or of a place's phase-type holding time: `stages` and `mean` of a
    /// chain, `exit` (an output transition's share of the stays; `old` is its share of the
    /// net's rates).
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
/// outputs' business alone) whose stays a Kolmogorov–Smirnov test of exponentiality (mean
/// estimated from them, Lilliefors) rejects at [`ALPHA`] — gets an
/// Erlang holding time by the method of moments (mean `m`, variance `v`, `k = round(m²/v)`
/// stages of rate `k/m`, at most [`Options::max_stages`]). When the stays depend on how the
/// agent came in (a drive after `Go_Check`, a short re-measure after `AlarmOff`: the entry
/// transitions with at least [`Options::min_gaps`] stays differ in mean by a one-way
/// analysis of variance at [`ALPHA`]), each such entry gets its own chain, and the other
/// entries and the initial tokens one chain fitted to all the stays (a hyper-Erlang
/// mixture by entry); otherwise one chain, kept only when `k ≥ 2`.
///
/// In the net, `P` keeps its tokens for the whole stay (a policy or a plan that reads `P`
/// reads the same marking); an entry `e` also puts its tokens in its chain's first stage
/// (`P~1`, or `P~e~1` when split); infinite-server stage transitions move them on to
/// `P~done`; each output `t` of `P` becomes immediate (weight `q_t`, the share of the stays
/// that left by `t`; priority above every other immediate transition) and also takes its
/// token from `P~done`. The parameters are listed as `stages` and `mean` per chain (named
/// `P` or `P from e`) and `exit` per output.
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
    let phases = phase_fits(net, obs, opts);
    // Exits of a phase-type place fire as soon as an agent's stay ends: immediate, above
    // every other immediate transition (as the timed exit fired before anything it enabled).
    let top = net
        .transitions()
        .iter()
        .filter_map(|t| match t.timing {
            Timing::Immediate { priority, .. } => Some(priority),
            Timing::Exponential { .. } => None,
        })
        .max()
        .unwrap_or(0)
        + 1;
    for ph in &phases {
        let place = &net.place(ph.place).name;
        let total: f64 = ph
            .exits
            .iter()
            .map(|&(t, ..)| match net.transition(t).timing {
                Timing::Exponential { rate, .. } => rate,
                Timing::Immediate { .. } => 0.0,
            })
            .sum();
        for &(t, share, k) in &ph.exits {
            let old = match net.transition(t).timing {
                Timing::Exponential { rate, .. } => rate / total,
                Timing::Immediate { .. } => 0.0,
            };
            timings[t.index()] = Timing::Immediate {
                weight: share,
                priority: top,
            };
            let name = &net.transition(t).name;
            out.retain(|f| !(f.parameter == "rate" && &f.transition == name));
            let (lo, hi) = wilson(k, ph.n);
            out.push(Fitted {
                transition: name.clone(),
                parameter: "exit",
                old,
                new: share,
                interval: Some([lo, hi]),
                n: k,
                kept: false,
            });
        }
        for c in &ph.chains {
            let item = match &c.label {
                None => place.clone(),
                Some(l) => format!("{place} from {l}"),
            };
            out.push(Fitted {
                transition: item.clone(),
                parameter: "stages",
                old: 1.0,
                new: c.stages as f64,
                interval: None,
                n: c.n,
                kept: false,
            });
            out.push(Fitted {
                transition: item,
                parameter: "mean",
                old: 1.0 / total,
                new: c.mean,
                interval: c.interval,
                n: c.n,
                kept: false,
            });
        }
    }
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
    for ph in &phases {
        ph.add_stages(net, &mut b);
    }
    let fitted = b
        .build()
        .expect("the same net with positive finite rates and weights builds");
    (fitted, out)
}

/// One Erlang chain of a place's phase-type holding time.
struct Chain {
    /// The entry it is fitted to (a transition's name, or `other` for the entries with too
    /// few stays and the initial tokens); `None` for a place's only chain.
    label: Option<String>,
    /// The transitions whose tokens into the place start here.
    entries: Vec<TransitionId>,
    /// The place's initial tokens start here.
    initial: bool,
    stages: u32,
    mean: f64,
    /// 95% interval of the mean (Student t over the stays).
    interval: Option<[f64; 2]>,
    n: u64,
}

impl Chain {
    /// The chain fitted to stays `xs` by the method of moments (`None` without a positive
    /// finite mean).
    fn new(
        label: Option<String>,
        entries: Vec<TransitionId>,
        initial: bool,
        xs: &[f64],
        max_stages: u32,
    ) -> Option<Chain> {
        let n = xs.len();
        let mean = xs.iter().sum::<f64>() / n as f64;
        if !(mean > 0.0 && mean.is_finite()) || n < 2 {
            return None;
        }
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n as f64 - 1.0);
        let stages = if var > 0.0 {
            (mean * mean / var).round().min(max_stages as f64)
        } else {
            max_stages as f64
        }
        .max(1.0) as u32;
        let est = stats::estimate(xs);
        Some(Chain {
            label,
            entries,
            initial,
            stages,
            mean,
            interval: Some([est.lo(), est.hi()]),
            n: n as u64,
        })
    }

    fn stage_rate(&self) -> f64 {
        self.stages as f64 / self.mean
    }
}

/// The phase-type holding time fitted to one place: Erlang chains by entry and the exits'
/// shares.
struct PhaseFit {
    place: PlaceId,
    chains: Vec<Chain>,
    /// Each output transition, the share of the stays that left by it and their number.
    exits: Vec<(TransitionId, f64, u64)>,
    /// Stays.
    n: u64,
}

impl PhaseFit {
    /// The stage places and transitions (see [`fit`]), named after the place, beside it on
    /// the canvas.
    fn add_stages(&self, net: &Net, b: &mut NetBuilder) {
        let p = net.place(self.place);
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
        let done_name = unique(b, format!("{}~done", p.name));
        let done = b.add_place(crate::net::Place {
            name: done_name,
            initial: 0,
            capacity: None,
            position: at(0.0, -3.0),
        });
        for (row, c) in self.chains.iter().enumerate() {
            let k = c.stages as usize;
            let prefix = match &c.label {
                None => p.name.clone(),
                Some(l) => format!("{}~{l}", p.name),
            };
            let y = 3.0 + 3.0 * row as f64;
            let stages: Vec<PlaceId> = (1..=k)
                .map(|j| {
                    let name = unique(b, format!("{prefix}~{j}"));
                    b.add_place(crate::net::Place {
                        name,
                        initial: if j == 1 && c.initial { p.initial } else { 0 },
                        capacity: None,
                        position: at(2.0 * j as f64, y),
                    })
                })
                .collect();
            for j in 1..=k {
                let to = if j < k {
                    (j + 1).to_string()
                } else {
                    "done".to_string()
                };
                let name = unique(b, format!("{prefix}~{j}>{to}"));
                let t = b.add_transition(crate::net::Transition {
                    name,
                    timing: Timing::Exponential {
                        rate: c.stage_rate(),
                        servers: crate::net::Servers::Infinite,
                    },
                    position: at(2.0 * j as f64 + 1.0, y + 1.0),
                });
                b.input(stages[j - 1], t, 1);
                b.output(t, if j < k { stages[j] } else { done }, 1);
            }
            for &t in &c.entries {
                if let Some(&(_, w)) = net.outputs(t).iter().find(|(q, _)| *q == self.place) {
                    b.output(t, stages[0], w);
                }
            }
        }
        for &(t, ..) in &self.exits {
            b.input(done, t, 1);
        }
    }
}

/// The places that get a phase-type holding time (see [`fit`]).
fn phase_fits(net: &Net, obs: &Observations, opts: &Options) -> Vec<PhaseFit> {
    let mut fits = Vec::new();
    let min = opts.min_gaps.max(2);
    for (p, outs) in holding::by_place(net, &obs.holdings) {
        if holding::race_rate(net, p).is_none() {
            continue;
        }
        let stays: Vec<&Holding> = outs.iter().flat_map(|(_, hs)| hs.iter().copied()).collect();
        let xs: Vec<f64> = stays.iter().map(|h| h.duration).collect();
        let n = xs.len();
        if n < min || outs.iter().any(|(_, hs)| hs.is_empty()) {
            continue;
        }
        match stats::ks_exponential(&xs) {
            Some((_, p_value)) if p_value < ALPHA => {}
            _ => continue,
        }
        // The ways in, with the stays that came in by each.
        let by_entry: Vec<(TransitionId, Vec<f64>)> = net
            .transition_ids()
            .filter(|&t| net.outputs(t).iter().any(|(q, _)| *q == p))
            .map(|t| {
                let ys = stays
                    .iter()
                    .filter(|h| h.entry == Some(t))
                    .map(|h| h.duration)
                    .collect();
                (t, ys)
            })
            .collect();
        let (big, rest): (Vec<_>, Vec<_>) = by_entry.iter().partition(|(_, ys)| ys.len() >= min);
        let groups: Vec<&[f64]> = big.iter().map(|(_, ys)| ys.as_slice()).collect();
        let split = big.len() >= 2 && stats::anova_p(&groups) < ALPHA;
        let chains: Option<Vec<Chain>> = if split {
            let mut chains: Vec<Option<Chain>> = big
                .iter()
                .map(|(t, ys)| {
                    let name = net.transition(*t).name.clone();
                    Chain::new(Some(name), vec![*t], false, ys, opts.max_stages)
                })
                .collect();
            if !rest.is_empty() || net.place(p).initial > 0 {
                let entries = rest.iter().map(|(t, _)| *t).collect();
                let other = Some("other".to_string());
                chains.push(Chain::new(other, entries, true, &xs, opts.max_stages));
            }
            chains.into_iter().collect()
        } else {
            let entries = by_entry.iter().map(|(t, _)| *t).collect();
            Chain::new(None, entries, true, &xs, opts.max_stages)
                .filter(|c| c.stages >= 2)
                .map(|c| vec![c])
        };
        let Some(chains) = chains else { continue };
        fits.push(PhaseFit {
            place: p,
            chains,
            exits: outs
                .iter()
                .map(|(t, hs)| (*t, hs.len() as f64 / n as f64, hs.len() as u64))
                .collect(),
            n: n as u64,
        });
    }
    fits
}

/// Fits the weights of immediate transitions from the decisions without a policy rule:
/// the transitions that meet in a class form a group ([`choice_groups`]); a group with
/// enough decisions gets Luce's maximum-likelihood weights ([`luce_weights`]), scaled to
/// its old total, each with an interval ([`weight_interval`]); the others keep theirs.
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
    let mut wins = vec![0u64; nt];
    let mut decided = vec![0u64; nt];
    for d in &classes {
        let total: u64 = d.counts.iter().sum();
        for (&t, &c) in d.firable.iter().zip(&d.counts) {
            wins[t.index()] += c;
            decided[t.index()] += total;
        }
    }
    let (mut parent, groups) = choice_groups(&classes, nt);
    for members in groups.values() {
        let enough = members
            .iter()
            .all(|&t| decided[t] >= opts.min_firings && wins[t] > 0);
        let old_total: f64 = members
            .iter()
            .map(|&t| weight(TransitionId(t as u32)))
            .sum();
        let w = if enough {
            luce_weights(&classes, &mut parent, members, &wins, old_total)
        } else {
            vec![1.0; nt]
        };
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
            let interval = enough.then(|| weight_interval(&classes, id, &w)).flatten();
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

/// The union–find root of `i`, halving the path on the way.
fn root(parent: &mut [usize], mut i: usize) -> usize {
    while parent[i] != i {
        parent[i] = parent[parent[i]];
        i = parent[i];
    }
    i
}

/// Groups of transitions linked by appearing in one class (union–find): the parents, and
/// each group's members by root, in order of first appearance.
fn choice_groups(classes: &[&Decision], nt: usize) -> (Vec<usize>, BTreeMap<usize, Vec<usize>>) {
    let mut parent: Vec<usize> = (0..nt).collect();
    for d in classes {
        for w in d.firable.windows(2) {
            let (a, b) = (
                root(&mut parent, w[0].index()),
                root(&mut parent, w[1].index()),
            );
            parent[a] = b;
        }
    }
    let mut groups: BTreeMap<usize, Vec<usize>> = BTreeMap::new();
    for d in classes {
        for &t in &d.firable {
            let r = root(&mut parent, t.index());
            let g = groups.entry(r).or_default();
            if !g.contains(&t.index()) {
                g.push(t.index());
            }
        }
    }
    (parent, groups)
}

/// Luce's model's weights for one group by minorisation–maximisation (Hunter 2004),
/// scaled to the group's old total (or to one each when it had none); indexed by
/// transition, 1 outside the group.
fn luce_weights(
    classes: &[&Decision],
    parent: &mut [usize],
    members: &[usize],
    wins: &[u64],
    old_total: f64,
) -> Vec<f64> {
    let nt = wins.len();
    let mut w: Vec<f64> = vec![1.0; nt];
    for _ in 0..500 {
        let mut denom = vec![0.0; nt];
        for d in classes {
            if root(parent, d.firable[0].index()) != root(parent, members[0]) {
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
    w
}

/// The interval of `id`'s fitted weight: its share in the class where it was decided most,
/// as a weight against the others' fitted weights `w` there (Wilson score interval);
/// `None` when unbounded.
fn weight_interval(classes: &[&Decision], id: TransitionId, w: &[f64]) -> Option<[f64; 2]> {
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
    Some([odds(lo), odds(hi)]).filter(|[_, hi]| hi.is_finite())
}

/// The 95% Wilson score interval of a proportion `k / n`.
fn wilson(k: u64, n: u64) -> (f64, f64) {
    let (k, n, z) = (k as f64, n as f64, stats::Z975);
    let p = k / n;
    let c = (p + z * z / (2.0 * n)) / (1.0 + z * z / n);
    let h = z / (1.0 + z * z / n) * (p * (1.0 - p) / n + z * z / (4.0 * n * n)).sqrt();
    ((c - h).max(0.0), (c + h).min(1.0))
}
