//! Turns the records of one page into a [`Net`]: resolves constants and template
//! parameters, evaluates every expression, checks every value, and says where a bad one is.

use std::cell::RefCell;
use std::path::Path;

use rustc_hash::FxHashMap;

use super::scan::{Attr, Kind, Record, Scanned};
use crate::io::expr::{EvalError, Expr, ExprError};
use crate::io::{Format, LoadError, LoadErrorKind, Loaded, ReadOptions, Span};
use crate::net::{NetBuilder, Place, PlaceId, Position, Transition, TransitionId, overflowing_arc};

mod records;
use records::{arc, timing};

/// How many constants may stand in a chain, each defined by the next (`A = B + 1`,
/// `B = C * 2`, ...). Each link evaluates an expression up to
/// [`expr::MAX_DEPTH`](crate::io::expr::MAX_DEPTH) deep inside the one before, so the chain
/// is kept short enough that the worst case stays far from the stack's end.
pub const MAX_CONSTANT_CHAIN: usize = 16;

/// Constants and template parameters of the page, evaluated on demand.
struct Env<'a> {
    path: &'a Path,
    text: &'a str,
    page: &'a str,
    constants: FxHashMap<&'a str, &'a Record<'a>>,
    /// Template parameters with the value from `--param`, if one was given.
    templates: FxHashMap<&'a str, (&'a Record<'a>, Option<f64>)>,
    places: FxHashMap<&'a str, ()>,
    memo: RefCell<FxHashMap<String, f64>>,
    visiting: RefCell<Vec<String>>,
}

