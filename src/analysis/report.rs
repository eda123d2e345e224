//! The analysis report: typed, [`Serialize`] results that `plan-runner analyze --json` prints
//! ([`Report`]) and the viewer's analysis panel sends ([`Panel`]). Both are built here from
//! the same pieces — [`StateSpaceReport`], [`MeasuresReport`], [`DeadMarkingReport`] and the
//! by-name maps — so a measure is named and shaped once.
//!
//! Values per place or per transition are maps by name ([`ByName`]), serialized in name
//! order. A JSON value of a report (`serde_json::to_value`) has its keys sorted, as the CLI
//! prints it.

use std::collections::BTreeMap;

use serde::Serialize;

use super::invariants::Invariants;
use super::measures::{Measures, TransientPoint};
use super::properties::{DeadMarking, Liveness, Properties};
use super::state_space::Census;
use super::under_policy::{Regime, RewardRate};
use crate::net::{Net, TransitionId};

/// Values keyed by place or transition name.
pub type ByName<T> = BTreeMap<String, T>;

/// `values[i]` keyed by the name of place `i`.
pub fn by_place<T: Clone>(net: &Net, values: &[T]) -> ByName<T> {
    net.places()
        .iter()
        .zip(values)
        .map(|(p, v)| (p.name.clone(), v.clone()))
        .collect()
}

/// `values[i]` keyed by the name of transition `i`.
pub fn by_transition<T: Clone>(net: &Net, values: &[T]) -> ByName<T> {
    net.transitions()
        .iter()
        .zip(values)
        .map(|(t, v)| (t.name.clone(), v.clone()))
        .collect()
}

/// The names of transitions `ts`, in their order.
pub fn transition_names(net: &Net, ts: &[TransitionId]) -> Vec<String> {
    ts.iter().map(|&t| net.transition(t).name.clone()).collect()
}

/// `plan-runner analyze --json`: the state space, the steady state, transient measures.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// What was analysed: "bare net" or "net under plan policy"
    /// ([`Regime::label`](super::under_policy::Regime::label)).
    pub analysed: String,
    /// Reachability and properties.
    pub state_space: StateSpaceReport,
    /// The steady state (limiting distribution from the initial marking); `null` when not
    /// asked for or not computable.
    pub steady_state: Option<MeasuresReport>,
    /// Measures at each asked time.
    pub transient: Vec<MeasuresReport>,
    /// The answers to `--query`, in the order asked; left out when none was asked.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub queries: Vec<QueryAnswer>,
}

/// One query (`P=? [F<=600 done=1]`) and its value.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct QueryAnswer {
    /// The query as written.
    pub query: String,
    /// Its value; an infinite expected time or reward is written `"inf"` (JSON has no ∞).
    #[serde(serialize_with = "number_or_inf")]
    pub value: f64,
}

fn number_or_inf<S: serde::Serializer>(v: &f64, s: S) -> Result<S::Ok, S::Error> {
    if v.is_infinite() {
        s.serialize_str(if *v > 0.0 { "inf" } else { "-inf" })
    } else {
        s.serialize_f64(*v)
    }
}

/// What the state space says. Every field but `bounded`, `unbounded_places` and `safe` is
/// `null` for an unbounded net (no state space).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StateSpaceReport {
    /// Reachable markings.
    pub reachable: Option<usize>,
    /// Tangible ones.
    pub tangible: Option<usize>,
    /// Vanishing ones.
    pub vanishing: Option<usize>,
    /// Labelled edges of the reachability graph: one per marking and fired transition
    /// ([`Properties::edges`]).
    pub edges: Option<usize>,
    /// Distinct (marking, successor) pairs ([`Properties::successor_pairs`]).
    pub successor_pairs: Option<usize>,
    /// Dead markings, written as `Place=k` lists.
    pub dead_markings: Option<Vec<String>>,
    /// Whether the net is bounded.
    pub bounded: bool,
    /// Places that grow without limit (empty when bounded).
    pub unbounded_places: Vec<String>,
    /// Most tokens each place ever holds.
    pub place_bounds: Option<ByName<u32>>,
    /// Most tokens in one place.
    pub max_tokens_in_place: Option<u32>,
    /// Most tokens in one marking.
    pub max_tokens_per_marking: Option<u64>,
    /// No place ever holds more than one token.
    pub safe: bool,
    /// The initial marking is reachable from every reachable marking.
    pub reversible: Option<bool>,
    /// No reachable dead marking.
    pub deadlock_free: Option<bool>,
    /// Live transitions, by name.
    pub live_transitions: Option<Vec<String>>,
    /// Dead transitions, by name.
    pub dead_transitions: Option<Vec<String>>,
    /// P-invariants: weights by place name (non-zero only).
    pub p_invariants: Option<Vec<ByName<u64>>>,
    /// T-invariants: weights by transition name (non-zero only).
    pub t_invariants: Option<Vec<ByName<u64>>>,
}

