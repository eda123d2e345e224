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

mod add;
mod change;
mod history;
mod op;
mod remove;
pub(crate) mod routes;
mod state;

pub(crate) use history::History;
use op::kind_name;
pub(crate) use op::{ArcKindName, Edit, EditError};

use crate::io::LoadErrorKind;
use crate::net::{Arc, Net, NetBuilder, Place, PlaceId, Position, Transition, TransitionId};

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
/// when the edit is refused. Each operation applies itself to the net taken apart
/// ([`add`], [`remove`], [`change`]); the builder then checks the whole.
pub(crate) fn apply(net: &Net, edit: &Edit) -> Result<(Net, String), EditError> {
    let mut n = Parts::of(net);
    let label = match edit {
        Edit::AddPlace(e) => e.apply(&mut n),
        Edit::AddTransition(e) => e.apply(&mut n),
        Edit::AddArc(e) => e.apply(&mut n),
        Edit::Delete(e) => e.apply(&mut n),
        Edit::DeleteArc(e) => e.apply(&mut n),
        Edit::SetPlace(e) => e.apply(&mut n),
        Edit::SetTransition(e) => e.apply(&mut n),
        Edit::SetArc(e) => e.apply(&mut n),
        Edit::Move(e) => e.apply(&mut n),
    }?;
    Ok((n.build()?, label))
}

#[cfg(test)]
mod tests;