impl Env<'_> {
    fn span(&self, at: usize) -> Span {
        Span::locate(self.text.as_bytes(), at)
    }

    fn error(&self, at: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::at(self.path, self.span(at), kind)
    }

    fn expr_error(&self, attr: &Attr, owner: &str, e: ExprError) -> LoadError {
        self.error(
            attr.at + e.at.min(attr.value.len()),
            LoadErrorKind::Expression {
                expr: attr.value.to_string(),
                name: owner.to_string(),
                reason: e.reason,
            },
        )
    }

    /// The value of the expression in `attr`, which belongs to node `owner`.
    fn value(&self, attr: &Attr, owner: &str) -> Result<f64, LoadError> {
        // Most values are plain numbers: skip the parser (NaN and inf land in range checks).
        if let Ok(v) = attr.value.trim().parse::<f64>() {
            return Ok(v);
        }
        let expr = Expr::parse(&attr.value).map_err(|e| self.expr_error(attr, owner, e))?;
        expr.eval(&mut |name: &str, at| self.resolve(name, attr, at, owner))
            .map_err(|e| match e {
                EvalError::At(e) => self.expr_error(attr, owner, e),
                EvalError::Lookup(e) => e,
            })
    }

    fn resolve(&self, name: &str, attr: &Attr, at: usize, owner: &str) -> Result<f64, LoadError> {
        if let Some(&v) = self.memo.borrow().get(name) {
            return Ok(v);
        }
        let fail = |reason: String| self.expr_error(attr, owner, ExprError { at, reason });
        let v = if let Some(c) = self.constants.get(name) {
            if let Some(d) = c.get("domain") {
                return Err(fail(format!(
                    "`{name}` is a coloured constant (domain `{}`): coloured nets are not supported",
                    d.value
                )));
            }
            if self.visiting.borrow().iter().any(|n| n == name) {
                return Err(fail(format!(
                    "constant `{name}` is defined in terms of itself"
                )));
            }
            if self.visiting.borrow().len() >= MAX_CONSTANT_CHAIN {
                return Err(fail(format!(
                    "constant `{name}` is reached through a chain of more than \
                     {MAX_CONSTANT_CHAIN} constants, each defined by the next"
                )));
            }
            let value = c.get("value").ok_or_else(|| {
                self.error(
                    c.at,
                    LoadErrorKind::Missing {
                        what: "attribute `value`".into(),
                        name: Some(name.to_string()),
                    },
                )
            })?;
            self.visiting.borrow_mut().push(name.to_string());
            let v = self.value(value, name);
            self.visiting.borrow_mut().pop();
            let v = v?;
            if c.get("consttype").is_some_and(|t| t.value == "INTEGER") && v.fract() != 0.0 {
                return Err(self.error(
                    value.at,
                    LoadErrorKind::OutOfRange {
                        what: "INTEGER constant",
                        name: name.to_string(),
                        value: shown(value, v),
                        expected: "must be a whole number",
                    },
                ));
            }
            v
        } else if let Some((t, param)) = self.templates.get(name) {
            match (param, t.get("last-binding")) {
                (Some(v), _) => *v,
                (None, Some(b)) => {
                    let v = self.value(b, name)?;
                    check_template_type(t, v).map_err(|e| {
                        self.error(
                            b.at,
                            LoadErrorKind::Expression {
                                expr: b.value.to_string(),
                                name: name.to_string(),
                                reason: e.to_string(),
                            },
                        )
                    })?;
                    v
                }
                (None, None) => {
                    return Err(fail(format!(
                        "template parameter `{name}` has no value (the file gives no \
                         last-binding): set it with --param {name}=VALUE"
                    )));
                }
            }
        } else if self.places.contains_key(name) {
            return Err(fail(format!(
                "`{name}` is a place: marking-dependent expressions are not supported"
            )));
        } else {
            return Err(fail(format!(
                "unknown identifier `{name}`: not a constant or template parameter of page `{}`",
                self.page
            )));
        };
        self.memo.borrow_mut().insert(name.to_string(), v);
        Ok(v)
    }

    /// A whole number ≥ `min` from the expression in `attr`.
    fn whole(
        &self,
        attr: &Attr,
        owner: &str,
        what: &'static str,
        min: u32,
    ) -> Result<u32, LoadError> {
        let v = self.value(attr, owner)?;
        crate::io::whole_number(v, min)
            .map_err(|expected| self.out_of_range(attr, owner, what, v, expected))
    }

    /// `what` of `owner` in `attr` has the value `v`, which is not what was `expected`.
    fn out_of_range(
        &self,
        attr: &Attr,
        owner: &str,
        what: &'static str,
        v: f64,
        expected: &'static str,
    ) -> LoadError {
        self.error(
            attr.at,
            LoadErrorKind::OutOfRange {
                what,
                name: owner.to_string(),
                value: shown(attr, v),
                expected,
            },
        )
    }

    /// A real number from the expression in `attr`, checked by `ok`.
    fn real(
        &self,
        attr: &Attr,
        owner: &str,
        what: &'static str,
        check: fn(f64) -> Result<f64, &'static str>,
    ) -> Result<f64, LoadError> {
        let v = self.value(attr, owner)?;
        check(v).map_err(|expected| self.out_of_range(attr, owner, what, v, expected))
    }

    fn coord(&self, attr: &Attr, owner: &str, what: &'static str) -> Result<f64, LoadError> {
        match attr.value.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(self.error(
                attr.at,
                LoadErrorKind::NotANumber {
                    what,
                    name: owner.to_string(),
                    value: attr.value.to_string(),
                },
            )),
        }
    }

    fn position(&self, r: &Record, owner: &str) -> Result<Option<Position>, LoadError> {
        match (r.get("x"), r.get("y")) {
            (Some(x), Some(y)) => Ok(Some(Position {
                x: self.coord(x, owner, "x coordinate")?,
                y: self.coord(y, owner, "y coordinate")?,
            })),
            _ => Ok(None),
        }
    }
}

/// The value as the file wrote it, with what it evaluated to when that differs.
fn shown(attr: &Attr, v: f64) -> String {
    match attr.value.trim().parse::<f64>() {
        Ok(_) => attr.value.trim().to_string(),
        Err(_) => format!("{} = {v}", attr.value.trim()),
    }
}

/// A template parameter's value that its type refuses: a fraction for an INTEGER.
#[derive(Debug, thiserror::Error)]
#[error("{0} is not a whole number, but the parameter is INTEGER")]
struct NotInteger(f64);

