//! The lexer of [`Predicate`](super::Predicate): text to tokens with their columns.

use std::fmt;

use super::{PredicateError, PredicateErrorKind};

#[derive(Clone, Debug, PartialEq)]
pub(super) enum TokKind {
    Int(i64),
    Name(String),
    Op(&'static str),
    LParen,
    RParen,
}

impl fmt::Display for TokKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            TokKind::Int(i) => write!(f, "{i}"),
            TokKind::Name(n) => write!(f, "{n}"),
            TokKind::Op(o) => write!(f, "{o}"),
            TokKind::LParen => f.write_str("("),
            TokKind::RParen => f.write_str(")"),
        }
    }
}

#[derive(Clone, Debug)]
pub(super) struct Tok {
    pub(super) kind: TokKind,
    pub(super) column: usize,
}

fn is_name_char(c: char) -> bool {
    c.is_alphanumeric() || matches!(c, '_' | ':' | '.' | '?' | '@' | '$' | '#')
}

/// Splits `text` into tokens. With `prism`, PRISM's and Storm's single-character `=`, `&`
/// and `|` are read as `==`, `&&` and `||` (a query's state formulas are written that way).
/// Each token is an [`operator`], a [`quoted`] name, a [`number`] or a bare name.
pub(super) fn lex(text: &str, prism: bool) -> Result<Vec<Tok>, PredicateError> {
    let chars: Vec<char> = text.chars().collect();
    let mut out = Vec::new();
    let mut i = 0;
    while i < chars.len() {
        let c = chars[i];
        let column = i + 1;
        if c.is_whitespace() {
            i += 1;
            continue;
        }
        let (kind, next) = if let Some((kind, len)) = operator(&chars, i, prism)? {
            (kind, i + len)
        } else if c == '`' {
            quoted(&chars, i)?
        } else if c.is_ascii_digit() {
            number(&chars, i)?
        } else if is_name_char(c) {
            let end = i + chars[i..].iter().take_while(|&&d| is_name_char(d)).count();
            (TokKind::Name(chars[i..end].iter().collect()), end)
        } else {
            return Err(PredicateError::new(
                column,
                format!("unexpected character `{c}` (quote unusual place names with backticks)"),
            ));
        };
        out.push(Tok { kind, column });
        i = next;
    }
    Ok(out)
}

/// The operator or parenthesis at `i`, and how many characters it takes; `None` when
/// there is none there.
fn operator(
    chars: &[char],
    i: usize,
    prism: bool,
) -> Result<Option<(TokKind, usize)>, PredicateError> {
    let c = chars[i];
    let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
    if let Some(op) = ["&&", "||", "<=", ">=", "==", "!="]
        .into_iter()
        .find(|o| *o == two)
    {
        return Ok(Some((TokKind::Op(op), 2)));
    }
    let kind = match c {
        '(' => TokKind::LParen,
        ')' => TokKind::RParen,
        '<' => TokKind::Op("<"),
        '>' => TokKind::Op(">"),
        '!' => TokKind::Op("!"),
        '+' => TokKind::Op("+"),
        '-' => TokKind::Op("-"),
        '*' => TokKind::Op("*"),
        '=' | '&' | '|' if prism => TokKind::Op(match c {
            '=' => "==",
            '&' => "&&",
            _ => "||",
        }),
        '=' | '&' | '|' => {
            return Err(PredicateError::new(
                i + 1,
                format!("`{c}` alone is not an operator (did you mean `{c}{c}`?)"),
            ));
        }
        _ => return Ok(None),
    };
    Ok(Some((kind, 1)))
}

/// A place name in backticks opening at `i`, and where the token ends.
fn quoted(chars: &[char], i: usize) -> Result<(TokKind, usize), PredicateError> {
    let start = i + 1;
    let end = chars[start..]
        .iter()
        .position(|&d| d == '`')
        .map(|k| start + k)
        .ok_or_else(|| PredicateError::new(i + 1, "unclosed backtick".into()))?;
    let name: String = chars[start..end].iter().collect();
    if name.is_empty() {
        return Err(PredicateError::new(i + 1, "empty place name ``".into()));
    }
    Ok((TokKind::Name(name), end + 1))
}

/// An integer starting at `i` (a word that starts with a digit is refused), and where the
/// token ends.
fn number(chars: &[char], start: usize) -> Result<(TokKind, usize), PredicateError> {
    let column = start + 1;
    let mut i = start;
    while i < chars.len() && chars[i].is_ascii_digit() {
        i += 1;
    }
    if i < chars.len() && is_name_char(chars[i]) {
        let word: String = chars[start..]
            .iter()
            .take_while(|&&d| is_name_char(d))
            .collect();
        return Err(PredicateError {
            column,
            name: Some(word.clone()),
            kind: PredicateErrorKind::Syntax,
            message: format!("`{word}` starts with a digit: quote the place name with backticks"),
        });
    }
    let digits: String = chars[start..i].iter().collect();
    let v = digits
        .parse::<i64>()
        .map_err(|_| PredicateError::new(column, format!("`{digits}` is too large an integer")))?;
    Ok((TokKind::Int(v), i))
}
