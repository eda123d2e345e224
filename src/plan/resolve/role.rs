//! A place's role in a plan: a resource, or an action (a program, a robot program of the
//! map, a built-in, `ros2`, or a name registered by the library's user) with its timeout
//! and failure policy.

use std::ops::Range;

use toml::Spanned;

use super::super::file::PlaceFile;
use super::super::programs::{ActionFile, Programs};
use super::{out_of_range, unknown};
use crate::io::{LoadError, LoadErrorKind};
use crate::net::{Net, PlaceId};
use crate::runtime::{FailurePolicy, Role};

pub(super) fn resolve_role(
    net: &Net,
    p: PlaceId,
    role: &Spanned<PlaceFile>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    programs: &mut Programs,
    has_map: bool,
) -> Result<Role, LoadError> {
    let place = &net.place(p).name;
    let f = role.get_ref();
    let resource = match &f.role {
        None => false,
        Some(r) if r.get_ref() == "resource" => true,
        Some(r) if r.get_ref() == "action" => false,
        Some(r) => {
            return Err(at(
                r.span(),
                LoadErrorKind::Invalid(format!(
                    "role `{}` of place `{place}`: expected \"resource\" or \"action\"",
                    r.get_ref()
                )),
            ));
        }
    };
    if resource {
        if let Some(a) = &f.action {
            return Err(at(
                a.span(),
                LoadErrorKind::Invalid(format!(
                    "place `{place}` is a resource and also has an action: choose one"
                )),
            ));
        }
        for (key, span) in [
            ("timeout", f.timeout.as_ref().map(Spanned::span)),
            ("on_failure", f.on_failure.as_ref().map(Spanned::span)),
        ] {
            if let Some(span) = span {
                return Err(at(
                    span,
                    LoadErrorKind::Invalid(format!(
                        "place `{place}` is a resource: `{key}` applies to actions only"
                    )),
                ));
            }
        }
        if f.robot.is_some() {
            return Err(at(
                role.span(),
                LoadErrorKind::Invalid(format!(
                    "place `{place}` is a resource: `robot` applies to action places only"
                )),
            ));
        }
        return Ok(Role::Resource);
    }
    let Some(action) = &f.action else {
        return Err(at(
            role.span(),
            LoadErrorKind::Missing {
                what: "`action` (or `role = \"resource\"`)".into(),
                name: Some(place.clone()),
            },
        ));
    };
    let name = match action.get_ref() {
        ActionFile::Program(prog) => programs
            .add(place, prog)
            .map_err(|k| at(action.span(), k))?,
        ActionFile::Name(n) if n.trim().is_empty() => {
            return Err(at(
                action.span(),
                LoadErrorKind::Invalid(format!("place `{place}`: the action name is empty")),
            ));
        }
        ActionFile::Name(n) => {
            // A built-in written wrongly (`wait x`, `fire T` with T not an output) is refused
            // here, with its line.
            // (With a `[map]`, `wait 2; decide` is a robot program: checked with the map.)
            if !has_map && let Err(e) = check_builtin(net, p, n, action.span(), at) {
                return Err(e);
            }
            n.clone()
        }
    };
    let timeout = match &f.timeout {
        None => None,
        Some(t) => {
            let v = *t.get_ref();
            if !crate::limits::valid_seconds(v) {
                return Err(at(
                    t.span(),
                    out_of_range("timeout", place, v, crate::limits::SECONDS_EXPECTED),
                ));
            }
            Some(v)
        }
    };
    let on_failure = match &f.on_failure {
        None => FailurePolicy::Stop,
        Some(s) => parse_failure(net, p, s.get_ref()).map_err(|kind| at(s.span(), kind))?,
    };
    Ok(Role::Action {
        name,
        timeout,
        on_failure,
        robot: f.robot.clone(),
    })
}

/// Refuses a built-in action (`wait S`, `log MSG`, `fire T [after S]`) written wrongly.
pub(super) fn check_builtin(
    net: &Net,
    p: PlaceId,
    text: &str,
    span: Range<usize>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<(), LoadError> {
    match crate::runtime::Builtin::parse(text, net, p) {
        Some(Err(reason)) => Err(at(
            span,
            LoadErrorKind::Invalid(format!("place `{}`: {reason}", net.place(p).name)),
        )),
        _ => Ok(()),
    }
}

/// Parses `stop`, `retry N` or `fire T` for place `p`.
fn parse_failure(net: &Net, p: PlaceId, s: &str) -> Result<FailurePolicy, LoadErrorKind> {
    let place = &net.place(p).name;
    let s = s.trim();
    let (word, rest) = s.split_once(char::is_whitespace).unwrap_or((s, ""));
    let rest = rest.trim();
    match (word, rest) {
        ("stop", "") => Ok(FailurePolicy::Stop),
        ("retry", n) => {
            n.parse::<u32>()
                .map(FailurePolicy::Retry)
                .map_err(|_| LoadErrorKind::NotANumber {
                    what: "retry count",
                    name: place.clone(),
                    value: n.to_string(),
                })
        }
        ("fire", t) if !t.is_empty() => {
            let t = t.trim_matches('`');
            let id = net
                .transition_by_name(t)
                .ok_or_else(|| unknown("transition", t))?;
            if !net.inputs(id).iter().any(|&(q, _)| q == p) {
                return Err(LoadErrorKind::Invalid(format!(
                    "on_failure of `{place}`: transition `{t}` is not an output of the place"
                )));
            }
            Ok(FailurePolicy::Fire(id))
        }
        _ => Err(LoadErrorKind::Invalid(format!(
            "on_failure of `{place}`: `{s}` is not \"stop\", \"retry N\" or \"fire T\""
        ))),
    }
}
