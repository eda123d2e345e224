//! Policy: marking → distribution over immediate transitions, with an indexed lookup.
//!
//! A [`Policy`] is stationary: a list of [`Rule`]s, each a marking [`Pattern`] and the
//! probabilities of the immediate transitions to fire there. A pattern is a full marking
//! ([`Pattern::Exact`]) or a partial one ([`Pattern::Partial`]: the listed places must hold
//! exactly the listed counts, the others are free — the thesis wrote `'-'` for free).
//!
//! # Lookup
//!
//! 1. the exact marking, through a hash index;
//! 2. the partial patterns, in the order they were given (file order).
//!
//! The first rule that matches **and** gives positive probability to at least one of the
//! transitions that can fire now is applied: its probabilities are restricted to those
//! transitions and renormalised. A rule that matches but names none of them is skipped, so
//! a general rule placed after a specific one still applies when the specific one cannot.
//! When no rule applies, [`Policy::distribution`] returns `None` and the caller uses the
//! net's own weights.
//!
//! ```
//! use gspn::net::{NetBuilder, Servers, PlaceId};
//! use gspn::policy::{Pattern, Policy, Rule};
//! let mut b = NetBuilder::new("choice");
//! let p = b.place("p", 1);
//! let a = b.immediate("a", 1.0, 1);
//! let c = b.immediate("c", 1.0, 1);
//! b.input(p, a, 1);
//! b.input(p, c, 1);
//! let net = b.build().unwrap();
//! let policy = Policy::new(&net, vec![Rule {
//!     pattern: Pattern::Partial(vec![(p, 1)]),
//!     choose: vec![(a, 0.25), (c, 0.75)],
//! }]).unwrap();
//! let d = policy.distribution(&[1], &[a, c]).unwrap();
//! assert_eq!(d, vec![(a, 0.25), (c, 0.75)]);
//! // Only `a` can fire: the rule is renormalised over it.
//! assert_eq!(policy.distribution(&[1], &[a]).unwrap(), vec![(a, 1.0)]);
//! ```

use rustc_hash::FxHashMap;

use crate::net::{Net, PlaceId, Timing, TransitionId};

/// How far the probabilities of one rule may sum away from 1.
pub const SUM_TOLERANCE: f64 = 1e-6;

/// Which markings a rule applies to.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Pattern {
    /// Exactly this marking (one count per place, indexed by [`PlaceId`]).
    Exact(Vec<u32>),
    /// The listed places hold exactly the listed counts; the other places are free.
    Partial(Vec<(PlaceId, u32)>),
}

impl Pattern {
    /// True when marking `m` matches the pattern.
    #[inline]
    pub fn matches(&self, m: &[u32]) -> bool {
        match self {
            Pattern::Exact(e) => e.as_slice() == m,
            Pattern::Partial(v) => v.iter().all(|&(p, k)| m[p.index()] == k),
        }
    }

    /// The count the pattern requires in place `p`, or `None` when `p` is free.
    pub fn required(&self, p: PlaceId) -> Option<u32> {
        match self {
            Pattern::Exact(e) => e.get(p.index()).copied(),
            Pattern::Partial(v) => v.iter().find(|&&(q, _)| q == p).map(|&(_, k)| k),
        }
    }
}

/// One rule: in markings matching `pattern`, fire the immediate transitions of `choose` with
/// these probabilities.
#[derive(Clone, Debug, PartialEq)]
pub struct Rule {
    /// Where the rule applies.
    pub pattern: Pattern,
    /// Immediate transitions and their probabilities (each in [0, 1], summing to 1).
    pub choose: Vec<(TransitionId, f64)>,
}

impl Rule {
    /// The probability the rule gives `t` (0 when it does not name it).
    #[inline]
    pub fn probability(&self, t: TransitionId) -> f64 {
        self.choose
            .iter()
            .find(|&&(u, _)| u == t)
            .map_or(0.0, |&(_, p)| p)
    }
}

