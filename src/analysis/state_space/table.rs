//! Per-state groups of [`Move`]s in fixed-size chunks: no reallocation spike when a search
//! grows to tens of millions of arcs, and each state's group stays contiguous.

use super::Move;

/// Moves per chunk (24 MB).
const CHUNK: usize = 1 << 20;

#[derive(Clone, Copy, Debug, Default)]
struct Span {
    chunk: u32,
    offset: u32,
    len: u32,
}

/// Groups of moves, one group per state, in push order.
#[derive(Debug, Default)]
pub(crate) struct MoveTable {
    chunks: Vec<Vec<Move>>,
    spans: Vec<Span>,
    total: usize,
}

impl MoveTable {
    /// Appends the group of the next state.
    pub(crate) fn push_group(&mut self, group: &[Move]) {
        let fits = self
            .chunks
            .last()
            .is_some_and(|c| c.capacity() - c.len() >= group.len());
        if !fits {
            self.chunks.push(Vec::with_capacity(CHUNK.max(group.len())));
        }
        let chunk = self.chunks.len() - 1;
        let c = &mut self.chunks[chunk];
        self.spans.push(Span {
            chunk: chunk as u32,
            offset: c.len() as u32,
            len: group.len() as u32,
        });
        c.extend_from_slice(group);
        self.total += group.len();
    }

    /// The group of state `s`.
    #[inline]
    pub(crate) fn group(&self, s: usize) -> &[Move] {
        let sp = self.spans[s];
        &self.chunks[sp.chunk as usize][sp.offset as usize..(sp.offset + sp.len) as usize]
    }

    /// The group of state `s`, to rewrite in place.
    pub(crate) fn group_mut(&mut self, s: usize) -> &mut [Move] {
        let sp = self.spans[s];
        &mut self.chunks[sp.chunk as usize][sp.offset as usize..(sp.offset + sp.len) as usize]
    }

    /// Total moves over all groups.
    #[inline]
    pub(crate) fn total(&self) -> usize {
        self.total
    }

    /// Rewrites every move's target through `map` and reorders the groups: new group `i` is
    /// old group `order[i]`.
    pub(crate) fn renumber(&mut self, order: &[u32], map: &[u32]) {
        for c in &mut self.chunks {
            for m in c.iter_mut() {
                m.to = map[m.to as usize];
            }
        }
        self.spans = order.iter().map(|&o| self.spans[o as usize]).collect();
    }

    /// Frees spare chunk capacity.
    pub(crate) fn shrink(&mut self) {
        if let Some(c) = self.chunks.last_mut() {
            c.shrink_to_fit();
        }
        self.spans.shrink_to_fit();
    }

    /// Approximate heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.chunks
            .iter()
            .map(|c| c.capacity() * std::mem::size_of::<Move>())
            .sum::<usize>()
            + self.spans.capacity() * std::mem::size_of::<Span>()
    }
}
