//! The editor: one operation type ([`Edit`]) that the page sends as JSON, applied to the
//! served net by rebuilding it through [`NetBuilder`] — so an edit is checked as a file is
//! (the readers' messages for a number out of range, an unknown or repeated name, then the
//! builder's own checks) and a refused edit leaves the net as it was. [`History`] keeps
//! each version of the net (snapshots: undo and redo move between them).
//!
//! | `op` | fields |
//! |---|---|
//! | `add_place` | `name`? (default `P<k>`), `tokens`?, `capacity`?, `x`, `y` |
//! | `add_transition` | `name`? (default `T<k>`), `kind` (`exponential` \| `immediate`), `rate`?, `servers`?, `weight`?, `priority`?, `x`, `y` |
//! | `add_arc` | `from`, `to` (`{"place": name}` or `{"transition": name}`), `inhibitor`?, `weight`? |
//! | `delete` | `node` (with its arcs) |
//! | `delete_arc` | `place`, `transition`, `kind` (`input` \| `output` \| `inhibitor`) |
//! | `set_place` | `place`, then what changes: `name`, `tokens`, `capacity` (`null`: unbounded) |
//! | `set_transition` | `transition`, then `name`, `kind`, `rate`, `servers` (`single`, `infinite` or k), `weight`, `priority` |
//! | `set_arc` | `place`, `transition`, `kind`, then `weight`, `new_kind` (`input` ⇄ `inhibitor`) |
//! | `move` | `places`, `transitions`: `{name: [x, y]}` |
//!
//! Numbers may come as JSON numbers or as the text of a field (`"2.5"`), and are checked as
//! the GreatSPN reader checks them: a marking is a whole number of at least 0, a rate a
//! finite number above 0, a weight at least 0, a priority, a number of servers and an arc
//! multiplicity whole numbers of at least 1.

mod history;
pub(crate) mod routes;

pub(crate) use history::History;

use std::collections::BTreeMap;

use serde::{Deserialize, Deserializer};

use crate::io::LoadErrorKind;
use crate::net::{
    Arc, ArcKind, Net, NetBuilder, NetError, Place, PlaceId, Position, Servers, Timing, Transition,
    TransitionId,
};

/// A number as the page sends it: a JSON number or the text typed in a field.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(untagged)]
pub(crate) enum Num {
    /// A JSON number.
    Number(f64),
    /// The text of a field.
    Text(String),
}

/// A place or a transition, by name: `{"place": "P1"}`, `{"transition": "T1"}`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum NodeRef {
    /// A place.
    Place(String),
    /// A transition.
    Transition(String),
}

/// A transition's kind, as `/api/net` names it.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum Kind {
    /// Fires after an exponential delay.
    Exponential,
    /// Fires at once.
    Immediate,
}

/// An arc's kind, as `/api/net` names it.
#[derive(Clone, Copy, Debug, Deserialize, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub(crate) enum ArcKindName {
    /// Place → transition.
    Input,
    /// Transition → place.
    Output,
    /// Place —o transition.
    Inhibitor,
}

impl ArcKindName {
    fn kind(self) -> ArcKind {
        match self {
            ArcKindName::Input => ArcKind::Input,
            ArcKindName::Output => ArcKind::Output,
            ArcKindName::Inhibitor => ArcKind::Inhibitor,
        }
    }
}

/// `Some(value)` for a field that is present, `null` included (`capacity: null` = unbounded).
fn present<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Option<Num>>, D::Error> {
    Option::<Num>::deserialize(d).map(Some)
}

