//! [`Role`]: what a place does when tokens enter it, and [`FailurePolicy`]: what happens when
//! its action fails. A plan file's `[places."…"]` tables resolve to these.

use crate::net::TransitionId;

/// What a place does when tokens enter it.
#[derive(Clone, Debug, PartialEq)]
pub enum Role {
    /// Each token is an agent running this action.
    Action {
        /// The registered action's name.
        name: String,
        /// Seconds the action may run before it fails; `None` = no limit.
        timeout: Option<f64>,
        /// What to do when it fails.
        on_failure: FailurePolicy,
        /// The robot the place's agents are bound to, when there is one.
        robot: Option<String>,
    },
    /// Tokens are plain counters (a shared resource).
    Resource,
}

/// What to do when an action fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FailurePolicy {
    /// Stop the plan (the default).
    #[default]
    Stop,
    /// Run the action again, at most this many more times, then stop.
    Retry(u32),
    /// Fire this transition (an output of the place) as if the action had chosen it.
    Fire(TransitionId),
}
