//! The robot-token check: after removing resource places, no transition may create or
//! destroy tokens — a structural P-invariant with weight 1 on every non-resource place,
//! checked by [`conserves_tokens`] in one pass over the arcs (milliseconds for large nets).

use super::Role;
use super::RuntimeError;
use crate::analysis::invariants::conserves_tokens;
use crate::net::{Net, PlaceId};

/// Refuses a net whose transitions change the number of tokens outside resource places,
/// naming the first transition that does.
pub(crate) fn check_robot_tokens(net: &Net, roles: &[Option<Role>]) -> Result<(), RuntimeError> {
    let resources: Vec<PlaceId> = net
        .place_ids()
        .filter(|p| matches!(roles.get(p.index()), Some(Some(Role::Resource))))
        .collect();
    match conserves_tokens(net, &resources) {
        Ok(()) => Ok(()),
        Err(leaks) => {
            let leak = &leaks[0];
            Err(RuntimeError::RobotTokens {
                transition: net.transition(leak.transition).name.clone(),
                change: leak.delta,
            })
        }
    }
}
