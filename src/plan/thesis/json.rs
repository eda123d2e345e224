//! A small JSON reader that keeps positions: the thesis inputs are one JSON object whose
//! values are strings holding Python literals, and an error inside such a literal must point
//! at the right line and column of the JSON file. serde_json decodes strings but forgets
//! where each character came from, so this reader keeps, for every decoded byte, the byte
//! offset in the file it was read from.

use super::cursor::{Cursor, SyntaxError};

/// A JSON string value with, for each byte of `text`, its offset in the file.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct JsonStr {
    /// The decoded string.
    pub(crate) text: String,
    /// Offset in the file of the opening quote.
    pub(crate) start: usize,
    /// `raw[i]` = offset in the file of decoded byte `i` (an escape maps to its backslash);
    /// one more entry for the closing quote.
    pub(crate) raw: Vec<usize>,
}

impl JsonStr {
    /// The file offset of decoded byte `i` (clamped to the closing quote).
    pub(crate) fn file_offset(&self, i: usize) -> usize {
        self.raw
            .get(i)
            .or(self.raw.last())
            .copied()
            .unwrap_or(self.start)
    }
}

/// A value of the top-level object.
#[derive(Clone, Debug, PartialEq)]
pub(crate) enum JsonValue {
    /// A string, with positions.
    Str(JsonStr),
    /// Anything else (number, boolean, null, array, object), with its offset.
    Other(usize),
}

/// One `"key": value` pair of the top-level object.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Field {
    /// The key.
    pub(crate) key: JsonStr,
    /// The value.
    pub(crate) value: JsonValue,
}

/// Parses `text` as one JSON object and returns its fields in file order.
pub(crate) fn parse_object(text: &str) -> Result<Vec<Field>, SyntaxError> {
    let mut p = Cursor::new(text, "the file");
    // A UTF-8 byte order mark is allowed before the object.
    if p.b.starts_with(b"\xEF\xBB\xBF") {
        p.i = 3;
    }
    p.ws();
    if p.peek() != Some(b'{') {
        return Err(p.err("expected a JSON object `{ ... }`"));
    }
    p.i += 1;
    let mut fields = Vec::new();
    p.ws();
    if p.peek() == Some(b'}') {
        p.i += 1;
    } else {
        loop {
            p.ws();
            if p.peek() != Some(b'"') {
                return Err(p.err("expected a key in double quotes"));
            }
            let key = p.string()?;
            p.ws();
            if p.peek() != Some(b':') {
                return Err(p.err("expected `:` after the key"));
            }
            p.i += 1;
            p.ws();
            let value = if p.peek() == Some(b'"') {
                JsonValue::Str(p.string()?)
            } else {
                let at = p.i;
                p.skip_value(0)?;
                JsonValue::Other(at)
            };
            fields.push(Field { key, value });
            p.ws();
            match p.peek() {
                Some(b',') => p.i += 1,
                Some(b'}') => {
                    p.i += 1;
                    break;
                }
                _ => return Err(p.err("expected `,` or `}`")),
            }
        }
    }
    p.ws();
    if p.i < p.b.len() {
        return Err(p.err("unexpected text after the JSON object"));
    }
    Ok(fields)
}

