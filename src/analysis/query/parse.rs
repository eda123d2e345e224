//! The reader of a [`Query`]: the operator and its brackets here, the state formulas by
//! [`Predicate::parse_prism`] (their error columns shifted to the query's).

use super::{Kind, Query, QueryError};
use crate::analysis::decision::RewardSpec;
use crate::net::Net;
use crate::net::predicate::Predicate;

/// The query's characters and a cursor.
struct Reader<'a> {
    chars: Vec<char>,
    pos: usize,
    net: &'a Net,
}

fn err(column: usize, message: impl Into<String>) -> QueryError {
    QueryError::Syntax {
        column,
        name: None,
        message: message.into(),
    }
}

/// A character that may continue a bare name (as in a predicate).
fn is_name_char(c: char) -> bool {
    c.is_alphanumeric() || matches!(c, '_' | ':' | '.' | '?' | '@' | '$' | '#')
}

impl Reader<'_> {
    fn column(&self) -> usize {
        self.pos + 1
    }

    fn skip_space(&mut self) {
        while self.chars.get(self.pos).is_some_and(|c| c.is_whitespace()) {
            self.pos += 1;
        }
    }

    fn peek(&self) -> Option<char> {
        self.chars.get(self.pos).copied()
    }

    fn eat(&mut self, s: &str) -> bool {
        let n = s.chars().count();
        if self.chars.len() >= self.pos + n
            && s.chars()
                .eq(self.chars[self.pos..self.pos + n].iter().copied())
        {
            self.pos += n;
            true
        } else {
            false
        }
    }

    fn expect(&mut self, s: &str, what: &str) -> Result<(), QueryError> {
        self.skip_space();
        if self.eat(s) {
            Ok(())
        } else {
            Err(err(self.column(), format!("expected {what}")))
        }
    }

    /// A word of letters (`P`, `Pmax`, `F`, `C`).
    fn word(&mut self) -> String {
        let start = self.pos;
        while self.peek().is_some_and(|c| c.is_ascii_alphabetic()) {
            self.pos += 1;
        }
        self.chars[start..self.pos].iter().collect()
    }

    /// `<= t` (after F, G, U, C): a time ≥ 0.
    fn bound(&mut self) -> Result<Option<f64>, QueryError> {
        self.skip_space();
        if !self.eat("<=") {
            if self.peek() == Some('<') || self.peek() == Some('[') {
                return Err(err(
                    self.column(),
                    "only `<=t` time bounds are read (e.g. `F<=600 done=1`)",
                ));
            }
            return Ok(None);
        }
        self.skip_space();
        let start = self.pos;
        while self
            .peek()
            .is_some_and(|c| c.is_ascii_digit() || matches!(c, '.' | 'e' | 'E' | '+' | '-'))
        {
            self.pos += 1;
        }
        let text: String = self.chars[start..self.pos].iter().collect();
        match text.parse::<f64>() {
            Ok(t) if t.is_finite() && t >= 0.0 => Ok(Some(t)),
            _ => Err(err(start + 1, "expected a time ≥ 0 after `<=`")),
        }
    }

    /// The state formula in `chars[from..to]`, its errors at the query's columns.
    fn formula(&self, from: usize, to: usize) -> Result<Predicate, QueryError> {
        let text: String = self.chars[from..to].iter().collect();
        if text.trim().is_empty() {
            return Err(err(from + 1, "expected a condition on the marking"));
        }
        Predicate::parse_prism(self.net, &text).map_err(|e| QueryError::Syntax {
            column: from + e.column,
            name: e.name.clone(),
            message: e.message.clone(),
        })
    }

    /// The index of the `]` that closes the body (outside backticks), which must end the
    /// query.
    fn closing(&self, open_col: usize) -> Result<usize, QueryError> {
        let mut in_tick = false;
        let mut close = None;
        for (i, &c) in self.chars.iter().enumerate().skip(self.pos) {
            match c {
                '`' => in_tick = !in_tick,
                ']' if !in_tick => {
                    close = Some(i);
                    break;
                }
                _ => {}
            }
        }
        let close = close.ok_or_else(|| err(open_col, "`[` is never closed by `]`"))?;
        if let Some(extra) = (close + 1..self.chars.len()).find(|&i| !self.chars[i].is_whitespace())
        {
            return Err(err(extra + 1, "unexpected text after the closing `]`"));
        }
        Ok(close)
    }

    /// The top-level `U` of `chars[from..to]` (outside backticks and parentheses, a word on
    /// its own), if any.
    fn until(&self, from: usize, to: usize) -> Option<usize> {
        let mut in_tick = false;
        let mut depth = 0i32;
        for i in from..to {
            match self.chars[i] {
                '`' => in_tick = !in_tick,
                '(' if !in_tick => depth += 1,
                ')' if !in_tick => depth -= 1,
                'U' if !in_tick && depth == 0 => {
                    let before = i == from || !is_name_char(self.chars[i - 1]);
                    let after = i + 1 >= to || !is_name_char(self.chars[i + 1]);
                    if before && after {
                        return Some(i);
                    }
                }
                _ => {}
            }
        }
        None
    }

    /// `F`, `G` or `C` as a word of its own at the cursor (a place named `Fuel` is not `F`).
    fn path_op(&mut self, op: char) -> bool {
        if self.peek() == Some(op)
            && !self
                .chars
                .get(self.pos + 1)
                .is_some_and(|&c| is_name_char(c))
        {
            self.pos += 1;
            true
        } else {
            false
        }
    }
}

