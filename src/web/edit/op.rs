//! What an edit says: the operation type the page sends ([`Edit`]), its numbers as typed
//! ([`Num`], checked as the GreatSPN reader checks them), why an edit is refused
//! ([`EditError`]), and a transition's timing from an edit's fields.

use serde::{Deserialize, Deserializer};

use super::add::{AddArc, AddPlace, AddTransition};
use super::change::{Move, SetArc, SetPlace, SetTransition};
use super::remove::{Delete, DeleteArc};

use crate::io::LoadErrorKind;
use crate::net::{ArcKind, NetError, Servers, Timing};

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
    pub(super) fn kind(self) -> ArcKind {
        match self {
            ArcKindName::Input => ArcKind::Input,
            ArcKindName::Output => ArcKind::Output,
            ArcKindName::Inhibitor => ArcKind::Inhibitor,
        }
    }
}

/// `Some(value)` for a field that is present, `null` included (`capacity: null` = unbounded).
pub(super) fn present<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Option<Num>>, D::Error> {
    Option::<Num>::deserialize(d).map(Some)
}

/// One change of the net, as the page sends it (see the [editor module](super) for the
/// table): one command struct per operation, each with its own `apply`, as mini-redis's
/// `Command` delegates to `Get`, `Set`, …
#[derive(Clone, Debug, Deserialize, PartialEq)]
#[serde(tag = "op", rename_all = "snake_case")]
pub(crate) enum Edit {
    /// A new place.
    AddPlace(AddPlace),
    /// A new transition.
    AddTransition(AddTransition),
    /// A new arc.
    AddArc(AddArc),
    /// A node and its arcs gone.
    Delete(Delete),
    /// Arcs gone.
    DeleteArc(DeleteArc),
    /// A place changed.
    SetPlace(SetPlace),
    /// A transition changed.
    SetTransition(SetTransition),
    /// Arcs changed.
    SetArc(SetArc),
    /// Nodes moved.
    Move(Move),
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
    /// A name longer than [`MAX_NAME_CHARS`](crate::web::limits::MAX_NAME_CHARS) (not
    /// echoed: it may be megabytes).
    #[error(
        "{what} name of {chars} characters: at most {} per name",
        crate::web::limits::MAX_NAME_CHARS
    )]
    NameTooLong {
        /// "place" or "transition".
        what: &'static str,
        /// Its length in characters.
        chars: usize,
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
    /// The viewer shows a live run, a replay, or a policy or rewards without their plan.
    #[error("{0}")]
    NotEditable(String),
    /// The edited net no longer fits the plan served with it: the plan reader's own error
    /// (the plan's file, line and column, the name it cannot find or the kind it needs) and
    /// that line of the plan.
    #[error("the plan would no longer load: {error}{}", .line.as_ref().map(|l| format!(" (`{l}`)")).unwrap_or_default())]
    BreaksPlan {
        /// The reader's message.
        error: String,
        /// The plan's line it points at.
        line: Option<String>,
    },
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

pub(super) fn kind_name(k: ArcKind) -> &'static str {
    match k {
        ArcKind::Input => "input",
        ArcKind::Output => "output",
        ArcKind::Inhibitor => "inhibitor",
    }
}

/// An arc as the readers name it: `tail → head`.
pub(super) fn arc_owner(kind: ArcKind, place: &str, transition: &str) -> String {
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
    pub(super) fn value(&self, what: &'static str, name: &str) -> Result<f64, EditError> {
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

    pub(super) fn shown(&self, v: f64) -> String {
        match self {
            Num::Text(s) => s.trim().to_string(),
            Num::Number(_) => format!("{v}"),
        }
    }

    /// A whole number ≥ `min`, checked as the GreatSPN reader checks one.
    pub(super) fn whole(&self, what: &'static str, name: &str, min: u32) -> Result<u32, EditError> {
        let v = self.value(what, name)?;
        crate::io::whole_number(v, min)
            .map_err(|expected| out_of_range(what, name, self.shown(v), expected))
    }

    pub(super) fn rate(&self, name: &str) -> Result<f64, EditError> {
        let v = self.value("rate", name)?;
        Timing::rate(v).map_err(|expected| out_of_range("rate", name, self.shown(v), expected))
    }

    pub(super) fn weight(&self, name: &str) -> Result<f64, EditError> {
        let v = self.value("weight", name)?;
        Timing::weight(v).map_err(|expected| out_of_range("weight", name, self.shown(v), expected))
    }

    /// `single`, `infinite`, or a number of servers k ≥ 1 (1 is single).
    pub(super) fn servers(&self, name: &str) -> Result<Servers, EditError> {
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

/// The timing of transition `name` of `kind`: the parameters given, else those of `before`
/// when it is of the same kind, else the defaults (rate 1, single server; weight 1,
/// priority 1). A parameter of the other kind is refused.
pub(super) fn timing(
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
pub(super) fn describe_timing(before: Timing, after: Timing) -> String {
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
