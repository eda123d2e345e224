//! [`PlaceId`] and [`TransitionId`]: dense, `Copy` handles into a net's per-place and
//! per-transition arrays (names live at the edges).

use serde::{Deserialize, Serialize};

/// Dense index of a place in its [`Net`].
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct PlaceId(pub u32);

/// Dense index of a transition in its [`Net`].
#[repr(transparent)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
pub struct TransitionId(pub u32);

impl PlaceId {
    /// The index into per-place arrays.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

impl TransitionId {
    /// The index into per-transition arrays.
    #[inline]
    pub fn index(self) -> usize {
        self.0 as usize
    }
}
