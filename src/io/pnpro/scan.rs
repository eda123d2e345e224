//! Streams a `.PNPRO` file through the XML layer ([`XmlStream`]) and keeps, for the selected `<gspn>` page only,
//! the few attributes the net needs (with their byte offsets, for error positions).

use std::borrow::Cow;
use std::path::Path;

use quick_xml::events::BytesStart;

use crate::io::xml::{XmlEvent, XmlStream};
use crate::io::{LoadError, LoadErrorKind, ReadOptions, Span};

/// What a kept element is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Kind {
    Place,
    Transition,
    Constant,
    Template,
    Arc,
}

/// One attribute value and the byte offset where it starts in the file.
#[derive(Clone, Debug)]
pub(super) struct Attr<'a> {
    pub(super) key: &'static str,
    /// Unescaped; borrowed from the file unless it held an entity.
    pub(super) value: Cow<'a, str>,
    pub(super) at: usize,
}

/// An element of the selected page: its kind, where it starts, the attributes we read, and
/// (arcs only) its bend points.
#[derive(Clone, Debug)]
pub(super) struct Record<'a> {
    pub(super) kind: Kind,
    pub(super) at: usize,
    pub(super) attrs: Vec<Attr<'a>>,
    pub(super) points: Vec<(Attr<'a>, Attr<'a>)>,
}

impl<'a> Record<'a> {
    pub(super) fn get(&self, key: &str) -> Option<&Attr<'a>> {
        self.attrs.iter().find(|a| a.key == key)
    }
}

/// The selected page, and the names of every page (for messages).
#[derive(Debug)]
pub(super) struct Scanned<'a> {
    pub(super) page: String,
    pub(super) page_at: usize,
    pub(super) pages: Vec<String>,
    pub(super) records: Vec<Record<'a>>,
}

/// Attributes worth keeping; the editor's label offsets, magnets, rotations... are dropped.
const KEYS: [&str; 21] = [
    "name",
    "marking",
    "domain",
    "x",
    "y",
    "type",
    "delay",
    "rate",
    "weight",
    "priority",
    "nservers",
    "guard",
    "consttype",
    "value",
    "last-binding",
    "head",
    "tail",
    "kind",
    "mult",
    "multiplicity",
    "definition",
];

/// Where we are in the document.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Ctx {
    Project,
    /// A `<gspn>` page; `true` when it is the one being read.
    Page(bool),
    Nodes(bool),
    Edges(bool),
    /// An `<arc>` of the selected page, collecting its `<point>`s.
    Arc,
    Other,
}

/// Reads the elements of `text` that make the selected page ([`Scan::open`] for each
/// element as it opens) through the XML layer the other readers use ([`XmlStream`]: it
/// refuses malformed and truncated files), then checks the project ([`Scan::finish`]).
pub(super) fn scan<'a>(
    path: &Path,
    text: &'a str,
    opts: &ReadOptions,
) -> Result<Scanned<'a>, LoadError> {
    let mut scan = Scan {
        path,
        text,
        base: text.as_ptr() as usize,
        opts,
        stack: Vec::new(),
        pages: Vec::new(),
        chosen: None,
        records: Vec::new(),
        project_at: None,
    };
    let mut x = XmlStream::new(path, text.as_bytes());
    while let Some(event) = x.next()? {
        match event {
            XmlEvent::Start(tag) => {
                let ctx = scan.open(tag.start(), tag.at)?;
                scan.stack.push((ctx, tag.at));
            }
            XmlEvent::End => {
                scan.stack.pop();
            }
            XmlEvent::Text(..) => {}
        }
    }
    scan.finish()
}

/// The scanner's state while it reads.
struct Scan<'a, 'p> {
    path: &'p Path,
    text: &'a str,
    /// The address of `text`, to turn a borrowed attribute into an offset.
    base: usize,
    opts: &'p ReadOptions,
    /// Open elements: what each is, and where it starts.
    stack: Vec<(Ctx, usize)>,
    pages: Vec<String>,
    /// The page being read, and where it starts.
    chosen: Option<(String, usize)>,
    records: Vec<Record<'a>>,
    project_at: Option<usize>,
}