/// One change of the net, as the page sends it (see the [module](self) for the table).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case", deny_unknown_fields)]
pub(crate) enum Edit {
    /// A new place at `(x, y)`.
    AddPlace {
        name: Option<String>,
        tokens: Option<Num>,
        capacity: Option<Num>,
        x: f64,
        y: f64,
    },
    /// A new transition at `(x, y)`.
    AddTransition {
        name: Option<String>,
        kind: Kind,
        rate: Option<Num>,
        servers: Option<Num>,
        weight: Option<Num>,
        priority: Option<Num>,
        x: f64,
        y: f64,
    },
    /// A new arc: place → transition (input, or inhibitor with `inhibitor`) or
    /// transition → place (output).
    AddArc {
        from: NodeRef,
        to: NodeRef,
        #[serde(default)]
        inhibitor: bool,
        weight: Option<Num>,
    },
    /// A node and every arc that touches it.
    Delete { node: NodeRef },
    /// The arcs of `kind` between `place` and `transition`.
    DeleteArc {
        place: String,
        transition: String,
        kind: ArcKindName,
    },
    /// A place's name, initial tokens or capacity.
    SetPlace {
        place: String,
        name: Option<String>,
        tokens: Option<Num>,
        #[serde(default, deserialize_with = "present")]
        capacity: Option<Option<Num>>,
    },
    /// A transition's name, kind and parameters.
    SetTransition {
        transition: String,
        name: Option<String>,
        kind: Option<Kind>,
        rate: Option<Num>,
        servers: Option<Num>,
        weight: Option<Num>,
        priority: Option<Num>,
    },
    /// The multiplicity or the kind of the arcs of `kind` between `place` and
    /// `transition` (parallel arcs become one).
    SetArc {
        place: String,
        transition: String,
        kind: ArcKindName,
        weight: Option<Num>,
        new_kind: Option<ArcKindName>,
    },
    /// New positions, in the file's units.
    Move {
        #[serde(default)]
        places: BTreeMap<String, [f64; 2]>,
        #[serde(default)]
        transitions: BTreeMap<String, [f64; 2]>,
    },
}

/// Why an edit was refused (the net is left as it was).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub(crate) enum EditError {
    /// What a reader says of the same value or name in a file.
    #[error("{0}")]
    Invalid(LoadErrorKind),
    /// Both ends of a new arc are places, or both are transitions.
    #[error("an arc joins a place and a transition: `{from}` and `{to}` are both {kind}s")]
    SameKind {
        /// Its first end.
        from: String,
        /// Its second end.
        to: String,
        /// "place" or "transition".
        kind: &'static str,
    },
    /// An inhibitor arc that would run from a transition to a place.
    #[error(
        "an inhibitor arc runs from a place to a transition, not from transition `{from}` to \
         place `{to}`"
    )]
    InhibitorFromTransition {
        /// The transition.
        from: String,
        /// The place.
        to: String,
    },
    /// An empty name, or one with spaces at its ends.
    #[error("{what} name {name:?}: {why}")]
    BadName {
        /// "place" or "transition".
        what: &'static str,
        /// The name given.
        name: String,
        /// What is wrong with it.
        why: &'static str,
    },
    /// A parameter given for the other kind of transition (a rate for an immediate one).
    #[error("{what} does not apply to {kind} transition `{name}`")]
    NotApplicable {
        /// The parameter.
        what: &'static str,
        /// The transition's kind after the edit.
        kind: &'static str,
        /// The transition.
        name: String,
    },
    /// An output arc cannot become an inhibitor arc, nor an inhibitor arc an output one.
    #[error("an {from} arc cannot become an {to} arc: only input ⇄ inhibitor")]
    KindChange {
        /// The arc's kind.
        from: &'static str,
        /// The kind asked for.
        to: &'static str,
    },
    /// No arc of that kind between the two nodes.
    #[error("there is no {kind} arc between place `{place}` and transition `{transition}`")]
    NoArc {
        /// "input", "output" or "inhibitor".
        kind: &'static str,
        /// The place.
        place: String,
        /// The transition.
        transition: String,
    },
    /// A `set_*` or `move` that names nothing to change.
    #[error("the edit changes nothing")]
    Nothing,
    /// A coordinate that is not a finite number.
    #[error("position of `{0}`: coordinates must be finite numbers")]
    BadPosition(String),
    /// Undo at the first version.
    #[error("nothing to undo")]
    NothingToUndo,
    /// Redo at the last version.
    #[error("nothing to redo")]
    NothingToRedo,
    /// The viewer shows a live run, a replay or a plan whose policy names the net's nodes.
    #[error("{0}")]
    NotEditable(String),
}

impl From<NetError> for EditError {
    fn from(e: NetError) -> Self {
        EditError::Invalid(LoadErrorKind::Net(e))
    }
}

