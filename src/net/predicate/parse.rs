//! The recursive-descent parser of [`Predicate`](super::Predicate), with its depth limit.

use super::lex::{Tok, TokKind, lex};
use super::{CmpOp, Linear, MAX_DEPTH, Node, PredicateError, PredicateErrorKind};
use crate::net::Net;

/// Parses `text` against `net`'s place names into the root of a predicate (`prism`: see
/// [`lex`]).
pub(super) fn parse(net: &Net, text: &str, prism: bool) -> Result<Node, PredicateError> {
    let tokens = lex(text, prism)?;
    let mut p = Parser {
        net,
        tokens,
        pos: 0,
        text_len: text.chars().count(),
        depth: 0,
    };
    let expr = p.or()?;
    if let Some(t) = p.peek() {
        return Err(PredicateError::new(
            t.column,
            format!("unexpected `{}` after the end of the condition", t.kind),
        ));
    }
    match expr {
        Expr::Bool(n) => Ok(n),
        Expr::Num(_, col) => Err(PredicateError::new(
            col,
            "this is a number, not a condition: compare it (e.g. `P > 0`)".into(),
        )),
    }
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
    /// Levels open now: parentheses, `!` and unary `-`.
    depth: usize,
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

    /// Opens one level of nesting at `column`, refusing to go past [`MAX_DEPTH`]; the caller
    /// closes it with [`Parser::leave`] once the nested part is parsed.
    fn enter(&mut self, column: usize) -> Result<(), PredicateError> {
        self.depth += 1;
        if self.depth > MAX_DEPTH {
            return Err(PredicateError::new(
                column,
                format!(
                    "the condition nests deeper than {MAX_DEPTH} levels \
                     (parentheses, `!` and unary `-` each open one)"
                ),
            ));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.depth -= 1;
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
        self.chain("||", Self::and, Node::Or)
    }

    fn and(&mut self) -> Result<Expr, PredicateError> {
        self.chain("&&", Self::not, Node::And)
    }

    /// `operand (op operand)*`: one operand as it is, more joined into one `node`.
    fn chain(
        &mut self,
        op: &str,
        operand: fn(&mut Self) -> Result<Expr, PredicateError>,
        node: fn(Vec<Node>) -> Node,
    ) -> Result<Expr, PredicateError> {
        let first = operand(self)?;
        if self.peek_op() != Some(op) {
            return Ok(first);
        }
        let mut v = vec![self.bool_of(first, op)?];
        while self.peek_op() == Some(op) {
            self.pos += 1;
            let e = operand(self)?;
            v.push(self.bool_of(e, op)?);
        }
        Ok(Expr::Bool(node(v)))
    }

    fn not(&mut self) -> Result<Expr, PredicateError> {
        if self.peek_op() == Some("!") {
            let column = self.peek().map_or(self.end_column(), |t| t.column);
            self.enter(column)?;
            self.pos += 1;
            let e = self.not()?;
            self.leave();
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
                    kind: PredicateErrorKind::UnknownPlace,
                    name: Some(name),
                }),
            },
            TokKind::Op("-") => {
                self.enter(tok.column)?;
                let c = self.peek().map_or(self.end_column(), |t| t.column);
                let e = self.atom()?;
                self.leave();
                let l = self.num_of(e, c, "-")?;
                Ok(Expr::Num(l.scale(-1), tok.column))
            }
            TokKind::LParen => {
                self.enter(tok.column)?;
                let inner = self.or()?;
                self.leave();
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
