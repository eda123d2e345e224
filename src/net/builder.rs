//! Building and validating a [`Net`].

use rustc_hash::FxHashMap;

use super::{
    Arc, ArcKind, Net, Place, PlaceId, Position, Servers, Timing, Transition, TransitionId,
};

/// Why a net could not be built. Readers check the same things earlier, with the file
/// position; these errors are the last line for nets built in code.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum NetError {
    /// Two places or two transitions share a name (names must be unique per kind).
    #[error("duplicate {kind} name `{name}`")]
    Duplicate {
        /// "place" or "transition".
        kind: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A rate is zero, negative, NaN or infinite.
    #[error("transition `{transition}`: rate {rate} {}", Timing::RATE_EXPECTED)]
    BadRate {
        /// The transition's name.
        transition: String,
        /// The offending rate.
        rate: f64,
    },
    /// A weight is negative, NaN or infinite.
    #[error(
        "transition `{transition}`: weight {weight} {}",
        Timing::WEIGHT_EXPECTED
    )]
    BadWeight {
        /// The transition's name.
        transition: String,
        /// The offending weight.
        weight: f64,
    },
    /// Priority 0, or `K(0)` servers.
    #[error("transition `{transition}`: {what} must be ≥ 1")]
    BadCount {
        /// The transition's name.
        transition: String,
        /// What was zero.
        what: &'static str,
    },
    /// Parallel arcs whose weights add up to more than the maximum token count.
    #[error(
        "arcs between `{place}` and `{transition}` add up to more than the maximum token count {max}",
        max = u32::MAX
    )]
    WeightOverflow {
        /// The place end.
        place: String,
        /// The transition end.
        transition: String,
    },
    /// An arc with multiplicity 0.
    #[error("arc between `{place}` and `{transition}` has weight 0")]
    ZeroWeight {
        /// The place end.
        place: String,
        /// The transition end.
        transition: String,
    },
    /// The initial marking exceeds a place's capacity.
    #[error("place `{place}`: initial marking {initial} exceeds its capacity {capacity}")]
    OverCapacity {
        /// The place's name.
        place: String,
        /// Its initial tokens.
        initial: u32,
        /// Its capacity.
        capacity: u32,
    },
}

/// Collects places, transitions and arcs, then validates them into a [`Net`].
#[derive(Debug, Clone)]
pub struct NetBuilder {
    name: String,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    arcs: Vec<Arc>,
}

impl NetBuilder {
    /// An empty net called `name`.
    pub fn new(name: impl Into<String>) -> Self {
        NetBuilder {
            name: name.into(),
            places: Vec::new(),
            transitions: Vec::new(),
            arcs: Vec::new(),
        }
    }

    /// Renames the net.
    pub fn set_name(&mut self, name: impl Into<String>) {
        self.name = name.into();
    }

    /// Adds an unbounded place with `initial` tokens.
    pub fn place(&mut self, name: impl Into<String>, initial: u32) -> PlaceId {
        self.place_with_capacity(name, initial, None)
    }

    /// Adds a place with an optional capacity.
    pub fn place_with_capacity(
        &mut self,
        name: impl Into<String>,
        initial: u32,
        capacity: Option<u32>,
    ) -> PlaceId {
        self.add_place(Place {
            name: name.into(),
            initial,
            capacity,
            position: None,
        })
    }

    /// Adds a fully described place.
    pub fn add_place(&mut self, place: Place) -> PlaceId {
        self.places.push(place);
        PlaceId(self.places.len() as u32 - 1)
    }

    /// Adds an immediate transition.
    pub fn immediate(
        &mut self,
        name: impl Into<String>,
        weight: f64,
        priority: u32,
    ) -> TransitionId {
        self.add_transition(Transition {
            name: name.into(),
            timing: Timing::Immediate { weight, priority },
            position: None,
        })
    }

    /// Adds an exponential transition.
    pub fn exponential(
        &mut self,
        name: impl Into<String>,
        rate: f64,
        servers: Servers,
    ) -> TransitionId {
        self.add_transition(Transition {
            name: name.into(),
            timing: Timing::Exponential { rate, servers },
            position: None,
        })
    }