impl EditError {
    /// A refusal of the edit's content (422), as opposed to one of the situation (409:
    /// nothing to undo, a net that cannot be edited here).
    pub(crate) fn is_conflict(&self) -> bool {
        matches!(
            self,
            EditError::NothingToUndo | EditError::NothingToRedo | EditError::NotEditable(_)
        )
    }
}

fn kind_name(k: ArcKind) -> &'static str {
    match k {
        ArcKind::Input => "input",
        ArcKind::Output => "output",
        ArcKind::Inhibitor => "inhibitor",
    }
}

/// An arc as the readers name it: `tail → head`.
fn arc_owner(kind: ArcKind, place: &str, transition: &str) -> String {
    match kind {
        ArcKind::Output => format!("{transition} → {place}"),
        ArcKind::Input | ArcKind::Inhibitor => format!("{place} → {transition}"),
    }
}

fn out_of_range(
    what: &'static str,
    name: &str,
    value: String,
    expected: &'static str,
) -> EditError {
    EditError::Invalid(LoadErrorKind::OutOfRange {
        what,
        name: name.to_string(),
        value,
        expected,
    })
}

impl Num {
    /// The number, or the reader's "not a number" for `what` of `name`.
    fn value(&self, what: &'static str, name: &str) -> Result<f64, EditError> {
        match self {
            Num::Number(v) => Ok(*v),
            Num::Text(s) => s.trim().parse::<f64>().map_err(|_| {
                EditError::Invalid(LoadErrorKind::NotANumber {
                    what,
                    name: name.to_string(),
                    value: s.clone(),
                })
            }),
        }
    }

    fn shown(&self, v: f64) -> String {
        match self {
            Num::Text(s) => s.trim().to_string(),
            Num::Number(_) => format!("{v}"),
        }
    }

    /// A whole number ≥ `min`, checked as the GreatSPN reader checks one.
    fn whole(&self, what: &'static str, name: &str, min: u32) -> Result<u32, EditError> {
        let v = self.value(what, name)?;
        crate::io::whole_number(v, min)
            .map_err(|expected| out_of_range(what, name, self.shown(v), expected))
    }

    fn rate(&self, name: &str) -> Result<f64, EditError> {
        let v = self.value("rate", name)?;
        if v.is_finite() && v > 0.0 {
            return Ok(v);
        }
        Err(out_of_range(
            "rate",
            name,
            self.shown(v),
            "must be a finite number > 0",
        ))
    }

    fn weight(&self, name: &str) -> Result<f64, EditError> {
        let v = self.value("weight", name)?;
        if v.is_finite() && v >= 0.0 {
            return Ok(v);
        }
        Err(out_of_range(
            "weight",
            name,
            self.shown(v),
            "must be a finite number ≥ 0",
        ))
    }

    /// `single`, `infinite`, or a number of servers k ≥ 1 (1 is single).
    fn servers(&self, name: &str) -> Result<Servers, EditError> {
        if let Num::Text(s) = self {
            match s.trim().to_ascii_lowercase().as_str() {
                "single" => return Ok(Servers::Single),
                "infinite" => return Ok(Servers::Infinite),
                _ => {}
            }
        }
        Ok(match self.whole("number of servers", name, 1)? {
            1 => Servers::Single,
            k => Servers::K(k),
        })
    }
}

/// A name the page typed: not empty, no spaces at its ends.
fn check_name(what: &'static str, name: &str) -> Result<(), EditError> {
    let why = if name.trim().is_empty() {
        "a name cannot be empty"
    } else if name.trim() != name {
        "a name cannot start or end with a space"
    } else {
        return Ok(());
    };
    Err(EditError::BadName {
        what,
        name: name.to_string(),
        why,
    })
}

fn position(name: &str, x: f64, y: f64) -> Result<Position, EditError> {
    if x.is_finite() && y.is_finite() {
        Ok(Position { x, y })
    } else {
        Err(EditError::BadPosition(name.to_string()))
    }
}

/// A net taken apart, to be changed and built again.
struct Parts {
    name: String,
    places: Vec<Place>,
    transitions: Vec<Transition>,
    arcs: Vec<Arc>,
}

impl Parts {
    fn of(net: &Net) -> Parts {
        Parts {
            name: net.name().to_string(),
            places: net.places().to_vec(),
            transitions: net.transitions().to_vec(),
            arcs: net.arcs().to_vec(),
        }
    }

