//! Turns the records of a `<pnml>` document into a [`Net`], checking every value where it
//! was written: ids unique, arcs joining a place and a transition that exist, numbers in
//! range. Shared by the PIPE and PNML readers; the defaults are the same for both (a
//! transition without `<timed>` is exponential with rate 1, single-server; `Default,k` and
//! plain `k` are both accepted for markings and weights).

use std::path::Path;

use rustc_hash::{FxHashMap, FxHashSet};

use crate::io::{Format, LoadError, LoadErrorKind, Loaded, ReadOptions, Span};
use crate::net::{
    ArcKind, NetBuilder, NetError, Place, PlaceId, Position, Servers, Timing, Transition,
    TransitionId, overflowing_arc,
};

use super::nodes::{ArcRecord, NodeRecord, Record, RecordKind, Value, collect};
use super::{Dialect, XmlStream, to_utf8};

#[derive(Clone, Copy)]
enum NodeRef {
    Place(u32),
    Transition(u32),
}

struct PendingNode {
    id: String,
    name: Option<String>,
    at: usize,
}

/// Reads a PIPE or PNML net from `bytes`: the records as they close ([`Nodes::node`],
/// [`Nodes::arc`]), then the names made unique and checked, and the arcs whose ends came
/// later resolved.
pub(crate) fn read(
    path: &Path,
    bytes: &[u8],
    _opts: &ReadOptions,
    dialect: Dialect,
) -> Result<Loaded, LoadError> {
    let text = to_utf8(path, bytes)?;
    let mut x = XmlStream::new(path, &text);
    let mut warnings = Vec::new();
    let mut nodes = Nodes::default();
    let mut vip = false;
    let doc = collect(
        &mut x,
        |x, doc| {
            if let Some(t) = &doc.net_type {
                vip = t.text.contains("VIPschema");
                check_net_type(x, t)?;
            }
            Ok(())
        },
        |x, rec| match rec {
            Record::Node(n) => nodes.node(x, n),
            Record::Arc(a) => nodes.arc(x, a),
        },
    )?;

    if doc.extra_nets > 0 {
        warnings.push(format!(
            "{} more `<net>` element(s) after the first were not read",
            doc.extra_nets
        ));
    }
    if nodes.dup_arc_ids > 0 {
        warnings.push(format!(
            "{} arc id(s) repeat an earlier arc's id (arc ids are not used)",
            nodes.dup_arc_ids
        ));
    }
    if vip {
        warnings.push("VipTool dialect (VIPschema.xsd): read as a P/T net".into());
    }

    let Nodes {
        ids,
        mut places,
        mut transitions,
        mut arcs,
        deferred,
        ..
    } = nodes;
    let mut b = NetBuilder::new(net_name(path, &doc.net_name, &doc.net_id));
    let place_names = unique_names(&mut places, "place", &mut warnings);
    let transition_names = unique_names(&mut transitions, "transition", &mut warnings);
    check_clashes(&x, &places, &place_names, "place")?;
    check_clashes(&x, &transitions, &transition_names, "transition")?;
    for ((_, mut p), name) in places.into_iter().zip(place_names) {
        p.name = name;
        b.add_place(p);
    }
    let mut transition_at = Vec::with_capacity(transitions.len());
    for ((pending, mut t), name) in transitions.into_iter().zip(transition_names) {
        t.name = name;
        b.add_transition(t);
        transition_at.push(pending.at);
    }
    for a in deferred {
        arcs.push(resolve_arc(&x, &ids, &a, true)?.expect("final resolution errs or resolves"));
    }
    let overflow = overflowing_arc(
        arcs.iter()
            .map(|a| (a.0, PlaceId(a.1), TransitionId(a.2), a.3)),
    )
    .map(|i| arcs[i].5);
    for (kind, p, t, w, points, _) in arcs {
        b.arc(kind, PlaceId(p), TransitionId(t), w, points);
    }
    let net = b.build().map_err(|e| match (&e, overflow) {
        (NetError::WeightOverflow { .. }, Some(at)) => x.error(at, LoadErrorKind::Net(e)),
        _ => LoadError::file(path, LoadErrorKind::Net(e)),
    })?;
    let format = match dialect {
        Dialect::Pipe => Format::Pipe,
        Dialect::Pnml => Format::Pnml,
    };
    Ok(Loaded {
        net,
        format,
        warnings,
        transition_at: Span::locate_all(&text, transition_at),
    })
}

/// The nodes and arcs read so far.
#[derive(Default)]
struct Nodes {
    ids: FxHashMap<String, NodeRef>,
    places: Vec<(PendingNode, Place)>,
    transitions: Vec<(PendingNode, Transition)>,
    /// Arcs whose ends were known when they closed, resolved at once (a few bytes each).
    arcs: Vec<Resolved>,
    /// The others: they wait for the end of the file.
    deferred: Vec<ArcRecord>,
    arc_ids: FxHashSet<String>,
    dup_arc_ids: usize,
}

