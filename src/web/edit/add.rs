//! The commands that add a node or an arc.

use serde::Deserialize;

use super::op::{EditError, Kind, NodeRef, Num, arc_owner, timing};
use super::{Parts, position};
use crate::net::{Arc, ArcKind, Place, PlaceId, Transition, TransitionId};

/// A new place at `(x, y)`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct AddPlace {
    pub(crate) name: Option<String>,
    pub(crate) tokens: Option<Num>,
    pub(crate) capacity: Option<Num>,
    pub(crate) x: f64,
    pub(crate) y: f64,
}

impl AddPlace {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let name = n.new_name(&self.name, "place")?;
        let initial = match &self.tokens {
            Some(k) => k.whole("initial marking", &name, 0)?,
            None => 0,
        };
        let capacity = match &self.capacity {
            Some(c) => Some(c.whole("capacity", &name, 1)?),
            None => None,
        };
        n.places.push(Place {
            position: Some(position(&name, self.x, self.y)?),
            name: name.clone(),
            initial,
            capacity,
        });
        Ok(format!("add place {name}"))
    }
}

/// A new transition at `(x, y)`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct AddTransition {
    pub(crate) name: Option<String>,
    pub(crate) kind: Kind,
    pub(crate) rate: Option<Num>,
    pub(crate) servers: Option<Num>,
    pub(crate) weight: Option<Num>,
    pub(crate) priority: Option<Num>,
    pub(crate) x: f64,
    pub(crate) y: f64,
}

impl AddTransition {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let name = n.new_name(&self.name, "transition")?;
        let timing = timing(
            &name,
            self.kind,
            None,
            &self.rate,
            &self.servers,
            &self.weight,
            &self.priority,
        )?;
        n.transitions.push(Transition {
            position: Some(position(&name, self.x, self.y)?),
            name: name.clone(),
            timing,
        });
        Ok(format!("add transition {name}"))
    }
}

/// A new arc: place → transition (input, or inhibitor with `inhibitor`) or
/// transition → place (output).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct AddArc {
    pub(crate) from: NodeRef,
    pub(crate) to: NodeRef,
    #[serde(default)]
    pub(crate) inhibitor: bool,
    pub(crate) weight: Option<Num>,
}

impl AddArc {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let (kind, place, transition) = self.ends()?;
        let p = n.place(place)?;
        let t = n.transition(transition)?;
        let owner = arc_owner(kind, place, transition);
        let weight = match &self.weight {
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
        Ok(match kind {
            ArcKind::Input => format!("add arc {place} → {transition}"),
            ArcKind::Output => format!("add arc {transition} → {place}"),
            ArcKind::Inhibitor => format!("add inhibitor arc {place} ⊸ {transition}"),
        })
    }

    /// The arc's kind, place and transition, from its two ends in the order drawn.
    fn ends(&self) -> Result<(ArcKind, &str, &str), EditError> {
        match (&self.from, &self.to) {
            (NodeRef::Place(p), NodeRef::Transition(t)) => {
                let kind = if self.inhibitor {
                    ArcKind::Inhibitor
                } else {
                    ArcKind::Input
                };
                Ok((kind, p, t))
            }
            (NodeRef::Transition(t), NodeRef::Place(p)) => {
                if self.inhibitor {
                    return Err(EditError::InhibitorFromTransition {
                        from: t.clone(),
                        to: p.clone(),
                    });
                }
                Ok((ArcKind::Output, p, t))
            }
            (NodeRef::Place(a), NodeRef::Place(b)) => Err(EditError::SameKind {
                from: a.clone(),
                to: b.clone(),
                kind: "place",
            }),
            (NodeRef::Transition(a), NodeRef::Transition(b)) => Err(EditError::SameKind {
                from: a.clone(),
                to: b.clone(),
                kind: "transition",
            }),
        }
    }
}