    fn place(&self, name: &str) -> Result<usize, EditError> {
        self.places
            .iter()
            .position(|p| p.name == name)
            .ok_or_else(|| unknown("place", name))
    }

    fn transition(&self, name: &str) -> Result<usize, EditError> {
        self.transitions
            .iter()
            .position(|t| t.name == name)
            .ok_or_else(|| unknown("transition", name))
    }

    /// The first name `prefix<k>` (k from the count + 1) that no node of that kind has.
    fn fresh(&self, prefix: &str, place: bool) -> String {
        let taken = |n: &str| {
            if place {
                self.places.iter().any(|p| p.name == n)
            } else {
                self.transitions.iter().any(|t| t.name == n)
            }
        };
        let start = if place {
            self.places.len()
        } else {
            self.transitions.len()
        } + 1;
        (start..)
            .map(|k| format!("{prefix}{k}"))
            .find(|n| !taken(n))
            .expect("an unused name")
    }

    /// The arcs of `kind` between place `p` and transition `t` (indices into `arcs`).
    fn arcs_between(
        &self,
        place: &str,
        transition: &str,
        kind: ArcKindName,
    ) -> Result<Vec<usize>, EditError> {
        let p = PlaceId(self.place(place)? as u32);
        let t = TransitionId(self.transition(transition)? as u32);
        let found: Vec<usize> = (0..self.arcs.len())
            .filter(|&i| {
                let a = &self.arcs[i];
                a.place == p && a.transition == t && a.kind == kind.kind()
            })
            .collect();
        if found.is_empty() {
            return Err(EditError::NoArc {
                kind: kind_name(kind.kind()),
                place: place.to_string(),
                transition: transition.to_string(),
            });
        }
        Ok(found)
    }

    /// Removes place `i` (`place`) or transition `i` with its arcs, renumbering the arcs of
    /// the later ones; how many arcs went.
    fn remove(&mut self, place: bool, i: usize) -> usize {
        if place {
            self.places.remove(i);
        } else {
            self.transitions.remove(i);
        }
        let end = |a: &Arc| {
            if place {
                a.place.index()
            } else {
                a.transition.index()
            }
        };
        let before = self.arcs.len();
        self.arcs.retain(|a| end(a) != i);
        for a in self.arcs.iter_mut().filter(|a| end(a) > i) {
            if place {
                a.place = PlaceId(a.place.0 - 1);
            } else {
                a.transition = TransitionId(a.transition.0 - 1);
            }
        }
        before - self.arcs.len()
    }

    fn build(self) -> Result<Net, EditError> {
        let mut b = NetBuilder::new(self.name);
        for p in self.places {
            b.add_place(p);
        }
        for t in self.transitions {
            b.add_transition(t);
        }
        for a in self.arcs {
            b.arc(a.kind, a.place, a.transition, a.weight, a.points);
        }
        Ok(b.build()?)
    }
}

fn unknown(what: &'static str, name: &str) -> EditError {
    EditError::Invalid(LoadErrorKind::UnknownNode {
        what,
        name: name.to_string(),
    })
}

/// `net` with a position for every node: the drawn layout's for the nodes that have none
/// (so that the first edit of a net drawn by the automatic layout keeps the drawing).
pub(crate) fn positioned(net: &Net) -> Net {
    let complete = net.places().iter().all(|p| p.position.is_some())
        && net.transitions().iter().all(|t| t.position.is_some());
    if complete {
        return net.clone();
    }
    let l = crate::web::layout::layout(net);
    let mut parts = Parts::of(net);
    for (p, pos) in parts.places.iter_mut().zip(&l.places) {
        p.position = p.position.or(Some(*pos));
    }
    for (t, pos) in parts.transitions.iter_mut().zip(&l.transitions) {
        t.position = t.position.or(Some(*pos));
    }
    parts
        .build()
        .expect("the same net with positions builds as it did")
}

