//! Python literals as the thesis framework wrote them (and read them with `ast.literal_eval`):
//! tuples, lists, dicts, strings in `'` or `"`, integers, floats, `True`/`False`/`None`.
//! Every value keeps the byte offset where it starts, so an error can name its position.

use super::cursor::{Cursor, SyntaxError};

/// A Python literal value and the byte offset where it starts.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Py {
    /// Byte offset of the first character of the value.
    pub(crate) at: usize,
    /// The value.
    pub(crate) kind: PyKind,
}

/// The kinds of literal the thesis inputs use.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum PyKind {
    /// `1`, `-3`.
    Int(i64),
    /// `0.5`, `1e-3`.
    Float(f64),
    /// `'p1'` or `"p1"`.
    Str(String),
    /// `True` / `False`.
    Bool(bool),
    /// `None`.
    None,
    /// `(a, b)` (a parenthesised single value without a comma is that value, as in Python).
    Tuple(Vec<Py>),
    /// `[a, b]`.
    List(Vec<Py>),
    /// `{k: v, ...}` in the order written.
    Dict(Vec<(Py, Py)>),
}

impl PyKind {
    /// What the value is, for messages.
    pub(crate) fn describe(&self) -> &'static str {
        match self {
            PyKind::Int(_) => "an integer",
            PyKind::Float(_) => "a number",
            PyKind::Str(_) => "a string",
            PyKind::Bool(_) => "a boolean",
            PyKind::None => "None",
            PyKind::Tuple(_) => "a tuple",
            PyKind::List(_) => "a list",
            PyKind::Dict(_) => "a dict",
        }
    }
}

/// Parses `text` as exactly one Python literal.
pub(crate) fn parse(text: &str) -> Result<Py, SyntaxError> {
    let mut p = Cursor::new(text, "the text");
    let v = p.value(0)?;
    p.ws();
    if p.i < p.b.len() {
        return Err(p.err("unexpected text after the value"));
    }
    Ok(v)
}