/// The P- and T-invariants of `net` with place and transition names.
fn named_invariants(
    net: &Net,
    pinv: &Invariants,
    tinv: &Invariants,
) -> (Vec<ByName<u64>>, Vec<ByName<u64>>) {
    let places: Vec<&str> = net.places().iter().map(|p| p.name.as_str()).collect();
    let transitions: Vec<&str> = net.transitions().iter().map(|t| t.name.as_str()).collect();
    (invariants(pinv, &places), invariants(tinv, &transitions))
}

fn invariants(inv: &Invariants, names: &[&str]) -> Vec<ByName<u64>> {
    inv.vectors
        .iter()
        .map(|v| {
            v.entries()
                .iter()
                .map(|&(i, w)| (names[i as usize].to_string(), w))
                .collect()
        })
        .collect()
}

impl StateSpaceReport {
    /// The report of a bounded net.
    pub fn new(net: &Net, p: &Properties, pinv: &Invariants, tinv: &Invariants) -> Self {
        let (p_invariants, t_invariants) = named_invariants(net, pinv, tinv);
        StateSpaceReport {
            reachable: Some(p.reachable),
            tangible: Some(p.tangible),
            vanishing: Some(p.vanishing),
            edges: Some(p.edges),
            successor_pairs: Some(p.successor_pairs),
            dead_markings: Some(
                p.dead_markings
                    .iter()
                    .map(|d| net.format_marking(&d.marking))
                    .collect(),
            ),
            bounded: true,
            unbounded_places: Vec::new(),
            place_bounds: Some(by_place(net, &p.place_bounds)),
            max_tokens_in_place: Some(p.max_tokens_in_place),
            max_tokens_per_marking: Some(p.max_tokens_per_marking),
            safe: p.safe,
            reversible: Some(p.reversible),
            deadlock_free: Some(p.deadlock_free),
            live_transitions: Some(transition_names(net, &p.live_transitions())),
            dead_transitions: Some(transition_names(net, &p.dead_transitions())),
            p_invariants: Some(p_invariants),
            t_invariants: Some(t_invariants),
        }
    }

    /// The report of a search that stored no arc ([`Census`]): counts, bounds and dead
    /// markings; what needs the arcs (reversibility, liveness) and the invariants are left
    /// out. `edges` is the labelled arcs when there are no vanishing markings (then it is
    /// [`Properties::edges`]); with vanishing markings that count needs them eliminated, so
    /// it is left out and `successor_pairs` counts the full graph.
    pub fn census(net: &Net, c: &Census) -> Self {
        let max_tokens_in_place = c.place_bounds.iter().copied().max().unwrap_or(0);
        StateSpaceReport {
            reachable: Some(c.reachable),
            tangible: Some(c.tangible),
            vanishing: Some(c.vanishing),
            edges: (c.vanishing == 0).then_some(c.arcs),
            successor_pairs: Some(c.successor_pairs),
            dead_markings: Some(
                c.dead_markings
                    .iter()
                    .map(|d| net.format_marking(&d.marking))
                    .collect(),
            ),
            bounded: true,
            unbounded_places: Vec::new(),
            place_bounds: Some(by_place(net, &c.place_bounds)),
            max_tokens_in_place: Some(max_tokens_in_place),
            max_tokens_per_marking: Some(c.max_tokens_per_marking),
            safe: max_tokens_in_place <= 1,
            reversible: None,
            deadlock_free: Some(c.dead_markings.is_empty()),
            live_transitions: None,
            dead_transitions: None,
            p_invariants: None,
            t_invariants: None,
        }
    }