impl Nodes {
    /// A place or a transition: its id (present, not empty, not seen before) and its
    /// values checked.
    fn node(&mut self, x: &XmlStream<'_>, n: NodeRecord) -> Result<(), LoadError> {
        let id = n.id.clone().ok_or_else(|| {
            x.error(
                n.at,
                LoadErrorKind::Missing {
                    what: format!("attribute `id` of a {}", kind_name(n.kind)),
                    name: n.name.as_ref().map(|v| v.text.clone()),
                },
            )
        })?;
        if id.text.is_empty() {
            return Err(x.error(
                id.at,
                LoadErrorKind::Missing {
                    what: format!("the id of a {}", kind_name(n.kind)),
                    name: None,
                },
            ));
        }
        let pending = PendingNode {
            id: id.text.clone(),
            name: n
                .name
                .as_ref()
                .map(|v| v.text.clone())
                .filter(|s| !s.is_empty()),
            at: id.at,
        };
        let label = pending.name.clone().unwrap_or_else(|| id.text.clone());
        let r = match n.kind {
            RecordKind::Place => {
                let p = place(x, &n, &label)?;
                self.places.push((pending, p));
                NodeRef::Place(self.places.len() as u32 - 1)
            }
            RecordKind::Transition => {
                let t = transition(x, &n, &label)?;
                self.transitions.push((pending, t));
                NodeRef::Transition(self.transitions.len() as u32 - 1)
            }
        };
        if self.ids.insert(id.text.clone(), r).is_some() {
            return Err(x.error(
                id.at,
                LoadErrorKind::Duplicate {
                    what: "id",
                    name: id.text,
                },
            ));
        }
        Ok(())
    }

    /// An arc: resolved now when both ends are known, else at the end of the file.
    fn arc(&mut self, x: &XmlStream<'_>, a: ArcRecord) -> Result<(), LoadError> {
        if let Some(id) = &a.id
            && !id.text.is_empty()
            && !self.arc_ids.insert(id.text.clone())
        {
            self.dup_arc_ids += 1;
        }
        match resolve_arc(x, &self.ids, &a, false)? {
            Some(r) => self.arcs.push(r),
            None => self.deferred.push(a),
        }
        Ok(())
    }
}

fn kind_name(k: RecordKind) -> &'static str {
    match k {
        RecordKind::Place => "place",
        RecordKind::Transition => "transition",
    }
}

/// P/T nets (ISO `…/ptnet`, PIPE's `P/T net`, VipTool) are read; other PNML net types
/// (symmetric, high-level, coloured) are refused, naming the type.
fn check_net_type(x: &XmlStream<'_>, t: &Value) -> Result<(), LoadError> {
    let ty = t.text.to_ascii_lowercase();
    let ok = ty.is_empty()
        || ty.ends_with("ptnet")
        || ty.contains("p/t")
        || ty.contains("vipschema")
        || ty.contains("gspn")
        || ty.contains("spn");
    if ok {
        return Ok(());
    }
    Err(x.error(
        t.at,
        LoadErrorKind::Unsupported(format!(
            "PNML net type `{}`: only place/transition nets are read \
             (type http://www.pnml.org/version-2009/grammar/ptnet); coloured, symmetric \
             and high-level nets are not",
            t.text
        )),
    ))
}

fn net_name(path: &Path, name: &Option<Value>, id: &Option<Value>) -> String {
    for v in [name, id].into_iter().flatten() {
        if !v.text.is_empty() {
            return v.text.clone();
        }
    }
    path.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("net")
        .to_string()
}

/// Names as shown to users: the `<name>` when it is given and unique among nodes of the
/// same kind, otherwise the id (ids are unique).
fn unique_names<T>(
    nodes: &mut [(PendingNode, T)],
    what: &str,
    warnings: &mut Vec<String>,
) -> Vec<String> {
    let mut count: FxHashMap<&str, u32> = FxHashMap::default();
    for (n, _) in nodes.iter() {
        if let Some(name) = &n.name {
            *count.entry(name.as_str()).or_default() += 1;
        }
    }
    let mut by_id = 0;
    let names: Vec<String> = nodes
        .iter()
        .map(|(n, _)| match &n.name {
            Some(name) if count[name.as_str()] == 1 => name.clone(),
            _ => {
                by_id += 1;
                n.id.clone()
            }
        })
        .collect();
    if by_id > 0 {
        warnings.push(format!(
            "{by_id} {what}(s) without a unique name are named by their id"
        ));
    }
    names
}