/// `net` after `edit`, and a short description of the edit (`add place P4`); the error
/// when the edit is refused.
pub(crate) fn apply(net: &Net, edit: &Edit) -> Result<(Net, String), EditError> {
    let mut n = Parts::of(net);
    let label = match edit {
        Edit::AddPlace {
            name,
            tokens,
            capacity,
            x,
            y,
        } => {
            let name = match name {
                Some(s) => s.clone(),
                None => n.fresh("P", true),
            };
            check_name("place", &name)?;
            let initial = match tokens {
                Some(k) => k.whole("initial marking", &name, 0)?,
                None => 0,
            };
            let capacity = match capacity {
                Some(c) => Some(c.whole("capacity", &name, 1)?),
                None => None,
            };
            n.places.push(Place {
                position: Some(position(&name, *x, *y)?),
                name: name.clone(),
                initial,
                capacity,
            });
            format!("add place {name}")
        }
        Edit::AddTransition {
            name,
            kind,
            rate,
            servers,
            weight,
            priority,
            x,
            y,
        } => {
            let name = match name {
                Some(s) => s.clone(),
                None => n.fresh("T", false),
            };
            check_name("transition", &name)?;
            let timing = timing(&name, *kind, None, rate, servers, weight, priority)?;
            n.transitions.push(Transition {
                position: Some(position(&name, *x, *y)?),
                name: name.clone(),
                timing,
            });
            format!("add transition {name}")
        }
        Edit::AddArc {
            from,
            to,
            inhibitor,
            weight,
        } => {
            let (kind, place, transition) = match (from, to) {
                (NodeRef::Place(p), NodeRef::Transition(t)) => {
                    let kind = if *inhibitor {
                        ArcKind::Inhibitor
                    } else {
                        ArcKind::Input
                    };
                    (kind, p, t)
                }
                (NodeRef::Transition(t), NodeRef::Place(p)) => {
                    if *inhibitor {
                        return Err(EditError::InhibitorFromTransition {
                            from: t.clone(),
                            to: p.clone(),
                        });
                    }
                    (ArcKind::Output, p, t)
                }
                (NodeRef::Place(a), NodeRef::Place(b)) => {
                    return Err(EditError::SameKind {
                        from: a.clone(),
                        to: b.clone(),
                        kind: "place",
                    });
                }
                (NodeRef::Transition(a), NodeRef::Transition(b)) => {
                    return Err(EditError::SameKind {
                        from: a.clone(),
                        to: b.clone(),
                        kind: "transition",
                    });
                }
            };
            let p = n.place(place)?;
            let t = n.transition(transition)?;
            let owner = arc_owner(kind, place, transition);
            let weight = match weight {
                Some(w) => w.whole("arc multiplicity", &owner, 1)?,
                None => 1,
            };
            n.arcs.push(Arc {
                kind,
                place: PlaceId(p as u32),
                transition: TransitionId(t as u32),
                weight,
                points: Vec::new(),
            });
            match kind {
                ArcKind::Input => format!("add arc {place} → {transition}"),
                ArcKind::Output => format!("add arc {transition} → {place}"),
                ArcKind::Inhibitor => format!("add inhibitor arc {place} ⊸ {transition}"),
            }
        }
        Edit::Delete { node } => {
            let (what, name, arcs) = match node {
                NodeRef::Place(name) => ("place", name, n.remove(true, n.place(name)?)),
                NodeRef::Transition(name) => {
                    ("transition", name, n.remove(false, n.transition(name)?))
                }
            };
            match arcs {
                0 => format!("delete {what} {name}"),
                1 => format!("delete {what} {name} and its arc"),
                k => format!("delete {what} {name} and its {k} arcs"),
            }
        }
        Edit::DeleteArc {
            place,
            transition,
            kind,
        } => {
            let found = n.arcs_between(place, transition, *kind)?;
            for i in found.into_iter().rev() {
                n.arcs.remove(i);
            }
            format!(
                "delete {} arc {place} – {transition}",
                kind_name(kind.kind())
            )
        }
        Edit::SetPlace {
            place,
            name,
            tokens,
            capacity,
        } => {
            let i = n.place(place)?;
            if name.is_none() && tokens.is_none() && capacity.is_none() {
                return Err(EditError::Nothing);
            }
            let mut what = Vec::new();
            let p = &mut n.places[i];
            if let Some(new) = name {
                check_name("place", new)?;
                what.push(format!("name {new}"));
                p.name = new.clone();
            }
            if let Some(k) = tokens {
                p.initial = k.whole("initial marking", &p.name, 0)?;
                what.push(format!("tokens {}", p.initial));
            }
            if let Some(c) = capacity {
                p.capacity = match c {
                    Some(c) => Some(c.whole("capacity", &p.name, 1)?),
                    None => None,
                };
                what.push(match p.capacity {
                    Some(c) => format!("capacity {c}"),
                    None => "unbounded".to_string(),
                });
            }
            format!("change place {place} ({})", what.join(", "))
        }
        Edit::SetTransition {
            transition,
            name,
            kind,
            rate,
            servers,
            weight,
            priority,
        } => {
            let i = n.transition(transition)?;
            let nothing = [rate, servers, weight, priority]
                .iter()
                .all(|v| v.is_none());
            if name.is_none() && kind.is_none() && nothing {
                return Err(EditError::Nothing);
            }
            let t = &mut n.transitions[i];
            let mut what = Vec::new();
            if let Some(new) = name {
                check_name("transition", new)?;
                what.push(format!("name {new}"));
                t.name = new.clone();
            }
            let current = if t.is_immediate() {
                Kind::Immediate
            } else {
                Kind::Exponential
            };
            let kind = kind.unwrap_or(current);
            if kind != current || !nothing {
                let before = t.timing;
                t.timing = timing(
                    &t.name,
                    kind,
                    Some(t.timing),
                    rate,
                    servers,
                    weight,
                    priority,
                )?;
                what.push(describe_timing(before, t.timing));
            }
            format!("change transition {transition} ({})", what.join(", "))
        }
        Edit::SetArc {
            place,
            transition,
            kind,
            weight,
            new_kind,
        } => {
            let found = n.arcs_between(place, transition, *kind)?;
            if weight.is_none() && new_kind.is_none() {
                return Err(EditError::Nothing);
            }
            let mut arc = n.arcs[found[0]].clone();
            for &i in found.iter().skip(1).rev() {
                n.arcs.remove(i);
            }
            let mut what = Vec::new();
            if let Some(k) = new_kind
                && *k != *kind
            {
                if *kind == ArcKindName::Output || *k == ArcKindName::Output {
                    return Err(EditError::KindChange {
                        from: kind_name(kind.kind()),
                        to: kind_name(k.kind()),
                    });
                }
                arc.kind = k.kind();
                what.push(kind_name(arc.kind).to_string());
            }
            if let Some(w) = weight {
                let owner = arc_owner(arc.kind, place, transition);
                arc.weight = w.whole("arc multiplicity", &owner, 1)?;
                what.push(format!("multiplicity {}", arc.weight));
            }
            n.arcs[found[0]] = arc;
            format!(
                "change {} arc {place} – {transition} ({})",
                kind_name(kind.kind()),
                what.join(", ")
            )
        }
        Edit::Move {
            places,
            transitions,
        } => {
            if places.is_empty() && transitions.is_empty() {
                return Err(EditError::Nothing);
            }
            for (name, &[x, y]) in places {
                let i = n.place(name)?;
                n.places[i].position = Some(position(name, x, y)?);
            }
            for (name, &[x, y]) in transitions {
                let i = n.transition(name)?;
                n.transitions[i].position = Some(position(name, x, y)?);
            }
            match places.len() + transitions.len() {
                1 => format!(
                    "move {}",
                    places.keys().chain(transitions.keys()).next().expect("one")
                ),
                k => format!("move {k} nodes"),
            }
        }
    };
    Ok((n.build()?, label))
}

