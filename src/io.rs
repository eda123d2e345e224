//! Net formats: PIPE XML (the thesis format), PNML (ISO P/T plus the `<timed>` / `<rate>`
//! extension), GreatSPN PNPRO, and exports (DOT, PRISM); measures over time as CSV and SVG ([`series`]). Plan files are read by
//! [`crate::plan`].
//!
//! Every reader streams the file through quick-xml (no DOM) and reports bad input as a
//! [`LoadError`] carrying the file, the line and column, and the offending name.

pub mod dot;
pub mod drn;
pub mod expr;
pub mod pipe;
pub mod pnml;
pub mod pnpro;
pub mod prism;
pub mod series;
pub(crate) mod xml;

pub use xml::MAX_XML_DEPTH;

use std::fmt;
use std::path::{Path, PathBuf};

use crate::net::{Net, NetError};

/// `text` as a message quotes it: whole when it has at most `max` characters, else its first
/// `max` characters and `…` (a generated 100,000-character expression is not echoed whole).
pub fn excerpt(text: &str, max: usize) -> std::borrow::Cow<'_, str> {
    match text.char_indices().nth(max) {
        None => text.into(),
        Some((cut, _)) => format!("{}…", &text[..cut]).into(),
    }
}

/// A 1-based line and column in a file.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Span {
    /// Line, from 1.
    pub line: u32,
    /// Column in characters, from 1.
    pub column: u32,
}

impl Span {
    /// The line and column of byte `offset` in `text` (clamped to its end). The column
    /// counts characters, not bytes, so it matches what an editor shows.
    pub fn locate(text: &[u8], offset: usize) -> Span {
        LineIndex::new(text).locate(text, offset)
    }

    /// [`Span::locate`] for many offsets, the text indexed once ([`LineIndex`]): linear in
    /// the text's size plus a binary search per offset, in any order.
    pub fn locate_all(text: &[u8], offsets: impl IntoIterator<Item = usize>) -> Vec<Span> {
        let index = LineIndex::new(text);
        offsets
            .into_iter()
            .map(|offset| index.locate(text, offset))
            .collect()
    }
}

/// The start of every line of a text, and character counts at fixed steps, found once: then
/// locating an offset costs a binary search and a short count, instead of a scan from the
/// start of the text (or of a long line). Readers that locate every name — thesis inputs are
/// one JSON object on a few lines, plans have many rules — were quadratic in the file's size.
#[derive(Clone, Debug)]
pub struct LineIndex {
    starts: Vec<usize>,
    /// Characters in `text[..k * STEP]`, per k; empty when the text is ASCII (a character
    /// per byte, nothing to count).
    chars: Vec<usize>,
}

impl LineIndex {
    const STEP: usize = 256;

    /// Indexes the lines of `text`.
    pub fn new(text: &[u8]) -> LineIndex {
        let mut starts = vec![0];
        starts.extend(
            text.iter()
                .enumerate()
                .filter(|&(_, &b)| b == b'\n')
                .map(|(i, _)| i + 1),
        );
        let mut chars = Vec::new();
        if !text.is_ascii() {
            chars.reserve(text.len() / Self::STEP + 1);
            let mut n = 0;
            chars.push(0);
            for block in text.chunks(Self::STEP) {
                n += char_starts(block);
                chars.push(n);
            }
        }
        LineIndex { starts, chars }
    }

    /// Characters in `text[..offset]`.
    fn chars_before(&self, text: &[u8], offset: usize) -> usize {
        if self.chars.is_empty() {
            return offset;
        }
        let k = offset / Self::STEP;
        self.chars[k] + char_starts(&text[k * Self::STEP..offset])
    }

    /// The line and column of byte `offset` in the text this index was built from
    /// (clamped to its end): the one place the crate turns an offset into a [`Span`].
    pub fn locate(&self, text: &[u8], offset: usize) -> Span {
        let offset = offset.min(text.len());
        let line = self.starts.partition_point(|&s| s <= offset);
        let start = self.starts[line - 1];
        let column = self.chars_before(text, offset) - self.chars_before(text, start) + 1;
        Span {
            line: line as u32,
            column: column as u32,
        }
    }
}

/// Characters that start in `bytes` (UTF-8: every byte but the continuation bytes).
fn char_starts(bytes: &[u8]) -> usize {
    bytes.iter().filter(|&&b| b & 0xC0 != 0x80).count()
}

impl fmt::Display for Span {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}:{}", self.line, self.column)
    }
}

