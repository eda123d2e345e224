//! Packed markings: a few bits per place in `u64` words, and the hash-indexed store of them.
//!
//! Places with a known bound (structural or from the coverability set) get just enough bits;
//! the others start small and grow: a marking that does not fit reports the place, the
//! explorer widens the layout and [`MarkingStore::relayout`] repacks everything stored.

use std::hash::Hasher;

use hashbrown::HashTable;
use rustc_hash::FxHasher;

use crate::net::Net;

/// Where each place's count lives: word index and bit shift, and its width.
#[derive(Clone, Debug)]
pub(crate) struct Layout {
    bits: Vec<u8>,
    word: Vec<u32>,
    shift: Vec<u8>,
    words: usize,
}

/// Bits needed to hold `v`.
fn bits_for(v: u64) -> u8 {
    (64 - v.leading_zeros()).max(1) as u8
}

impl Layout {
    /// A layout for places with these bounds (`None`: unknown, start with room for twice the
    /// initial count, at least 4 bits).
    pub(crate) fn new(bounds: &[Option<u64>], initial: &[u32]) -> Layout {
        let bits = bounds
            .iter()
            .zip(initial)
            .map(|(b, &m)| match b {
                Some(b) => bits_for((*b).min(u32::MAX as u64)),
                None => bits_for(2 * m as u64 + 1).max(4),
            })
            .collect();
        Layout::from_bits(bits)
    }

    fn from_bits(bits: Vec<u8>) -> Layout {
        let mut word = Vec::with_capacity(bits.len());
        let mut shift = Vec::with_capacity(bits.len());
        let (mut w, mut used) = (0u32, 0u8);
        for &b in &bits {
            if used as u32 + b as u32 > 64 {
                w += 1;
                used = 0;
            }
            word.push(w);
            shift.push(used);
            used += b;
        }
        let words = if bits.is_empty() { 1 } else { w as usize + 1 };
        Layout {
            bits,
            word,
            shift,
            words,
        }
    }

    /// Words per marking.
    #[inline]
    pub(crate) fn words(&self) -> usize {
        self.words
    }

    /// A copy with place `p` able to hold `value`.
    pub(crate) fn widened(&self, p: usize, value: u32) -> Layout {
        let mut bits = self.bits.clone();
        bits[p] = bits_for(value as u64).max(bits[p] * 2).min(32);
        Layout::from_bits(bits)
    }

    /// Largest count place `p` can hold.
    #[inline]
    pub(crate) fn max_value(&self, p: usize) -> u64 {
        let b = self.bits[p];
        if b >= 32 {
            u32::MAX as u64
        } else {
            (1u64 << b) - 1
        }
    }

    /// Per transition, the numbers to add (wrapping) to the words of a packed marking to
    /// fire it: each place's delta shifted into its field. Correct whenever the result fits,
    /// since a field that stays in range neither borrows from nor carries into its
    /// neighbours. Sparse, so its size follows the arcs (a dense table of transitions ×
    /// words grew with the square of a chain's length).
    pub(crate) fn transition_deltas(&self, net: &Net) -> Deltas {
        let mut start = Vec::with_capacity(net.transition_count() + 1);
        let mut items: Vec<(u32, u64)> = Vec::new();
        start.push(0);
        for t in net.transition_ids() {
            let first = items.len();
            for &(p, d) in net.delta(t) {
                let word = self.word[p.index()];
                let add = (d as u64).wrapping_shl(self.shift[p.index()] as u32);
                match items[first..].iter_mut().find(|(w, _)| *w == word) {
                    Some((_, x)) => *x = x.wrapping_add(add),
                    None => items.push((word, add)),
                }
            }
            start.push(items.len() as u32);
        }
        Deltas { start, items }
    }

    /// Packs `m` into `out`; `Err(place)` when a count does not fit.
    #[inline]
    pub(crate) fn pack(&self, m: &[u32], out: &mut [u64]) -> Result<(), usize> {
        out.fill(0);
        for (p, &k) in m.iter().enumerate() {
            let b = self.bits[p];
            if b < 32 && k >> b != 0 {
                return Err(p);
            }
            out[self.word[p] as usize] |= (k as u64) << self.shift[p];
        }
        Ok(())
    }

    /// Unpacks `words` into `out` (one count per place).
    #[inline]
    pub(crate) fn unpack(&self, words: &[u64], out: &mut [u32]) {
        for (p, o) in out.iter_mut().enumerate() {
            let b = self.bits[p];
            let mask = if b >= 64 { u64::MAX } else { (1u64 << b) - 1 };
            *o = ((words[self.word[p] as usize] >> self.shift[p]) & mask) as u32;
        }
    }
}

/// What firing each transition adds to the words of a packed marking
/// ([`Layout::transition_deltas`]).
#[derive(Clone, Debug)]
pub(crate) struct Deltas {
    start: Vec<u32>,
    items: Vec<(u32, u64)>,
}

impl Deltas {
    /// `(word, number to add)` for transition `t`.
    #[inline]
    pub(crate) fn of(&self, t: usize) -> &[(u32, u64)] {
        &self.items[self.start[t] as usize..self.start[t + 1] as usize]
    }
}

/// Hash of a packed marking.
#[inline]
fn hash_words(w: &[u64]) -> u64 {
    let mut h = FxHasher::default();
    for &x in w {
        h.write_u64(x);
    }
    h.finish()
}

/// Word-by-word equality (short slices: cheaper than a `memcmp` call).
#[inline]
fn same(a: &[u64], b: &[u64]) -> bool {
    a.iter().zip(b).all(|(x, y)| x == y)
}