/// The timing of transition `name` of `kind`: the parameters given, else those of `before`
/// when it is of the same kind, else the defaults (rate 1, single server; weight 1,
/// priority 1). A parameter of the other kind is refused.
fn timing(
    name: &str,
    kind: Kind,
    before: Option<Timing>,
    rate: &Option<Num>,
    servers: &Option<Num>,
    weight: &Option<Num>,
    priority: &Option<Num>,
) -> Result<Timing, EditError> {
    let not_applicable = |what: &'static str, kind: &'static str| EditError::NotApplicable {
        what,
        kind,
        name: name.to_string(),
    };
    match kind {
        Kind::Exponential => {
            if weight.is_some() {
                return Err(not_applicable("weight", "exponential"));
            }
            if priority.is_some() {
                return Err(not_applicable("priority", "exponential"));
            }
            let (r0, s0) = match before {
                Some(Timing::Exponential { rate, servers }) => (rate, servers),
                _ => (1.0, Servers::Single),
            };
            Ok(Timing::Exponential {
                rate: rate.as_ref().map_or(Ok(r0), |r| r.rate(name))?,
                servers: servers.as_ref().map_or(Ok(s0), |s| s.servers(name))?,
            })
        }
        Kind::Immediate => {
            if rate.is_some() {
                return Err(not_applicable("rate", "immediate"));
            }
            if servers.is_some() {
                return Err(not_applicable("number of servers", "immediate"));
            }
            let (w0, p0) = match before {
                Some(Timing::Immediate { weight, priority }) => (weight, priority),
                _ => (1.0, 1),
            };
            Ok(Timing::Immediate {
                weight: weight.as_ref().map_or(Ok(w0), |w| w.weight(name))?,
                priority: priority
                    .as_ref()
                    .map_or(Ok(p0), |p| p.whole("priority", name, 1))?,
            })
        }
    }
}

