//! The arc and transition-timing records of a page, checked value by value.

use super::super::scan::{Attr, Record};
use super::{Env, Ids};
use crate::io::LoadError;
use crate::io::LoadErrorKind;
use crate::net::{ArcKind, PlaceId, Position, Servers, Timing, TransitionId};

/// An arc record: its kind, place, transition, multiplicity and bend points.
#[allow(clippy::type_complexity)]
pub(super) fn arc(
    env: &Env<'_>,
    r: &Record<'_>,
    ids: &Ids<'_>,
) -> Result<(ArcKind, PlaceId, TransitionId, u32, Vec<Position>), LoadError> {
    let get = |key: &str| {
        r.get(key).ok_or_else(|| {
            env.error(
                r.at,
                LoadErrorKind::Missing {
                    what: format!("attribute `{key}` of <arc>"),
                    name: None,
                },
            )
        })
    };
    // The editor writes `kind`/`mult`; files of its v100 format spell them
    // `type`/`multiplicity` (Storm reads both).
    let kind_attr = match r.get("kind").or_else(|| r.get("type")) {
        Some(a) => a,
        None => get("kind")?,
    };
    let (head, tail) = (get("head")?, get("tail")?);
    let kind = match kind_attr.value.to_ascii_uppercase().as_str() {
        "INPUT" => ArcKind::Input,
        "OUTPUT" => ArcKind::Output,
        "INHIBITOR" => ArcKind::Inhibitor,
        other => {
            return Err(env.error(
                kind_attr.at,
                LoadErrorKind::Invalid(format!(
                    "arc kind `{other}`: expected INPUT, OUTPUT or INHIBITOR"
                )),
            ));
        }
    };
    let (p_attr, t_attr) = match kind {
        ArcKind::Output => (head, tail),
        _ => (tail, head),
    };
    let owner = format!("{} → {}", tail.value, head.value);
    // An endpoint that names nothing, or a node of the other kind.
    let missing = |attr: &Attr, what: &'static str| {
        let name = attr.value.as_ref();
        let other_kind = match what {
            "place" => ids.transitions.contains_key(name),
            _ => ids.places.contains_key(name),
        };
        let kind = if other_kind {
            LoadErrorKind::Invalid(format!(
                "{} arc {owner}: `{}` is not a {what}",
                kind_attr.value, attr.value
            ))
        } else {
            LoadErrorKind::UnknownNode {
                what,
                name: attr.value.to_string(),
            }
        };
        env.error(attr.at, kind)
    };
    let p = *ids
        .places
        .get(p_attr.value.as_ref())
        .ok_or_else(|| missing(p_attr, "place"))?;
    let t = *ids
        .transitions
        .get(t_attr.value.as_ref())
        .ok_or_else(|| missing(t_attr, "transition"))?;
    let weight = match r.get("mult").or_else(|| r.get("multiplicity")) {
        Some(m) => env.whole(m, &owner, "arc multiplicity", 1)?,
        None => 1,
    };
    let points = r
        .points
        .iter()
        .map(|(x, y)| {
            Ok(Position {
                x: env.coord(x, &owner, "x coordinate")?,
                y: env.coord(y, &owner, "y coordinate")?,
            })
        })
        .collect::<Result<Vec<_>, LoadError>>()?;
    Ok((kind, p, t, weight, points))
}

/// A transition record's timing: exponential (rate, servers) or immediate (weight,
/// priority); the other GreatSPN kinds are refused, naming the transition.
pub(super) fn timing(env: &Env<'_>, r: &Record, name: &str) -> Result<Timing, LoadError> {
    let ty = r.get("type").map_or("EXP", |a| a.value.as_ref());
    let unsupported = |what: &str| {
        env.error(
            r.get("type").map_or(r.at, |a| a.at),
            LoadErrorKind::Unsupported(format!(
                "transition `{name}` is {what} (type {ty}): only exponential (EXP) and \
                 immediate (IMM) transitions are supported"
            )),
        )
    };
    match ty {
        "EXP" => {
            let rate = match r.get("delay").or_else(|| r.get("rate")) {
                Some(d) => env.real(d, name, "rate", Timing::rate)?,
                None => 1.0,
            };
            let servers = match r.get("nservers") {
                None => Servers::Infinite,
                Some(a) => match a.value.trim() {
                    "Infinite" => Servers::Infinite,
                    "Single" => Servers::Single,
                    _ => match env.whole(a, name, "number of servers", 1)? {
                        1 => Servers::Single,
                        k => Servers::K(k),
                    },
                },
            };
            Ok(Timing::Exponential { rate, servers })
        }
        "IMM" => {
            let weight = match r.get("weight") {
                Some(w) => env.real(w, name, "weight", Timing::weight)?,
                None => 1.0,
            };
            let priority = match r.get("priority") {
                Some(p) => env.whole(p, name, "priority", 1)?,
                None => 1,
            };
            Ok(Timing::Immediate { weight, priority })
        }
        "GEN" | "DET" => Err(unsupported("general (non-exponential)")),
        "CONT" => Err(unsupported("continuous (fluid)")),
        _ => Err(env.error(
            r.get("type").map_or(r.at, |a| a.at),
            LoadErrorKind::Invalid(format!(
                "transition `{name}`: unknown type `{ty}` (expected EXP or IMM)"
            )),
        )),
    }
}