fn check_template_type(t: &Record, v: f64) -> Result<(), NotInteger> {
    if t.get("type").is_some_and(|ty| ty.value == "INTEGER") && v.fract() != 0.0 {
        return Err(NotInteger(v));
    }
    Ok(())
}

fn name_of<'r>(env: &Env<'_>, r: &'r Record, what: &str) -> Result<&'r str, LoadError> {
    r.get("name").map(|a| a.value.as_ref()).ok_or_else(|| {
        env.error(
            r.at,
            LoadErrorKind::Missing {
                what: format!("attribute `name` of <{what}>"),
                name: None,
            },
        )
    })
}

/// The page's net, read in the order its checks need: the names of constants, templates
/// and places ([`Env::new`]), coloured places refused ([`refuse_coloured`]), the template
/// parameters given from outside ([`Env::set_params`]), then [`places`], [`transitions`]
/// and [`arc`]s, and the builder's own checks.
pub(super) fn build(
    path: &Path,
    text: &str,
    scanned: &Scanned<'_>,
    opts: &ReadOptions,
) -> Result<Loaded, LoadError> {
    let mut env = Env::new(path, text, scanned);
    refuse_coloured(&env, &scanned.records)?;
    env.set_params(opts)?;
    let net_name = if scanned.page.is_empty() {
        path.file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default()
    } else {
        scanned.page.clone()
    };
    let mut b = NetBuilder::new(net_name);
    let ids = Ids {
        places: places(&env, &mut b, &scanned.records)?,
        transitions: FxHashMap::default(),
    };
    let (transitions, transition_at) = transitions(&env, &mut b, &scanned.records)?;
    let ids = Ids { transitions, ..ids };
    let mut arcs = Vec::new();
    for r in scanned.records.iter().filter(|r| r.kind == Kind::Arc) {
        let (kind, p, t, weight, points) = arc(&env, r, &ids)?;
        b.arc(kind, p, t, weight, points);
        arcs.push((kind, p, t, weight, r.at));
    }
    // Parallel arcs adding past the maximum: the arc that did it; otherwise the page.
    let blamed = overflowing_arc(arcs.iter().map(|a| (a.0, a.1, a.2, a.3)))
        .map_or(scanned.page_at, |i| arcs[i].4);
    let net = b
        .build()
        .map_err(|e| LoadError::at(path, env.span(blamed), LoadErrorKind::Net(e)))?;
    let mut warnings = Vec::new();
    if scanned.pages.len() > 1 {
        warnings.push(format!(
            "read page `{}` of {} (`{}`); choose another with --page",
            scanned.page,
            scanned.pages.len(),
            scanned.pages.join("`, `")
        ));
    }
    Ok(Loaded {
        net,
        format: Format::Pnpro,
        warnings,
        transition_at: Span::locate_all(text.as_bytes(), transition_at),
    })
}

impl<'a> Env<'a> {
    /// The page's constants, template parameters and place names, indexed by name.
    fn new(path: &'a Path, text: &'a str, scanned: &'a Scanned<'a>) -> Env<'a> {
        let mut env = Env {
            path,
            text,
            page: &scanned.page,
            constants: FxHashMap::default(),
            templates: FxHashMap::default(),
            places: FxHashMap::default(),
            memo: RefCell::default(),
            visiting: RefCell::default(),
        };
        for r in &scanned.records {
            let Some(name) = r.get("name").map(|a| a.value.as_ref()) else {
                continue;
            };
            match r.kind {
                Kind::Constant => {
                    env.constants.insert(name, r);
                }
                Kind::Template => {
                    env.templates.insert(name, (r, None));
                }
                Kind::Place => {
                    env.places.insert(name, ());
                }
                _ => {}
            }
        }
        env
    }

    /// The template parameters given from outside (a plan's `[params]`, `--param`): each
    /// must name a template of the page and be a number its type accepts.
    fn set_params(&mut self, opts: &ReadOptions) -> Result<(), LoadError> {
        let path = self.path;
        for (k, v) in &opts.params {
            let Some((t, slot)) = self.templates.get_mut(k.as_str()) else {
                return Err(LoadError::file(
                    path,
                    LoadErrorKind::UnknownNode {
                        what: "template parameter",
                        name: k.clone(),
                    },
                ));
            };
            let value = Expr::parse(v)
                .ok()
                .and_then(|e| e.eval(&mut |_: &str, _| Err(())).ok())
                .filter(|x| x.is_finite())
                .ok_or_else(|| {
                    LoadError::file(
                        path,
                        LoadErrorKind::NotANumber {
                            what: "template parameter",
                            name: k.clone(),
                            value: v.clone(),
                        },
                    )
                })?;
            check_template_type(t, value).map_err(|e| {
                LoadError::file(
                    path,
                    LoadErrorKind::BadParam {
                        name: k.clone(),
                        value: v.clone(),
                        reason: e.to_string(),
                    },
                )
            })?;
            *slot = Some(value);
        }
        Ok(())
    }
}

