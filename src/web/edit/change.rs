//! The commands that change a node, arcs, or where nodes are drawn.

use std::collections::BTreeMap;

use serde::Deserialize;

use super::op::{
    ArcKindName, EditError, Kind, Num, arc_owner, describe_timing, kind_name, present, timing,
};
use super::{Parts, check_name, position};

/// A place's name, initial tokens or capacity.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct SetPlace {
    pub(crate) place: String,
    pub(crate) name: Option<String>,
    pub(crate) tokens: Option<Num>,
    #[serde(default, deserialize_with = "present")]
    pub(crate) capacity: Option<Option<Num>>,
}

impl SetPlace {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let i = n.place(&self.place)?;
        if self.name.is_none() && self.tokens.is_none() && self.capacity.is_none() {
            return Err(EditError::Nothing);
        }
        let mut what = Vec::new();
        let p = &mut n.places[i];
        if let Some(new) = &self.name {
            check_name("place", new)?;
            what.push(format!("name {new}"));
            p.name = new.clone();
        }
        if let Some(k) = &self.tokens {
            p.initial = k.whole("initial marking", &p.name, 0)?;
            what.push(format!("tokens {}", p.initial));
        }
        if let Some(c) = &self.capacity {
            p.capacity = match c {
                Some(c) => Some(c.whole("capacity", &p.name, 1)?),
                None => None,
            };
            what.push(match p.capacity {
                Some(c) => format!("capacity {c}"),
                None => "unbounded".to_string(),
            });
        }
        Ok(format!("change place {} ({})", self.place, what.join(", ")))
    }
}

/// A transition's name, kind and parameters.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct SetTransition {
    pub(crate) transition: String,
    pub(crate) name: Option<String>,
    pub(crate) kind: Option<Kind>,
    pub(crate) rate: Option<Num>,
    pub(crate) servers: Option<Num>,
    pub(crate) weight: Option<Num>,
    pub(crate) priority: Option<Num>,
}

impl SetTransition {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let i = n.transition(&self.transition)?;
        let nothing = [&self.rate, &self.servers, &self.weight, &self.priority]
            .iter()
            .all(|v| v.is_none());
        if self.name.is_none() && self.kind.is_none() && nothing {
            return Err(EditError::Nothing);
        }
        let t = &mut n.transitions[i];
        let mut what = Vec::new();
        if let Some(new) = &self.name {
            check_name("transition", new)?;
            what.push(format!("name {new}"));
            t.name = new.clone();
        }
        let current = if t.is_immediate() {
            Kind::Immediate
        } else {
            Kind::Exponential
        };
        let kind = self.kind.unwrap_or(current);
        if kind != current || !nothing {
            let before = t.timing;
            t.timing = timing(
                &t.name,
                kind,
                Some(t.timing),
                &self.rate,
                &self.servers,
                &self.weight,
                &self.priority,
            )?;
            what.push(describe_timing(before, t.timing));
        }
        Ok(format!(
            "change transition {} ({})",
            self.transition,
            what.join(", ")
        ))
    }
}

/// The multiplicity or the kind of the arcs of `kind` between `place` and `transition`
/// (parallel arcs become one).
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct SetArc {
    pub(crate) place: String,
    pub(crate) transition: String,
    pub(crate) kind: ArcKindName,
    pub(crate) weight: Option<Num>,
    pub(crate) new_kind: Option<ArcKindName>,
}

impl SetArc {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let (place, transition, kind) = (&self.place, &self.transition, self.kind);
        let found = n.arcs_between(place, transition, kind)?;
        if self.weight.is_none() && self.new_kind.is_none() {
            return Err(EditError::Nothing);
        }
        let mut arc = n.arcs[found[0]].clone();
        for &i in found.iter().skip(1).rev() {
            n.arcs.remove(i);
        }
        let mut what = Vec::new();
        if let Some(k) = self.new_kind
            && k != kind
        {
            if kind == ArcKindName::Output || k == ArcKindName::Output {
                return Err(EditError::KindChange {
                    from: kind_name(kind.kind()),
                    to: kind_name(k.kind()),
                });
            }
            arc.kind = k.kind();
            what.push(kind_name(arc.kind).to_string());
        }
        if let Some(w) = &self.weight {
            let owner = arc_owner(arc.kind, place, transition);
            arc.weight = w.whole("arc multiplicity", &owner, 1)?;
            what.push(format!("multiplicity {}", arc.weight));
        }
        n.arcs[found[0]] = arc;
        Ok(format!(
            "change {} arc {place} – {transition} ({})",
            kind_name(kind.kind()),
            what.join(", ")
        ))
    }
}

/// New positions, in the file's units.
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub(crate) struct Move {
    #[serde(default)]
    pub(crate) places: BTreeMap<String, [f64; 2]>,
    #[serde(default)]
    pub(crate) transitions: BTreeMap<String, [f64; 2]>,
}

impl Move {
    pub(super) fn apply(&self, n: &mut Parts) -> Result<String, EditError> {
        let (places, transitions) = (&self.places, &self.transitions);
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
        Ok(match places.len() + transitions.len() {
            1 => format!(
                "move {}",
                places.keys().chain(transitions.keys()).next().expect("one")
            ),
            k => format!("move {k} nodes"),
        })
    }
}
