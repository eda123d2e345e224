//! The net model: places, transitions, arcs, markings, enabling and firing.
//!
//! Pure data and arithmetic: no async, no I/O. A [`Net`] is built once through a
//! [`NetBuilder`] (which validates it) and is then immutable; the hot paths see dense
//! [`PlaceId`] / [`TransitionId`] indices, never names.
//!
//! # Semantics
//!
//! - Input arcs need at least `w` tokens; inhibitor arcs need fewer than `w` tokens.
//! - The enabling degree of `t` is `min over input places of ⌊m(p)/w⌋` (1 for a transition
//!   without input places).
//! - An exponential transition fires at `rate × min(servers, degree)`.
//! - A place with a capacity refuses a firing that would leave more tokens than it allows.
//!
//! ```
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("cycle");
//! let p1 = b.place("P1", 2);
//! let p2 = b.place("P2", 0);
//! let t1 = b.exponential("T1", 1.0, Servers::Single);
//! let t2 = b.immediate("t2", 1.0, 1);
//! b.input(p1, t1, 1);
//! b.output(t1, p2, 1);
//! b.input(p2, t2, 1);
//! b.output(t2, p1, 1);
//! let net = b.build().unwrap();
//! let mut m = net.initial_marking();
//! assert!(net.is_enabled(&m, t1));
//! net.fire(&mut m, t1);
//! assert_eq!(m.as_slice(), &[1, 1]);
//! assert!(net.is_vanishing(&m));
//! ```

mod builder;
mod element;
mod id;
mod marking;
pub mod predicate;

pub(crate) use builder::overflowing_arc;
pub use builder::{NetBuilder, NetError};
pub use element::{Arc, ArcKind, Place, Position, Servers, Timing, Transition};
pub use id::{PlaceId, TransitionId};
pub use marking::Marking;

use rustc_hash::FxHashMap;

/// The most tokens a place can hold: counts are `u32`, and a firing that would go past this
/// is refused ([`Net::fire`]), a file that asks for more is refused with its position.
pub const MAX_TOKENS: u32 = u32::MAX;

/// How a reader or a driver says a count is too large (the sentence ends the message).
pub const TOO_MANY_TOKENS: &str = "exceeds the maximum token count 4294967295";

/// A firing that would put more than [`MAX_TOKENS`] tokens in a place.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("firing transition {} would put {tokens} tokens in place {}", transition.0, place.0)]
pub struct TokenOverflow {
    /// The transition.
    pub transition: TransitionId,
    /// The place that would overflow.
    pub place: PlaceId,
    /// The count it would reach.
    pub tokens: u64,
}

/// A validated, immutable Petri net with the indices that make firing cheap.
#[derive(Clone, Debug)]
pub struct Net {
    name: String,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    arcs: Vec<Arc>,
    /// Per transition: (place, weight) consumed.
    pre: Vec<Vec<(PlaceId, u32)>>,
    /// Per transition: (place, weight) produced.
    post: Vec<Vec<(PlaceId, u32)>>,
    /// Per transition: (place, weight) of inhibitor arcs.
    inhib: Vec<Vec<(PlaceId, u32)>>,
    /// Per transition: net change (place, delta) with delta ≠ 0.
    delta: Vec<Vec<(PlaceId, i64)>>,
    /// Per transition: the transitions whose enabling its firing can change (itself included
    /// when it changes one of its own places).
    affects: Vec<Vec<TransitionId>>,
    /// Per place: the transitions with an input arc from it, in net order.
    consumers: Vec<Vec<TransitionId>>,
    /// Per place: capacities, dense, `u32::MAX` when unbounded.
    capacity: Vec<u32>,
    has_capacity: bool,
    has_immediate: bool,
    /// Place names → ids, built once so lookups by name cost O(1).
    place_index: FxHashMap<Box<str>, u32>,
    /// Transition names → ids.
    transition_index: FxHashMap<Box<str>, u32>,
}