#[inline]
fn rehash(words: &[u64], w: usize, id: u32) -> u64 {
    hash_words(&words[id as usize * w..(id as usize + 1) * w])
}

/// Packed markings, numbered in insertion order, with a hash index over them.
#[derive(Debug)]
pub(crate) struct MarkingStore {
    pub(crate) layout: Layout,
    words: Vec<u64>,
    /// (first word, id) per marking.
    index: HashTable<(u64, u32)>,
    places: usize,
}

impl MarkingStore {
    /// An empty store.
    pub(crate) fn new(layout: Layout, places: usize) -> MarkingStore {
        MarkingStore {
            layout,
            words: Vec::new(),
            index: HashTable::new(),
            places,
        }
    }

    /// Heap bytes held: the packed words and the hash index (gone after the search).
    pub(crate) fn heap_bytes(&self) -> usize {
        self.words.capacity() * 8 + self.index.capacity() * std::mem::size_of::<(u64, u32)>()
    }

    /// Number of markings stored.
    #[inline]
    pub(crate) fn len(&self) -> usize {
        self.words.len() / self.layout.words()
    }

    /// The packed words of marking `id`.
    #[inline]
    pub(crate) fn packed(&self, id: usize) -> &[u64] {
        let w = self.layout.words();
        &self.words[id * w..(id + 1) * w]
    }

    /// Unpacks marking `id` into `out`.
    #[inline]
    pub(crate) fn get(&self, id: usize, out: &mut [u32]) {
        self.layout.unpack(self.packed(id), out);
    }

    /// The id of the packed marking `key`, inserting it when new: `(id, new)`.
    #[inline]
    pub(crate) fn insert(&mut self, key: &[u64]) -> (u32, bool) {
        self.insert_hashed(key, hash_words(key))
    }

    /// As [`insert`](Self::insert), with the hash computed by the caller.
    #[inline]
    pub(crate) fn insert_hashed(&mut self, key: &[u64], hash: u64) -> (u32, bool) {
        let w = self.layout.words();
        let words = &self.words;
        // The first word sits in the table: one-word markings never touch `words` here.
        let found = self.index.find(hash, |&(k0, id)| {
            k0 == key[0] && (w == 1 || same(&words[id as usize * w..(id as usize + 1) * w], key))
        });
        if let Some(&(_, id)) = found {
            return (id, false);
        }
        let id = self.len() as u32;
        self.words.extend_from_slice(key);
        let words = &self.words;
        self.index
            .insert_unique(hash, (key[0], id), |&(_, id)| rehash(words, w, id));
        (id, true)
    }

    /// Repacks every stored marking with `layout` (which must hold them all).
    pub(crate) fn relayout(&mut self, layout: Layout) {
        let mut m = vec![0u32; self.places];
        let mut out = vec![0u64; layout.words()];
        let n = self.len();
        let mut words = Vec::with_capacity(n * layout.words());
        for id in 0..n {
            self.get(id, &mut m);
            layout
                .pack(&m, &mut out)
                .expect("a wider layout holds every stored marking");
            words.extend_from_slice(&out);
        }
        self.layout = layout;
        self.words = words;
        self.rebuild_index();
    }

    fn rebuild_index(&mut self) {
        let w = self.layout.words();
        let mut index = HashTable::with_capacity(self.len());
        for id in 0..self.len() {
            let key = &self.words[id * w..(id + 1) * w];
            let words = &self.words;
            index.insert_unique(hash_words(key), (key[0], id as u32), |&(_, id)| {
                rehash(words, w, id)
            });
        }
        self.index = index;
    }

    /// Drops the hash index (after the search) and keeps only the markings.
    pub(crate) fn drop_index(&mut self) {
        self.index = HashTable::new();
        self.words.shrink_to_fit();
    }

    /// Reorders the markings: new id `i` holds old id `order[i]`.
    pub(crate) fn permute(&mut self, order: &[u32]) {
        let w = self.layout.words();
        let mut words = Vec::with_capacity(self.words.len());
        for &old in order {
            words.extend_from_slice(&self.words[old as usize * w..(old as usize + 1) * w]);
        }
        self.words = words;
    }

    /// Hash used by the index, for callers that hash off the main thread.
    #[inline]
    pub(crate) fn hash(key: &[u64]) -> u64 {
        hash_words(key)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_round_trips_and_reports_overflow() {
        let l = Layout::new(&[Some(1), None, Some(1000)], &[0, 3, 7]);
        let mut w = vec![0; l.words()];
        l.pack(&[1, 5, 999], &mut w).unwrap();
        let mut m = [0; 3];
        l.unpack(&w, &mut m);
        assert_eq!(m, [1, 5, 999]);
        assert_eq!(l.pack(&[2, 0, 0], &mut w), Err(0));
        let l2 = l.widened(0, 2);
        l2.pack(&[2, 0, 0], &mut w).unwrap();
    }

    #[test]
    fn store_finds_and_relayouts() {
        let l = Layout::new(&[None, None], &[0, 0]);
        let mut s = MarkingStore::new(l.clone(), 2);
        let mut w = vec![0; l.words()];
        l.pack(&[3, 4], &mut w).unwrap();
        assert_eq!(s.insert(&w), (0, true));
        assert_eq!(s.insert(&w), (0, false));
        let l2 = l.widened(1, 1 << 20);
        s.relayout(l2.clone());
        let mut w2 = vec![0; l2.words()];
        l2.pack(&[3, 4], &mut w2).unwrap();
        assert_eq!(s.insert(&w2), (0, false));
        let mut m = [0; 2];
        s.get(0, &mut m);
        assert_eq!(m, [3, 4]);
    }
}