/// Coloured nets first: their markings and multiplicities would fail less clearly later.
fn refuse_coloured(env: &Env<'_>, records: &[Record<'_>]) -> Result<(), LoadError> {
    for r in records.iter().filter(|r| r.kind == Kind::Place) {
        if let Some(d) = r.get("domain") {
            let name = name_of(env, r, "place")?;
            return Err(env.error(
                d.at,
                LoadErrorKind::Unsupported(format!(
                    "place `{name}` has colour domain `{}`: coloured (SWN) nets are not \
                     supported; unfold the net first (GreatSPN's unfolding gives a P/T net)",
                    d.value
                )),
            ));
        }
    }
    Ok(())
}

/// The ids of the places and transitions added, by name.
struct Ids<'a> {
    places: FxHashMap<&'a str, PlaceId>,
    transitions: FxHashMap<&'a str, TransitionId>,
}

fn duplicate(env: &Env<'_>, at: usize, what: &'static str, name: &str) -> LoadError {
    let name = name.to_string();
    env.error(at, LoadErrorKind::Duplicate { what, name })
}

/// Adds the page's places.
fn places<'r>(
    env: &Env<'_>,
    b: &mut NetBuilder,
    records: &'r [Record<'r>],
) -> Result<FxHashMap<&'r str, PlaceId>, LoadError> {
    let mut ids: FxHashMap<&str, PlaceId> = FxHashMap::default();
    for r in records.iter().filter(|r| r.kind == Kind::Place) {
        let name = name_of(env, r, "place")?;
        let initial = match r.get("marking") {
            Some(m) => env.whole(m, name, "initial marking", 0)?,
            None => 0,
        };
        let position = env.position(r, name)?;
        if ids.contains_key(name) {
            return Err(duplicate(env, r.at, "place", name));
        }
        let id = b.add_place(Place {
            name: name.to_string(),
            initial,
            capacity: None,
            position,
        });
        ids.insert(name, id);
    }
    Ok(ids)
}

/// Adds the page's transitions; their ids, and where each starts in the file.
#[allow(clippy::type_complexity)]
fn transitions<'r>(
    env: &Env<'_>,
    b: &mut NetBuilder,
    records: &'r [Record<'r>],
) -> Result<(FxHashMap<&'r str, TransitionId>, Vec<usize>), LoadError> {
    let mut ids = FxHashMap::default();
    let mut at = Vec::new();
    for r in records.iter().filter(|r| r.kind == Kind::Transition) {
        let name = name_of(env, r, "transition")?;
        if let Some(g) = r.get("guard").filter(|g| g.value.trim() != "True") {
            return Err(env.error(
                g.at,
                LoadErrorKind::Unsupported(format!(
                    "transition `{name}` has guard `{}`: guards belong to coloured nets, \
                     which are not supported",
                    g.value
                )),
            ));
        }
        let timing = timing(env, r, name)?;
        if ids.contains_key(name) {
            return Err(duplicate(env, r.at, "transition", name));
        }
        let position = env.position(r, name)?;
        let id = b.add_transition(Transition {
            name: name.to_string(),
            timing,
            position,
        });
        ids.insert(name, id);
        at.push(r.at);
    }
    Ok((ids, at))
}