    /// The report of an unbounded net: these places grow without limit.
    pub fn unbounded(places: &[String]) -> Self {
        StateSpaceReport {
            reachable: None,
            tangible: None,
            vanishing: None,
            edges: None,
            successor_pairs: None,
            dead_markings: None,
            bounded: false,
            unbounded_places: places.to_vec(),
            place_bounds: None,
            max_tokens_in_place: None,
            max_tokens_per_marking: None,
            safe: false,
            reversible: None,
            deadlock_free: None,
            live_transitions: None,
            dead_transitions: None,
            p_invariants: None,
            t_invariants: None,
        }
    }
}

/// Measures of one distribution (the steady state, or the state at time `t`). The CLI's
/// steady state carries every field; a transient point has `t` and no `ergodic`,
/// `prob_nonempty` or `mean_wait`; the viewer's steady state only `ergodic`, `mean_tokens`
/// and `throughput`. Absent fields are left out of the JSON.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct MeasuresReport {
    /// The time of a transient point.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub t: Option<f64>,
    /// Whether the chain is ergodic (steady state only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ergodic: Option<bool>,
    /// E[tokens] per place.
    pub mean_tokens: ByName<f64>,
    /// P(place holds a token).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub prob_nonempty: Option<ByName<f64>>,
    /// Firings per unit time.
    pub throughput: ByName<f64>,
    /// Mean time a token spends in each place (`null` when nothing leaves it).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub mean_wait: Option<ByName<Option<f64>>>,
    /// Probabilities of the asked predicates, by their text.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub probability: Option<ByName<f64>>,
    /// Long-run rates of the plan's reward structures, by name (steady state only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub rewards: Option<ByName<RewardReport>>,
}

/// The long-run rate of one reward structure (per unit of time).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RewardReport {
    /// Total rate: `places + transitions`.
    pub rate: f64,
    /// Earned by place rates.
    pub places: f64,
    /// Earned by transition impulses.
    pub transitions: f64,
}

impl MeasuresReport {
    /// The steady state: every measure (`analyze --json`).
    pub fn steady(net: &Net, ergodic: bool, m: &Measures) -> Self {
        MeasuresReport {
            ergodic: Some(ergodic),
            mean_tokens: by_place(net, &m.mean_tokens),
            prob_nonempty: Some(by_place(net, &m.prob_nonempty)),
            throughput: by_transition(net, &m.throughput),
            mean_wait: Some(by_place(net, &m.mean_wait)),
            ..MeasuresReport::default()
        }
    }

    /// The state at time `t`: mean tokens and throughputs.
    pub fn transient(net: &Net, t: f64, m: &Measures) -> Self {
        MeasuresReport {
            t: Some(t),
            ..MeasuresReport::tokens_and_throughput(net, m)
        }
    }

    /// A transient point with the probabilities of the predicates `exprs` (their texts, in
    /// the order [`Solver::transient_points`](crate::analysis::measures::Solver::transient_points)
    /// was given them): one entry of `analyze --json`'s `transient`, and of the viewer's.
    pub fn point(net: &Net, p: &TransientPoint, exprs: &[String]) -> Self {
        MeasuresReport::transient(net, p.t, &p.measures).with_probabilities(exprs, &p.probabilities)
    }

    /// The steady state as the viewer's panel shows it: mean tokens and throughputs.
    pub fn panel(net: &Net, ergodic: bool, m: &Measures) -> Self {
        MeasuresReport {
            ergodic: Some(ergodic),
            ..MeasuresReport::tokens_and_throughput(net, m)
        }
    }