/// Why a set of rules is not a policy for a net. `rule` is the index of the offending rule;
/// messages number rules from 1, in file order, as `check` and the plan's comments do.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum PolicyError {
    /// An exact pattern with the wrong number of places.
    #[error("rule {}: the marking has {got} places, the net {expected}", .rule + 1)]
    WrongLength {
        /// The rule.
        rule: usize,
        /// Places in the net.
        expected: usize,
        /// Places in the pattern.
        got: usize,
    },
    /// A place id outside the net.
    #[error("rule {}: place #{place} is not in the net", .rule + 1)]
    UnknownPlace {
        /// The rule.
        rule: usize,
        /// The id.
        place: u32,
    },
    /// A place listed twice in a partial pattern.
    #[error("rule {}: place `{name}` is listed twice", .rule + 1)]
    DuplicatePlace {
        /// The rule.
        rule: usize,
        /// The place.
        name: String,
    },
    /// A transition id outside the net.
    #[error("rule {}: transition #{transition} is not in the net", .rule + 1)]
    UnknownTransition {
        /// The rule.
        rule: usize,
        /// The id.
        transition: u32,
    },
    /// A rule names an exponential transition (a policy only chooses immediate ones).
    #[error(
        "rule {}: transition `{name}` is exponential; a policy chooses among immediate transitions",
        .rule + 1
    )]
    NotImmediate {
        /// The rule.
        rule: usize,
        /// The transition.
        name: String,
    },
    /// A transition listed twice in one rule.
    #[error("rule {}: transition `{name}` is listed twice", .rule + 1)]
    DuplicateTransition {
        /// The rule.
        rule: usize,
        /// The transition.
        name: String,
    },
    /// A probability outside [0, 1] or not finite.
    #[error("rule {}: probability of `{name}` is {value}: must be in [0, 1]", .rule + 1)]
    BadProbability {
        /// The rule.
        rule: usize,
        /// The transition.
        name: String,
        /// The value given.
        value: f64,
    },
    /// The probabilities of a rule do not sum to 1.
    #[error("rule {}: the probabilities sum to {sum}, not 1", .rule + 1)]
    BadSum {
        /// The rule.
        rule: usize,
        /// Their sum.
        sum: f64,
    },
    /// A rule with no transition.
    #[error("rule {}: chooses no transition", .rule + 1)]
    Empty {
        /// The rule.
        rule: usize,
    },
    /// Two exact rules for the same marking.
    #[error("rule {}: the same marking as rule {}", .rule + 1, .first + 1)]
    DuplicateMarking {
        /// The later rule.
        rule: usize,
        /// The earlier one.
        first: usize,
    },
}

impl PolicyError {
    /// The index of the rule the error is about.
    pub fn rule(&self) -> usize {
        match *self {
            PolicyError::WrongLength { rule, .. }
            | PolicyError::UnknownPlace { rule, .. }
            | PolicyError::DuplicatePlace { rule, .. }
            | PolicyError::UnknownTransition { rule, .. }
            | PolicyError::NotImmediate { rule, .. }
            | PolicyError::DuplicateTransition { rule, .. }
            | PolicyError::BadProbability { rule, .. }
            | PolicyError::BadSum { rule, .. }
            | PolicyError::Empty { rule }
            | PolicyError::DuplicateMarking { rule, .. } => rule,
        }
    }
}

/// A stationary policy over immediate transitions. The empty policy defers to the net's
/// weights everywhere.
#[derive(Clone, Debug, Default)]
pub struct Policy {
    rules: Vec<Rule>,
    /// Exact marking → index into `rules`.
    exact: FxHashMap<Box<[u32]>, usize>,
    /// Indices of partial rules, in file order.
    partial: Vec<usize>,
}

impl Policy {
    /// The policy with no rules.
    pub fn empty() -> Self {
        Policy::default()
    }

