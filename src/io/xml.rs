//! Streaming XML with positions: a thin layer over quick-xml that yields start tags, end
//! tags and text with their byte offsets, so every element, attribute and value can be
//! located ([`Span::locate`]) when it turns out to be wrong. No DOM is built: the net
//! readers ([`super::pipe`], [`super::pnml`], [`super::pnpro`]) keep only the records they
//! need. The one layer over quick-xml: its checks (one root, a depth limit, end tags that
//! match, a truncated file named by the element left open) hold for every format.
//!
//! Malformed or truncated XML becomes [`LoadErrorKind::Xml`] at the position quick-xml
//! stopped at (or at the end of the file, naming the element left open).

mod assemble;
mod nodes;

pub(crate) use assemble::read;
pub(crate) use nodes::{Dialect, Value};

use std::borrow::Cow;
use std::path::Path;

use quick_xml::Reader;
use quick_xml::XmlVersion;
use quick_xml::events::{BytesStart, Event};

use super::{LoadError, LoadErrorKind, Span};
use crate::net::Net;

/// How many elements may be open at once in a PIPE or PNML file. Real files nest six or
/// seven deep; deeper text (thousands of nested `<page>`s) is refused at the element that
/// goes one level too deep, so no reader can exhaust its stack on it.
pub const MAX_XML_DEPTH: usize = 256;

/// One step of the stream. Names are local names (namespace prefixes dropped).
#[derive(Debug)]
pub(crate) enum XmlEvent<'a> {
    /// `<name attr="..">` (empty elements yield `Start` then `End`).
    Start(Tag<'a>),
    /// `</name>`.
    End,
    /// Character data (entity references already replaced), with the offset of its first
    /// non-whitespace character.
    Text(Cow<'a, str>, usize),
}

/// A start tag: its local name, raw attributes, and where it begins.
#[derive(Debug)]
pub(crate) struct Tag<'a> {
    start: BytesStart<'a>,
    /// Byte offset of the `<`.
    pub(crate) at: usize,
}

impl<'a> Tag<'a> {
    /// The tag as quick-xml read it, borrowed from the text (the PNPRO scanner takes its
    /// attributes from it without copying).
    pub(crate) fn start(&self) -> &BytesStart<'a> {
        &self.start
    }

    /// The local name (`pnml:place` → `place`).
    pub(crate) fn name(&self) -> &str {
        let raw = self.start.name().into_inner();
        raw.rsplit(':').next().unwrap_or(raw)
    }

    /// The value of attribute `key` (local name) with its offset, or `None` when absent.
    /// A malformed attribute list is an XML error.
    pub(crate) fn attr(&self, x: &XmlStream<'_>, key: &str) -> Result<Option<Value>, LoadError> {
        for a in self.start.attributes().with_checks(false) {
            let a = a.map_err(|e| x.error_at(self.at, e.to_string()))?;
            let k = a.key.local_name().into_inner();
            if k == key {
                let v = a
                    .normalized_value(XmlVersion::Implicit1_0)
                    .map_err(|e| x.error_at(self.at, e.to_string()))?;
                return Ok(Some(Value {
                    text: v.into_owned(),
                    at: self.attr_offset(key),
                }));
            }
        }
        Ok(None)
    }

    /// Offset of the first character of attribute `key`'s value (the tag's `<` when the
    /// attribute cannot be found textually).
    fn attr_offset(&self, key: &str) -> usize {
        let raw: &str = &self.start;
        // `raw` is the tag's content after `<`: name, then attributes.
        let bytes = raw.as_bytes();
        let mut from = 0;
        while let Some(i) = raw[from..].find(key) {
            let i = from + i;
            let before_ok = i > 0 && bytes[i - 1].is_ascii_whitespace();
            let mut j = i + key.len();
            while j < bytes.len() && bytes[j].is_ascii_whitespace() {
                j += 1;
            }
            if before_ok && j < bytes.len() && bytes[j] == b'=' {
                j += 1;
                while j < bytes.len() && bytes[j].is_ascii_whitespace() {
                    j += 1;
                }
                if j < bytes.len() && (bytes[j] == b'"' || bytes[j] == b'\'') {
                    j += 1;
                }
                return self.at + 1 + j;
            }
            from = i + key.len();
        }
        self.at
    }
}

/// A streaming reader over the bytes of one file.
pub(crate) struct XmlStream<'a> {
    reader: Reader<&'a [u8]>,
    text: &'a [u8],
    path: &'a Path,
    /// Offsets of the open elements' `<`, for "never closed" errors.
    open: Vec<usize>,
    /// An empty element's pending `End`.
    pending_end: bool,
    seen_root: bool,
}

impl std::fmt::Debug for XmlStream<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("XmlStream")
            .field("path", &self.path)
            .field("depth", &self.open.len())
            .finish()
    }
}

impl<'a> XmlStream<'a> {
    /// A stream over `text` (already UTF-8; see [`to_utf8`]).
    pub(crate) fn new(path: &'a Path, text: &'a [u8]) -> Self {
        let mut reader = Reader::from_reader(text);
        reader.config_mut().check_end_names = true;
        XmlStream {
            reader,
            text,
            path,
            open: Vec::new(),
            pending_end: false,
            seen_root: false,
        }
    }