/// An I/O error kept whole — its [`std::io::ErrorKind`], its OS code — in a [`LoadError`],
/// which is `Clone` and `PartialEq`: shared behind an `Arc`, and equal to another when both
/// say the same (kind and message).
#[derive(Clone, Debug)]
pub struct IoError(std::sync::Arc<std::io::Error>);

impl IoError {
    /// The error as the system gave it.
    pub fn get(&self) -> &std::io::Error {
        &self.0
    }
}

impl From<std::io::Error> for IoError {
    fn from(e: std::io::Error) -> Self {
        IoError(std::sync::Arc::new(e))
    }
}

impl PartialEq for IoError {
    fn eq(&self, other: &Self) -> bool {
        self.0.kind() == other.0.kind() && self.0.to_string() == other.0.to_string()
    }
}

impl fmt::Display for IoError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.0.fmt(f)
    }
}

/// Transparent: the chain goes on with the system error's own source, if it has one.
impl std::error::Error for IoError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        self.0.source()
    }
}

/// A file we could not load: where, and what was wrong.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadError {
    /// The file.
    pub path: PathBuf,
    /// Where in the file, when known.
    pub span: Option<Span>,
    /// What was wrong.
    pub kind: LoadErrorKind,
}

impl LoadError {
    /// The template parameter this error is about, when it is about one given from outside
    /// the net file (a plan's `[params]` or `--param`): the plan reader then points at it.
    pub fn template_parameter(&self) -> Option<&str> {
        match &self.kind {
            LoadErrorKind::UnknownNode {
                what: "template parameter",
                name,
            }
            | LoadErrorKind::NotANumber {
                what: "template parameter",
                name,
                ..
            }
            | LoadErrorKind::BadParam { name, .. } => Some(name),
            _ => None,
        }
    }

    /// An error at a known position.
    pub fn at(path: impl Into<PathBuf>, span: Span, kind: LoadErrorKind) -> Self {
        LoadError {
            path: path.into(),
            span: Some(span),
            kind,
        }
    }

    /// The file is empty (or only whitespace): blamed on its first line and column, where
    /// its content should start.
    pub fn empty(path: impl Into<PathBuf>) -> Self {
        LoadError::at(path, Span { line: 1, column: 1 }, LoadErrorKind::Empty)
    }

    /// An error about the file as a whole.
    pub fn file(path: impl Into<PathBuf>, kind: LoadErrorKind) -> Self {
        LoadError {
            path: path.into(),
            span: None,
            kind,
        }
    }
}

impl fmt::Display for LoadError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.span {
            Some(s) => write!(f, "{}:{}: {}", self.path.display(), s, self.kind),
            None => write!(f, "{}: {}", self.path.display(), self.kind),
        }
    }
}

impl std::error::Error for LoadError {}

