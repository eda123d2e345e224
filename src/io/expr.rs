//! Expressions of the GreatSPN editor's language, as `.PNPRO` files write them in markings,
//! rates, weights, priorities, server counts and arc multiplicities.
//!
//! The subset read here is the constant one: numbers, identifiers (constants and template
//! parameters, resolved by the caller), `+ - * /`, unary `-`, parentheses, comparisons and
//! `&& || !` (for `If`), and the editor's functions written with square brackets —
//! `Min[a, b]`, `Max`, `Mod`, `Pow`, `Binomial`, `Abs`, `Factorial`, `Ceil`, `Floor`,
//! `Round`, `Sqrt`, `Exp`, `Log`, `Sin`, `Cos`, `Tan`, `Asin`, `Acos`, `Atan` and
//! `If[cond, a, b]` (round brackets are accepted too). Marking-dependent terms (`#P`) are
//! refused: a rate that changes with the marking has no place in the net model.
//!
//! ```
//! use gspn::io::expr::Expr;
//! let e = Expr::parse("2 * Max[N, 3] - 1").unwrap();
//! let v = e.eval(&mut |name, _| if name == "N" { Ok::<f64, ()>(5.0) } else { Err(()) });
//! assert_eq!(v.unwrap(), 9.0);
//! ```

mod parse;

use std::fmt;

/// How deeply an expression may nest: parentheses, unary operators (`-`, `+`, `!`), function
/// calls and each operator of a chain (`1 + 1 + 1` is two deep) open one level. Deeper text
/// is refused by [`Expr::parse`] at the character that goes one level too deep, so neither
/// parsing, evaluating nor dropping an expression can exhaust the stack.
pub const MAX_DEPTH: usize = 256;

/// A parsed expression.
#[derive(Clone, Debug, PartialEq)]
pub enum Expr {
    /// A number literal (or `True` = 1, `False` = 0).
    Num(f64),
    /// A name to resolve: a constant or a template parameter.
    Ident {
        /// The name.
        name: String,
        /// Byte offset of the name in the expression text.
        at: usize,
    },
    /// Unary minus.
    Neg(Box<Expr>),
    /// Logical not (0 → 1, anything else → 0).
    Not(Box<Expr>),
    /// A binary operation.
    Bin(BinOp, Box<Expr>, Box<Expr>),
    /// A function call.
    Call {
        /// The function.
        func: Func,
        /// Its arguments (as many as [`Func::arity`] says).
        args: Vec<Expr>,
        /// Byte offset of the function name.
        at: usize,
    },
}

/// Binary operators, loosest first: `||`, `&&`, comparisons, `+ -`, `* /`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BinOp {
    /// `+`
    Add,
    /// `-`
    Sub,
    /// `*`
    Mul,
    /// `/` (real division)
    Div,
    /// `<`
    Lt,
    /// `<=`
    Le,
    /// `>`
    Gt,
    /// `>=`
    Ge,
    /// `==`
    Eq,
    /// `!=`
    Ne,
    /// `&&`
    And,
    /// `||`
    Or,
}

/// The functions of the editor's language that have a constant meaning.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Func {
    /// `Min[a, b]`
    Min,
    /// `Max[a, b]`
    Max,
    /// `Mod[a, b]` (the remainder, with the sign of `b`)
    Mod,
    /// `Pow[a, b]`
    Pow,
    /// `Binomial[n, k]`
    Binomial,
    /// `Abs[x]`
    Abs,
    /// `Factorial[n]`
    Factorial,
    /// `Ceil[x]`
    Ceil,
    /// `Floor[x]`
    Floor,
    /// `Round[x]`
    Round,
    /// `Sqrt[x]`
    Sqrt,
    /// `Exp[x]`
    Exp,
    /// `Log[x]` (natural logarithm)
    Log,
    /// `Sin[x]`
    Sin,
    /// `Cos[x]`
    Cos,
    /// `Tan[x]`
    Tan,
    /// `Asin[x]`
    Asin,
    /// `Acos[x]`
    Acos,
    /// `Atan[x]`
    Atan,
    /// `If[cond, then, else]`
    If,
}

impl Func {
    /// The function a name denotes (case-sensitive, as in the editor).
    pub fn from_name(name: &str) -> Option<Func> {
        use Func::*;
        Some(match name {
            "Min" => Min,
            "Max" => Max,
            "Mod" => Mod,
            "Pow" => Pow,
            "Binomial" => Binomial,
            "Abs" => Abs,
            "Factorial" => Factorial,
            "Ceil" => Ceil,
            "Floor" => Floor,
            "Round" => Round,
            "Sqrt" => Sqrt,
            "Exp" => Exp,
            "Log" => Log,
            "Sin" => Sin,
            "Cos" => Cos,
            "Tan" => Tan,
            "Asin" => Asin,
            "Acos" => Acos,
            "Atan" => Atan,
            "If" => If,
            _ => return None,
        })
    }

