//! Marking predicates: `P1 > 0 && P3 == 0`, `` `p1:Check_Temperature_L1` + P2 >= 2 ``.
//!
//! A [`Predicate`] is parsed once against a [`Net`] (names become [`PlaceId`]s) and then
//! evaluated on plain token slices, so the hot paths never see a name.
//!
//! # Syntax
//!
//! ```text
//! or      := and ( "||" and )*
//! and     := not ( "&&" not )*
//! not     := "!" not | "(" or ")" | "true" | "false" | compare
//! compare := sum ( "<" | "<=" | "==" | "!=" | ">=" | ">" ) sum
//! sum     := product ( ( "+" | "-" ) product )*
//! product := atom ( "*" atom )*            (at most one factor may name a place)
//! atom    := INTEGER | PLACE | "(" sum ")" | "-" atom
//! ```
//!
//! A place is written bare when its name is made of letters, digits and `_ : . ? @ $ #`
//! and does not start with a digit (`p1:Check_Temperature_L1`, `p.LowBat`); any other name
//! is quoted with backticks (`` `ArrivedL1-L2` ``, `` `my place` ``). A place stands for its
//! token count. Every comparison is linear in the token counts, so a predicate can be
//! evaluated in one pass over the places it names.
//!
//! ```
//! use gspn::net::{NetBuilder, Servers, predicate::Predicate};
//! let mut b = NetBuilder::new("n");
//! b.place("p1:Check", 2);
//! b.place("P2", 0);
//! let net = b.build().unwrap();
//! let p = Predicate::parse(&net, "p1:Check + P2 >= 2 && !(P2 > 0)").unwrap();
//! assert!(p.eval(&[2, 0]));
//! assert!(!p.eval(&[1, 0]));
//! let err = Predicate::parse(&net, "P9 > 0").unwrap_err();
//! assert_eq!((err.column, err.name.as_deref()), (1, Some("P9")));
//! ```

use std::fmt;

use super::{Net, PlaceId};

/// A marking predicate compiled against a net.
#[derive(Clone, Debug, PartialEq)]
pub struct Predicate {
    text: String,
    root: Node,
}

/// A compiled node: boolean structure over linear comparisons.
#[derive(Clone, Debug, PartialEq)]
enum Node {
    Const(bool),
    Not(Box<Node>),
    And(Vec<Node>),
    Or(Vec<Node>),
    /// `Σ coef·m(p) + constant  op  0`.
    Cmp(Linear, CmpOp),
}

/// A linear form over token counts: `Σ coef·m(p) + constant`.
#[derive(Clone, Debug, PartialEq, Default)]
struct Linear {
    terms: Vec<(PlaceId, i64)>,
    constant: i64,
}

impl Linear {
    fn constant(c: i64) -> Self {
        Linear {
            terms: Vec::new(),
            constant: c,
        }
    }

    fn place(p: PlaceId) -> Self {
        Linear {
            terms: vec![(p, 1)],
            constant: 0,
        }
    }

    fn add(mut self, other: Linear, sign: i64) -> Linear {
        self.constant = self
            .constant
            .saturating_add(other.constant.saturating_mul(sign));
        for (p, c) in other.terms {
            match self.terms.iter_mut().find(|(q, _)| *q == p) {
                Some((_, k)) => *k = k.saturating_add(c.saturating_mul(sign)),
                None => self.terms.push((p, c.saturating_mul(sign))),
            }
        }
        self.terms.retain(|&(_, c)| c != 0);
        self
    }

    fn scale(mut self, k: i64) -> Linear {
        self.constant = self.constant.saturating_mul(k);
        for (_, c) in &mut self.terms {
            *c = c.saturating_mul(k);
        }
        self.terms.retain(|&(_, c)| c != 0);
        self
    }

    #[inline]
    fn eval(&self, m: &[u32]) -> i64 {
        let mut v = self.constant;
        for &(p, c) in &self.terms {
            v = v.saturating_add(c.saturating_mul(m[p.index()] as i64));
        }
        v
    }
}

/// A comparison operator.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum CmpOp {
    Lt,
    Le,
    Eq,
    Ne,
    Ge,
    Gt,
}

impl CmpOp {
    #[inline]
    fn holds(self, v: i64) -> bool {
        match self {
            CmpOp::Lt => v < 0,
            CmpOp::Le => v <= 0,
            CmpOp::Eq => v == 0,
            CmpOp::Ne => v != 0,
            CmpOp::Ge => v >= 0,
            CmpOp::Gt => v > 0,
        }
    }
}