impl Cursor<'_> {
    /// A string starting at the current `"`.
    fn string(&mut self) -> Result<JsonStr, SyntaxError> {
        let start = self.i;
        self.i += 1;
        let mut out: Vec<u8> = Vec::new();
        let mut raw = Vec::new();
        loop {
            let at = self.i;
            match self.peek() {
                None => {
                    self.i = start;
                    return Err(self.err("unterminated string"));
                }
                Some(b'"') => {
                    self.i += 1;
                    raw.push(at);
                    break;
                }
                Some(b'\\') => {
                    self.i += 1;
                    let c = self.peek().ok_or_else(|| self.err("unterminated escape"))?;
                    self.i += 1;
                    let ch = match c {
                        b'"' => '"',
                        b'\\' => '\\',
                        b'/' => '/',
                        b'b' => '\u{8}',
                        b'f' => '\u{c}',
                        b'n' => '\n',
                        b'r' => '\r',
                        b't' => '\t',
                        b'u' => self.unicode_escape(at)?,
                        _ => {
                            self.i = at;
                            return Err(self.err("unknown escape"));
                        }
                    };
                    let mut buf = [0u8; 4];
                    for &byte in ch.encode_utf8(&mut buf).as_bytes() {
                        out.push(byte);
                        raw.push(at);
                    }
                }
                Some(c) if c < 0x20 => {
                    return Err(self.err("control character in a string (escape it)"));
                }
                Some(c) => {
                    out.push(c);
                    raw.push(at);
                    self.i += 1;
                }
            }
        }
        // The input was a &str and escapes produce whole characters, so this is UTF-8.
        let text = String::from_utf8(out).map_err(|_| SyntaxError {
            offset: start,
            message: "string is not UTF-8".into(),
        })?;
        Ok(JsonStr { text, start, raw })
    }

    fn hex4(&mut self) -> Result<u32, SyntaxError> {
        let digits = self.b.get(self.i..self.i + 4).unwrap_or_default();
        let s = std::str::from_utf8(digits).unwrap_or("");
        let v = u32::from_str_radix(s, 16)
            .ok()
            .filter(|_| s.len() == 4)
            .ok_or_else(|| self.err("expected 4 hex digits after \\u"))?;
        self.i += 4;
        Ok(v)
    }

    fn unicode_escape(&mut self, at: usize) -> Result<char, SyntaxError> {
        let hi = self.hex4()?;
        let code = if (0xD800..0xDC00).contains(&hi) {
            if self.b.get(self.i..self.i + 2) != Some(b"\\u") {
                return Err(self.err("unpaired surrogate in \\u escape"));
            }
            self.i += 2;
            let lo = self.hex4()?;
            if !(0xDC00..0xE000).contains(&lo) {
                return Err(self.err("unpaired surrogate in \\u escape"));
            }
            0x10000 + ((hi - 0xD800) << 10) + (lo - 0xDC00)
        } else {
            hi
        };
        char::from_u32(code).ok_or(SyntaxError {
            offset: at,
            message: "invalid \\u escape".into(),
        })
    }

    /// Skips any JSON value (checking its syntax).
    fn skip_value(&mut self, depth: usize) -> Result<(), SyntaxError> {
        if depth > 128 {
            return Err(self.err("nested too deeply"));
        }
        self.ws();
        match self.peek() {
            Some(b'"') => self.string().map(drop),
            Some(open @ (b'{' | b'[')) => {
                let close = if open == b'{' { b'}' } else { b']' };
                self.i += 1;
                self.ws();
                if self.peek() == Some(close) {
                    self.i += 1;
                    return Ok(());
                }
                loop {
                    self.ws();
                    if open == b'{' {
                        if self.peek() != Some(b'"') {
                            return Err(self.err("expected a key in double quotes"));
                        }
                        self.string()?;
                        self.ws();
                        if self.peek() != Some(b':') {
                            return Err(self.err("expected `:`"));
                        }
                        self.i += 1;
                    }
                    self.skip_value(depth + 1)?;
                    self.ws();
                    match self.peek() {
                        Some(b',') => self.i += 1,
                        Some(c) if c == close => {
                            self.i += 1;
                            return Ok(());
                        }
                        _ => return Err(self.err("expected `,` or a closing bracket")),
                    }
                }
            }
            Some(b't') if self.b[self.i..].starts_with(b"true") => {
                self.i += 4;
                Ok(())
            }
            Some(b'f') if self.b[self.i..].starts_with(b"false") => {
                self.i += 5;
                Ok(())
            }
            Some(b'n') if self.b[self.i..].starts_with(b"null") => {
                self.i += 4;
                Ok(())
            }
            Some(b'-' | b'0'..=b'9') => {
                let start = self.i;
                while matches!(
                    self.peek(),
                    Some(b'-' | b'+' | b'.' | b'e' | b'E' | b'0'..=b'9')
                ) {
                    self.i += 1;
                }
                let s = std::str::from_utf8(&self.b[start..self.i]).unwrap_or("");
                if s.parse::<f64>().is_err() {
                    self.i = start;
                    return Err(self.err("malformed number"));
                }
                Ok(())
            }
            _ => Err(self.err("expected a JSON value")),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fields_keep_their_file_offsets() {
        let text = "{ \"a\": \"x\\\"y\", \"n\": [1, {\"k\": null}],\n \"b\":\"\\u00e9z\" }";
        let f = parse_object(text).unwrap();
        assert_eq!(f.len(), 3);
        assert_eq!(f[0].key.text, "a");
        let JsonValue::Str(a) = &f[0].value else {
            panic!()
        };
        assert_eq!(a.text, "x\"y");
        assert_eq!(&text[a.file_offset(0)..=a.file_offset(0)], "x");
        assert_eq!(&text[a.file_offset(1)..a.file_offset(1) + 2], "\\\"");
        assert_eq!(&text[a.file_offset(2)..=a.file_offset(2)], "y");
        assert!(matches!(f[1].value, JsonValue::Other(_)));
        let JsonValue::Str(b) = &f[2].value else {
            panic!()
        };
        assert_eq!(b.text, "éz");
        assert_eq!(&text[b.file_offset(2)..=b.file_offset(2)], "z");
    }

    #[test]
    fn errors_have_offsets() {
        assert_eq!(parse_object("[1]").unwrap_err().offset, 0);
        assert_eq!(parse_object("{\"a\" 1}").unwrap_err().offset, 5);
        let e = parse_object("{\"a\": \"x").unwrap_err();
        assert_eq!(e.offset, 6);
        assert!(e.message.contains("unterminated"));
        assert!(parse_object("{\"a\": 1} x").is_err());
        assert!(parse_object("{\"a\": 1,}").is_err());
    }
}
