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
        let two: String = chars[i..(i + 2).min(chars.len())].iter().collect();
        let op2 = ["&&", "||", "<=", ">=", "==", "!="]
            .into_iter()
            .find(|o| *o == two);
        if let Some(op) = op2 {
            out.push(Tok {
                kind: TokKind::Op(op),
                column,
            });
            i += 2;
            continue;
        }
        let kind = match c {
            '(' => Some(TokKind::LParen),
            ')' => Some(TokKind::RParen),
            '<' => Some(TokKind::Op("<")),
            '>' => Some(TokKind::Op(">")),
            '!' => Some(TokKind::Op("!")),
            '+' => Some(TokKind::Op("+")),
            '-' => Some(TokKind::Op("-")),
            '*' => Some(TokKind::Op("*")),
            _ => None,
        };
        if let Some(kind) = kind {
            out.push(Tok { kind, column });
            i += 1;
            continue;
        }
        if prism && (c == '=' || c == '&' || c == '|') {
            let op = match c {
                '=' => "==",
                '&' => "&&",
                _ => "||",
            };
            out.push(Tok {
                kind: TokKind::Op(op),
                column,
            });
            i += 1;
            continue;
        }
        if c == '=' || c == '&' || c == '|' {
            return Err(PredicateError::new(
                column,
                format!("`{c}` alone is not an operator (did you mean `{c}{c}`?)"),
            ));
        }
        if c == '`' {
            let start = i + 1;
            let end = chars[start..]
                .iter()
                .position(|&d| d == '`')
                .map(|k| start + k)
                .ok_or_else(|| PredicateError::new(column, "unclosed backtick".into()))?;
            let name: String = chars[start..end].iter().collect();
            if name.is_empty() {
                return Err(PredicateError::new(column, "empty place name ``".into()));
            }
            out.push(Tok {
                kind: TokKind::Name(name),
                column,
            });
            i = end + 1;
            continue;
        }
        if c.is_ascii_digit() {
            let start = i;
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
                    message: format!(
                        "`{word}` starts with a digit: quote the place name with backticks"
                    ),
                });
            }
            let digits: String = chars[start..i].iter().collect();
            let v = digits.parse::<i64>().map_err(|_| {
                PredicateError::new(column, format!("`{digits}` is too large an integer"))
            })?;
            out.push(Tok {
                kind: TokKind::Int(v),
                column,
            });
            continue;
        }
        if is_name_char(c) {
            let start = i;
            while i < chars.len() && is_name_char(chars[i]) {
                i += 1;
            }
            out.push(Tok {
                kind: TokKind::Name(chars[start..i].iter().collect()),
                column,
            });
            continue;
        }
        return Err(PredicateError::new(
            column,
            format!("unexpected character `{c}` (quote unusual place names with backticks)"),
        ));
    }
    Ok(out)
}