    fn tokens_and_throughput(net: &Net, m: &Measures) -> Self {
        MeasuresReport {
            mean_tokens: by_place(net, &m.mean_tokens),
            throughput: by_transition(net, &m.throughput),
            ..MeasuresReport::default()
        }
    }

    /// Adds the reward rates (none: nothing is added).
    pub fn with_rewards(mut self, rewards: &[RewardRate]) -> Self {
        if !rewards.is_empty() {
            self.rewards = Some(
                rewards
                    .iter()
                    .map(|r| {
                        let v = RewardReport {
                            rate: r.rate,
                            places: r.places,
                            transitions: r.transitions,
                        };
                        (r.name.clone(), v)
                    })
                    .collect(),
            );
        }
        self
    }

    /// Adds the probabilities of the predicates `exprs` (none: nothing is added).
    pub fn with_probabilities(mut self, exprs: &[String], probs: &[f64]) -> Self {
        if !exprs.is_empty() {
            self.probability = Some(exprs.iter().cloned().zip(probs.iter().copied()).collect());
        }
        self
    }
}

/// A dead marking as the viewer's panel lists it: tokens by place, the `Place=k` text, and
/// one shortest firing sequence that reaches it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DeadMarkingReport {
    /// Tokens by place name.
    pub marking: ByName<u32>,
    /// The marking as text.
    pub text: String,
    /// Transition names from the initial marking.
    pub path: Vec<String>,
}

impl DeadMarkingReport {
    /// The report of `d`.
    pub fn new(net: &Net, d: &DeadMarking) -> Self {
        DeadMarkingReport {
            marking: by_place(net, &d.marking),
            text: net.format_marking(&d.marking),
            path: transition_names(net, &d.path),
        }
    }
}

/// The viewer's analysis panel: properties, dead markings with their paths, the steady
/// state or why there is none.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Panel {
    /// The net's name.
    pub name: String,
    /// What was analysed: "bare net" or "net under plan policy"
    /// ([`Regime::label`](super::under_policy::Regime::label)).
    pub analysed: String,
    /// Reachable markings.
    pub reachable: usize,
    /// Tangible ones.
    pub tangible: usize,
    /// Vanishing ones.
    pub vanishing: usize,
    /// Edges of the reachability graph.
    pub edges: usize,
    /// No place ever holds more than one token.
    pub safe: bool,
    /// The initial marking is reachable from every reachable marking.
    pub reversible: bool,
    /// No reachable dead marking.
    pub deadlock_free: bool,
    /// Most tokens each place ever holds.
    pub place_bounds: ByName<u32>,
    /// How alive each transition is.
    pub liveness: ByName<Liveness>,
    /// Dead markings with the way to them.
    pub dead_markings: Vec<DeadMarkingReport>,
    /// P-invariants: weights by place name (non-zero only); empty when none was found or
    /// the computation hit its cap.
    pub p_invariants: Vec<ByName<u64>>,
    /// T-invariants: weights by transition name (non-zero only).
    pub t_invariants: Vec<ByName<u64>>,
    /// The steady state, when computed.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steady: Option<MeasuresReport>,
    /// Why there is no steady state.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub steady_error: Option<String>,
}

impl Panel {
    /// The panel's properties part (no steady state yet) of `net` analysed as `regime`.
    pub fn new(
        net: &Net,
        regime: Regime,
        p: &Properties,
        pinv: &Invariants,
        tinv: &Invariants,
    ) -> Self {
        let (p_invariants, t_invariants) = named_invariants(net, pinv, tinv);
        Panel {
            name: net.name().to_string(),
            analysed: regime.label().to_string(),
            reachable: p.reachable,
            tangible: p.tangible,
            vanishing: p.vanishing,
            edges: p.edges,
            safe: p.safe,
            reversible: p.reversible,
            deadlock_free: p.deadlock_free,
            place_bounds: by_place(net, &p.place_bounds),
            liveness: by_transition(net, &p.liveness),
            dead_markings: p
                .dead_markings
                .iter()
                .map(|d| DeadMarkingReport::new(net, d))
                .collect(),
            p_invariants,
            t_invariants,
            steady: None,
            steady_error: None,
        }
    }
}
