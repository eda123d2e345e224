//! Questions about a net in Storm's and PRISM's property syntax, answered exactly.
//!
//! ```text
//! P=? [F<=t φ]      probability that φ holds within t            (uniformisation)
//! P=? [F φ]         probability that φ ever holds                 (embedded chain, sparse LU)
//! P=? [φ1 U<=t φ2]  φ2 within t, φ1 holding until then; `U` unbounded too
//! P=? [G<=t φ]      φ holds throughout [0, t]; `G φ` for ever      (1 − P[F ¬φ])
//! T=? [F φ]         expected time until φ holds (∞ unless reached with probability 1)
//! S=? [φ]           long-run fraction of time in φ (the limiting distribution)
//! R{"name"}=? [S]   long-run rate of the reward structure `[rewards.name]`
//! R{"name"}=? [C<=t] reward accumulated up to t
//! R{"name"}=? [F φ] reward accumulated until φ holds (∞ unless reached with probability 1)
//! Pmax=? Pmin=? Tmax=? Tmin=? R{"name"}max=? …   the best and worst the plan's controllable
//!                   transitions can do ([`extreme`], through the synthesis engine)
//! ```
//!
//! φ is a marking predicate ([`Predicate::parse_prism`]): place names bare or in backticks,
//! `=` or `==`, `&` or `&&`, `|` or `||`. Errors carry the column in the query text.
//!
//! Paths are read on the full reachability graph, vanishing markings included, as Storm
//! reads a GSPN (a Markov automaton): a path that passes through a vanishing marking where φ
//! holds has reached φ, at the time of the exponential firing that led there. The answers
//! are Storm's to 1e-6 on random nets and the thesis nets (`tests/analysis/queries_match_storm.rs`).
//!
//! ```
//! use gspn::analysis::query::{Evaluator, Query};
//! use gspn::analysis::state_space::{Options, StateSpace};
//! use gspn::net::{NetBuilder, Servers};
//! // A job (rate 2) then a check (rate 3).
//! let mut b = NetBuilder::new("two");
//! let (a, m, d) = (b.place("A", 1), b.place("M", 0), b.place("Done", 0));
//! let (t1, t2) = (b.exponential("t1", 2.0, Servers::Single), b.exponential("t2", 3.0, Servers::Single));
//! b.input(a, t1, 1); b.output(t1, m, 1); b.input(m, t2, 1); b.output(t2, d, 1);
//! let net = b.build().unwrap();
//! let space = StateSpace::build(&net, &Options::default()).unwrap();
//! let ev = Evaluator::new(&net, &space, &[]);
//! let t = ev.evaluate(&Query::parse(&net, &[], "T=? [F Done=1]").unwrap()).unwrap();
//! assert!((t - (1.0 / 2.0 + 1.0 / 3.0)).abs() < 1e-12);
//! let p = ev.evaluate(&Query::parse(&net, &[], "P=? [F<=1 Done=1]").unwrap()).unwrap();
//! // Hypoexponential(2, 3): 1 − 3e^{−2} + 2e^{−3}.
//! assert!((p - (1.0 - 3.0 * (-2f64).exp() + 2.0 * (-3f64).exp())).abs() < 1e-10);
//! let err = Query::parse(&net, &[], "P=? [F<=1 Dne=1]").unwrap_err();
//! assert_eq!(err.column(), Some(11));
//! ```

mod absorbing;
mod eval;
pub mod extreme;
mod parse;

use thiserror::Error;

pub use eval::{Evaluator, state_rewards};

use crate::analysis::ctmc::SolveError;
use crate::analysis::decision::DecisionError;
use crate::net::predicate::Predicate;

/// A parsed query.
#[derive(Clone, Debug)]
pub struct Query {
    text: String,
    /// What it asks.
    pub kind: Kind,
    /// `None` for `=?`; `Some(true)` for `max=?`, `Some(false)` for `min=?`.
    pub extreme: Option<bool>,
}

/// What a query asks.
#[derive(Clone, Debug)]
pub enum Kind {
    /// `P=? [safe U<=bound goal]`; `F` is `true U`.
    Until {
        /// φ1 (`None`: `true`).
        safe: Option<Predicate>,
        /// φ2.
        goal: Predicate,
        /// The time bound (`None`: unbounded).
        bound: Option<f64>,
    },
    /// `P=? [G<=bound φ]`.
    Globally {
        /// φ.
        phi: Predicate,
        /// The time bound (`None`: for ever).
        bound: Option<f64>,
    },
    /// `T=? [F goal]`.
    Time {
        /// φ.
        goal: Predicate,
    },
    /// `S=? [φ]`.
    Steady {
        /// φ.
        phi: Predicate,
    },
    /// `R{"name"}=? [S]`.
    RewardSteady {
        /// Index into the reward structures given to [`Query::parse`].
        reward: usize,
    },
    /// `R{"name"}=? [C<=t]`.
    RewardCumulative {
        /// Index into the reward structures.
        reward: usize,
        /// t.
        bound: f64,
    },
    /// `R{"name"}=? [F goal]`.
    RewardReach {
        /// Index into the reward structures.
        reward: usize,
        /// φ.
        goal: Predicate,
    },
}

impl Query {
    /// Parses `text` against `net`'s place names and the names of `rewards` (the plan's
    /// `[rewards.NAME]` structures, for `R{"NAME"}`).
    pub fn parse(
        net: &crate::net::Net,
        rewards: &[crate::analysis::decision::RewardSpec],
        text: &str,
    ) -> Result<Query, QueryError> {
        parse::parse(net, rewards, text)
    }

    /// The text it was parsed from.
    pub fn source(&self) -> &str {
        &self.text
    }
}

impl std::fmt::Display for Query {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.text)
    }
}

/// Why a query could not be read or answered.
#[derive(Clone, Debug, PartialEq, Error)]
#[non_exhaustive]
pub enum QueryError {
    /// The text is not a query: the 1-based column (in characters) and what is wrong.
    #[error("column {column}: {message}")]
    Syntax {
        /// Column of the offending token, from 1.
        column: usize,
        /// The offending name (an unknown place or reward structure), when there is one.
        name: Option<String>,
        /// What is wrong.
        message: String,
    },
    /// A well-formed query this engine does not answer, and why.
    #[error("{0}")]
    Unsupported(String),
    /// A linear system of the answer could not be solved, or the solver was stopped.
    #[error(transparent)]
    Solve(#[from] SolveError),
    /// The decision model of a `max`/`min` query failed.
    #[error(transparent)]
    Decision(#[from] DecisionError),
}

impl QueryError {
    /// The column of a syntax error.
    pub fn column(&self) -> Option<usize> {
        match self {
            QueryError::Syntax { column, .. } => Some(*column),
            _ => None,
        }
    }
}
