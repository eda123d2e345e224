//! The byte cursor the thesis inputs' two hand-written parsers share (JSON objects and
//! Python literals): peek, whitespace, and a syntax error at the current offset. Each
//! parser adds its own methods to [`Cursor`] in its module.

/// A syntax error at a byte offset.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct SyntaxError {
    pub(crate) offset: usize,
    pub(crate) message: String,
}

/// A position in a text being parsed.
pub(crate) struct Cursor<'a> {
    pub(crate) s: &'a str,
    pub(crate) b: &'a [u8],
    pub(crate) i: usize,
    /// Said after an error's message when the text ended before it: "the file", "the text".
    what: &'static str,
}

impl<'a> Cursor<'a> {
    /// At the start of `s`, which errors call `what` when they reach its end.
    pub(crate) fn new(s: &'a str, what: &'static str) -> Cursor<'a> {
        Cursor {
            s,
            b: s.as_bytes(),
            i: 0,
            what,
        }
    }

    pub(crate) fn peek(&self) -> Option<u8> {
        self.b.get(self.i).copied()
    }

    pub(crate) fn err(&self, message: &str) -> SyntaxError {
        let message = if self.i >= self.b.len() {
            format!("{message} ({} ends here)", self.what)
        } else {
            message.to_string()
        };
        SyntaxError {
            offset: self.i,
            message,
        }
    }

    /// Skips spaces, tabs and line ends.
    pub(crate) fn ws(&mut self) {
        while matches!(self.peek(), Some(b' ' | b'\t' | b'\n' | b'\r')) {
            self.i += 1;
        }
    }
}