/// What was wrong with a file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum LoadErrorKind {
    /// The file could not be read (or written), with the system's error as its source.
    #[error("cannot read: {0}")]
    Io(#[source] IoError),
    /// The file is empty (or only whitespace).
    #[error("the file is empty")]
    Empty,
    /// Neither the extension nor the content tells which format this is.
    #[error("unknown format `{0}`: expected .xml (PIPE), .pnml, .PNPRO or .toml (plan)")]
    UnknownFormat(String),
    /// The XML itself is malformed or truncated.
    #[error("malformed XML: {0}")]
    Xml(String),
    /// An arc (or rule) names a node that does not exist.
    #[error("{what} `{name}` does not exist")]
    UnknownNode {
        /// "place", "transition", "node", "page", "parameter"...
        what: &'static str,
        /// The missing name.
        name: String,
    },
    /// Two nodes share an id or a name.
    #[error("duplicate {what} `{name}`")]
    Duplicate {
        /// "place", "transition", "id"...
        what: &'static str,
        /// The repeated name.
        name: String,
    },
    /// A value that should be a number is not one.
    #[error("{what} of `{name}`: `{value}` is not a number")]
    NotANumber {
        /// What the value is ("rate", "initial marking", "arc weight"...).
        what: &'static str,
        /// The node it belongs to.
        name: String,
        /// The text found.
        value: String,
    },
    /// A number out of its allowed range (negative marking, zero rate, NaN...).
    #[error("{what} of `{name}` is {value}: {expected}")]
    OutOfRange {
        /// What the value is.
        what: &'static str,
        /// The node it belongs to.
        name: String,
        /// The value, as written.
        value: String,
        /// What was expected, e.g. "must be a finite number > 0".
        expected: &'static str,
    },
    /// A required element or attribute is missing.
    #[error("{what} is missing{}", name.as_ref().map(|n| format!(" on `{n}`")).unwrap_or_default())]
    Missing {
        /// What is missing.
        what: String,
        /// The node it should belong to, when there is one.
        name: Option<String>,
    },
    /// Valid input that we do not read (a PNML dialect, a coloured net...), with what exactly.
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// An expression (PNPRO rates, markings, multiplicities) could not be evaluated.
    #[error("expression `{}` of `{name}`: {reason}", excerpt(expr, 80))]
    Expression {
        /// The expression text.
        expr: String,
        /// The node it belongs to.
        name: String,
        /// Why it failed (unknown identifier, syntax...).
        reason: String,
    },
    /// A template parameter's value does not suit the parameter (a fraction for an INTEGER).
    #[error("template parameter `{name}` = {value}: {reason}")]
    BadParam {
        /// The parameter.
        name: String,
        /// The value given.
        value: String,
        /// Why it does not suit.
        reason: String,
    },
    /// A semantic check on the finished net failed.
    #[error("{0}")]
    Net(#[from] NetError),
    /// A plan or input file is wrong in some other way, described in full.
    #[error("{0}")]
    Invalid(String),
}

/// `v` as a count of at least `min` (0 or 1), or what a count must be: one rule for the
/// readers (markings, multiplicities, priorities, servers) and the viewer's editor.
pub(crate) fn whole_number(v: f64, min: u32) -> Result<u32, &'static str> {
    if v.is_finite() && v.fract() == 0.0 && v >= min as f64 && v <= u32::MAX as f64 {
        return Ok(v as u32);
    }
    Err(if v.fract() == 0.0 && v > u32::MAX as f64 {
        crate::net::TOO_MANY_TOKENS
    } else if min == 0 {
        "must be a whole number ≥ 0"
    } else {
        "must be a whole number ≥ 1"
    })
}

/// The file formats gspn knows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// PIPE-style XML, as written by the thesis framework (`.xml`).
    Pipe,
    /// ISO/IEC 15909-2 PNML P/T nets, optionally with `<timed>`/`<rate>` (`.pnml`).
    Pnml,
    /// GreatSPN editor project (`.PNPRO`).
    Pnpro,
    /// Graphviz DOT (write only).
    Dot,
    /// A gspn plan (`.toml`).
    Plan,
}

impl Format {
    /// The name used in CLI output and JSON (`"pipe"`, `"pnml"`, ...).
    pub fn name(self) -> &'static str {
        match self {
            Format::Pipe => "pipe",
            Format::Pnml => "pnml",
            Format::Pnpro => "pnpro",
            Format::Dot => "dot",
            Format::Plan => "plan",
        }
    }

    /// The format an extension names, case-insensitively; `None` when unknown.
    pub fn from_extension(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        match ext.as_str() {
            "xml" => Some(Format::Pipe),
            "pnml" => Some(Format::Pnml),
            "pnpro" => Some(Format::Pnpro),
            "dot" | "gv" => Some(Format::Dot),
            "toml" => Some(Format::Plan),
            _ => None,
        }
    }
}

/// Options every net reader takes.
#[derive(Clone, Debug, Default)]
pub struct ReadOptions {
    /// The page (PNPRO `<gspn name>`) to read; `None` = the first one.
    pub page: Option<String>,
    /// Template parameters (`--param NAME=VALUE`), overriding the file's `last-binding`.
    pub params: Vec<(String, String)>,
}

/// A net read from a file, with the format it was in and non-fatal remarks.
#[derive(Clone, Debug)]
pub struct Loaded {
    /// The net.
    pub net: Net,
    /// The format it was read from.
    pub format: Format,
    /// Things the reader accepted but the user should know (ignored elements, defaults used).
    pub warnings: Vec<String>,
    /// Where each transition is defined in the file, by [`TransitionId`] index: a check made
    /// after reading (a rate too slow for real time) can still name the line and column.
    ///
    /// [`TransitionId`]: crate::net::TransitionId
    pub transition_at: Vec<Span>,
}