/// Parses `text`: the operator (with a reward structure's name for `R`,
/// [`Reader::reward_name`]), `=?`, then the bracketed body the operator takes
/// ([`Reader::probability`], [`Reader::time`], [`Reader::reward`]).
pub(super) fn parse(net: &Net, rewards: &[RewardSpec], text: &str) -> Result<Query, QueryError> {
    let mut r = Reader {
        chars: text.chars().collect(),
        pos: 0,
        net,
    };
    r.skip_space();
    let op_col = r.column();
    let op = r.word();
    let (letter, rest) = op.split_at(op.len().min(1));
    let mut reward = None;
    let mut suffix = rest.to_string();
    if letter == "R" {
        if !rest.is_empty() {
            return Err(err(
                op_col,
                format!("unknown operator `{op}`: write `R{{\"name\"}}=?`"),
            ));
        }
        reward = Some(r.reward_name(rewards)?);
        suffix = r.word();
    }
    let extreme = match suffix.as_str() {
        "" => None,
        "max" => Some(true),
        "min" => Some(false),
        _ => None,
    };
    if !matches!(letter, "P" | "T" | "S" | "R")
        || (!suffix.is_empty() && extreme.is_none())
        || (letter == "S" && extreme.is_some())
    {
        return Err(err(
            op_col,
            format!(
                "unknown operator `{op}{}`: P, Pmax, Pmin, T, Tmax, Tmin, S, R{{\"name\"}}",
                if letter == "R" { suffix.as_str() } else { "" }
            ),
        ));
    }
    r.expect(
        "=?",
        "`=?` (this engine computes values, not bounds like `>=0.9`)",
    )?;
    r.expect("[", "`[`")?;
    let open_col = r.pos;
    let close = r.closing(open_col)?;
    r.skip_space();
    let kind = match (letter, reward) {
        ("P", _) => r.probability(close)?,
        ("T", _) => r.time(close)?,
        ("S", _) => Kind::Steady {
            phi: r.formula(r.pos, close)?,
        },
        (_, Some(reward)) => r.reward(reward, close)?,
        _ => unreachable!("R parsed its name"),
    };
    Ok(Query {
        text: text.to_string(),
        kind,
        extreme,
    })
}

