//! The records of a `<pnml><net>` document (PIPE, ISO PNML and VipTool alike): places,
//! transitions and arcs with their labels and offsets, handed out one at a time as each
//! element closes. Labels are read from a `<value>` or `<text>` child (PIPE / ISO), or
//! from text directly inside the label; `<graphics>` and `<toolspecific>` are skipped
//! except for positions.

use crate::io::LoadError;
use crate::io::LoadErrorKind;
use crate::net::Position;

use super::{Tag, XmlEvent, XmlStream};

/// Which flavour of `<pnml>` the document is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Dialect {
    /// The thesis framework's PIPE files.
    Pipe,
    /// ISO/IEC 15909-2 PNML (P/T), with or without the `<timed>`/`<rate>` extension.
    Pnml,
}

/// A text value and the byte offset of its first character.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct Value {
    /// The text, trimmed.
    pub(crate) text: String,
    /// Where it starts.
    pub(crate) at: usize,
}

/// What a record describes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum RecordKind {
    Place,
    Transition,
}

/// A place or a transition as written.
#[derive(Clone, Debug)]
pub(crate) struct NodeRecord {
    pub(crate) kind: RecordKind,
    /// The element's `<`.
    pub(crate) at: usize,
    pub(crate) id: Option<Value>,
    pub(crate) name: Option<Value>,
    pub(crate) initial_marking: Option<Value>,
    pub(crate) capacity: Option<Value>,
    pub(crate) timed: Option<Value>,
    pub(crate) rate: Option<Value>,
    pub(crate) infinite_server: Option<Value>,
    pub(crate) servers: Option<Value>,
    pub(crate) priority: Option<Value>,
    pub(crate) position: Option<Position>,
}

/// An arc as written.
#[derive(Clone, Debug)]
pub(crate) struct ArcRecord {
    pub(crate) at: usize,
    pub(crate) id: Option<Value>,
    pub(crate) source: Option<Value>,
    pub(crate) target: Option<Value>,
    pub(crate) inscription: Option<Value>,
    /// `<type value="inhibitor"/>` (PIPE) or `<type><text>inhibitor</text></type>`.
    pub(crate) arc_type: Option<Value>,
    pub(crate) points: Vec<Position>,
}

/// What the document says about itself.
#[derive(Clone, Debug, Default)]
pub(crate) struct NetDoc {
    pub(crate) net_id: Option<Value>,
    pub(crate) net_type: Option<Value>,
    pub(crate) net_name: Option<Value>,
    /// `<net>` elements after the first, which are not read.
    pub(crate) extra_nets: usize,
    pub(crate) pages: usize,
}

/// One record, handed to the sink as its element closes.
#[derive(Debug)]
pub(crate) enum Record {
    Node(NodeRecord),
    Arc(ArcRecord),
}