impl Net {
    /// The net's name (from the file, or the file stem).
    pub fn name(&self) -> &str {
        &self.name
    }

    /// All places, indexed by [`PlaceId`].
    pub fn places(&self) -> &[Place] {
        &self.places
    }

    /// All transitions, indexed by [`TransitionId`].
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }

    /// All arcs, in file order.
    pub fn arcs(&self) -> &[Arc] {
        &self.arcs
    }

    /// Number of places.
    pub fn place_count(&self) -> usize {
        self.places.len()
    }

    /// Number of transitions.
    pub fn transition_count(&self) -> usize {
        self.transitions.len()
    }

    /// The place with this id.
    pub fn place(&self, p: PlaceId) -> &Place {
        &self.places[p.index()]
    }

    /// The transition with this id.
    pub fn transition(&self, t: TransitionId) -> &Transition {
        &self.transitions[t.index()]
    }

    /// Every place id, in order.
    pub fn place_ids(&self) -> impl ExactSizeIterator<Item = PlaceId> + use<> {
        (0..self.places.len() as u32).map(PlaceId)
    }

    /// Every transition id, in order.
    pub fn transition_ids(&self) -> impl ExactSizeIterator<Item = TransitionId> + use<> {
        (0..self.transitions.len() as u32).map(TransitionId)
    }

    /// Looks a place up by name (edges only: files, CLI, viewer).
    pub fn place_by_name(&self, name: &str) -> Option<PlaceId> {
        self.place_index.get(name).map(|&i| PlaceId(i))
    }

    /// Looks a transition up by name (edges only: files, CLI, viewer).
    pub fn transition_by_name(&self, name: &str) -> Option<TransitionId> {
        self.transition_index.get(name).map(|&i| TransitionId(i))
    }

    /// The initial marking.
    pub fn initial_marking(&self) -> Marking {
        Marking::from(self.places.iter().map(|p| p.initial).collect::<Vec<_>>())
    }

    /// Input places of `t` with their weights.
    #[inline]
    pub fn inputs(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        &self.pre[t.index()]
    }

    /// Output places of `t` with their weights.
    #[inline]
    pub fn outputs(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        &self.post[t.index()]
    }

    /// Inhibitor places of `t` with their thresholds.
    #[inline]
    pub fn inhibitors(&self, t: TransitionId) -> &[(PlaceId, u32)] {
        &self.inhib[t.index()]
    }

    /// Net token change per place when `t` fires (zero entries left out).
    #[inline]
    pub fn delta(&self, t: TransitionId) -> &[(PlaceId, i64)] {
        &self.delta[t.index()]
    }

    /// The output transitions of place `p` (those with an input arc from it), in net order.
    #[inline]
    pub fn consumers(&self, p: PlaceId) -> &[TransitionId] {
        &self.consumers[p.index()]
    }

    /// Transitions whose enabling can change when `t` fires.
    #[inline]
    pub fn affected_by(&self, t: TransitionId) -> &[TransitionId] {
        &self.affects[t.index()]
    }

    /// True when the net has at least one immediate transition.
    pub fn has_immediate(&self) -> bool {
        self.has_immediate
    }

    /// Capacity of a place as a number (`u32::MAX` when unbounded).
    #[inline]
    pub fn capacity_of(&self, p: PlaceId) -> u32 {
        self.capacity[p.index()]
    }

    /// Enabling degree of `t` in `m`, ignoring inhibitors and capacities: how many times its
    /// input arcs could be satisfied at once (1 for a transition with no input place).
    #[inline]
    pub fn enabling_degree(&self, m: &[u32], t: TransitionId) -> u32 {
        let pre = &self.pre[t.index()];
        if pre.is_empty() {
            return 1;
        }
        let mut d = u32::MAX;
        for &(p, w) in pre {
            d = d.min(m[p.index()] / w);
            if d == 0 {
                return 0;
            }
        }
        d
    }

    /// True when `t` may fire in `m`: inputs satisfied, inhibitors below threshold, and no
    /// capacity exceeded by the result. The one home of the enabling rule: the firing core,
    /// the explorer, the token game and the runtime all ask here.
    #[inline]
    pub fn is_enabled(&self, m: &[u32], t: TransitionId) -> bool {
        self.pre[t.index()].iter().all(|&(p, w)| m[p.index()] >= w) && self.side_conditions(m, t)
    }

    /// Inhibitors below threshold and no capacity exceeded (the input arcs checked apart).
    #[inline]
    fn side_conditions(&self, m: &[u32], t: TransitionId) -> bool {
        let i = t.index();
        for &(p, w) in &self.inhib[i] {
            if m[p.index()] >= w {
                return false;
            }
        }
        if self.has_capacity {
            for &(p, d) in &self.delta[i] {
                if d > 0 && m[p.index()] as i64 + d > self.capacity[p.index()] as i64 {
                    return false;
                }
            }
        }
        true
    }

    /// Enabling degree counting inhibitors and capacities: 0 when `t` is not enabled.
    #[inline]
    pub fn enabled_degree(&self, m: &[u32], t: TransitionId) -> u32 {
        if self.is_enabled(m, t) {
            self.enabling_degree(m, t)
        } else {
            0
        }
    }

    /// Firing rate of exponential transition `t` in `m` (`rate × min(servers, degree)`);
    /// 0 when `t` is not enabled or is immediate.
    #[inline]
    pub fn exp_rate(&self, m: &[u32], t: TransitionId) -> f64 {
        match self.transitions[t.index()].timing {
            Timing::Exponential { rate, servers } => {
                self.race_rate(m, t, (rate, servers), u32::MAX)
            }
            Timing::Immediate { .. } => 0.0,
        }
    }

    /// The rate rule, once: exponential `t` with per-server `rate` and `servers` fires in `m`
    /// at `rate × min(servers, degree, cap)`, 0 when it is not enabled. `cap` bounds the
    /// degree from outside (the runtime: how many agents handed the choice back to the net;
    /// `u32::MAX` for the net's own race). The caller passes the timing it has at hand.
    #[inline]
    pub(crate) fn race_rate(
        &self,
        m: &[u32],
        t: TransitionId,
        (rate, servers): (f64, Servers),
        cap: u32,
    ) -> f64 {
        let inputs = &self.pre[t.index()];
        let active = if servers == Servers::Single && cap > 0 {
            // Enabled is all a single server needs: no divisions.
            if !inputs.iter().all(|&(p, w)| m[p.index()] >= w) {
                return 0.0;
            }
            1
        } else {
            let mut degree = if inputs.is_empty() { 1 } else { u32::MAX };
            for &(p, w) in inputs {
                let k = m[p.index()];
                if k < w {
                    return 0.0;
                }
                degree = degree.min(if w == 1 { k } else { k / w });
            }
            servers.active(degree.min(cap))
        };
        if active == 0 || !self.side_conditions(m, t) {
            return 0.0;
        }
        rate * active as f64
    }

    /// The first place that firing `t` in `m` would push past [`MAX_TOKENS`], if any: every
    /// driver asks before it changes a marking, so a count never wraps.
    #[inline]
    pub fn overflow(&self, m: &[u32], t: TransitionId) -> Option<TokenOverflow> {
        self.delta[t.index()]
            .iter()
            .find(|&&(p, d)| d > 0 && m[p.index()] as i64 + d > MAX_TOKENS as i64)
            .map(|&(place, d)| TokenOverflow {
                transition: t,
                place,
                tokens: m[place.index()] as u64 + d as u64,
            })
    }

    /// Fires `t` in place: subtracts inputs, adds outputs; a firing that would put more than
    /// [`MAX_TOKENS`] in a place changes nothing and is refused. The caller checks enabling;
    /// firing a disabled transition is a logic error (checked in debug builds).
    #[inline]
    pub fn fire(&self, m: &mut [u32], t: TransitionId) -> Result<(), TokenOverflow> {
        debug_assert!(self.is_enabled(m, t), "fired a disabled transition");
        if let Some(o) = self.overflow(m, t) {
            return Err(o);
        }
        for &(p, d) in &self.delta[t.index()] {
            let v = &mut m[p.index()];
            *v = (*v as i64 + d) as u32;
        }
        Ok(())
    }

    /// The marking reached by firing `t` from `m`, or `None` when `t` is not enabled or the
    /// firing would overflow a place.
    pub fn fire_checked(&self, m: &Marking, t: TransitionId) -> Option<Marking> {
        if !self.is_enabled(m, t) {
            return None;
        }
        let mut next = m.clone();
        self.fire(&mut next, t).ok()?;
        Some(next)
    }

    /// The sentence for an overflow, with the names.
    pub fn describe_overflow(&self, o: &TokenOverflow) -> String {
        format!(
            "firing `{}` would put {} tokens in place `{}`, which {TOO_MANY_TOKENS}",
            self.transition(o.transition).name,
            o.tokens,
            self.place(o.place).name
        )
    }

    /// True when some immediate transition is enabled in `m` (time cannot pass there).
    pub fn is_vanishing(&self, m: &[u32]) -> bool {
        self.has_immediate
            && self
                .transition_ids()
                .any(|t| self.transitions[t.index()].is_immediate() && self.is_enabled(m, t))
    }

    /// Transitions that may fire in `m` under GSPN rules: in a vanishing marking, the enabled
    /// immediate transitions of the highest enabled priority; otherwise every enabled
    /// exponential transition.
    pub fn firable(&self, m: &[u32]) -> Vec<TransitionId> {
        let mut best = 0u32;
        let mut out = Vec::new();
        for t in self.transition_ids() {
            if let Timing::Immediate { priority, .. } = self.transitions[t.index()].timing
                && self.is_enabled(m, t)
            {
                if priority > best {
                    best = priority;
                    out.clear();
                }
                if priority == best {
                    out.push(t);
                }
            }
        }
        if !out.is_empty() {
            return out;
        }
        self.transition_ids()
            .filter(|&t| !self.transitions[t.index()].is_immediate() && self.is_enabled(m, t))
            .collect()
    }

    /// Renders a marking as `name=k,...` with empty places left out (the fixtures' notation).
    pub fn format_marking(&self, m: &[u32]) -> String {
        let mut s = String::new();
        for (i, &k) in m.iter().enumerate() {
            if k > 0 {
                if !s.is_empty() {
                    s.push(',');
                }
                s.push_str(&self.places[i].name);
                s.push('=');
                s.push_str(&k.to_string());
            }
        }
        s
    }

    /// Total tokens in the initial marking.
    pub fn initial_tokens(&self) -> u64 {
        self.places.iter().map(|p| p.initial as u64).sum()
    }

    /// The differences between two nets, compared by name (places, transitions, initial
    /// marking, capacity, timing, and arcs as a set of `(kind, place, transition, weight)`).
    /// Positions and the net's name are not compared. Empty when the nets are the same;
    /// round-trip tests use it.
    pub fn diff(&self, other: &Net) -> Vec<String> {
        let mut out = Vec::new();
        for p in &self.places {
            match other.place_by_name(&p.name).map(|q| other.place(q)) {
                None => out.push(format!("place {} missing", p.name)),
                Some(q) => {
                    if q.initial != p.initial {
                        out.push(format!(
                            "place {}: marking {} vs {}",
                            p.name, p.initial, q.initial
                        ));
                    }
                    if q.capacity != p.capacity {
                        out.push(format!(
                            "place {}: capacity {:?} vs {:?}",
                            p.name, p.capacity, q.capacity
                        ));
                    }
                }
            }
        }
        for q in &other.places {
            if self.place_by_name(&q.name).is_none() {
                out.push(format!("place {} added", q.name));
            }
        }
        for t in &self.transitions {
            match other
                .transition_by_name(&t.name)
                .map(|u| other.transition(u))
            {
                None => out.push(format!("transition {} missing", t.name)),
                Some(u) if u.timing != t.timing => out.push(format!(
                    "transition {}: {:?} vs {:?}",
                    t.name, t.timing, u.timing
                )),
                Some(_) => {}
            }
        }
        for u in &other.transitions {
            if self.transition_by_name(&u.name).is_none() {
                out.push(format!("transition {} added", u.name));
            }
        }
        let arcs = |n: &Net| {
            let mut v: Vec<(u8, String, String, u32)> = n
                .arcs
                .iter()
                .map(|a| {
                    (
                        a.kind as u8,
                        n.place(a.place).name.clone(),
                        n.transition(a.transition).name.clone(),
                        a.weight,
                    )
                })
                .collect();
            v.sort();
            v
        };
        let (a, b) = (arcs(self), arcs(other));
        if a != b {
            for x in a.iter().filter(|x| !b.contains(x)) {
                out.push(format!("arc {x:?} missing"));
            }
            for x in b.iter().filter(|x| !a.contains(x)) {
                out.push(format!("arc {x:?} added"));
            }
        }
        out
    }
}

