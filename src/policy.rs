//! Policy: marking → distribution over immediate transitions, with an indexed lookup
//! (being written).

use crate::net::{Net, TransitionId};

/// A stationary policy over immediate transitions. The empty policy defers to the net's
/// weights everywhere.
#[derive(Clone, Debug, Default)]
pub struct Policy {}

impl Policy {
    /// The policy with no rules.
    pub fn empty() -> Self {
        Policy {}
    }

    /// The distribution the policy prescribes in marking `m` over `firable` (the immediate
    /// transitions that may fire now), renormalised over them; `None` when no rule matches
    /// (use the net's weights).
    pub fn distribution(
        &self,
        net: &Net,
        m: &[u32],
        firable: &[TransitionId],
    ) -> Option<Vec<(TransitionId, f64)>> {
        let _ = (net, m, firable);
        None
    }
}