/// A name chosen above may still equal another node's id-based name.
fn check_clashes<T>(
    x: &XmlStream<'_>,
    nodes: &[(PendingNode, T)],
    names: &[String],
    what: &'static str,
) -> Result<(), LoadError> {
    let mut seen: FxHashSet<&str> = FxHashSet::default();
    for ((n, _), name) in nodes.iter().zip(names) {
        if !seen.insert(name.as_str()) {
            return Err(x.error(
                n.at,
                LoadErrorKind::Duplicate {
                    what,
                    name: name.clone(),
                },
            ));
        }
    }
    Ok(())
}

fn place(x: &XmlStream<'_>, n: &NodeRecord, name: &str) -> Result<Place, LoadError> {
    // PIPE writes `<initialMarking><value></value>` (and an empty capacity) for a place it
    // was never given a value for: empty is 0, as PIPE reads it.
    let initial = match &n.initial_marking {
        Some(v) if !v.text.trim().is_empty() => count(x, v, Of("initial marking", name), 0)?,
        _ => 0,
    };
    let capacity = match &n.capacity {
        Some(v) if v.text.trim().is_empty() => None,
        Some(v) => match count(x, v, Of("capacity", name), 0)? {
            0 => None,
            k => Some(k),
        },
        None => None,
    };
    if let Some(c) = capacity
        && initial > c
    {
        let v = n.initial_marking.as_ref().expect("initial > 0 was written");
        let expected = "must not exceed the place's capacity";
        return Err(Of("initial marking", name).out_of_range(x, v, &initial.to_string(), expected));
    }
    Ok(Place {
        name: name.to_string(),
        initial,
        capacity,
        position: n.position,
    })
}

fn transition(x: &XmlStream<'_>, n: &NodeRecord, name: &str) -> Result<Transition, LoadError> {
    let timed = match &n.timed {
        Some(v) => boolean(x, v, Of("timed", name))?,
        None => true,
    };
    let timing = if timed {
        let rate = match &n.rate {
            Some(v) => real(x, v, Of("rate", name), Timing::rate)?,
            None => 1.0,
        };
        let infinite = match &n.infinite_server {
            Some(v) => boolean(x, v, Of("infiniteServer", name))?,
            None => false,
        };
        let servers = match (&n.servers, infinite) {
            (_, true) => Servers::Infinite,
            (Some(v), false) => match count(x, v, Of("servers", name), 1)? {
                1 => Servers::Single,
                k => Servers::K(k),
            },
            (None, false) => Servers::Single,
        };
        Timing::Exponential { rate, servers }
    } else {
        let weight = match &n.rate {
            Some(v) => real(x, v, Of("weight", name), Timing::weight)?,
            None => 1.0,
        };
        let priority = match &n.priority {
            Some(v) => count(x, v, Of("priority", name), 1)?,
            None => 1,
        };
        Timing::Immediate { weight, priority }
    };
    Ok(Transition {
        name: name.to_string(),
        timing,
        position: n.position,
    })
}

/// An arc ready for the builder: kind, place, transition, weight, bend points.
/// An arc with its ends resolved: kind, place, transition, weight, points, and the offset
/// of its element.
type Resolved = (ArcKind, u32, u32, u32, Vec<Position>, usize);