/// The three-place cycle of the fixtures (`greatspn/cyc3`), for unit tests.
#[cfg(test)]
pub(crate) fn cyc3(servers: Servers) -> Net {
    let mut b = NetBuilder::new("cyc3");
    let p1 = b.place("P1", 2);
    let p2 = b.place("P2", 0);
    let p3 = b.place("P3", 0);
    let t1 = b.exponential("T1", 1.0, servers);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", 2.0, servers);
    b.moves(p1, t1, p2);
    b.moves(p2, t2, p3);
    b.moves(p3, t3, p1);
    b.build().unwrap()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exponential_rate_follows_server_semantics() {
        let single = cyc3(Servers::Single);
        let infinite = cyc3(Servers::Infinite);
        let m = single.initial_marking();
        let t1 = single.transition_by_name("T1").unwrap();
        assert_eq!(single.exp_rate(&m, t1), 1.0);
        assert_eq!(infinite.exp_rate(&m, t1), 2.0);
        assert_eq!(Servers::K(3).active(5), 3);
    }

    #[test]
    fn inhibitor_and_capacity_disable() {
        let mut b = NetBuilder::new("n");
        let p = b.place("p", 1);
        let q = b.place_with_capacity("q", 0, Some(1));
        let t = b.exponential("t", 1.0, Servers::Single);
        let u = b.immediate("u", 1.0, 1);
        b.inhibitor(p, u, 1);
        b.output(t, q, 2);
        b.output(u, q, 1);
        let net = b.build().unwrap();
        let m = net.initial_marking();
        assert!(!net.is_enabled(&m, t), "capacity 1 refuses 2 tokens");
        assert!(!net.is_enabled(&m, u), "inhibited by p");
    }

    #[test]
    fn affects_lists_only_transitions_sharing_changed_places() {
        let net = cyc3(Servers::Single);
        let t1 = net.transition_by_name("T1").unwrap();
        let names: Vec<_> = net
            .affected_by(t1)
            .iter()
            .map(|&t| net.transition(t).name.as_str())
            .collect();
        assert_eq!(names, vec!["T1", "t2"]);
    }

    #[test]
    fn firable_respects_priority() {
        let mut b = NetBuilder::new("n");
        let p = b.place("p", 1);
        let a = b.immediate("a", 1.0, 1);
        let c = b.immediate("c", 1.0, 2);
        let e = b.exponential("e", 1.0, Servers::Single);
        for t in [a, c, e] {
            b.input(p, t, 1);
        }
        let net = b.build().unwrap();
        assert_eq!(net.firable(&net.initial_marking()), vec![c]);
    }
}