    /// Checks `rules` against `net` and indexes them. Rules keep their order (the order of
    /// the partial ones is their lookup order).
    pub fn new(net: &Net, rules: Vec<Rule>) -> Result<Policy, PolicyError> {
        let mut exact = FxHashMap::default();
        let mut partial = Vec::new();
        for (i, r) in rules.iter().enumerate() {
            match &r.pattern {
                Pattern::Exact(m) => {
                    if m.len() != net.place_count() {
                        return Err(PolicyError::WrongLength {
                            rule: i,
                            expected: net.place_count(),
                            got: m.len(),
                        });
                    }
                    if let Some(&first) = exact.get(m.as_slice()) {
                        return Err(PolicyError::DuplicateMarking { rule: i, first });
                    }
                    exact.insert(m.clone().into_boxed_slice(), i);
                }
                Pattern::Partial(v) => {
                    for (k, &(p, _)) in v.iter().enumerate() {
                        if p.index() >= net.place_count() {
                            return Err(PolicyError::UnknownPlace {
                                rule: i,
                                place: p.0,
                            });
                        }
                        if v[..k].iter().any(|&(q, _)| q == p) {
                            return Err(PolicyError::DuplicatePlace {
                                rule: i,
                                name: net.place(p).name.clone(),
                            });
                        }
                    }
                    partial.push(i);
                }
            }
            check_choice(net, i, &r.choose)?;
        }
        Ok(Policy {
            rules,
            exact,
            partial,
        })
    }

    /// True when the policy has no rule.
    pub fn is_empty(&self) -> bool {
        self.rules.is_empty()
    }

    /// The rules, in the order given.
    pub fn rules(&self) -> &[Rule] {
        &self.rules
    }

    /// The rule that applies in `m` given the transitions that can fire now (see the
    /// module's lookup order), with its index; `None` when none applies.
    pub fn rule_for(&self, m: &[u32], firable: &[TransitionId]) -> Option<(usize, &Rule)> {
        if self.rules.is_empty() {
            return None;
        }
        let applies = |r: &Rule| firable.iter().any(|&t| r.probability(t) > 0.0);
        if let Some(&i) = self.exact.get(m)
            && applies(&self.rules[i])
        {
            return Some((i, &self.rules[i]));
        }
        self.partial
            .iter()
            .map(|&i| (i, &self.rules[i]))
            .find(|(_, r)| r.pattern.matches(m) && applies(r))
    }

    /// The distribution the policy prescribes in marking `m` over `firable` (the immediate
    /// transitions that may fire now), renormalised over them; `None` when no rule applies
    /// (use the net's weights). Transitions with probability 0 are left out.
    pub fn distribution(
        &self,
        m: &[u32],
        firable: &[TransitionId],
    ) -> Option<Vec<(TransitionId, f64)>> {
        let mut out = Vec::new();
        self.distribution_into(m, firable, &mut out).then_some(out)
    }

    /// Like [`Policy::distribution`], writing into `out` (cleared first) so a hot loop can
    /// reuse one buffer; returns false when no rule applies (and leaves `out` empty).
    pub fn distribution_into(
        &self,
        m: &[u32],
        firable: &[TransitionId],
        out: &mut Vec<(TransitionId, f64)>,
    ) -> bool {
        out.clear();
        let Some((_, rule)) = self.rule_for(m, firable) else {
            return false;
        };
        let mut total = 0.0;
        for &t in firable {
            let p = rule.probability(t);
            if p > 0.0 {
                out.push((t, p));
                total += p;
            }
        }
        for (_, p) in out.iter_mut() {
            *p /= total;
        }
        true
    }
}

