//! The robot-token check: after removing resource places, no transition may create or
//! destroy tokens (the sum of each transition's change over the other places is 0). That is a
//! structural P-invariant with weight 1 on every non-resource place: one pass over the arcs,
//! milliseconds even for large nets.
//!
//! (A local check; the general invariant code lives in `analysis` once it lands there.)

use super::RuntimeError;
use crate::io::plan::Role;
use crate::net::Net;

/// Refuses a net whose transitions change the number of tokens outside resource places.
pub(crate) fn check_robot_tokens(net: &Net, roles: &[Option<Role>]) -> Result<(), RuntimeError> {
    for t in net.transition_ids() {
        let sum: i64 = net
            .delta(t)
            .iter()
            .filter(|&&(p, _)| !matches!(roles.get(p.index()), Some(Some(Role::Resource))))
            .map(|&(_, d)| d)
            .sum();
        if sum != 0 {
            return Err(RuntimeError::RobotTokens {
                transition: net.transition(t).name.clone(),
                change: sum,
            });
        }
    }
    Ok(())
}