impl Node {
    fn eval(&self, m: &[u32]) -> bool {
        match self {
            Node::Const(b) => *b,
            Node::Not(n) => !n.eval(m),
            Node::And(v) => v.iter().all(|n| n.eval(m)),
            Node::Or(v) => v.iter().any(|n| n.eval(m)),
            Node::Cmp(l, op) => op.holds(l.eval(m)),
        }
    }

    fn collect_places(&self, out: &mut Vec<PlaceId>) {
        match self {
            Node::Const(_) => {}
            Node::Not(n) => n.collect_places(out),
            Node::And(v) | Node::Or(v) => v.iter().for_each(|n| n.collect_places(out)),
            Node::Cmp(l, _) => out.extend(l.terms.iter().map(|&(p, _)| p)),
        }
    }
}

impl Predicate {
    /// Parses `text` against `net`'s place names.
    pub fn parse(net: &Net, text: &str) -> Result<Predicate, PredicateError> {
        let tokens = lex(text)?;
        let mut p = Parser {
            net,
            tokens,
            pos: 0,
            text_len: text.chars().count(),
        };
        let expr = p.or()?;
        if let Some(t) = p.peek() {
            return Err(PredicateError::new(
                t.column,
                format!("unexpected `{}` after the end of the condition", t.kind),
            ));
        }
        let root = match expr {
            Expr::Bool(n) => n,
            Expr::Num(_, col) => {
                return Err(PredicateError::new(
                    col,
                    "this is a number, not a condition: compare it (e.g. `P > 0`)".into(),
                ));
            }
        };
        Ok(Predicate {
            text: text.to_string(),
            root,
        })
    }

    /// The predicate that always holds.
    pub fn always() -> Predicate {
        Predicate {
            text: "true".into(),
            root: Node::Const(true),
        }
    }

    /// True when the predicate holds in marking `m` (token counts indexed by place id).
    #[inline]
    pub fn eval(&self, m: &[u32]) -> bool {
        self.root.eval(m)
    }

    /// The text it was parsed from.
    pub fn source(&self) -> &str {
        &self.text
    }

    /// The places it reads, each once, in id order.
    pub fn places(&self) -> Vec<PlaceId> {
        let mut v = Vec::new();
        self.root.collect_places(&mut v);
        v.sort();
        v.dedup();
        v
    }
}

impl fmt::Display for Predicate {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(&self.text)
    }
}

/// Why a predicate could not be parsed: where (1-based column, in characters) and what.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[error("column {column}: {message}")]
pub struct PredicateError {
    /// Column of the offending token, from 1, counted in characters.
    pub column: usize,
    /// The offending name (an unknown place), when there is one.
    pub name: Option<String>,
    /// What was wrong.
    pub message: String,
}

impl PredicateError {
    fn new(column: usize, message: String) -> Self {
        PredicateError {
            column,
            name: None,
            message,
        }
    }
}

#[derive(Clone, Debug, PartialEq)]
enum TokKind {
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
struct Tok {
    kind: TokKind,
    column: usize,
}

fn is_name_char(c: char) -> bool {
    c.is_alphanumeric() || matches!(c, '_' | ':' | '.' | '?' | '@' | '$' | '#')
}

fn lex(text: &str) -> Result<Vec<Tok>, PredicateError> {
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

/// A parsed sub-expression: a condition, or a linear number with the column it started at.
enum Expr {
    Bool(Node),
    Num(Linear, usize),
}

struct Parser<'a> {
    net: &'a Net,
    tokens: Vec<Tok>,
    pos: usize,
    text_len: usize,
}

impl Parser<'_> {
    fn peek(&self) -> Option<&Tok> {
        self.tokens.get(self.pos)
    }