impl Policy {
    /// The distribution to fire with in marking `m` over `firable` (the immediate
    /// transitions that may fire now): the policy's when a rule applies, else the net's
    /// weights, normalised (uniform when every weight is 0 — weight 0 leaves the choice to a
    /// policy, and none was given). Empty only when `firable` is.
    pub fn distribution_or_weights(
        &self,
        net: &Net,
        m: &[u32],
        firable: &[TransitionId],
    ) -> Vec<(TransitionId, f64)> {
        if let Some(d) = self.distribution(m, firable) {
            return d;
        }
        let weight = |t: TransitionId| match net.transition(t).timing {
            Timing::Immediate { weight, .. } => weight,
            Timing::Exponential { .. } => 0.0,
        };
        let total: f64 = firable.iter().map(|&t| weight(t)).sum();
        if total > 0.0 {
            firable
                .iter()
                .filter(|&&t| weight(t) > 0.0)
                .map(|&t| (t, weight(t) / total))
                .collect()
        } else {
            let u = 1.0 / firable.len() as f64;
            firable.iter().map(|&t| (t, u)).collect()
        }
    }
}

fn check_choice(net: &Net, rule: usize, choose: &[(TransitionId, f64)]) -> Result<(), PolicyError> {
    if choose.is_empty() {
        return Err(PolicyError::Empty { rule });
    }
    let mut sum = 0.0;
    for (k, &(t, p)) in choose.iter().enumerate() {
        if t.index() >= net.transition_count() {
            return Err(PolicyError::UnknownTransition {
                rule,
                transition: t.0,
            });
        }
        let name = || net.transition(t).name.clone();
        if !matches!(net.transition(t).timing, Timing::Immediate { .. }) {
            return Err(PolicyError::NotImmediate { rule, name: name() });
        }
        if choose[..k].iter().any(|&(u, _)| u == t) {
            return Err(PolicyError::DuplicateTransition { rule, name: name() });
        }
        if !(p.is_finite() && (0.0..=1.0).contains(&p)) {
            return Err(PolicyError::BadProbability {
                rule,
                name: name(),
                value: p,
            });
        }
        sum += p;
    }
    if (sum - 1.0).abs() > SUM_TOLERANCE {
        return Err(PolicyError::BadSum { rule, sum });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    /// p (1 token) feeds immediate a, b, c and exponential e; q is a second, free place.
    fn net() -> (Net, [TransitionId; 4]) {
        let mut b = NetBuilder::new("n");
        let p = b.place("p", 1);
        let _q = b.place("q", 0);
        let a = b.immediate("a", 1.0, 1);
        let bb = b.immediate("b", 1.0, 1);
        let c = b.immediate("c", 1.0, 1);
        let e = b.exponential("e", 1.0, Servers::Single);
        for t in [a, bb, c, e] {
            b.input(p, t, 1);
        }
        (b.build().unwrap(), [a, bb, c, e])
    }

    fn partial(p: u32, k: u32) -> Pattern {
        Pattern::Partial(vec![(PlaceId(p), k)])
    }

    fn rule(pattern: Pattern, choose: Vec<(TransitionId, f64)>) -> Rule {
        Rule { pattern, choose }
    }

    /// The policy of `rules`, given [`net`]'s transitions a, b, c, e; and those transitions.
    fn policy(rules: impl FnOnce([TransitionId; 4]) -> Vec<Rule>) -> (Policy, [TransitionId; 4]) {
        let (net, ts) = net();
        (Policy::new(&net, rules(ts)).unwrap(), ts)
    }

    #[test]
    fn exact_rule_wins_over_an_earlier_partial_one() {
        let (policy, [a, b, c, _]) = policy(|[a, b, c, _]| {
            vec![
                rule(partial(0, 1), vec![(a, 1.0)]),
                rule(Pattern::Exact(vec![1, 0]), vec![(b, 0.4), (c, 0.6)]),
            ]
        });
        let d = policy.distribution(&[1, 0], &[a, b, c]).unwrap();
        assert_eq!(d, vec![(b, 0.4), (c, 0.6)]);
        // Another marking: only the partial rule matches.
        let d = policy.distribution(&[1, 5], &[a, b, c]).unwrap();
        assert_eq!(d, vec![(a, 1.0)]);
        // No rule for p = 2.
        assert_eq!(policy.distribution(&[2, 0], &[a, b, c]), None);
    }

    #[test]
    fn restricted_to_firable_and_renormalised() {
        let (policy, [_, b, c, _]) = policy(|[a, b, c, _]| {
            vec![Rule {
                pattern: partial(0, 1),
                choose: vec![(a, 0.2), (b, 0.3), (c, 0.5)],
            }]
        });
        let d = policy.distribution(&[1, 0], &[b, c]).unwrap();
        assert_eq!(d.len(), 2);
        assert!((d[0].1 - 0.375).abs() < 1e-12 && d[0].0 == b);
        assert!((d[1].1 - 0.625).abs() < 1e-12 && d[1].0 == c);
    }

    #[test]
    fn a_rule_that_names_nothing_firable_falls_through() {
        let (policy, [a, b, c, _]) = policy(|[a, b, c, _]| {
            vec![
                rule(partial(0, 1), vec![(a, 1.0), (b, 0.0)]),
                rule(partial(1, 0), vec![(c, 1.0)]),
            ]
        });
        // First rule matches but gives b zero mass and a is not firable: the second applies.
        assert_eq!(
            policy.distribution(&[1, 0], &[b, c]).unwrap(),
            vec![(c, 1.0)]
        );
        // Nothing applies at all: the net's weights.
        assert_eq!(policy.distribution(&[1, 3], &[b]), None);
        let mut buf = vec![(a, 9.0)];
        assert!(!policy.distribution_into(&[1, 3], &[b], &mut buf));
        assert!(buf.is_empty());
    }

    #[test]
    fn partial_rules_apply_in_file_order() {
        let (policy, [a, b, _, _]) = policy(|[a, b, _, _]| {
            vec![
                rule(partial(1, 0), vec![(b, 1.0)]),
                rule(partial(0, 1), vec![(a, 1.0)]),
            ]
        });
        assert_eq!(policy.rule_for(&[1, 0], &[a, b]).map(|r| r.0), Some(0));
        assert_eq!(policy.rule_for(&[1, 2], &[a, b]).map(|r| r.0), Some(1));
    }

    #[test]
    fn bad_rules_are_refused() {
        let (net, [a, b, _, e]) = net();
        let err = |rules| Policy::new(&net, rules).unwrap_err();
        assert_eq!(
            err(vec![rule(partial(0, 1), vec![(e, 1.0)])]),
            PolicyError::NotImmediate {
                rule: 0,
                name: "e".into()
            }
        );
        assert_eq!(
            err(vec![rule(partial(0, 1), vec![(a, 0.5), (b, 0.4)])]),
            PolicyError::BadSum { rule: 0, sum: 0.9 }
        );
        assert!(matches!(
            err(vec![rule(partial(0, 1), vec![(a, f64::NAN)])]),
            PolicyError::BadProbability { .. }
        ));
        assert!(matches!(
            err(vec![rule(partial(7, 1), vec![(a, 1.0)])]),
            PolicyError::UnknownPlace { place: 7, .. }
        ));
        assert!(matches!(
            err(vec![rule(partial(0, 1), vec![(TransitionId(9), 1.0)])]),
            PolicyError::UnknownTransition { transition: 9, .. }
        ));
        assert_eq!(
            err(vec![rule(Pattern::Exact(vec![1]), vec![(a, 1.0)])]),
            PolicyError::WrongLength {
                rule: 0,
                expected: 2,
                got: 1
            }
        );
        assert_eq!(
            err(vec![
                rule(Pattern::Exact(vec![1, 0]), vec![(a, 1.0)]),
                rule(Pattern::Exact(vec![1, 0]), vec![(b, 1.0)]),
            ]),
            PolicyError::DuplicateMarking { rule: 1, first: 0 }
        );
        assert_eq!(
            err(vec![rule(partial(0, 1), vec![])]),
            PolicyError::Empty { rule: 0 }
        );
    }

    #[test]
    fn empty_policy_defers_to_weights() {
        let (_, [a, ..]) = net();
        assert_eq!(Policy::empty().distribution(&[1, 0], &[a]), None);
    }
}