impl<'a> Scan<'a, '_> {
    fn err(&self, at: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::at(self.path, Span::locate(self.text.as_bytes(), at), kind)
    }

    /// The attributes of `e` worth keeping.
    fn keep(&self, e: &BytesStart<'_>) -> Result<Vec<Attr<'a>>, LoadError> {
        keep(e, self.base, self.text, &|at, kind| self.err(at, kind))
    }

    /// Element `e`, opening at `at`: what it is in its parent, and the record it adds when
    /// it is a node or an arc of the selected page (or a point of such an arc).
    fn open(&mut self, e: &BytesStart<'_>, at: usize) -> Result<Ctx, LoadError> {
        let local = e.local_name();
        let name: &str = local.as_ref();
        let parent = self.stack.last().map(|s| s.0);
        Ok(match (parent, name) {
            (None, "project") => {
                self.project_at = Some(at);
                Ctx::Project
            }
            (None, other) => {
                return Err(self.err(
                    at,
                    LoadErrorKind::Invalid(format!(
                        "not a GreatSPN project: the root element is `<{other}>`, expected `<project>`"
                    )),
                ));
            }
            (Some(Ctx::Project), "gspn") => {
                let attrs = self.keep(e)?;
                let page = attrs
                    .iter()
                    .find(|a| a.key == "name")
                    .map(|a| a.value.to_string())
                    .unwrap_or_default();
                self.pages.push(page.clone());
                let this = self.chosen.is_none()
                    && self.opts.page.as_ref().is_none_or(|wanted| *wanted == page);
                if this {
                    self.chosen = Some((page, at));
                }
                Ctx::Page(this)
            }
            (Some(Ctx::Page(sel)), "nodes") => Ctx::Nodes(sel),
            (Some(Ctx::Page(sel)), "edges") => Ctx::Edges(sel),
            (Some(Ctx::Nodes(true)), n) => {
                let kind = match n {
                    "place" => Some(Kind::Place),
                    "transition" => Some(Kind::Transition),
                    "constant" => Some(Kind::Constant),
                    "template" => Some(Kind::Template),
                    _ => None,
                };
                if let Some(kind) = kind {
                    let attrs = self.keep(e)?;
                    self.records.push(Record {
                        kind,
                        at,
                        attrs,
                        points: Vec::new(),
                    });
                }
                Ctx::Other
            }
            (Some(Ctx::Edges(true)), "arc") => {
                let attrs = self.keep(e)?;
                self.records.push(Record {
                    kind: Kind::Arc,
                    at,
                    attrs,
                    points: Vec::new(),
                });
                Ctx::Arc
            }
            (Some(Ctx::Arc), "point") => {
                let attrs = self.keep(e)?;
                let coord = |k: &str| {
                    attrs.iter().find(|a| a.key == k).cloned().ok_or_else(|| {
                        self.err(
                            at,
                            LoadErrorKind::Missing {
                                what: format!("attribute `{k}` of <point>"),
                                name: None,
                            },
                        )
                    })
                };
                let p = (coord("x")?, coord("y")?);
                if let Some(r) = self.records.last_mut() {
                    r.points.push(p);
                }
                Ctx::Other
            }
            _ => Ctx::Other,
        })
    }

    /// The file read to its end (every element closed: [`XmlStream`] saw to it): a project,
    /// and the page asked for (or a first one).
    fn finish(mut self) -> Result<Scanned<'a>, LoadError> {
        let Some(project_at) = self.project_at else {
            return Err(LoadError::file(
                self.path,
                LoadErrorKind::Invalid("no `<project>` element: not a GreatSPN project".into()),
            ));
        };
        let Some((page, page_at)) = self.chosen.take() else {
            if let Some(wanted) = &self.opts.page {
                let pages = &self.pages;
                let list = pages
                    .iter()
                    .map(|p| format!("`{p}`"))
                    .collect::<Vec<_>>()
                    .join(", ");
                return Err(self.err(
                    project_at,
                    LoadErrorKind::Invalid(format!(
                        "page `{wanted}` does not exist; this file has {}: {list}",
                        if pages.len() == 1 {
                            "one page"
                        } else {
                            "pages"
                        }
                    )),
                ));
            }
            return Err(self.err(
                project_at,
                LoadErrorKind::Missing {
                    what: "a `<gspn>` page".into(),
                    name: None,
                },
            ));
        };
        Ok(Scanned {
            page,
            page_at,
            pages: self.pages,
            records: self.records,
        })
    }
}

/// The attributes of `e` that [`KEYS`] lists, unescaped, with their offsets in `text`.
fn keep<'a>(
    e: &BytesStart<'_>,
    base: usize,
    text: &'a str,
    err: &dyn Fn(usize, LoadErrorKind) -> LoadError,
) -> Result<Vec<Attr<'a>>, LoadError> {
    let mut out = Vec::new();
    let elem_at = (e.attributes_raw().as_ptr() as usize).saturating_sub(base);
    for a in e.attributes() {
        let a = a.map_err(|x| err(elem_at, LoadErrorKind::Xml(x.to_string())))?;
        let key = a.key.as_ref();
        let Some(key) = KEYS.iter().find(|k| **k == key) else {
            continue;
        };
        // The raw value borrows from the input, so its address gives its offset.
        let raw = a.value.as_ptr() as usize;
        let in_text = raw >= base && raw + a.value.len() <= base + text.len();
        let at = if in_text { raw - base } else { elem_at };
        let value = match a
            .normalized_value(quick_xml::XmlVersion::Implicit1_0)
            .map_err(|x| err(at, LoadErrorKind::Xml(x.to_string())))?
        {
            // Unchanged: borrow it from the file rather than copy it.
            Cow::Borrowed(_) if in_text => Cow::Borrowed(&text[at..at + a.value.len()]),
            v => Cow::Owned(v.into_owned()),
        };
        out.push(Attr { key, value, at });
    }
    Ok(out)
}
