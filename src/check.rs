//! `plan-runner check`: a summary of a net or a plan, and warnings about parts that can never
//! do anything.
//!
//! Most warnings come from structural facts ([`Structure`]: place bounds from P-invariants and
//! from which transitions can ever produce or consume), so every warning is a proof:
//!
//! - a **transition that can never fire**: an input place that never gets enough tokens (no
//!   producer and too few initial tokens, or a structural bound below the arc weight), or an
//!   inhibitor place that always holds too many tokens;
//! - an **isolated place** (no arc at all);
//! - a **place that grows without limit** (coverability, [`endless`]), with the transitions
//!   that pump it; and for a plan with no stop condition, a **run that never ends**: the
//!   net reaches a closed loop of markings (a search of at most [`ENDING_BUDGET_CELLS`] marking ×
//!   place cells, silent when it is not enough);
//! - a **policy rule that can never apply**: its pattern asks for a count outside a place's
//!   bounds, contradicts a P-invariant, or none of its transitions can be enabled in a marking
//!   that matches it.
//!
//! ```
//! use gspn::check::Report;
//! use gspn::io::Format;
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("n");
//! let p = b.place("P", 1);
//! b.place("Lonely", 0);
//! let t = b.exponential("T", 1.0, Servers::Single);
//! b.input(p, t, 2);
//! let report = Report::for_net(&b.build().unwrap(), Format::Pipe, &[]);
//! assert_eq!((report.places, report.transitions, report.tokens), (2, 1, 1));
//! assert_eq!(report.warnings.len(), 2);
//! ```

pub mod endless;
pub(crate) mod structure;

use serde::Serialize;

pub use self::structure::Structure;
use crate::io::Format;
use crate::net::{ArcKind, Net, PlaceId, Timing};
use crate::plan::Plan;
use crate::policy::{Pattern, Rule};

/// Marking × place cells the search for [`endless::ending`] may visit before it gives up
/// (silently): 200,000 markings of a 100-place net. Counted in cells, not markings, so the
/// search costs the same at most on any net — a budget of markings alone made `check` of a
/// 100,000-place chain quadratic (24 s; the chain's markings are each 100,000 places wide).
pub const ENDING_BUDGET_CELLS: usize = 20_000_000;

/// Markings [`endless::ending`] may visit on `net`: [`ENDING_BUDGET_CELLS`] over its places,
/// at most 200,000.
pub fn ending_budget(net: &Net) -> usize {
    (ENDING_BUDGET_CELLS / net.place_count().max(1)).min(200_000)
}

/// What `check` reports. Serialised as JSON with exactly these keys.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Report {
    /// The file's format: `pipe`, `pnml`, `pnpro` or `plan`.
    pub format: String,
    /// Places.
    pub places: usize,
    /// Transitions.
    pub transitions: usize,
    /// Immediate transitions.
    pub immediate: usize,
    /// Exponential transitions.
    pub exponential: usize,
    /// Arcs of every kind (input, output and inhibitor).
    pub arcs: usize,
    /// Inhibitor arcs (counted in `arcs` too).
    pub inhibitor_arcs: usize,
    /// Tokens in the initial marking.
    pub tokens: u64,
    /// Warnings, one sentence each.
    pub warnings: Vec<String>,
}

impl Report {
    /// The report for a net read in `format`; `remarks` (the reader's warnings) come first.
    pub fn for_net(net: &Net, format: Format, remarks: &[String]) -> Report {
        let structure = Structure::of(net);
        let mut warnings = remarks.to_vec();
        warnings.extend(net_warnings(net, &structure));
        let ending = endless::ending(net, ending_budget(net));
        warnings.extend(endless::unbounded_warnings(net, &ending));
        Report::new(net, format.name(), warnings)
    }

    /// The report for a plan: the net's warnings, the plan's remarks, and the policy rules
    /// that can never apply.
    pub fn for_plan(plan: &Plan) -> Report {
        let net = &plan.net;
        let structure = Structure::of(net);
        let mut warnings = plan.warnings.clone();
        warnings.extend(net_warnings(net, &structure));
        for (i, rule) in plan.policy.rules().iter().enumerate() {
            if let Some(why) = rule_never_applies(net, &structure, rule) {
                let line = plan
                    .rule_spans
                    .get(i)
                    .map_or_else(String::new, |s| format!(" (line {})", s.line));
                warnings.push(format!(
                    "policy rule {}{line} can never apply: {why}",
                    i + 1
                ));
            }
        }
        let ending = endless::ending(net, ending_budget(net));
        warnings.extend(endless::unbounded_warnings(net, &ending));
        if plan.stop.is_empty()
            && let Some(why) = ending.describe(net)
        {
            warnings.push(format!(
                "the plan has no stop condition and {why}: `run` goes on until Ctrl-C (add [stop] max_firings, time_limit or when)"
            ));
        }
        Report::new(net, Format::Plan.name(), warnings)
    }

    fn new(net: &Net, format: &str, warnings: Vec<String>) -> Report {
        let immediate = net
            .transitions()
            .iter()
            .filter(|t| t.is_immediate())
            .count();
        Report {
            format: format.to_string(),
            places: net.place_count(),
            transitions: net.transition_count(),
            immediate,
            exponential: net.transition_count() - immediate,
            arcs: net.arcs().len(),
            inhibitor_arcs: net
                .arcs()
                .iter()
                .filter(|a| a.kind == ArcKind::Inhibitor)
                .count(),
            tokens: net.initial_tokens(),
            warnings,
        }
    }
}