    /// How many arguments it takes.
    pub fn arity(self) -> usize {
        use Func::*;
        match self {
            Min | Max | Mod | Pow | Binomial => 2,
            If => 3,
            _ => 1,
        }
    }

    fn name(self) -> String {
        format!("{self:?}")
    }
}

/// A syntax or evaluation error, at a byte offset of the expression text.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ExprError {
    /// Byte offset in the expression text.
    pub at: usize,
    /// What is wrong.
    pub reason: String,
}

impl fmt::Display for ExprError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{} (at character {})", self.reason, self.at + 1)
    }
}

impl std::error::Error for ExprError {}

/// Why evaluation failed: in the expression itself, or in resolving a name.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum EvalError<E> {
    /// Division by zero, a function outside its domain...
    At(ExprError),
    /// The resolver refused a name (its own error).
    Lookup(E),
}

impl Expr {
    /// Parses `text`; an empty text is an error.
    pub fn parse(text: &str) -> Result<Expr, ExprError> {
        parse::parse(text)
    }

    /// The value, with names resolved by `lookup(name, offset)`.
    pub fn eval<E>(
        &self,
        lookup: &mut dyn FnMut(&str, usize) -> Result<f64, E>,
    ) -> Result<f64, EvalError<E>> {
        Ok(match self {
            Expr::Num(v) => *v,
            Expr::Ident { name, at } => lookup(name, *at).map_err(EvalError::Lookup)?,
            Expr::Neg(e) => -e.eval(lookup)?,
            Expr::Not(e) => truth(e.eval(lookup)? == 0.0),
            Expr::Bin(op, a, b) => {
                let x = a.eval(lookup)?;
                // Short-circuit like the editor, so `If`-guards can protect a division.
                match op {
                    BinOp::And if x == 0.0 => return Ok(0.0),
                    BinOp::Or if x != 0.0 => return Ok(1.0),
                    _ => {}
                }
                let y = b.eval(lookup)?;
                match op {
                    BinOp::Add => x + y,
                    BinOp::Sub => x - y,
                    BinOp::Mul => x * y,
                    BinOp::Div => {
                        if y == 0.0 {
                            return Err(EvalError::At(ExprError {
                                at: 0,
                                reason: "division by zero".into(),
                            }));
                        }
                        x / y
                    }
                    BinOp::Lt => truth(x < y),
                    BinOp::Le => truth(x <= y),
                    BinOp::Gt => truth(x > y),
                    BinOp::Ge => truth(x >= y),
                    BinOp::Eq => truth(x == y),
                    BinOp::Ne => truth(x != y),
                    BinOp::And | BinOp::Or => truth(y != 0.0),
                }
            }
            Expr::Call { func, args, at } => {
                if *func == Func::If {
                    let c = args[0].eval(lookup)?;
                    return if c != 0.0 {
                        args[1].eval(lookup)
                    } else {
                        args[2].eval(lookup)
                    };
                }
                let mut v = [0.0; 2];
                for (slot, a) in v.iter_mut().zip(args) {
                    *slot = a.eval(lookup)?;
                }
                call(*func, v[0], v[1]).map_err(|reason| {
                    EvalError::At(ExprError {
                        at: *at,
                        reason: format!("{}: {reason}", func.name()),
                    })
                })?
            }
        })
    }
}

fn truth(b: bool) -> f64 {
    if b { 1.0 } else { 0.0 }
}