impl Reader<'_> {
    /// `{"name"}` after `R`: the index of the reward structure it names.
    fn reward_name(&mut self, rewards: &[RewardSpec]) -> Result<usize, QueryError> {
        self.expect("{", "`{\"name\"}` after R")?;
        self.skip_space();
        let name_col = self.column();
        if !self.eat("\"") {
            return Err(err(
                name_col,
                "expected the reward structure's name in quotes",
            ));
        }
        let start = self.pos;
        while self.peek().is_some_and(|c| c != '"') {
            self.pos += 1;
        }
        if self.peek().is_none() {
            return Err(err(name_col, "unclosed `\"`"));
        }
        let name: String = self.chars[start..self.pos].iter().collect();
        self.pos += 1;
        self.expect("}", "`}`")?;
        rewards.iter().position(|s| s.name == name).ok_or_else(|| {
            let known: Vec<&str> = rewards.iter().map(|s| s.name.as_str()).collect();
            QueryError::Syntax {
                column: name_col,
                name: Some(name.clone()),
                message: if known.is_empty() {
                    format!("no reward structure `{name}`: the plan has no `[rewards.NAME]`")
                } else {
                    format!(
                        "no reward structure `{name}` (the plan has {})",
                        known.join(", ")
                    )
                },
            }
        })
    }

    /// The body of `P=? [...]`: `F φ`, `F<=t φ`, `G<=t φ` or `φ1 U φ2`, up to `close`.
    fn probability(&mut self, close: usize) -> Result<Kind, QueryError> {
        let body_col = self.column();
        if self.path_op('F') {
            let bound = self.bound()?;
            Ok(Kind::Until {
                safe: None,
                goal: self.formula(self.pos, close)?,
                bound,
            })
        } else if self.path_op('G') {
            let bound = self.bound()?;
            Ok(Kind::Globally {
                phi: self.formula(self.pos, close)?,
                bound,
            })
        } else if let Some(u) = self.until(self.pos, close) {
            let safe = self.formula(self.pos, u)?;
            self.pos = u + 1;
            let bound = self.bound()?;
            Ok(Kind::Until {
                safe: Some(safe),
                goal: self.formula(self.pos, close)?,
                bound,
            })
        } else {
            Err(err(
                body_col,
                "expected a path formula: `F φ`, `F<=t φ`, `G<=t φ` or `φ1 U φ2`",
            ))
        }
    }

    /// The body of `T=? [F φ]`.
    fn time(&mut self, close: usize) -> Result<Kind, QueryError> {
        let body_col = self.column();
        if !self.path_op('F') {
            return Err(err(body_col, "expected `F φ`: T=? asks the time until φ"));
        }
        if self.bound()?.is_some() {
            return Err(err(body_col + 1, "T=? [F φ] takes no time bound"));
        }
        Ok(Kind::Time {
            goal: self.formula(self.pos, close)?,
        })
    }

    /// The body of `R{"name"}=? [...]`: `S` (or `LRA`), `C<=t` or `F φ`.
    fn reward(&mut self, reward: usize, close: usize) -> Result<Kind, QueryError> {
        let word_col = self.column();
        let word = self.word();
        match word.as_str() {
            "S" | "LRA" => {
                self.skip_space();
                if self.pos != close {
                    return Err(err(self.column(), "expected `]` after S"));
                }
                Ok(Kind::RewardSteady { reward })
            }
            "C" => {
                let Some(bound) = self.bound()? else {
                    return Err(err(self.column(), "expected `<=t` after C"));
                };
                self.skip_space();
                if self.pos != close {
                    return Err(err(self.column(), "expected `]` after the time bound"));
                }
                Ok(Kind::RewardCumulative { reward, bound })
            }
            "F" => {
                if self.bound()?.is_some() {
                    return Err(err(word_col + 1, "R=? [F φ] takes no time bound"));
                }
                Ok(Kind::RewardReach {
                    reward,
                    goal: self.formula(self.pos, close)?,
                })
            }
            _ => Err(err(
                word_col,
                "expected `S`, `C<=t` or `F φ` after R{\"name\"}=?",
            )),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::decision::RewardSpec;
    use crate::net::NetBuilder;

    fn net() -> Net {
        let mut b = NetBuilder::new("n");
        b.place("P1", 1);
        b.place("Fuel", 0);
        b.place("a-b", 0);
        b.build().unwrap()
    }

    fn rewards() -> Vec<RewardSpec> {
        vec![RewardSpec {
            name: "energy".into(),
            ..RewardSpec::default()
        }]
    }

    fn col(text: &str) -> usize {
        let e = parse(&net(), &rewards(), text).unwrap_err();
        e.column().unwrap_or_else(|| panic!("{text}: {e}"))
    }

    #[test]
    fn every_form_reads() {
        let n = net();
        let rw = rewards();
        let q = |t: &str| parse(&n, &rw, t).unwrap_or_else(|e| panic!("{t}: {e}"));
        assert!(
            matches!(q("P=? [F<=600 P1=0]").kind, Kind::Until { bound: Some(b), safe: None, .. } if b == 600.0)
        );
        assert!(matches!(
            q("P=? [F P1==0 & Fuel>0]").kind,
            Kind::Until { bound: None, .. }
        ));
        assert!(
            matches!(q("P=? [Fuel>0 U<=2.5 P1=0]").kind, Kind::Until { bound: Some(b), safe: Some(_), .. } if b == 2.5)
        );
        assert!(matches!(
            q("P=?[ `a-b`=0 U P1=0 ]").kind,
            Kind::Until {
                bound: None,
                safe: Some(_),
                ..
            }
        ));
        assert!(
            matches!(q("P=? [G<=1e2 Fuel=0]").kind, Kind::Globally { bound: Some(b), .. } if b == 100.0)
        );
        assert!(matches!(q("T=? [F Fuel = 1]").kind, Kind::Time { .. }));
        assert!(matches!(q("S=? [P1=1 | Fuel>0]").kind, Kind::Steady { .. }));
        assert!(matches!(
            q("R{\"energy\"}=? [S]").kind,
            Kind::RewardSteady { reward: 0 }
        ));
        assert!(
            matches!(q("R{\"energy\"}=? [C<=10]").kind, Kind::RewardCumulative { reward: 0, bound: b } if b == 10.0)
        );
        assert!(matches!(
            q("R{\"energy\"}min=? [F P1=0]").kind,
            Kind::RewardReach { .. }
        ));
        assert_eq!(q("Pmax=? [F P1=0]").extreme, Some(true));
        assert_eq!(q("Tmin=? [F P1=0]").extreme, Some(false));
        // `Fuel` is a place, not `F` followed by `uel`.
        assert!(matches!(
            q("P=? [Fuel>0 U P1=0]").kind,
            Kind::Until { safe: Some(_), .. }
        ));
    }

    #[test]
    fn errors_point_at_their_column() {
        assert_eq!(col("Q=? [F P1=0]"), 1);
        assert_eq!(col("P>=0.9 [F P1=0]"), 2);
        assert_eq!(col("P=? F P1=0"), 5);
        assert_eq!(col("P=? [F P1=0"), 5);
        assert_eq!(col("P=? [F<=x P1=0]"), 9);
        assert_eq!(col("P=? [F<=1 Pz=0]"), 11);
        assert_eq!(col("P=? [F<=1 P1=]"), 14);
        assert_eq!(col("P=? [X P1=0]"), 6);
        assert_eq!(col("P=? [F P1=0] x"), 14);
        assert_eq!(col("R{\"cost\"}=? [S]"), 3);
        assert_eq!(col("R{\"energy\"}=? [Q]"), 16);
        assert_eq!(col("T=? [F<=3 P1=0]"), 7);
        assert_eq!(col("Smax=? [P1=0]"), 1);
        let e = parse(&net(), &rewards(), "P=? [F<=1 Pz=0]").unwrap_err();
        assert!(
            matches!(e, QueryError::Syntax { name: Some(ref n), .. } if n == "Pz"),
            "{e}"
        );
    }
}