/// Reads the net in `path`, choosing the reader from the extension and, for XML, the content
/// (an `.xml` file in the ISO PNML namespace is read as PNML; a `.pnml` file in PIPE's
/// dialect as PIPE).
pub fn read_net(path: &Path, opts: &ReadOptions) -> Result<Loaded, LoadError> {
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::file(path, LoadErrorKind::Io(e.into())))?;
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::empty(path));
    }
    let ext = path
        .extension()
        .and_then(|e| e.to_str())
        .unwrap_or("")
        .to_string();
    let format = match Format::from_extension(path) {
        Some(Format::Pipe) | Some(Format::Pnml) => sniff_xml(&bytes),
        Some(Format::Pnpro) => Format::Pnpro,
        Some(f @ (Format::Dot | Format::Plan)) => {
            return Err(LoadError::file(
                path,
                LoadErrorKind::Invalid(format!("a {} file is not a net file", f.name())),
            ));
        }
        None => return Err(LoadError::file(path, LoadErrorKind::UnknownFormat(ext))),
    };
    match format {
        Format::Pipe => pipe::read(path, &bytes, opts),
        Format::Pnml => pnml::read(path, &bytes, opts),
        Format::Pnpro => pnpro::read(path, &bytes, opts),
        Format::Dot | Format::Plan => unreachable!("filtered above"),
    }
}

/// Tells ISO PNML (namespace or net type on `pnml.org`, or VipTool's `VIPschema`) from
/// PIPE's `<pnml>` dialect by the first few KB.
fn sniff_xml(bytes: &[u8]) -> Format {
    let head = &bytes[..bytes.len().min(4096)];
    let head = String::from_utf8_lossy(head);
    if head.contains("pnml.org") || head.contains("VIPschema") {
        Format::Pnml
    } else {
        Format::Pipe
    }
}

/// Writes `net` to `path` in `format`.
pub fn write_net(net: &Net, path: &Path, format: Format) -> Result<(), LoadError> {
    let text = match format {
        Format::Pnpro => pnpro::write(net),
        Format::Pnml => pnml::write(net),
        Format::Dot => dot::write(net),
        Format::Pipe => pipe::write(net),
        Format::Plan => {
            return Err(LoadError::file(
                path,
                LoadErrorKind::Invalid("a plan is not written from a net".into()),
            ));
        }
    };
    std::fs::write(path, text).map_err(|e| LoadError::file(path, LoadErrorKind::Io(e.into())))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn locate_all_gives_locate_s_answers_in_one_pass() {
        let text = "ab\ncdé\n\nxyz\n".as_bytes();
        let offsets = [0, 1, 3, 7, 8, 9, 12, 14, 99, 4, 2];
        let expect: Vec<Span> = offsets.iter().map(|&o| Span::locate(text, o)).collect();
        assert_eq!(Span::locate_all(text, offsets), expect);
        assert_eq!(expect[3], Span { line: 2, column: 4 });
        assert_eq!(expect[9], Span { line: 2, column: 2 });
    }

    #[test]
    fn locate_counts_lines_and_characters() {
        let text = "ab\ncdé\nxyz".as_bytes();
        assert_eq!(Span::locate(text, 0), Span { line: 1, column: 1 });
        assert_eq!(Span::locate(text, 3), Span { line: 2, column: 1 });
        // 'é' is two bytes but one column.
        assert_eq!(Span::locate(text, 7), Span { line: 2, column: 4 });
        assert_eq!(Span::locate(text, 9), Span { line: 3, column: 2 });
        let index = LineIndex::new(text);
        for at in 0..=text.len() + 1 {
            assert_eq!(
                index.locate(text, at),
                Span::locate(text, at),
                "offset {at}"
            );
        }
        // ASCII text: columns are byte counts, no character table.
        let ascii = format!("a\n{}\nb", "xy".repeat(5000));
        let (ascii, index) = (ascii.as_bytes(), LineIndex::new(ascii.as_bytes()));
        for at in [
            0,
            1,
            2,
            3,
            257,
            9000,
            ascii.len() - 1,
            ascii.len(),
            ascii.len() + 5,
        ] {
            assert_eq!(
                index.locate(ascii, at),
                Span::locate(ascii, at),
                "offset {at}"
            );
        }
        // Past the first step of the character table, on a long line.
        let long = format!("é\n{}\nab", "xé".repeat(5000));
        let (long, index) = (long.as_bytes(), LineIndex::new(long.as_bytes()));
        for at in [0, 2, 3, 4097, 9000, 15_003, long.len()] {
            if std::str::from_utf8(long).unwrap().is_char_boundary(at) {
                assert_eq!(
                    index.locate(long, at),
                    Span::locate(long, at),
                    "offset {at}"
                );
            }
        }
    }
}
