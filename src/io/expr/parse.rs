//! The lexer and recursive-descent parser of [`Expr`](super::Expr), with its depth limit.
//!
//! Two depths are bounded by [`MAX_DEPTH`]: the parser's own nesting (parentheses, unary
//! operators, function calls), which is its recursion, and the depth of the tree it builds
//! (a chain `1 + 1 + … + 1` is as deep as it has operators), which is the recursion of
//! [`Expr::eval`](super::Expr::eval) and of dropping the tree.

use super::{BinOp, Expr, ExprError, Func, MAX_DEPTH};

#[derive(Clone, Debug, PartialEq)]
enum Tok {
    Num(f64),
    Ident(String),
    /// Operators and punctuation.
    Sym(&'static str),
    End,
}

const SYMBOLS: [&str; 18] = [
    "<=", ">=", "==", "!=", "&&", "||", "+", "-", "*", "/", "(", ")", "[", "]", ",", "<", ">", "!",
];

fn lex(text: &str) -> Result<Vec<(Tok, usize)>, ExprError> {
    let b = text.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < b.len() {
        let c = b[i];
        if c.is_ascii_whitespace() {
            i += 1;
        } else if c.is_ascii_digit() || (c == b'.' && b.get(i + 1).is_some_and(u8::is_ascii_digit))
        {
            let start = i;
            while i < b.len() && b[i].is_ascii_digit() {
                i += 1;
            }
            if i < b.len() && b[i] == b'.' {
                i += 1;
                while i < b.len() && b[i].is_ascii_digit() {
                    i += 1;
                }
            }
            if i < b.len() && (b[i] == b'e' || b[i] == b'E') {
                let mut j = i + 1;
                if j < b.len() && (b[j] == b'+' || b[j] == b'-') {
                    j += 1;
                }
                if j < b.len() && b[j].is_ascii_digit() {
                    while j < b.len() && b[j].is_ascii_digit() {
                        j += 1;
                    }
                    i = j;
                }
            }
            let s = &text[start..i];
            let v: f64 = s.parse().map_err(|_| ExprError {
                at: start,
                reason: format!("`{s}` is not a number"),
            })?;
            out.push((Tok::Num(v), start));
        } else if c.is_ascii_alphabetic() || c == b'_' {
            let start = i;
            while i < b.len() && (b[i].is_ascii_alphanumeric() || b[i] == b'_') {
                i += 1;
            }
            out.push((Tok::Ident(text[start..i].to_string()), start));
        } else if c == b'#' {
            return Err(ExprError {
                at: i,
                reason: "marking-dependent expressions (`#place`) are not supported".into(),
            });
        } else if let Some(s) = SYMBOLS.iter().find(|s| text[i..].starts_with(**s)) {
            out.push((Tok::Sym(s), i));
            i += s.len();
        } else {
            let ch = text[i..].chars().next().unwrap_or('?');
            return Err(ExprError {
                at: i,
                reason: format!("unexpected character `{ch}`"),
            });
        }
    }
    out.push((Tok::End, text.len()));
    Ok(out)
}

struct Parser {
    toks: Vec<(Tok, usize)>,
    pos: usize,
    /// Levels open now: parentheses, unary operators, function calls.
    nesting: usize,
}

/// A parsed sub-expression and the depth of its tree: how many operators, function calls
/// and unary signs are nested in it (a leaf is 0, `-x` is 1, `1 + 1 + 1` is 2).
struct Sub {
    expr: Expr,
    depth: usize,
}

fn too_deep(at: usize) -> ExprError {
    ExprError {
        at,
        reason: format!(
            "the expression nests deeper than {MAX_DEPTH} levels (parentheses, unary \
             operators, function calls and chained operators each add one)"
        ),
    }
}

impl Sub {
    fn leaf(expr: Expr) -> Sub {
        Sub { expr, depth: 0 }
    }

    /// A node over `children`, refused at `at` when it would be deeper than [`MAX_DEPTH`].
    fn node(expr: Expr, children_depth: usize, at: usize) -> Result<Sub, ExprError> {
        let depth = children_depth + 1;
        if depth > MAX_DEPTH {
            return Err(too_deep(at));
        }
        Ok(Sub { expr, depth })
    }
}

impl Parser {
    fn peek(&self) -> &Tok {
        &self.toks[self.pos].0
    }

    fn at(&self) -> usize {
        self.toks[self.pos].1
    }

    fn bump(&mut self) -> (Tok, usize) {
        let t = self.toks[self.pos].clone();
        if self.pos + 1 < self.toks.len() {
            self.pos += 1;
        }
        t
    }

    fn eat(&mut self, sym: &str) -> bool {
        if *self.peek() == Tok::Sym(static_sym(sym)) {
            self.bump();
            true
        } else {
            false
        }
    }

    fn unexpected(&self) -> ExprError {
        let reason = match self.peek() {
            Tok::End => "unexpected end of expression".to_string(),
            Tok::Num(v) => format!("unexpected number `{v}`"),
            Tok::Ident(s) => format!("unexpected name `{s}`"),
            Tok::Sym(s) => format!("unexpected `{s}`"),
        };
        ExprError {
            at: self.at(),
            reason,
        }
    }

    fn expect(&mut self, sym: &str) -> Result<(), ExprError> {
        if self.eat(sym) {
            Ok(())
        } else {
            let mut e = self.unexpected();
            e.reason = format!("expected `{sym}`: {}", e.reason);
            Err(e)
        }
    }

