//! The commands that delete a node or arcs.

use serde::Deserialize;

use super::Parts;
use super::op::{ArcKindName, EditError, NodeRef, kind_name};

/// A node and every arc that touches it.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct Delete {
    pub(crate) node: NodeRef,
}

impl Delete {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let (what, name, arcs) = match &self.node {
            NodeRef::Place(name) => ("place", name, n.remove(true, n.place(name)?)),
            NodeRef::Transition(name) => ("transition", name, n.remove(false, n.transition(name)?)),
        };
        Ok(match arcs {
            0 => format!("delete {what} {name}"),
            1 => format!("delete {what} {name} and its arc"),
            k => format!("delete {what} {name} and its {k} arcs"),
        })
    }
}

/// The arcs of `kind` between `place` and `transition`.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct DeleteArc {
    pub(crate) place: String,
    pub(crate) transition: String,
    pub(crate) kind: ArcKindName,
}

impl DeleteArc {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let (place, transition) = (&self.place, &self.transition);
        let found = n.arcs_between(place, transition, self.kind)?;
        for i in found.into_iter().rev() {
            n.arcs.remove(i);
        }
        Ok(format!(
            "delete {} arc {place} – {transition}",
            kind_name(self.kind.kind())
        ))
    }
}
