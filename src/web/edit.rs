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
mod op;
pub(crate) mod routes;
mod state;

pub(crate) use history::History;
pub(crate) use op::{ArcKindName, Edit, EditError, Kind, NodeRef};
use op::{arc_owner, describe_timing, kind_name, timing};

use crate::io::LoadErrorKind;
use crate::net::{
    Arc, ArcKind, Net, NetBuilder, Place, PlaceId, Position, Transition, TransitionId,
};

/// A name the page typed: not empty, no spaces at its ends, at most
/// [`MAX_NAME_CHARS`](crate::web::limits::MAX_NAME_CHARS) characters.
fn check_name(what: &'static str, name: &str) -> Result<(), EditError> {
    let why = if name.trim().is_empty() {
        "a name cannot be empty"
    } else if name.trim() != name {
        "a name cannot start or end with a space"
    } else if let Some(chars) = crate::web::limits::name_too_long(name) {
        return Err(EditError::NameTooLong { what, chars });
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

    /// The name of a new place or transition (`what`): the one `given`, checked, or the
    /// first free `P<k>` / `T<k>`.
    fn new_name(&self, given: &Option<String>, what: &'static str) -> Result<String, EditError> {
        let place = what == "place";
        let name = match given {
            Some(s) => s.clone(),
            None => self.fresh(if place { "P" } else { "T" }, place),
        };
        check_name(what, &name)?;
        Ok(name)
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
            let name = n.new_name(name, "place")?;
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
            let name = n.new_name(name, "transition")?;
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

#[cfg(test)]
mod tests;