    /// Adds a fully described transition.
    pub fn add_transition(&mut self, t: Transition) -> TransitionId {
        self.transitions.push(t);
        TransitionId(self.transitions.len() as u32 - 1)
    }

    /// Sets a place's position.
    pub fn set_place_position(&mut self, p: PlaceId, pos: Position) {
        self.places[p.index()].position = Some(pos);
    }

    /// Sets a transition's position.
    pub fn set_transition_position(&mut self, t: TransitionId, pos: Position) {
        self.transitions[t.index()].position = Some(pos);
    }

    /// Adds an input arc `p → t` of weight `w`.
    pub fn input(&mut self, p: PlaceId, t: TransitionId, w: u32) {
        self.arc(ArcKind::Input, p, t, w, Vec::new());
    }

    /// Adds an output arc `t → p` of weight `w`.
    pub fn output(&mut self, t: TransitionId, p: PlaceId, w: u32) {
        self.arc(ArcKind::Output, p, t, w, Vec::new());
    }

    /// Adds the arcs `from → t → to`, both of weight 1: `t` moves one token (a robot, a
    /// job) from `from` to `to`, the most common shape in a plan's net.
    pub fn moves(&mut self, from: PlaceId, t: TransitionId, to: PlaceId) {
        self.input(from, t, 1);
        self.output(t, to, 1);
    }

    /// Adds an inhibitor arc `p —o t` of threshold `w`.
    pub fn inhibitor(&mut self, p: PlaceId, t: TransitionId, w: u32) {
        self.arc(ArcKind::Inhibitor, p, t, w, Vec::new());
    }

    /// Adds an arc of any kind, with bend points.
    pub fn arc(
        &mut self,
        kind: ArcKind,
        p: PlaceId,
        t: TransitionId,
        w: u32,
        points: Vec<Position>,
    ) {
        self.arcs.push(Arc {
            kind,
            place: p,
            transition: t,
            weight: w,
            points,
        });
    }

    /// Looks up a place added so far.
    pub fn find_place(&self, name: &str) -> Option<PlaceId> {
        self.places
            .iter()
            .position(|p| p.name == name)
            .map(|i| PlaceId(i as u32))
    }

    /// Looks up a transition added so far.
    pub fn find_transition(&self, name: &str) -> Option<TransitionId> {
        self.transitions
            .iter()
            .position(|t| t.name == name)
            .map(|i| TransitionId(i as u32))
    }

    /// Places added so far.
    pub fn places(&self) -> &[Place] {
        &self.places
    }

    /// Transitions added so far.
    pub fn transitions(&self) -> &[Transition] {
        &self.transitions
    }

    /// Validates and indexes the net: the places and transitions one by one
    /// ([`check_places`], [`check_transitions`]), the arcs gathered per transition
    /// ([`arc_lists`]), then the indices the firing rule reads ([`deltas`], [`affects`]).
    pub fn build(self) -> Result<Net, NetError> {
        let NetBuilder {
            name,
            places,
            transitions,
            arcs,
        } = self;
        let place_index = index_names("place", places.iter().map(|p| p.name.as_str()))?;
        let transition_index =
            index_names("transition", transitions.iter().map(|t| t.name.as_str()))?;
        check_places(&places)?;
        check_transitions(&transitions)?;
        let ArcLists { pre, post, inhib } = arc_lists(&places, &transitions, &arcs)?;
        let delta = deltas(&pre, &post);
        let capacity: Vec<u32> = places
            .iter()
            .map(|p| p.capacity.unwrap_or(u32::MAX))
            .collect();
        let has_capacity = places.iter().any(|p| p.capacity.is_some());
        let affects = affects(&pre, &post, &inhib, &delta, &capacity, has_capacity);
        let mut consumers: Vec<Vec<TransitionId>> = vec![Vec::new(); places.len()];
        for (t, inputs) in pre.iter().enumerate() {
            for &(p, _) in inputs {
                consumers[p.index()].push(TransitionId(t as u32));
            }
        }
        let has_immediate = transitions.iter().any(Transition::is_immediate);
        Ok(Net {
            name,
            places,
            transitions,
            arcs,
            pre,
            post,
            inhib,
            delta,
            affects,
            consumers,
            capacity,
            has_capacity,
            has_immediate,
            place_index,
            transition_index,
        })
    }
}