    fn peek_op(&self) -> Option<&'static str> {
        match self.peek() {
            Some(Tok {
                kind: TokKind::Op(o),
                ..
            }) => Some(o),
            _ => None,
        }
    }

    fn end_column(&self) -> usize {
        self.text_len + 1
    }

    fn bool_of(&self, e: Expr, what: &str) -> Result<Node, PredicateError> {
        match e {
            Expr::Bool(n) => Ok(n),
            Expr::Num(_, col) => Err(PredicateError::new(
                col,
                format!("`{what}` needs conditions on both sides; this is a number"),
            )),
        }
    }

    fn num_of(&self, e: Expr, col: usize, what: &str) -> Result<Linear, PredicateError> {
        match e {
            Expr::Num(l, _) => Ok(l),
            Expr::Bool(_) => Err(PredicateError::new(
                col,
                format!("`{what}` needs numbers on both sides; this is a condition"),
            )),
        }
    }

    fn or(&mut self) -> Result<Expr, PredicateError> {
        let first = self.and()?;
        if self.peek_op() != Some("||") {
            return Ok(first);
        }
        let mut v = vec![self.bool_of(first, "||")?];
        while self.peek_op() == Some("||") {
            self.pos += 1;
            let e = self.and()?;
            v.push(self.bool_of(e, "||")?);
        }
        Ok(Expr::Bool(Node::Or(v)))
    }

    fn and(&mut self) -> Result<Expr, PredicateError> {
        let first = self.not()?;
        if self.peek_op() != Some("&&") {
            return Ok(first);
        }
        let mut v = vec![self.bool_of(first, "&&")?];
        while self.peek_op() == Some("&&") {
            self.pos += 1;
            let e = self.not()?;
            v.push(self.bool_of(e, "&&")?);
        }
        Ok(Expr::Bool(Node::And(v)))
    }

    fn not(&mut self) -> Result<Expr, PredicateError> {
        if self.peek_op() == Some("!") {
            self.pos += 1;
            let e = self.not()?;
            let n = self.bool_of(e, "!")?;
            return Ok(Expr::Bool(Node::Not(Box::new(n))));
        }
        self.compare()
    }

    fn compare(&mut self) -> Result<Expr, PredicateError> {
        let left_col = self.peek().map_or(self.end_column(), |t| t.column);
        let left = self.sum()?;
        let op = match self.peek_op() {
            Some("<") => CmpOp::Lt,
            Some("<=") => CmpOp::Le,
            Some("==") => CmpOp::Eq,
            Some("!=") => CmpOp::Ne,
            Some(">=") => CmpOp::Ge,
            Some(">") => CmpOp::Gt,
            _ => return Ok(left),
        };
        let op_text = self.peek_op().unwrap_or("?");
        self.pos += 1;
        let right_col = self.peek().map_or(self.end_column(), |t| t.column);
        let l = self.num_of(left, left_col, op_text)?;
        let right = self.sum()?;
        let r = self.num_of(right, right_col, op_text)?;
        Ok(Expr::Bool(Node::Cmp(l.add(r, -1), op)))
    }

    fn sum(&mut self) -> Result<Expr, PredicateError> {
        let col = self.peek().map_or(self.end_column(), |t| t.column);
        let first = self.product()?;
        if !matches!(self.peek_op(), Some("+") | Some("-")) {
            return Ok(first);
        }
        let mut acc = self.num_of(first, col, "+")?;
        while let Some(op @ ("+" | "-")) = self.peek_op() {
            self.pos += 1;
            let c = self.peek().map_or(self.end_column(), |t| t.column);
            let e = self.product()?;
            let l = self.num_of(e, c, op)?;
            acc = acc.add(l, if op == "+" { 1 } else { -1 });
        }
        Ok(Expr::Num(acc, col))
    }

    fn product(&mut self) -> Result<Expr, PredicateError> {
        let col = self.peek().map_or(self.end_column(), |t| t.column);
        let first = self.atom()?;
        if self.peek_op() != Some("*") {
            return Ok(first);
        }
        let mut acc = self.num_of(first, col, "*")?;
        while self.peek_op() == Some("*") {
            self.pos += 1;
            let c = self.peek().map_or(self.end_column(), |t| t.column);
            let e = self.atom()?;
            let l = self.num_of(e, c, "*")?;
            acc = if l.terms.is_empty() {
                acc.scale(l.constant)
            } else if acc.terms.is_empty() {
                l.scale(acc.constant)
            } else {
                return Err(PredicateError::new(
                    c,
                    "two place counts multiplied: only a constant may multiply a place".into(),
                ));
            };
        }
        Ok(Expr::Num(acc, col))
    }

    fn atom(&mut self) -> Result<Expr, PredicateError> {
        let Some(tok) = self.tokens.get(self.pos).cloned() else {
            return Err(PredicateError::new(
                self.end_column(),
                "the condition ends too early".into(),
            ));
        };
        self.pos += 1;
        match tok.kind {
            TokKind::Int(v) => Ok(Expr::Num(Linear::constant(v), tok.column)),
            TokKind::Name(name) if name == "true" || name == "false" => {
                Ok(Expr::Bool(Node::Const(name == "true")))
            }
            TokKind::Name(name) => match self.net.place_by_name(&name) {
                Some(p) => Ok(Expr::Num(Linear::place(p), tok.column)),
                None => Err(PredicateError {
                    column: tok.column,
                    message: format!("place `{name}` does not exist"),
                    name: Some(name),
                }),
            },
            TokKind::Op("-") => {
                let c = self.peek().map_or(self.end_column(), |t| t.column);
                let e = self.atom()?;
                let l = self.num_of(e, c, "-")?;
                Ok(Expr::Num(l.scale(-1), tok.column))
            }
            TokKind::LParen => {
                let inner = self.or()?;
                match self.peek() {
                    Some(Tok {
                        kind: TokKind::RParen,
                        ..
                    }) => {
                        self.pos += 1;
                        Ok(match inner {
                            Expr::Num(l, _) => Expr::Num(l, tok.column),
                            b => b,
                        })
                    }
                    Some(t) => Err(PredicateError::new(
                        t.column,
                        format!("expected `)` to close the `(` at column {}", tok.column),
                    )),
                    None => Err(PredicateError::new(
                        self.end_column(),
                        format!("the `(` at column {} is never closed", tok.column),
                    )),
                }
            }
            other => Err(PredicateError::new(
                tok.column,
                format!("unexpected `{other}`: expected a place, a number or `(`"),
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::NetBuilder;

    fn net() -> Net {
        let mut b = NetBuilder::new("n");
        b.place("P1", 0);
        b.place("P2", 0);
        b.place("p1:Check_Temperature_L1", 0);
        b.place("ArrivedL1-L2", 0);
        b.build().unwrap()
    }

    fn holds(text: &str, m: &[u32]) -> bool {
        Predicate::parse(&net(), text).unwrap().eval(m)
    }

    #[test]
    fn comparisons_and_connectives() {
        assert!(holds("P1 > 0 && P2 == 0", &[1, 0, 0, 0]));
        assert!(!holds("P1 > 0 && P2 == 0", &[1, 1, 0, 0]));
        assert!(holds("P1 > 0 || P2 == 0", &[0, 0, 0, 0]));
        assert!(holds("!(P1 < 1)", &[1, 0, 0, 0]));
        assert!(holds("P1 <= 1 && P1 >= 1 && P1 != 2", &[1, 0, 0, 0]));
        assert!(holds("3 > P1", &[2, 0, 0, 0]));
        assert!(!holds("3 > P1", &[3, 0, 0, 0]));
    }

    #[test]
    fn and_binds_tighter_than_or() {
        // false || (true && false) = false; (false || true) && false would also be false,
        // so use a case that tells them apart: true || (false && false) = true.
        assert!(holds("P1 == 1 || P2 == 1 && P2 == 2", &[1, 0, 0, 0]));
        assert!(!holds("(P1 == 1 || P2 == 1) && P2 == 2", &[1, 0, 0, 0]));
    }

    #[test]
    fn sums_and_scaled_terms() {
        assert!(holds("P1 + P2 >= 2", &[1, 1, 0, 0]));
        assert!(!holds("P1 + P2 >= 2", &[1, 0, 0, 0]));
        assert!(holds("2*P1 - P2 == 3", &[2, 1, 0, 0]));
        assert!(holds("(P1 + P2) * 2 > 3", &[1, 1, 0, 0]));
        assert!(holds("-P1 + 2 == 0", &[2, 0, 0, 0]));
    }

    #[test]
    fn names_with_colons_bare_and_others_quoted() {
        assert!(holds("p1:Check_Temperature_L1 >= 1", &[0, 0, 1, 0]));
        assert!(holds("`ArrivedL1-L2` == 1", &[0, 0, 0, 1]));
        let p = Predicate::parse(&net(), "`ArrivedL1-L2` + P2 > 0").unwrap();
        assert_eq!(p.places(), vec![PlaceId(1), PlaceId(3)]);
    }

    #[test]
    fn unknown_place_names_its_column() {
        let e = Predicate::parse(&net(), "P1 > 0 && Pzz == 1").unwrap_err();
        assert_eq!(e.column, 11);
        assert_eq!(e.name.as_deref(), Some("Pzz"));
        // An unquoted name with `-` is a subtraction of two names: the second is unknown.
        let e = Predicate::parse(&net(), "ArrivedL1-L2 == 1").unwrap_err();
        assert_eq!((e.column, e.name.as_deref()), (1, Some("ArrivedL1")));
    }

    #[test]
    fn syntax_errors_name_the_column() {
        let cases = [
            ("P1 = 1", 4),
            ("P1 > ", 6),
            ("(P1 > 0", 8),
            ("P1", 1),
            ("P1 > 0 && 3", 11),
            ("P1 > 0 P2", 8),
            ("P1 * P2 > 0", 6),
            ("P1 > `P2", 6),
            ("1P > 0", 1),
            ("P1 ~ 2", 4),
        ];
        for (text, col) in cases {
            let e = Predicate::parse(&net(), text).unwrap_err();
            assert_eq!(e.column, col, "{text}: {e}");
        }
    }

    #[test]
    fn literals() {
        assert!(holds("true", &[0, 0, 0, 0]));
        assert!(!holds("false || !true", &[0, 0, 0, 0]));
        assert!(Predicate::always().eval(&[]));
    }
}