/// Streams the document, calling `sink` for every place, transition and arc of the first
/// `<net>` (pages flattened). `on_net` sees the `<net>` header before any record.
pub(crate) fn collect(
    x: &mut XmlStream<'_>,
    mut on_net: impl FnMut(&XmlStream<'_>, &NetDoc) -> Result<(), LoadError>,
    mut sink: impl FnMut(&XmlStream<'_>, Record) -> Result<(), LoadError>,
) -> Result<NetDoc, LoadError> {
    let mut doc = NetDoc::default();
    let root = match x.next()? {
        Some(XmlEvent::Start(t)) => t,
        _ => unreachable!("XmlStream yields a root element or an error"),
    };
    if root.name() != "pnml" {
        return Err(x.error(
            root.at,
            LoadErrorKind::Unsupported(format!(
                "the root element is `<{}>`; PIPE and PNML files start with `<pnml>`",
                root.name()
            )),
        ));
    }
    let mut nets = 0;
    let mut root_at = root.at;
    loop {
        match x.next()? {
            None => break,
            Some(XmlEvent::Start(t)) if t.name() == "net" && x.depth() == 2 => {
                nets += 1;
                if nets > 1 {
                    doc.extra_nets += 1;
                    x.skip()?;
                    continue;
                }
                root_at = t.at;
                doc.net_id = t.attr(x, "id")?;
                doc.net_type = t.attr(x, "type")?;
                on_net(x, &doc)?;
                container(x, &mut doc, &mut sink, true)?;
            }
            Some(XmlEvent::Start(_)) => x.skip()?,
            Some(_) => {}
        }
    }
    if nets == 0 {
        return Err(x.error(
            root_at,
            LoadErrorKind::Missing {
                what: "a `<net>` element inside `<pnml>`".into(),
                name: None,
            },
        ));
    }
    Ok(doc)
}

/// Reads the inside of a `<net>` or `<page>` up to its end tag.
fn container(
    x: &mut XmlStream<'_>,
    doc: &mut NetDoc,
    sink: &mut impl FnMut(&XmlStream<'_>, Record) -> Result<(), LoadError>,
    is_net: bool,
) -> Result<(), LoadError> {
    loop {
        let t = match x.next()? {
            Some(XmlEvent::Start(t)) => t,
            Some(XmlEvent::End) | None => return Ok(()),
            Some(XmlEvent::Text(..)) => continue,
        };
        match t.name() {
            "place" => {
                let r = node(x, &t, RecordKind::Place)?;
                sink(x, Record::Node(r))?;
            }
            "transition" => {
                let r = node(x, &t, RecordKind::Transition)?;
                sink(x, Record::Node(r))?;
            }
            "arc" => {
                let r = arc(x, &t)?;
                sink(x, Record::Arc(r))?;
            }
            "page" => {
                doc.pages += 1;
                container(x, doc, sink, false)?;
            }
            "name" if is_net => doc.net_name = label(x)?,
            n @ ("referencePlace" | "referenceTransition") => {
                return Err(x.error(
                    t.at,
                    LoadErrorKind::Unsupported(format!(
                        "`<{n}>` (a node shared between pages): flatten the pages first"
                    )),
                ));
            }
            _ => x.skip()?,
        }
    }
}

fn node(x: &mut XmlStream<'_>, t: &Tag<'_>, kind: RecordKind) -> Result<NodeRecord, LoadError> {
    let mut r = NodeRecord {
        kind,
        at: t.at,
        id: t.attr(x, "id")?,
        name: None,
        initial_marking: None,
        capacity: None,
        timed: None,
        rate: None,
        infinite_server: None,
        servers: None,
        priority: None,
        position: None,
    };
    loop {
        let c = match x.next()? {
            Some(XmlEvent::Start(c)) => c,
            Some(XmlEvent::End) | None => return Ok(r),
            Some(XmlEvent::Text(..)) => continue,
        };
        let slot = match c.name() {
            "graphics" => {
                let mut pts = Vec::new();
                graphics(x, &mut pts)?;
                if r.position.is_none() {
                    r.position = pts.first().copied();
                }
                continue;
            }
            "name" => &mut r.name,
            "initialMarking" => &mut r.initial_marking,
            "capacity" => &mut r.capacity,
            "timed" => &mut r.timed,
            "rate" => &mut r.rate,
            "infiniteServer" => &mut r.infinite_server,
            "servers" => &mut r.servers,
            "priority" => &mut r.priority,
            _ => {
                x.skip()?;
                continue;
            }
        };
        *slot = label(x)?;
    }
}

fn arc(x: &mut XmlStream<'_>, t: &Tag<'_>) -> Result<ArcRecord, LoadError> {
    let mut r = ArcRecord {
        at: t.at,
        id: t.attr(x, "id")?,
        source: t.attr(x, "source")?,
        target: t.attr(x, "target")?,
        inscription: None,
        arc_type: None,
        points: Vec::new(),
    };
    loop {
        let c = match x.next()? {
            Some(XmlEvent::Start(c)) => c,
            Some(XmlEvent::End) | None => return Ok(r),
            Some(XmlEvent::Text(..)) => continue,
        };
        match c.name() {
            "graphics" => graphics(x, &mut r.points)?,
            "arcpath" => {
                if let Some(p) = point(x, &c)? {
                    r.points.push(p);
                }
                x.skip()?;
            }
            "inscription" => r.inscription = label(x)?,
            "type" => {
                let attr = c.attr(x, "value")?;
                let text = label(x)?;
                r.arc_type = attr.or(text);
            }
            _ => x.skip()?,
        }
    }
}

/// Reads `<graphics>`, pushing every `<position x y>` child.
fn graphics(x: &mut XmlStream<'_>, out: &mut Vec<Position>) -> Result<(), LoadError> {
    loop {
        let c = match x.next()? {
            Some(XmlEvent::Start(c)) => c,
            Some(XmlEvent::End) | None => return Ok(()),
            Some(XmlEvent::Text(..)) => continue,
        };
        if c.name() == "position"
            && let Some(p) = point(x, &c)?
        {
            out.push(p);
        }
        x.skip()?;
    }
}

/// The `x`, `y` attributes of a tag, when both are there.
fn point(x: &XmlStream<'_>, t: &Tag<'_>) -> Result<Option<Position>, LoadError> {
    let (Some(px), Some(py)) = (t.attr(x, "x")?, t.attr(x, "y")?) else {
        return Ok(None);
    };
    let num = |v: &Value| {
        v.text
            .parse::<f64>()
            .ok()
            .filter(|f| f.is_finite())
            .ok_or_else(|| {
                x.error(
                    v.at,
                    LoadErrorKind::NotANumber {
                        what: "position",
                        name: t.name().to_string(),
                        value: v.text.clone(),
                    },
                )
            })
    };
    Ok(Some(Position {
        x: num(&px)?,
        y: num(&py)?,
    }))
}

/// Reads a label element just opened (`<name>`, `<initialMarking>`...) to its end: the text
/// of its first `<value>` / `<text>` descendant outside `<graphics>`, or its own text.
fn label(x: &mut XmlStream<'_>) -> Result<Option<Value>, LoadError> {
    let depth = x.depth();
    let mut found: Option<Value> = None;
    let mut direct = String::new();
    let mut direct_at = None;
    loop {
        match x.next()? {
            None => return Ok(found),
            Some(XmlEvent::End) => {
                if x.depth() < depth {
                    break;
                }
            }
            Some(XmlEvent::Start(c)) => match c.name() {
                "graphics" | "toolspecific" => x.skip()?,
                "value" | "text" if found.is_none() => found = Some(text(x, c.at)?),
                _ => {}
            },
            Some(XmlEvent::Text(s, at)) => {
                // Indentation before the first word is dropped unread: it would be trimmed.
                if x.depth() == depth && (direct_at.is_some() || !s.trim().is_empty()) {
                    direct_at.get_or_insert(at);
                    direct.push_str(&s);
                }
            }
        }
    }
    Ok(found.or_else(|| {
        direct_at.map(|at| Value {
            text: trimmed(direct),
            at,
        })
    }))
}

/// `s` without its leading and trailing whitespace, reusing its buffer when it has none.
fn trimmed(s: String) -> String {
    if s.trim().len() == s.len() {
        s
    } else {
        s.trim().to_string()
    }
}

/// The text inside the element just opened, up to its end tag (nested elements skipped).
fn text(x: &mut XmlStream<'_>, tag_at: usize) -> Result<Value, LoadError> {
    let mut s = String::new();
    let mut at = None;
    loop {
        match x.next()? {
            None | Some(XmlEvent::End) => break,
            Some(XmlEvent::Start(_)) => x.skip()?,
            Some(XmlEvent::Text(t, off)) => {
                if at.is_some() || !t.trim().is_empty() {
                    at.get_or_insert(off);
                    s.push_str(&t);
                }
            }
        }
    }
    Ok(Value {
        text: trimmed(s),
        at: at.unwrap_or(tag_at),
    })
}