/// Resolves an arc's ends and checks its weight and type. `Ok(None)` when an end is not
/// known yet and `last` is false; when `last`, an unknown end is an error.
fn resolve_arc(
    x: &XmlStream<'_>,
    ids: &FxHashMap<String, NodeRef>,
    a: &ArcRecord,
    last: bool,
) -> Result<Option<Resolved>, LoadError> {
    if !last {
        let known = |v: &Option<Value>| v.as_ref().is_some_and(|v| ids.contains_key(&v.text));
        if !known(&a.source) || !known(&a.target) {
            return Ok(None);
        }
    }
    let end = |v: &Option<Value>, attr: &str| -> Result<(NodeRef, Value), LoadError> {
        let v = v.as_ref().ok_or_else(|| {
            x.error(
                a.at,
                LoadErrorKind::Missing {
                    what: format!("attribute `{attr}` of an arc"),
                    name: a.id.as_ref().map(|i| i.text.clone()),
                },
            )
        })?;
        match ids.get(&v.text) {
            Some(&r) => Ok((r, v.clone())),
            None => Err(x.error(
                v.at,
                LoadErrorKind::UnknownNode {
                    what: "node",
                    name: v.text.clone(),
                },
            )),
        }
    };
    let (src, src_v) = end(&a.source, "source")?;
    let (dst, _) = end(&a.target, "target")?;
    let arc_name = || match &a.id {
        Some(i) if !i.text.is_empty() => i.text.clone(),
        _ => format!(
            "{} to {}",
            src_v.text,
            a.target.as_ref().map_or("", |t| t.text.as_str())
        ),
    };
    let weight = match &a.inscription {
        Some(v) => count(x, v, Of("arc weight", &arc_name()), 1)?,
        None => 1,
    };
    let ty = a
        .arc_type
        .as_ref()
        .map(|v| v.text.to_ascii_lowercase())
        .unwrap_or_default();
    let inhibitor = match ty.as_str() {
        "" | "normal" => false,
        "inhibitor" => true,
        _ => {
            let v = a.arc_type.as_ref().expect("non-empty type");
            return Err(x.error(
                v.at,
                LoadErrorKind::Unsupported(format!(
                    "arc `{}` of type `{}`: only normal and inhibitor arcs are read",
                    arc_name(),
                    v.text
                )),
            ));
        }
    };
    let points: Vec<Position> = a.points.clone();
    let (kind, p, t) = match (src, dst) {
        (NodeRef::Place(p), NodeRef::Transition(t)) => (
            if inhibitor {
                ArcKind::Inhibitor
            } else {
                ArcKind::Input
            },
            p,
            t,
        ),
        (NodeRef::Transition(t), NodeRef::Place(p)) if !inhibitor => (ArcKind::Output, p, t),
        (NodeRef::Transition(_), NodeRef::Place(_)) => {
            return Err(x.error(
                a.at,
                LoadErrorKind::Invalid(format!(
                    "inhibitor arc `{}` must go from a place to a transition",
                    arc_name()
                )),
            ));
        }
        _ => {
            return Err(x.error(
                a.at,
                LoadErrorKind::Invalid(format!(
                    "arc `{}` joins two nodes of the same kind; arcs join a place and a \
                     transition",
                    arc_name()
                )),
            ));
        }
    };
    Ok(Some((kind, p, t, weight, points, a.at)))
}

/// The value of `what` (`"rate"`, `"arc weight"`…) of the node `name`, for errors naming both.
#[derive(Clone, Copy)]
struct Of<'a>(&'static str, &'a str);

impl Of<'_> {
    fn not_a_number(self, x: &XmlStream<'_>, v: &Value) -> LoadError {
        x.error(
            v.at,
            LoadErrorKind::NotANumber {
                what: self.0,
                name: self.1.to_string(),
                value: v.text.clone(),
            },
        )
    }

    fn out_of_range(
        self,
        x: &XmlStream<'_>,
        v: &Value,
        value: &str,
        expected: &'static str,
    ) -> LoadError {
        x.error(
            v.at,
            LoadErrorKind::OutOfRange {
                what: self.0,
                name: self.1.to_string(),
                value: value.to_string(),
                expected,
            },
        )
    }
}

/// A non-negative integer at least `min`; `Default,k` is read as `k`.
fn count(x: &XmlStream<'_>, v: &Value, of: Of<'_>, min: u32) -> Result<u32, LoadError> {
    let s = match v.text.split_once(',') {
        Some((_class, k)) if !k.contains(',') => k.trim(),
        Some(_) => {
            return Err(x.error(
                v.at,
                LoadErrorKind::Unsupported(format!(
                    "{} of `{}` is `{}`: tokens of several colours are not read",
                    of.0, of.1, v.text
                )),
            ));
        }
        None => v.text.as_str(),
    };
    let n: i64 = match s.parse::<i64>() {
        Ok(n) => n,
        Err(_) => match s.parse::<f64>() {
            // "2.0" is accepted as 2; "2.5" is not a count.
            Ok(f) if f.fract() == 0.0 && f.abs() < 1e15 => f as i64,
            _ => return Err(of.not_a_number(x, v)),
        },
    };
    if n < min as i64 || n > u32::MAX as i64 {
        let expected = if n > u32::MAX as i64 {
            crate::net::TOO_MANY_TOKENS
        } else if min == 0 {
            "must be a whole number ≥ 0"
        } else {
            "must be a whole number ≥ 1"
        };
        return Err(of.out_of_range(x, v, s, expected));
    }
    Ok(n as u32)
}

/// A number that passes `check` ([`Timing::rate`], [`Timing::weight`]).
fn real(
    x: &XmlStream<'_>,
    v: &Value,
    of: Of<'_>,
    check: fn(f64) -> Result<f64, &'static str>,
) -> Result<f64, LoadError> {
    let f: f64 = v.text.parse().map_err(|_| of.not_a_number(x, v))?;
    check(f).map_err(|expected| of.out_of_range(x, v, &v.text, expected))
}

fn boolean(x: &XmlStream<'_>, v: &Value, of: Of<'_>) -> Result<bool, LoadError> {
    match v.text.to_ascii_lowercase().as_str() {
        "true" | "1" | "yes" => Ok(true),
        "false" | "0" | "no" => Ok(false),
        _ => Err(of.out_of_range(x, v, &v.text, "must be `true` or `false`")),
    }
}