    /// Line and column of a byte offset.
    pub(crate) fn span(&self, offset: usize) -> Span {
        Span::locate(self.text, offset)
    }

    /// An error at a byte offset.
    pub(crate) fn error(&self, offset: usize, kind: LoadErrorKind) -> LoadError {
        LoadError::at(self.path, self.span(offset), kind)
    }

    fn error_at(&self, offset: usize, msg: String) -> LoadError {
        self.error(offset, LoadErrorKind::Xml(msg))
    }

    /// How many elements are open (the root is depth 1 while inside it).
    pub(crate) fn depth(&self) -> usize {
        self.open.len()
    }

    /// The next event, or `None` at the end of a well-formed document.
    pub(crate) fn next(&mut self) -> Result<Option<XmlEvent<'a>>, LoadError> {
        if self.pending_end {
            self.pending_end = false;
            self.open.pop();
            return Ok(Some(XmlEvent::End));
        }
        loop {
            let before = self.reader.buffer_position() as usize;
            let ev = match self.reader.read_event() {
                Ok(ev) => ev,
                Err(e) => {
                    let at = self.reader.error_position() as usize;
                    return Err(self.error_at(at, e.to_string()));
                }
            };
            match ev {
                Event::Start(start) | Event::Empty(start)
                    if self.open.is_empty() && self.seen_root =>
                {
                    let _ = start;
                    return Err(self.error_at(before, "a second root element".into()));
                }
                Event::Start(_) | Event::Empty(_) if self.open.len() >= MAX_XML_DEPTH => {
                    return Err(self.error_at(
                        before,
                        format!("elements nested deeper than {MAX_XML_DEPTH} levels"),
                    ));
                }
                Event::Start(start) => {
                    self.seen_root = true;
                    let tag = Tag { start, at: before };
                    self.open.push(before);
                    return Ok(Some(XmlEvent::Start(tag)));
                }
                Event::Empty(start) => {
                    self.seen_root = true;
                    let tag = Tag { start, at: before };
                    self.open.push(before);
                    self.pending_end = true;
                    return Ok(Some(XmlEvent::Start(tag)));
                }
                Event::End(_) => {
                    self.open.pop();
                    return Ok(Some(XmlEvent::End));
                }
                Event::Text(t) => {
                    if self.open.is_empty() {
                        if t.trim().is_empty() {
                            continue;
                        }
                        return Err(self.error_at(before, "text outside the root element".into()));
                    }
                    let raw: &str = &t;
                    let lead = raw.len() - raw.trim_start().len();
                    return Ok(Some(XmlEvent::Text(t.xml10_content(), before + lead)));
                }
                Event::CData(t) => {
                    return Ok(Some(XmlEvent::Text(
                        Cow::Owned(t.xml10_content().into_owned()),
                        before,
                    )));
                }
                Event::GeneralRef(r) => {
                    let s = match r.resolve_char_ref() {
                        Ok(Some(c)) => c.to_string(),
                        Ok(None) => match &*r {
                            "amp" => "&".into(),
                            "lt" => "<".into(),
                            "gt" => ">".into(),
                            "quot" => "\"".into(),
                            "apos" => "'".into(),
                            other => {
                                return Err(
                                    self.error_at(before, format!("unknown entity `&{other};`"))
                                );
                            }
                        },
                        Err(e) => return Err(self.error_at(before, e.to_string())),
                    };
                    return Ok(Some(XmlEvent::Text(Cow::Owned(s), before)));
                }
                Event::Eof => {
                    if let Some(&at) = self.open.last() {
                        let name: String = self.text[at + 1..]
                            .iter()
                            .take_while(|b| !b.is_ascii_whitespace() && !matches!(b, b'>' | b'/'))
                            .map(|&b| b as char)
                            .collect();
                        let msg = format!(
                            "the file ends inside `<{name}>` (opened at {}): truncated?",
                            self.span(at)
                        );
                        return Err(self.error_at(self.text.len(), msg));
                    }
                    if !self.seen_root {
                        return Err(self.error_at(self.text.len(), "no root element".into()));
                    }
                    return Ok(None);
                }
                Event::Decl(_) | Event::PI(_) | Event::Comment(_) | Event::DocType(_) => {}
            }
        }
    }

    /// Skips the rest of the element just started (its children and its end tag).
    pub(crate) fn skip(&mut self) -> Result<(), LoadError> {
        let depth = self.depth();
        while self.depth() >= depth {
            if self.next()?.is_none() {
                break;
            }
        }
        Ok(())
    }
}

