//! [`StopConditions`]: when a run ends, besides "nothing can ever fire again" (a plan file's
//! `[stop]` table).

use crate::net::predicate::Predicate;

/// When a run ends, besides "nothing can ever fire again".
#[derive(Clone, Debug, Default)]
pub struct StopConditions {
    /// Stop as soon as the marking satisfies this predicate.
    pub when: Option<Predicate>,
    /// Stop at this (model) time.
    pub time_limit: Option<f64>,
    /// Stop after this many firings.
    pub max_firings: Option<u64>,
}

impl StopConditions {
    /// True when there is none: the run ends only when nothing can fire any more (or on a
    /// failure, or when it is stopped).
    pub fn is_empty(&self) -> bool {
        self.when.is_none() && self.time_limit.is_none() && self.max_firings.is_none()
    }
}