/// What changed between two timings, for the edit's label (`rate 2`, `immediate, weight 1`).
fn describe_timing(before: Timing, after: Timing) -> String {
    let mut parts = Vec::new();
    match (before, after) {
        (
            Timing::Exponential {
                rate: r0,
                servers: s0,
            },
            Timing::Exponential { rate, servers },
        ) => {
            if r0 != rate {
                parts.push(format!("rate {rate}"));
            }
            if s0 != servers {
                parts.push(servers_text(servers));
            }
        }
        (
            Timing::Immediate {
                weight: w0,
                priority: p0,
            },
            Timing::Immediate { weight, priority },
        ) => {
            if w0 != weight {
                parts.push(format!("weight {weight}"));
            }
            if p0 != priority {
                parts.push(format!("priority {priority}"));
            }
        }
        (_, Timing::Exponential { rate, servers: s }) => {
            parts.push(format!("exponential, rate {rate}, {}", servers_text(s)));
        }
        (_, Timing::Immediate { weight, priority }) => {
            parts.push(format!("immediate, weight {weight}, priority {priority}"));
        }
    }
    if parts.is_empty() {
        "unchanged".to_string()
    } else {
        parts.join(", ")
    }
}

fn servers_text(s: Servers) -> String {
    match s {
        Servers::Single => "single server".to_string(),
        Servers::Infinite => "infinite servers".to_string(),
        Servers::K(k) => format!("{k} servers"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cyc3() -> Net {
        crate::net::cyc3(Servers::Single)
    }

    fn edit(v: serde_json::Value) -> Edit {
        serde_json::from_value(v).unwrap()
    }

    #[test]
    fn operations_read_from_the_pages_json() {
        assert_eq!(
            edit(serde_json::json!({"op": "set_place", "place": "P1", "capacity": null})),
            Edit::SetPlace {
                place: "P1".into(),
                name: None,
                tokens: None,
                capacity: Some(None),
            }
        );
        let e = serde_json::from_value::<Edit>(
            serde_json::json!({"op": "set_place", "place": "P1", "tokns": 3}),
        );
        assert!(e.unwrap_err().to_string().contains("unknown field `tokns`"));
    }

    #[test]
    fn deleting_a_place_renumbers_the_arcs_of_the_later_ones() {
        let net = cyc3();
        let (after, label) = apply(
            &net,
            &edit(serde_json::json!({"op": "delete", "node": {"place": "P1"}})),
        )
        .unwrap();
        assert_eq!(label, "delete place P1 and its 2 arcs");
        assert_eq!(after.place_count(), 2);
        assert_eq!(after.arcs().len(), net.arcs().len() - 2);
        for a in after.arcs() {
            let before = net
                .arcs()
                .iter()
                .find(|b| {
                    net.place(b.place).name == after.place(a.place).name
                        && net.transition(b.transition).name == after.transition(a.transition).name
                })
                .unwrap();
            assert_eq!(before.kind, a.kind);
        }
    }
}