/// No place starts above its capacity.
fn check_places(places: &[Place]) -> Result<(), NetError> {
    for p in places {
        if let Some(c) = p.capacity
            && p.initial > c
        {
            return Err(NetError::OverCapacity {
                place: p.name.clone(),
                initial: p.initial,
                capacity: c,
            });
        }
    }
    Ok(())
}

/// Rates, weights, servers and priorities in range ([`Timing::rate`], [`Timing::weight`]).
fn check_transitions(transitions: &[Transition]) -> Result<(), NetError> {
    for t in transitions {
        match t.timing {
            Timing::Exponential { rate, servers } => {
                if Timing::rate(rate).is_err() {
                    return Err(NetError::BadRate {
                        transition: t.name.clone(),
                        rate,
                    });
                }
                if servers == Servers::K(0) {
                    return Err(NetError::BadCount {
                        transition: t.name.clone(),
                        what: "servers",
                    });
                }
            }
            Timing::Immediate { weight, priority } => {
                if Timing::weight(weight).is_err() {
                    return Err(NetError::BadWeight {
                        transition: t.name.clone(),
                        weight,
                    });
                }
                if priority == 0 {
                    return Err(NetError::BadCount {
                        transition: t.name.clone(),
                        what: "priority",
                    });
                }
            }
        }
    }
    Ok(())
}

/// Per transition, its input, output and inhibitor arcs as `(place, weight)`.
struct ArcLists {
    pre: Vec<Vec<(PlaceId, u32)>>,
    post: Vec<Vec<(PlaceId, u32)>>,
    inhib: Vec<Vec<(PlaceId, u32)>>,
}

/// The arcs gathered per transition: no zero weight; parallel arcs of the same kind add up
/// (inhibitors: the tightest threshold), within the largest token count.
fn arc_lists(
    places: &[Place],
    transitions: &[Transition],
    arcs: &[Arc],
) -> Result<ArcLists, NetError> {
    let nt = transitions.len();
    let mut pre = vec![Vec::new(); nt];
    let mut post = vec![Vec::new(); nt];
    let mut inhib = vec![Vec::new(); nt];
    for a in arcs {
        if a.weight == 0 {
            return Err(NetError::ZeroWeight {
                place: places[a.place.index()].name.clone(),
                transition: transitions[a.transition.index()].name.clone(),
            });
        }
        let list: &mut Vec<(PlaceId, u32)> = match a.kind {
            ArcKind::Input => &mut pre[a.transition.index()],
            ArcKind::Output => &mut post[a.transition.index()],
            ArcKind::Inhibitor => &mut inhib[a.transition.index()],
        };
        match list.iter_mut().find(|(p, _)| *p == a.place) {
            Some((_, w)) if a.kind == ArcKind::Inhibitor => *w = (*w).min(a.weight),
            Some((_, w)) => {
                *w = w
                    .checked_add(a.weight)
                    .ok_or_else(|| NetError::WeightOverflow {
                        place: places[a.place.index()].name.clone(),
                        transition: transitions[a.transition.index()].name.clone(),
                    })?
            }
            None => list.push((a.place, a.weight)),
        }
    }
    Ok(ArcLists { pre, post, inhib })
}

/// The index of the first of `arcs` (kind, place, transition, weight) whose weight takes the
/// sum of its parallel arcs past the largest token count: the arc [`arc_lists`]'s
/// [`NetError::WeightOverflow`] is about (which names only its ends), for the readers to
/// point at it in the file.
pub(crate) fn overflowing_arc(
    arcs: impl IntoIterator<Item = (ArcKind, PlaceId, TransitionId, u32)>,
) -> Option<usize> {
    let mut sums: rustc_hash::FxHashMap<(ArcKind, PlaceId, TransitionId), u32> = Default::default();
    arcs.into_iter()
        .enumerate()
        .find_map(|(i, (kind, p, t, w))| {
            if kind == ArcKind::Inhibitor {
                return None;
            }
            let sum = sums.entry((kind, p, t)).or_insert(0);
            match sum.checked_add(w) {
                Some(s) => {
                    *sum = s;
                    None
                }
                None => Some(i),
            }
        })
}