    /// Opens one level of nesting at `at`, refusing to go past [`MAX_DEPTH`]; the caller
    /// closes it with [`Parser::leave`].
    fn enter(&mut self, at: usize) -> Result<(), ExprError> {
        self.nesting += 1;
        if self.nesting > MAX_DEPTH {
            return Err(too_deep(at));
        }
        Ok(())
    }

    fn leave(&mut self) {
        self.nesting -= 1;
    }

    fn binary(
        &mut self,
        ops: &[(&str, BinOp)],
        next: fn(&mut Parser) -> Result<Sub, ExprError>,
        chain: bool,
    ) -> Result<Sub, ExprError> {
        let mut lhs = next(self)?;
        loop {
            let Some(&(_, op)) = ops
                .iter()
                .find(|(s, _)| *self.peek() == Tok::Sym(static_sym(s)))
            else {
                return Ok(lhs);
            };
            let (_, at) = self.bump();
            let rhs = next(self)?;
            lhs = Sub::node(
                Expr::Bin(op, Box::new(lhs.expr), Box::new(rhs.expr)),
                lhs.depth.max(rhs.depth),
                at,
            )?;
            if !chain {
                return Ok(lhs);
            }
        }
    }

    fn or(&mut self) -> Result<Sub, ExprError> {
        self.binary(&[("||", BinOp::Or)], Parser::and, true)
    }

    fn and(&mut self) -> Result<Sub, ExprError> {
        self.binary(&[("&&", BinOp::And)], Parser::cmp, true)
    }

    fn cmp(&mut self) -> Result<Sub, ExprError> {
        use BinOp::*;
        let ops = [
            ("<=", Le),
            (">=", Ge),
            ("==", Eq),
            ("!=", Ne),
            ("<", Lt),
            (">", Gt),
        ];
        self.binary(&ops, Parser::add, false)
    }

    fn add(&mut self) -> Result<Sub, ExprError> {
        self.binary(&[("+", BinOp::Add), ("-", BinOp::Sub)], Parser::mul, true)
    }

    fn mul(&mut self) -> Result<Sub, ExprError> {
        self.binary(&[("*", BinOp::Mul), ("/", BinOp::Div)], Parser::unary, true)
    }

    fn unary(&mut self) -> Result<Sub, ExprError> {
        let at = self.at();
        let wrap: fn(Box<Expr>) -> Expr = match self.peek() {
            Tok::Sym("-") => Expr::Neg,
            Tok::Sym("!") => Expr::Not,
            Tok::Sym("+") => {
                self.enter(at)?;
                self.bump();
                let e = self.unary()?;
                self.leave();
                return Ok(e);
            }
            _ => return self.primary(),
        };
        self.enter(at)?;
        self.bump();
        let e = self.unary()?;
        self.leave();
        Sub::node(wrap(Box::new(e.expr)), e.depth, at)
    }

    fn primary(&mut self) -> Result<Sub, ExprError> {
        match self.peek().clone() {
            Tok::Num(v) => {
                self.bump();
                Ok(Sub::leaf(Expr::Num(v)))
            }
            Tok::Sym("(") => {
                let (_, at) = self.bump();
                self.enter(at)?;
                let e = self.or()?;
                self.leave();
                self.expect(")")?;
                Ok(e)
            }
            Tok::Ident(name) => {
                let (_, at) = self.bump();
                let open = match self.peek() {
                    Tok::Sym("[") => Some("]"),
                    Tok::Sym("(") => Some(")"),
                    _ => None,
                };
                match (name.as_str(), open) {
                    ("True", None) => Ok(Sub::leaf(Expr::Num(1.0))),
                    ("False", None) => Ok(Sub::leaf(Expr::Num(0.0))),
                    ("Infinite", None) => Err(ExprError {
                        at,
                        reason: "`Infinite` is only allowed as a whole server count".into(),
                    }),
                    (_, None) => Ok(Sub::leaf(Expr::Ident { name, at })),
                    (_, Some(close)) => {
                        let func = Func::from_name(&name).ok_or_else(|| ExprError {
                            at,
                            reason: format!("unknown function `{name}`"),
                        })?;
                        self.bump();
                        self.enter(at)?;
                        let first = self.or()?;
                        let mut depth = first.depth;
                        let mut args = vec![first.expr];
                        while self.eat(",") {
                            let a = self.or()?;
                            depth = depth.max(a.depth);
                            args.push(a.expr);
                        }
                        self.leave();
                        self.expect(close)?;
                        if args.len() != func.arity() {
                            return Err(ExprError {
                                at,
                                reason: format!(
                                    "`{name}` takes {} argument(s), got {}",
                                    func.arity(),
                                    args.len()
                                ),
                            });
                        }
                        Sub::node(Expr::Call { func, args, at }, depth, at)
                    }
                }
            }
            _ => Err(self.unexpected()),
        }
    }
}

/// Maps a symbol to the interned `&'static str` the lexer produces.
fn static_sym(s: &str) -> &'static str {
    SYMBOLS.iter().find(|x| **x == s).copied().unwrap_or("")
}

pub(super) fn parse(text: &str) -> Result<Expr, ExprError> {
    let toks = lex(text)?;
    let mut p = Parser {
        toks,
        pos: 0,
        nesting: 0,
    };
    let e = p.or()?;
    if *p.peek() != Tok::End {
        return Err(p.unexpected());
    }
    Ok(e.expr)
}
