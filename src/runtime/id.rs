//! The runtime's ids, at the bottom of the module so every part can name an agent without
//! importing the part that manages agents.

use serde::{Deserialize, Serialize};

/// A stable agent id: assigned once, kept while the agent moves through the net.
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct AgentId(pub u64);
