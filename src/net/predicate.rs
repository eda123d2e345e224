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

mod lex;
mod parse;

use std::fmt;

use super::{Net, PlaceId};

/// How deeply a predicate may nest: parentheses, `!` and unary `-` each open a level.
/// Deeper text is refused with [`PredicateError`] at the token that goes one level too deep,
/// so a generated predicate cannot exhaust the parser's stack.
pub const MAX_DEPTH: usize = 256;

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
        Ok(Predicate {
            text: text.to_string(),
            root: parse::parse(net, text, false)?,
        })
    }

    /// Parses `text` as a state formula of a PRISM or Storm property: as [`Predicate::parse`],
    /// and `=`, `&`, `|` also mean `==`, `&&`, `||` (`P1=0 & P2>0`).
    ///
    /// ```
    /// use gspn::net::{NetBuilder, predicate::Predicate};
    /// let mut b = NetBuilder::new("n");
    /// b.place("P1", 0);
    /// b.place("P2", 1);
    /// let net = b.build().unwrap();
    /// let p = Predicate::parse_prism(&net, "P1=0 & (P2>0 | P1>=3)").unwrap();
    /// assert!(p.eval(&[0, 1]));
    /// assert!(Predicate::parse(&net, "P1=0").is_err());
    /// ```
    pub fn parse_prism(net: &Net, text: &str) -> Result<Predicate, PredicateError> {
        Ok(Predicate {
            text: text.to_string(),
            root: parse::parse(net, text, true)?,
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
    /// The offending name (an unknown place, a malformed word), when there is one.
    pub name: Option<String>,
    /// What kind of mistake.
    pub kind: PredicateErrorKind,
    /// What was wrong.
    pub message: String,
}

/// The kinds of [`PredicateError`], for callers that report them in their own words.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[non_exhaustive]
pub enum PredicateErrorKind {
    /// A name that is no place of the net ([`PredicateError::name`] holds it).
    UnknownPlace,
    /// Anything else: a bad token, a missing operand, nesting too deep.
    Syntax,
}

impl PredicateError {
    fn new(column: usize, message: String) -> Self {
        PredicateError {
            column,
            name: None,
            kind: PredicateErrorKind::Syntax,
            message,
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
    fn comparisons_connectives_sums_and_scaled_terms() {
        assert!(holds("P1 > 0 && P2 == 0", &[1, 0, 0, 0]));
        assert!(!holds("P1 > 0 && P2 == 0", &[1, 1, 0, 0]));
        assert!(holds("P1 > 0 || P2 == 0", &[0, 0, 0, 0]));
        assert!(holds("!(P1 < 1)", &[1, 0, 0, 0]));
        assert!(holds("P1 <= 1 && P1 >= 1 && P1 != 2", &[1, 0, 0, 0]));
        assert!(holds("3 > P1", &[2, 0, 0, 0]));
        assert!(!holds("3 > P1", &[3, 0, 0, 0]));
        // Sums and scaled terms.
        assert!(holds("P1 + P2 >= 2", &[1, 1, 0, 0]));
        assert!(!holds("P1 + P2 >= 2", &[1, 0, 0, 0]));
        assert!(holds("2*P1 - P2 == 3", &[2, 1, 0, 0]));
        assert!(holds("(P1 + P2) * 2 > 3", &[1, 1, 0, 0]));
        assert!(holds("-P1 + 2 == 0", &[2, 0, 0, 0]));
    }

    #[test]
    fn and_binds_tighter_than_or() {
        // false || (true && false) = false; (false || true) && false would also be false,
        // so use a case that tells them apart: true || (false && false) = true.
        assert!(holds("P1 == 1 || P2 == 1 && P2 == 2", &[1, 0, 0, 0]));
        assert!(!holds("(P1 == 1 || P2 == 1) && P2 == 2", &[1, 0, 0, 0]));
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
