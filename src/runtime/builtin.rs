//! Built-in actions, in every backend, with or without a `[map]`:
//!
//! - `wait`: the net decides at once — the race of the place's exponential outputs at the
//!   net's rates (the runtime's one sampler), or the immediate choice;
//! - `wait S`: S model seconds, then the net decides;
//! - `log MSG`: records MSG as the agent's output, then the net decides;
//! - `fire T` / `fire T after S`: fires T (an output of the place), after S model seconds.
//!
//! The ones that take no model time (`wait`, `log MSG`, `fire T`) are [`Builtin::instant`]:
//! the supervisor applies them itself when the agent enters the place, with no task, so a
//! place with one is as transparent as a place without an action. The others sleep on the
//! run's [`ModelClock`](super::ModelClock).
//!
//! A backend with its own meaning for a name (the robot world's `wait` moves no robot but
//! holds one) registers it first; these fill in what is left.

use std::sync::Arc;

use super::action::{Action, ActionContext, ActionFuture, Outcome, OutputStream};
use crate::net::{Net, PlaceId, TransitionId};

/// A built-in action; see the [module docs](self).
#[derive(Clone, Debug, PartialEq)]
pub enum Builtin {
    /// `wait [S]`.
    Wait(Option<f64>),
    /// `log MSG`.
    Log(Arc<str>),
    /// `fire T [after S]`.
    Fire {
        /// The transition.
        transition: TransitionId,
        /// Model seconds to wait first.
        after: Option<f64>,
    },
}

/// Why an action text that starts with a built-in word is not a built-in.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BuiltinError {
    /// `wait S` or `fire T after S` with `S` not a number of seconds.
    #[error(
        "`{text}`: `{seconds}` is not a number of seconds (finite, ≥ 0, ≤ 315576000: 10 years)"
    )]
    Seconds {
        /// The action's text.
        text: String,
        /// The word that should be seconds.
        seconds: String,
    },
    /// `fire` followed by something other than `T` or `T after S`.
    #[error("`{text}`: expected `fire T` or `fire T after S`")]
    FireSyntax {
        /// The action's text.
        text: String,
    },
    /// `fire T` where `T` is not an output transition of the place.
    #[error(
        "`{text}`: `{name}` is not an output transition of `{place}` (outputs: {})",
        outputs.join(", ")
    )]
    NotAnOutput {
        /// The action's text.
        text: String,
        /// The transition named.
        name: String,
        /// The place.
        place: String,
        /// The place's output transitions.
        outputs: Vec<String>,
    },
}

/// The words that start a built-in action.
pub const BUILTIN_WORDS: [&str; 3] = ["wait", "log", "fire"];

impl Builtin {
    /// The built-in that `text` names for `place`: `None` when `text` does not start with a
    /// built-in word, `Some(Err(why))` when it does but is malformed (a bad number, a
    /// transition that is not an output of the place).
    pub fn parse(text: &str, net: &Net, place: PlaceId) -> Option<Result<Builtin, BuiltinError>> {
        let text = text.trim();
        let (word, rest) = text.split_once(char::is_whitespace).unwrap_or((text, ""));
        let rest = rest.trim();
        let seconds = |s: &str| -> Result<f64, BuiltinError> {
            match s.parse::<f64>() {
                Ok(v) if crate::limits::valid_wait(v) => Ok(v),
                _ => Err(BuiltinError::Seconds {
                    text: text.to_string(),
                    seconds: s.to_string(),
                }),
            }
        };
        Some(match word {
            "wait" if rest.is_empty() => Ok(Builtin::Wait(None)),
            "wait" => seconds(rest).map(|s| Builtin::Wait(Some(s))),
            "log" => Ok(Builtin::Log(Arc::from(rest))),
            "fire" => {
                let mut parts = rest.split_whitespace();
                let name = parts.next().unwrap_or("");
                let after = match (parts.next(), parts.next(), parts.next()) {
                    (None, _, _) => Ok(None),
                    (Some("after"), Some(s), None) => seconds(s).map(Some),
                    _ => Err(BuiltinError::FireSyntax {
                        text: text.to_string(),
                    }),
                };
                after.and_then(|after| {
                    let outputs = net.consumers(place);
                    match net.transition_by_name(name) {
                        Some(t) if outputs.contains(&t) => Ok(Builtin::Fire {
                            transition: t,
                            after,
                        }),
                        _ => Err(BuiltinError::NotAnOutput {
                            text: text.to_string(),
                            name: name.to_string(),
                            place: net.place(place).name.clone(),
                            outputs: outputs
                                .iter()
                                .map(|&t| net.transition(t).name.clone())
                                .collect(),
                        }),
                    }
                })
            }
            _ => return None,
        })
    }

    /// The action.
    pub(crate) fn action(self) -> BuiltinAction {
        BuiltinAction { builtin: self }
    }

    /// The outcome of a built-in that takes no model time (`wait`, `log MSG`, `fire T`), and
    /// the line it writes; `None` for one that waits.
    pub fn instant(&self) -> Option<(Outcome, Option<Arc<str>>)> {
        match self {
            Builtin::Wait(s) if s.is_none_or(|s| s <= 0.0) => Some((Outcome::Decide, None)),
            Builtin::Log(msg) => Some((Outcome::Decide, Some(Arc::clone(msg)))),
            Builtin::Fire { transition, after } if after.is_none_or(|s| s <= 0.0) => {
                Some((Outcome::Fire(*transition), None))
            }
            Builtin::Wait(_) | Builtin::Fire { .. } => None,
        }
    }
}

/// A [`Builtin`] ready to run.
#[derive(Debug)]
pub(crate) struct BuiltinAction {
    builtin: Builtin,
}

impl Action for BuiltinAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let (delay, outcome) = match &self.builtin {
            Builtin::Wait(s) => (*s, Outcome::Decide),
            Builtin::Log(msg) => {
                ctx.output_line(OutputStream::Stdout, msg.to_string());
                (None, Outcome::Decide)
            }
            Builtin::Fire { transition, after } => (*after, Outcome::Fire(*transition)),
        };
        let Some(s) = delay.filter(|&s| s > 0.0) else {
            return Box::pin(std::future::ready(outcome));
        };
        Box::pin(async move {
            tokio::select! {
                biased;
                () = ctx.cancel.cancelled() => Outcome::Cancelled,
                () = ctx.clock.sleep(s) => outcome,
            }
        })
    }
}
