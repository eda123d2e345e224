//! Markings: token counts per place, dense by [`PlaceId`](super::PlaceId).

use std::ops::{Deref, DerefMut, Index, IndexMut};

use serde::{Deserialize, Serialize};

use super::PlaceId;

/// Tokens per place, indexed by [`PlaceId`]. Derefs to `[u32]` so the net's arithmetic works
/// on plain slices.
#[derive(Clone, Debug, Default, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Marking(Vec<u32>);

impl Marking {
    /// A marking with `places` empty places.
    pub fn empty(places: usize) -> Self {
        Marking(vec![0; places])
    }

    /// The token counts as a slice.
    pub fn as_slice(&self) -> &[u32] {
        &self.0
    }

    /// Total number of tokens.
    pub fn total(&self) -> u64 {
        self.0.iter().map(|&k| k as u64).sum()
    }

    /// Consumes the marking, returning its counts.
    pub fn into_vec(self) -> Vec<u32> {
        self.0
    }
}

impl From<Vec<u32>> for Marking {
    fn from(v: Vec<u32>) -> Self {
        Marking(v)
    }
}

impl Deref for Marking {
    type Target = [u32];
    fn deref(&self) -> &[u32] {
        &self.0
    }
}

impl DerefMut for Marking {
    fn deref_mut(&mut self) -> &mut [u32] {
        &mut self.0
    }
}

impl Index<PlaceId> for Marking {
    type Output = u32;
    fn index(&self, p: PlaceId) -> &u32 {
        &self.0[p.index()]
    }
}

impl IndexMut<PlaceId> for Marking {
    fn index_mut(&mut self, p: PlaceId) -> &mut u32 {
        &mut self.0[p.index()]
    }
}