/// The file as UTF-8: unchanged when it already is; transcoded from ISO-8859-1 when its
/// declaration says so (one byte = one character, so lines and columns stay the same).
pub(crate) fn to_utf8<'b>(path: &Path, bytes: &'b [u8]) -> Result<Cow<'b, [u8]>, LoadError> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(_) => Ok(Cow::Borrowed(bytes)),
        Err(e) => {
            let head = String::from_utf8_lossy(&bytes[..bytes.len().min(200)]).to_ascii_lowercase();
            if head.contains("iso-8859-1") || head.contains("latin1") || head.contains("latin-1") {
                Ok(Cow::Owned(
                    bytes
                        .iter()
                        .map(|&b| b as char)
                        .collect::<String>()
                        .into_bytes(),
                ))
            } else {
                let at = e.valid_up_to();
                Err(LoadError::at(
                    path,
                    Span::locate(bytes, at),
                    LoadErrorKind::Xml(
                        "invalid UTF-8 (and the XML declaration names no other encoding we read)"
                            .into(),
                    ),
                ))
            }
        }
    }
}

/// Escapes text for an XML attribute or element.
pub(crate) fn esc(s: &str) -> Cow<'_, str> {
    quick_xml::escape::escape(s)
}

/// Ids for writing: the names themselves where they are usable and unique across places
/// and transitions (`sanitize` replaces characters an id should not hold), with a suffix
/// where two would collide. Returns (place ids, transition ids).
pub(crate) fn node_ids(net: &Net, sanitize: bool) -> (Vec<String>, Vec<String>) {
    let mut used = rustc_hash::FxHashSet::default();
    let mut make = |name: &str, prefix: &str| {
        let mut base: String = if sanitize {
            name.chars()
                .map(|c| {
                    if c.is_ascii_alphanumeric() || matches!(c, '_' | '-' | '.') {
                        c
                    } else {
                        '_'
                    }
                })
                .collect()
        } else {
            name.to_string()
        };
        if base.is_empty()
            || (sanitize && !base.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_'))
        {
            base = format!("{prefix}{base}");
        }
        let mut id = base.clone();
        let mut k = 1;
        while !used.insert(id.clone()) {
            k += 1;
            id = format!("{base}_{k}");
        }
        id
    };
    let p = net.places().iter().map(|p| make(&p.name, "p")).collect();
    let t = net
        .transitions()
        .iter()
        .map(|t| make(&t.name, "t"))
        .collect();
    (p, t)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn events(text: &str) -> Result<Vec<String>, LoadError> {
        let path = Path::new("t.xml");
        let mut x = XmlStream::new(path, text.as_bytes());
        let mut out = Vec::new();
        while let Some(ev) = x.next()? {
            out.push(match ev {
                XmlEvent::Start(t) => format!("<{}@{}", t.name(), x.span(t.at)),
                XmlEvent::End => "/".into(),
                XmlEvent::Text(s, at) if !s.trim().is_empty() => {
                    format!("{}@{}", s.trim(), x.span(at))
                }
                XmlEvent::Text(..) => continue,
            });
        }
        Ok(out)
    }

    #[test]
    fn events_carry_positions_and_resolve_entities() {
        let got = events("<pnml:a x='1'>\n  <b/> t&amp;u </pnml:a>").unwrap();
        assert_eq!(
            got,
            ["<a@1:1", "<b@2:3", "/", "t@2:8", "&@2:9", "u@2:14", "/"]
        );
    }

    #[test]
    fn attribute_values_are_located() {
        let text = "<r>\n  <arc id=\"a\"  target = \"q\"/></r>";
        let path = Path::new("t.xml");
        let mut x = XmlStream::new(path, text.as_bytes());
        x.next().unwrap();
        let t = loop {
            if let Some(XmlEvent::Start(t)) = x.next().unwrap() {
                break t;
            }
        };
        let v = t.attr(&x, "target").unwrap().unwrap();
        assert_eq!(v.text, "q");
        assert_eq!(
            x.span(v.at),
            Span {
                line: 2,
                column: 26
            }
        );
        assert!(t.attr(&x, "source").unwrap().is_none());
    }

    #[test]
    fn a_file_ending_inside_an_element_names_it() {
        let e = events("<pnml>\n<net id=\"n\">\n").unwrap_err();
        assert_eq!(e.span, Some(Span { line: 3, column: 1 }));
        let LoadErrorKind::Xml(msg) = e.kind else {
            panic!("{e}")
        };
        assert!(msg.contains("`<net>` (opened at 2:1)"), "{msg}");
    }

    #[test]
    fn no_root_and_stray_text_are_errors() {
        assert!(events("<?xml version=\"1.0\"?>\n").is_err());
        assert!(events("hello").is_err());
        assert!(events("<a/><b/>").is_err());
    }

    #[test]
    fn latin1_files_are_transcoded() {
        let bytes = b"<?xml version=\"1.0\" encoding=\"ISO-8859-1\"?><a>caf\xE9</a>";
        let text = to_utf8(Path::new("t.xml"), bytes).unwrap();
        assert_eq!(
            std::str::from_utf8(&text).unwrap().chars().last(),
            Some('>')
        );
        assert!(std::str::from_utf8(&text).unwrap().contains("café"));
        let err = to_utf8(Path::new("t.xml"), b"<a>caf\xE9</a>").unwrap_err();
        assert_eq!(err.span, Some(Span { line: 1, column: 7 }));
    }
}