/// Why a function of an expression has no value for its arguments (the evaluator adds the
/// function's name and where it stands).
#[derive(Debug, thiserror::Error)]
enum CallError {
    /// An argument that must be a whole number ≥ 0.
    #[error("{what} must be a whole number ≥ 0, got {x}")]
    NotWhole { what: &'static str, x: f64 },
    /// `Mod[x, 0]`.
    #[error("modulo by zero")]
    ModuloByZero,
    /// A binomial coefficient past the largest float.
    #[error("the result for n = {n}, k = {k} is too large")]
    BinomialTooLarge { n: f64, k: f64 },
    /// A factorial past the largest float.
    #[error("{0}! is too large")]
    FactorialTooLarge(f64),
}

fn whole(x: f64, what: &'static str) -> Result<f64, CallError> {
    if x.fract() == 0.0 && x.is_finite() && x >= 0.0 {
        Ok(x)
    } else {
        Err(CallError::NotWhole { what, x })
    }
}

fn call(f: Func, x: f64, y: f64) -> Result<f64, CallError> {
    use Func::*;
    Ok(match f {
        Min => x.min(y),
        Max => x.max(y),
        Mod => {
            if y == 0.0 {
                return Err(CallError::ModuloByZero);
            }
            x - y * (x / y).floor()
        }
        Pow => x.powf(y),
        Binomial => {
            let (n, k) = (whole(x, "n")?, whole(y, "k")?);
            if k > n {
                0.0
            } else {
                // C(n, i) > 2^i for 2i ≤ n: the product overflows within ~1030 steps, whatever
                // k is (a fuzzed `Binomial[6e12, 3e12]` used to loop 3·10¹² times).
                let k = k.min(n - k);
                let mut acc = 1.0f64;
                for i in 0..k as u64 {
                    acc = acc * (n - i as f64) / (i as f64 + 1.0);
                    if !acc.is_finite() {
                        return Err(CallError::BinomialTooLarge { n, k });
                    }
                }
                acc
            }
        }
        Abs => x.abs(),
        Factorial => {
            let n = whole(x, "the argument")?;
            if n > 170.0 {
                return Err(CallError::FactorialTooLarge(n));
            }
            (1..=n as u64).fold(1.0, |acc, i| acc * i as f64)
        }
        Ceil => x.ceil(),
        Floor => x.floor(),
        Round => x.round(),
        Sqrt => x.sqrt(),
        Exp => x.exp(),
        // Software libm: the same bits on every machine, like the sampler (`gspn::sample`).
        Log => libm::log(x),
        Sin => x.sin(),
        Cos => x.cos(),
        Tan => x.tan(),
        Asin => x.asin(),
        Acos => x.acos(),
        Atan => x.atan(),
        If => unreachable!("handled by the caller"),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ev(s: &str) -> Result<f64, String> {
        let e = Expr::parse(s).map_err(|e| e.reason)?;
        e.eval(&mut |n: &str, _| match n {
            "N" => Ok(5.0),
            "lambda" => Ok(0.5),
            _ => Err(format!("unknown `{n}`")),
        })
        .map_err(|e| match e {
            EvalError::At(e) => e.reason,
            EvalError::Lookup(s) => s,
        })
    }

    #[test]
    fn arithmetic_follows_precedence() {
        for (text, value) in [
            ("1 + 2 * 3", 7.0),
            ("(1 + 2) * 3", 9.0),
            ("-N + 1", -4.0),
            ("10 - 4 - 3", 3.0),
            ("N / 2", 2.5),
            ("1.000000e+00", 1.0),
            (".5e1", 5.0),
            ("2*lambda", 1.0),
        ] {
            assert_eq!(ev(text), Ok(value), "{text}");
        }
    }

    #[test]
    fn functions_take_square_or_round_brackets() {
        for (text, value) in [
            ("Min[N, 3]", 3.0),
            ("Max(N, 7)", 7.0),
            ("Pow[2, 10]", 1024.0),
            ("Mod[7, 3]", 1.0),
            ("Binomial[5, 2]", 10.0),
            ("Factorial[4]", 24.0),
            ("Floor[2.7] + Ceil[2.1] + Round[2.5]", 8.0),
            ("If[N > 3 && N != 4, 1, 2]", 1.0),
            ("If[!True || False, 1, 2]", 2.0),
        ] {
            assert_eq!(ev(text), Ok(value), "{text}");
        }
    }

    #[test]
    fn errors_say_where_and_why() {
        let e = Expr::parse("1 + ").unwrap_err();
        assert_eq!(e.at, 4);
        assert!(e.reason.contains("end of expression"), "{}", e.reason);
        let e = Expr::parse("2 * (N").unwrap_err();
        assert!(e.reason.contains("expected `)`"), "{}", e.reason);
        let e = Expr::parse("Foo[1]").unwrap_err();
        assert_eq!(e.reason, "unknown function `Foo`");
        let e = Expr::parse("#P1 * 2").unwrap_err();
        assert!(e.reason.contains("marking-dependent"));
        let e = Expr::parse("Min[1]").unwrap_err();
        assert!(e.reason.contains("takes 2"));
        let e = Expr::parse("<x>").unwrap_err();
        assert_eq!(e.at, 0);
        assert_eq!(ev("1/0"), Err("division by zero".into()));
        assert_eq!(ev("K + 1"), Err("unknown `K`".into()));
        assert!(Expr::parse("").is_err());
        assert!(Expr::parse("1 2").is_err());
    }

    #[test]
    fn huge_binomials_are_refused_at_once() {
        // Found by the `expr` fuzzer (fuzz/artifacts/expr/timeout-a5d4…): a binomial whose
        // k was ~3·10¹² ran for hours.
        assert_eq!(
            ev("Binomial[6000000000000, 3000000000000]"),
            Err(
                "Binomial: the result for n = 6000000000000, k = 3000000000000 is too large".into()
            )
        );
        assert!(ev("Binomial[1100, 550]").is_err());
        assert_eq!(ev("Binomial[40, 20]"), Ok(137846528820.0));
    }
}