/// Warnings about the net alone: dead transitions and isolated places.
pub fn net_warnings(net: &Net, s: &Structure) -> Vec<String> {
    let mut out = Vec::new();
    // Places some transition that may fire adds tokens to.
    let mut fed = vec![false; net.place_count()];
    for t in net.transition_ids().filter(|t| s.may_fire[t.index()]) {
        for &(p, d) in net.delta(t) {
            fed[p.index()] |= d > 0;
        }
    }
    let dead = s.may_fire.iter().filter(|&&f| !f).count();
    if dead > 1 && dead == net.transition_count() {
        out.push(format!(
            "none of the {dead} transitions can ever fire from the initial marking ({} token(s))",
            net.initial_tokens()
        ));
    }
    for t in net.transition_ids() {
        if s.may_fire[t.index()] || (dead > 1 && dead == net.transition_count()) {
            continue;
        }
        let name = &net.transition(t).name;
        let starved = net
            .inputs(t)
            .iter()
            .find(|&&(p, w)| s.upper[p.index()].is_some_and(|u| u < w as u64));
        let why = if let Some(&(p, w)) = starved {
            let place = net.place(p);
            let u = s.upper[p.index()].unwrap_or_default();
            if fed[p.index()] {
                format!(
                    "input place `{}` holds at most {u} token(s), the arc needs {w}",
                    place.name
                )
            } else {
                format!(
                    "input place `{}` has {} token(s), no transition that can fire adds to it, and the arc needs {w}",
                    place.name, place.initial
                )
            }
        } else if let Some(&(p, w)) = net
            .inhibitors(t)
            .iter()
            .find(|&&(p, w)| s.lower[p.index()] >= w as u64)
        {
            format!(
                "inhibitor place `{}` always holds at least {} token(s), the inhibitor arc's threshold is {w}",
                net.place(p).name,
                s.lower[p.index()]
            )
        } else {
            "its input places are only fed by transitions that can never fire".to_string()
        };
        out.push(format!("transition `{name}` can never fire: {why}"));
    }
    let mut touched = vec![false; net.place_count()];
    for a in net.arcs() {
        touched[a.place.index()] = true;
    }
    for p in net.place_ids().filter(|p| !touched[p.index()]) {
        out.push(format!(
            "place `{}` is isolated: no arc touches it",
            net.place(p).name
        ));
    }
    out
}

/// Why `rule` can never apply in `net`, or `None` when it might.
pub fn rule_never_applies(net: &Net, s: &Structure, rule: &Rule) -> Option<String> {
    let fixed: Vec<(PlaceId, u32)> = match &rule.pattern {
        Pattern::Exact(m) => m
            .iter()
            .enumerate()
            .map(|(i, &k)| (PlaceId(i as u32), k))
            .collect(),
        Pattern::Partial(v) => v.clone(),
    };
    for &(p, k) in &fixed {
        if !s.allows(p, k) {
            let upper = s.upper[p.index()].map_or("∞".to_string(), |u| u.to_string());
            return Some(format!(
                "it asks for {k} token(s) in `{}`, which always holds between {} and {upper}",
                net.place(p).name,
                s.lower[p.index()]
            ));
        }
    }
    // A P-invariant whose places the pattern all fixes must keep its value.
    let m0: Vec<u64> = net.places().iter().map(|p| p.initial as u64).collect();
    for y in &s.invariants {
        let support: Vec<usize> = (0..y.len()).filter(|&i| y[i] > 0).collect();
        let values: Option<u64> = support.iter().try_fold(0u64, |acc, &i| {
            let k = rule.pattern.required(PlaceId(i as u32))?;
            Some(acc.saturating_add(y[i].saturating_mul(k as u64)))
        });
        let total = structure::weighted(y, &m0);
        if let Some(v) = values
            && v != total
        {
            let names: Vec<String> = support
                .iter()
                .map(|&i| {
                    let coef = if y[i] == 1 {
                        String::new()
                    } else {
                        format!("{}·", y[i])
                    };
                    format!("{coef}{}", net.places()[i].name)
                })
                .collect();
            return Some(format!(
                "its marking has {} = {v}, but every reachable marking has {total}",
                names.join(" + ")
            ));
        }
    }
    let compatible = rule.choose.iter().any(|&(t, prob)| {
        prob > 0.0
            && s.may_fire[t.index()]
            && matches!(net.transition(t).timing, Timing::Immediate { .. })
            && net
                .inputs(t)
                .iter()
                .all(|&(p, w)| rule.pattern.required(p).is_none_or(|k| k >= w))
            && net
                .inhibitors(t)
                .iter()
                .all(|&(p, w)| rule.pattern.required(p).is_none_or(|k| k < w))
    });
    if !compatible {
        let names: Vec<String> = rule
            .choose
            .iter()
            .filter(|&&(_, p)| p > 0.0)
            .map(|&(t, _)| format!("`{}`", net.transition(t).name))
            .collect();
        return Some(format!(
            "none of {} can be enabled in a marking that matches it",
            names.join(", ")
        ));
    }
    None
}