impl Cursor<'_> {
    fn value(&mut self, depth: usize) -> Result<Py, SyntaxError> {
        if depth > 64 {
            return Err(self.err("nested too deeply"));
        }
        self.ws();
        let at = self.i;
        let kind = match self.peek() {
            Some(q @ (b'\'' | b'"')) => PyKind::Str(self.quoted(q)?),
            Some(b'(') => {
                let (items, comma) = self.sequence(b')', depth)?;
                if items.len() == 1 && !comma {
                    // `(x)` is x, not a tuple.
                    let mut it = items;
                    return Ok(it.remove(0));
                }
                PyKind::Tuple(items)
            }
            Some(b'[') => PyKind::List(self.sequence(b']', depth)?.0),
            Some(b'{') => PyKind::Dict(self.dict(depth)?),
            Some(b'-' | b'+' | b'.' | b'0'..=b'9') => self.number()?,
            Some(c) if c.is_ascii_alphabetic() || c == b'_' => {
                let start = self.i;
                while matches!(self.peek(), Some(c) if c.is_ascii_alphanumeric() || c == b'_') {
                    self.i += 1;
                }
                match &self.s[start..self.i] {
                    "True" => PyKind::Bool(true),
                    "False" => PyKind::Bool(false),
                    "None" => PyKind::None,
                    word => {
                        self.i = start;
                        return Err(
                            self.err(&format!("`{word}` is not a literal (strings need quotes)"))
                        );
                    }
                }
            }
            _ => return Err(self.err("expected a value")),
        };
        Ok(Py { at, kind })
    }

    /// Items up to `close`; also says whether a comma was seen (for 1-tuples).
    fn sequence(&mut self, close: u8, depth: usize) -> Result<(Vec<Py>, bool), SyntaxError> {
        self.i += 1;
        let mut items = Vec::new();
        let mut comma = false;
        loop {
            self.ws();
            if self.peek() == Some(close) {
                self.i += 1;
                return Ok((items, comma));
            }
            items.push(self.value(depth + 1)?);
            self.ws();
            match self.peek() {
                Some(b',') => {
                    comma = true;
                    self.i += 1;
                }
                Some(c) if c == close => {}
                _ => return Err(self.err(&format!("expected `,` or `{}`", close as char))),
            }
        }
    }

    fn dict(&mut self, depth: usize) -> Result<Vec<(Py, Py)>, SyntaxError> {
        self.i += 1;
        let mut items = Vec::new();
        loop {
            self.ws();
            if self.peek() == Some(b'}') {
                self.i += 1;
                return Ok(items);
            }
            let k = self.value(depth + 1)?;
            self.ws();
            if self.peek() != Some(b':') {
                return Err(self.err("expected `:` after a dict key"));
            }
            self.i += 1;
            let v = self.value(depth + 1)?;
            items.push((k, v));
            self.ws();
            match self.peek() {
                Some(b',') => self.i += 1,
                Some(b'}') => {}
                _ => return Err(self.err("expected `,` or `}`")),
            }
        }
    }

    fn quoted(&mut self, quote: u8) -> Result<String, SyntaxError> {
        let start = self.i;
        self.i += 1;
        let mut out = String::new();
        loop {
            let rest = &self.s[self.i..];
            let Some(c) = rest.chars().next() else {
                self.i = start;
                return Err(self.err("unterminated string"));
            };
            match c {
                '\n' => {
                    self.i = start;
                    return Err(self.err("unterminated string (end of line)"));
                }
                '\\' => {
                    let Some(e) = rest[1..].chars().next() else {
                        self.i = start;
                        return Err(self.err("unterminated string"));
                    };
                    let decoded = match e {
                        'n' => '\n',
                        't' => '\t',
                        'r' => '\r',
                        '0' => '\0',
                        '\\' | '\'' | '"' => e,
                        // Python keeps unknown escapes as written.
                        other => {
                            out.push('\\');
                            other
                        }
                    };
                    out.push(decoded);
                    self.i += 1 + e.len_utf8();
                }
                c if c as u32 == u32::from(quote) => {
                    self.i += 1;
                    return Ok(out);
                }
                c => {
                    out.push(c);
                    self.i += c.len_utf8();
                }
            }
        }
    }

    fn number(&mut self) -> Result<PyKind, SyntaxError> {
        let start = self.i;
        if matches!(self.peek(), Some(b'-' | b'+')) {
            self.i += 1;
        }
        while matches!(self.peek(), Some(b'0'..=b'9' | b'.' | b'e' | b'E' | b'_'))
            || (matches!(self.peek(), Some(b'-' | b'+'))
                && matches!(self.b.get(self.i - 1), Some(b'e' | b'E')))
        {
            self.i += 1;
        }
        let s: String = self.s[start..self.i]
            .chars()
            .filter(|&c| c != '_')
            .collect();
        if let Ok(v) = s.parse::<i64>() {
            return Ok(PyKind::Int(v));
        }
        match s.parse::<f64>() {
            Ok(v) if s.bytes().any(|b| b.is_ascii_digit()) => Ok(PyKind::Float(v)),
            _ => {
                self.i = start;
                Err(self.err(&format!("`{s}` is not a number")))
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kind(s: &str) -> PyKind {
        parse(s).unwrap().kind
    }

    #[test]
    fn reads_the_thesis_shapes() {
        let v = parse("{('-', 0,\"1\"): {'t1:Go':1, 't2': 0.5}, (): {}}").unwrap();
        let PyKind::Dict(items) = v.kind else {
            panic!()
        };
        assert_eq!(items.len(), 2);
        let (k, val) = &items[0];
        assert_eq!(k.at, 1);
        let PyKind::Tuple(key) = &k.kind else {
            panic!()
        };
        assert_eq!(key[0].kind, PyKind::Str("-".into()));
        assert_eq!((key[1].kind.clone(), key[1].at), (PyKind::Int(0), 7));
        assert_eq!(key[2].kind, PyKind::Str("1".into()));
        let PyKind::Dict(choose) = &val.kind else {
            panic!()
        };
        assert_eq!(choose[0].0.kind, PyKind::Str("t1:Go".into()));
        assert_eq!(choose[1].1.kind, PyKind::Float(0.5));
        assert_eq!(items[1].0.kind, PyKind::Tuple(vec![]));
    }

    #[test]
    fn scalars_and_one_tuples() {
        assert_eq!(kind("(1)"), PyKind::Int(1));
        assert!(matches!(kind("(1,)"), PyKind::Tuple(v) if v.len() == 1));
        assert_eq!(kind("-3"), PyKind::Int(-3));
        assert_eq!(kind("1e-3"), PyKind::Float(1e-3));
        assert_eq!(kind("'a\\'b'"), PyKind::Str("a'b".into()));
        assert_eq!(kind("True"), PyKind::Bool(true));
        assert_eq!(kind("None"), PyKind::None);
        assert!(matches!(kind("['p4', \"p5\"]"), PyKind::List(v) if v.len() == 2));
    }

    #[test]
    fn errors_point_at_the_problem() {
        assert_eq!(parse("('p1', p2)").unwrap_err().offset, 7);
        assert_eq!(parse("('p1' 'p2')").unwrap_err().offset, 6);
        assert_eq!(parse("{'a' 1}").unwrap_err().offset, 5);
        assert_eq!(parse("('p1").unwrap_err().offset, 1);
        assert!(parse("(1, 2) x").is_err());
        assert!(parse("").is_err());
    }
}