/// Per transition, the change of each place it touches (outputs minus inputs; zeros
/// dropped), sorted by place.
fn deltas(pre: &[Vec<(PlaceId, u32)>], post: &[Vec<(PlaceId, u32)>]) -> Vec<Vec<(PlaceId, i64)>> {
    let mut delta = Vec::with_capacity(pre.len());
    for t in 0..pre.len() {
        let mut d: Vec<(PlaceId, i64)> = Vec::new();
        for &(p, w) in &pre[t] {
            d.push((p, -(w as i64)));
        }
        for &(p, w) in &post[t] {
            match d.iter_mut().find(|(q, _)| *q == p) {
                Some((_, v)) => *v += w as i64,
                None => d.push((p, w as i64)),
            }
        }
        d.retain(|&(_, v)| v != 0);
        d.sort_by_key(|&(p, _)| p);
        delta.push(d);
    }
    delta
}

/// Per transition, the transitions whose enabling its firing may change: those that read
/// a place it changes (input or inhibitor arcs, or capacity-bound outputs).
fn affects(
    pre: &[Vec<(PlaceId, u32)>],
    post: &[Vec<(PlaceId, u32)>],
    inhib: &[Vec<(PlaceId, u32)>],
    delta: &[Vec<(PlaceId, i64)>],
    capacity: &[u32],
    has_capacity: bool,
) -> Vec<Vec<TransitionId>> {
    let mut readers: Vec<Vec<TransitionId>> = vec![Vec::new(); capacity.len()];
    for t in 0..pre.len() {
        let tid = TransitionId(t as u32);
        let mut touch = |p: PlaceId| {
            let r = &mut readers[p.index()];
            if r.last() != Some(&tid) {
                r.push(tid);
            }
        };
        for &(p, _) in pre[t].iter().chain(&inhib[t]) {
            touch(p);
        }
        if has_capacity {
            for &(p, _) in &post[t] {
                if capacity[p.index()] != u32::MAX {
                    touch(p);
                }
            }
        }
    }
    delta
        .iter()
        .map(|d| {
            let mut a: Vec<TransitionId> = d
                .iter()
                .flat_map(|&(p, _)| readers[p.index()].iter().copied())
                .collect();
            a.sort_unstable();
            a.dedup();
            a
        })
        .collect()
}

/// The names' index (name → position), or the first repeated name.
fn index_names<'a>(
    kind: &'static str,
    names: impl Iterator<Item = &'a str>,
) -> Result<FxHashMap<Box<str>, u32>, NetError> {
    let mut seen = FxHashMap::default();
    for (i, n) in names.enumerate() {
        if seen.insert(Box::from(n), i as u32).is_some() {
            return Err(NetError::Duplicate {
                kind,
                name: n.to_string(),
            });
        }
    }
    Ok(seen)
}

impl Net {
    /// The same net with another initial marking (`marking[p]` tokens in place `p`; places
    /// past the end of `marking` keep theirs). Fails like [`NetBuilder::build`] when a count
    /// exceeds a place's capacity.
    pub fn with_initial_marking(&self, marking: &[u32]) -> Result<Net, NetError> {
        let mut b = NetBuilder::new(self.name());
        for (i, p) in self.places().iter().enumerate() {
            b.add_place(Place {
                initial: marking.get(i).copied().unwrap_or(p.initial),
                ..p.clone()
            });
        }
        for t in self.transitions() {
            b.add_transition(t.clone());
        }
        for a in self.arcs() {
            b.arc(a.kind, a.place, a.transition, a.weight, a.points.clone());
        }
        b.build()
    }
}
