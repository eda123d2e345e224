//! Breadth-first search of the reachability graph, tangible and vanishing markings alike:
//! the exhaustive chooser of [`crate::firing`] (every move of [`firing::moves`] is taken).
//!
//! Markings get ids in discovery order, so processing ids in order *is* the breadth-first
//! queue, and the parent recorded at discovery gives a shortest firing sequence. Successors
//! of a block of states are computed into a [`Block`] (unpack, enabling, firing, packing,
//! hashing), then inserted in order by one thread. With several threads, worker threads
//! compute blocks while the main thread inserts, so the numbering is the same as the
//! sequential search.

use std::sync::mpsc;

use super::packing::{Deltas, Layout, MarkingStore};
use super::table::MoveTable;
use super::{AnalysisError, Monitor, Move};
use crate::firing::{self, Rules};
use crate::net::{Net, TransitionId};

/// States per block handed between threads.
const BLOCK: usize = 1024;
/// Frontiers smaller than this are expanded on the calling thread.
const PAR_MIN: usize = 2 * BLOCK;

/// The reachability graph as found: ids in discovery order.
#[derive(Debug)]
pub(crate) struct Raw {
    pub(crate) store: MarkingStore,
    /// Per id: tangible (no immediate transition enabled).
    pub(crate) tangible: Vec<bool>,
    /// Per id: moves out. Tangible sources carry the rate (prob 1); vanishing sources carry
    /// the firing probability (rate 0).
    pub(crate) moves: MoveTable,
    /// Per id: the marking it was first reached from and the transition fired (`u32::MAX`
    /// for the initial marking).
    pub(crate) parent: Vec<(u32, u32)>,
    /// What a search that keeps no arcs ([`Arcs::Count`]) counted instead; zero when the
    /// arcs are in `moves`.
    pub(crate) counted: Counted,
}

/// Whether a search stores the arcs it finds (for a CTMC, a decision model, the properties)
/// or only counts them: the cheapest question, how many markings and arcs and which are
/// dead, needs no arc kept, and arcs are most of a state space's memory (24 bytes each,
/// about ten per marking on the MCC models).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Arcs {
    /// Every marking's group of moves goes into [`Raw::moves`].
    Store,
    /// Only [`Raw::counted`] is kept.
    Count,
}

/// The arcs of a search that stored none ([`Arcs::Count`]).
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub(crate) struct Counted {
    /// Labelled arcs: one per (marking, fired transition).
    pub(crate) arcs: usize,
    /// Distinct (marking, successor) pairs.
    pub(crate) successor_pairs: usize,
    /// Markings where nothing is enabled, ascending.
    pub(crate) dead: Vec<u32>,
}

/// Successors of consecutive states `first..first + count.len()`.
#[derive(Debug, Default)]
struct Block {
    first: usize,
    count: Vec<u32>,
    tangible: Vec<bool>,
    /// (transition, rate or probability, hash of the target).
    items: Vec<(u32, f64, u64)>,
    /// Packed targets, `words` per item.
    keys: Vec<u64>,
    /// A target did not fit the layout: (state, place, value). States before it are done.
    overflow: Option<(usize, usize, u32)>,
}

/// How much the search may hold.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Limits {
    /// Most markings.
    pub(crate) states: usize,
    /// Most bytes, estimated ([`Search::bytes_per_marking`]).
    pub(crate) memory: usize,
}

/// How one search runs: what it may hold, on how many threads, the monitor that watches
/// it (progress and cancel: the only progress channel, a caller draws its own display by
/// polling it), and whether a vanishing marking's WAIT targets are searched too.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Settings<'a> {
    pub(crate) limits: Limits,
    /// Threads (1 = this one).
    pub(crate) threads: usize,
    pub(crate) monitor: &'a Monitor,
    /// Vanishing markings also list their enabled exponential transitions.
    pub(crate) wait: bool,
    /// Store the arcs, or only count them.
    pub(crate) arcs: Arcs,
}

/// Computes the successors of the states whose packed words are `frontier`.
fn generate(
    net: &Net,
    rules: &Rules,
    layout: &Layout,
    deltas: &Deltas,
    frontier: &[u64],
    first: usize,
    wait: bool,
) -> Block {
    let w = layout.words();
    let n = frontier.len() / w;
    let mut b = Block {
        first,
        count: Vec::with_capacity(n),
        tangible: Vec::with_capacity(n),
        items: Vec::with_capacity(n * 4),
        keys: Vec::with_capacity(n * 4 * w),
        overflow: None,
    };
    let mut m = vec![0u32; net.place_count()];
    let mut key = vec![0u64; w];
    let mut fire: Vec<(TransitionId, f64)> = Vec::new();
    for i in 0..n {
        let base = &frontier[i * w..(i + 1) * w];
        layout.unpack(base, &mut m);
        let tangible = firing::moves(net, rules, &m, &mut fire);
        if wait && !tangible {
            // Negative: an exponential rate out of a vanishing marking (see `Search::insert`).
            for &t in rules.exponentials() {
                let r = net.exp_rate(&m, t);
                if r > 0.0 {
                    fire.push((t, -r));
                }
            }
        }
        let (items_len, keys_len) = (b.items.len(), b.keys.len());
        for &(t, v) in &fire {
            for &(p, d) in net.delta(t) {
                let after = m[p.index()] as i64 + d;
                if d > 0 && after as u64 > layout.max_value(p.index()) {
                    b.items.truncate(items_len);
                    b.keys.truncate(keys_len);
                    let value = after.min(u32::MAX as i64) as u32;
                    b.overflow = Some((first + i, p.index(), value));
                    return b;
                }
            }
            key.copy_from_slice(base);
            for &(word, add) in deltas.of(t.index()) {
                let k = &mut key[word as usize];
                *k = k.wrapping_add(add);
            }
            b.items.push((t.0, v, MarkingStore::hash(&key)));
            b.keys.extend_from_slice(&key);
        }
        b.count.push(fire.len() as u32);
        b.tangible.push(tangible);
    }
    b
}

/// The search's mutable state, owned by the inserting thread.
struct Search<'m> {
    raw: Raw,
    monitor: &'m Monitor,
    max_states: usize,
    max_memory: usize,
    arcs: Arcs,
    group: Vec<Move>,
    /// The targets of one group, to count its distinct successors ([`Arcs::Count`]).
    targets: Vec<u32>,
}

impl Search<'_> {
    /// Estimated bytes one more marking costs: its packed words (stored, and copied once
    /// into the frontier), its index entry (with the table's spare room), its parent, its
    /// flag and its group's span.
    fn bytes_per_marking(&self) -> usize {
        let span = if self.arcs == Arcs::Store { 12 } else { 0 };
        self.raw.store.layout.words() * 8 * 2 + 32 + 8 + 1 + span
    }

    /// Refuses to grow past [`Limits::memory`]: the estimate is made before the store, the
    /// index and the move table take their next allocation.
    fn check_memory(&self) -> Result<(), AnalysisError> {
        let per = self.bytes_per_marking();
        let bytes = self
            .raw
            .store
            .len()
            .saturating_mul(per)
            .saturating_add(self.raw.moves.total() * std::mem::size_of::<Move>());
        if bytes > self.max_memory {
            return Err(AnalysisError::TooMuchMemory {
                limit_mib: self.max_memory >> 20,
                markings: self.raw.store.len(),
                bytes_per_marking: per,
            });
        }
        Ok(())
    }

    /// Inserts a block's targets; `Some(overflow)` when the block stopped early.
    fn insert(&mut self, b: &Block) -> Result<Option<(usize, usize, u32)>, AnalysisError> {
        let w = self.raw.store.layout.words();
        let mut it = 0;
        for (i, &cnt) in b.count.iter().enumerate() {
            let src = (b.first + i) as u32;
            let tangible = b.tangible[i];
            self.group.clear();
            for _ in 0..cnt {
                let (t, v, h) = b.items[it];
                let key = &b.keys[it * w..(it + 1) * w];
                let (to, new) = self.raw.store.insert_hashed(key, h);
                if new {
                    if self.raw.store.len() > self.max_states {
                        return Err(AnalysisError::TooManyStates {
                            limit: self.max_states,
                        });
                    }
                    self.check_memory()?;
                    self.raw.parent.push((src, t));
                }
                let (rate, prob) = match (tangible, v < 0.0) {
                    (true, _) => (v, 1.0),
                    // An exponential transition enabled in a vanishing marking (WAIT).
                    (false, true) => (-v, 0.0),
                    (false, false) => (0.0, v),
                };
                self.group.push(Move {
                    transition: TransitionId(t),
                    rate,
                    to,
                    prob,
                });
                it += 1;
            }
            self.raw.tangible.push(tangible);
            match self.arcs {
                Arcs::Store => self.raw.moves.push_group(&self.group),
                Arcs::Count => self.count_group(src),
            }
        }
        self.monitor.set_markings(self.raw.store.len());
        if self.monitor.is_cancelled() {
            return Err(AnalysisError::Cancelled {
                markings: self.raw.store.len(),
            });
        }
        Ok(b.overflow)
    }

    /// Counts the group of `src` into [`Raw::counted`] instead of storing it.
    fn count_group(&mut self, src: u32) {
        let counted = &mut self.raw.counted;
        counted.arcs += self.group.len();
        if self.group.is_empty() {
            counted.dead.push(src);
            return;
        }
        self.targets.clear();
        self.targets.extend(self.group.iter().map(|m| m.to));
        self.targets.sort_unstable();
        self.targets.dedup();
        counted.successor_pairs += self.targets.len();
    }
}

/// Searches the whole reachability graph from the initial marking; with `wait`, a vanishing marking's group also holds its enabled
/// exponential transitions (`rate > 0`, `prob == 0`) and their targets are searched too: the
/// markings a WAIT choice reaches.
pub(crate) fn explore_with(
    net: &Net,
    layout: Layout,
    settings: Settings<'_>,
) -> Result<Raw, AnalysisError> {
    let Settings {
        limits,
        threads,
        monitor,
        wait,
        arcs,
    } = settings;
    let rules = Rules::new(net);
    let mut store = MarkingStore::new(layout, net.place_count());
    let mut m0 = net.initial_marking().into_vec();
    let mut key = vec![0u64; store.layout.words()];
    while let Err(p) = store.layout.pack(&m0, &mut key) {
        store.layout = store.layout.widened(p, m0[p]);
        key = vec![0u64; store.layout.words()];
    }
    store.insert(&key);
    m0.clear();
    let mut s = Search {
        raw: Raw {
            store,
            tangible: Vec::new(),
            moves: MoveTable::default(),
            parent: vec![(u32::MAX, u32::MAX)],
            counted: Counted::default(),
        },
        monitor,
        max_states: limits.states.max(1),
        max_memory: limits.memory,
        arcs,
        group: Vec::new(),
        targets: Vec::new(),
    };
    s.check_memory()?;
    let mut cursor = 0;
    while cursor < s.raw.store.len() {
        let hi = s.raw.store.len();
        let w = s.raw.store.layout.words();
        let layout = s.raw.store.layout.clone();
        let deltas = layout.transition_deltas(net);
        let frontier: Vec<u64> = (cursor..hi)
            .flat_map(|id| s.raw.store.packed(id).iter().copied())
            .collect();
        let overflow = if threads <= 1 || hi - cursor < PAR_MIN {
            let mut over = None;
            for (k, chunk) in frontier.chunks(BLOCK * w).enumerate() {
                let b = generate(
                    net,
                    &rules,
                    &layout,
                    &deltas,
                    chunk,
                    cursor + k * BLOCK,
                    wait,
                );
                over = s.insert(&b)?;
                if over.is_some() {
                    break;
                }
            }
            over
        } else {
            let ctx = (net, &rules, &layout, &deltas);
            expand_parallel(ctx, &frontier, cursor, threads, &mut s, wait)?
        };
        match overflow {
            Some((state, p, value)) => {
                // The overflowing block's states before `state` were inserted; the search
                // resumes at `state`, so nothing is counted twice.
                if s.raw.store.layout.max_value(p) >= u32::MAX as u64 {
                    // A count past the largest one a marking holds.
                    return Err(AnalysisError::TooManyTokens {
                        place: net.place(crate::net::PlaceId(p as u32)).name.clone(),
                        tokens: u32::MAX as u64 + 1,
                    });
                }
                let wider = s.raw.store.layout.widened(p, value);
                s.raw.store.relayout(wider);
                cursor = state;
            }
            None => cursor = hi,
        }
    }
    s.raw.moves.shrink();
    s.raw.store.drop_index();
    Ok(s.raw)
}

/// Expands a large frontier: `threads - 1` workers compute blocks round-robin, the calling
/// thread inserts them in order.
#[allow(clippy::too_many_arguments)]
fn expand_parallel(
    (net, rules, layout, deltas): (&Net, &Rules, &Layout, &Deltas),
    frontier: &[u64],
    first: usize,
    threads: usize,
    s: &mut Search<'_>,
    wait: bool,
) -> Result<Option<(usize, usize, u32)>, AnalysisError> {
    let w = layout.words();
    let chunks: Vec<&[u64]> = frontier.chunks(BLOCK * w).collect();
    let workers = (threads - 1).max(1);
    std::thread::scope(|scope| {
        let mut rxs = Vec::with_capacity(workers);
        for k in 0..workers {
            let (tx, rx) = mpsc::sync_channel::<Block>(4);
            rxs.push(rx);
            let chunks = &chunks;
            scope.spawn(move || {
                for (j, chunk) in chunks.iter().enumerate().skip(k).step_by(workers) {
                    let b = generate(net, rules, layout, deltas, chunk, first + j * BLOCK, wait);
                    let stop = b.overflow.is_some();
                    if tx.send(b).is_err() || stop {
                        return;
                    }
                }
            });
        }
        let mut result = Ok(None);
        for j in 0..chunks.len() {
            let Ok(b) = rxs[j % workers].recv() else {
                break;
            };
            match s.insert(&b) {
                Ok(None) => {}
                other => {
                    result = other;
                    break;
                }
            }
        }
        drop(rxs);
        result
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    const BIG: Limits = Limits {
        states: 1 << 20,
        memory: 1 << 30,
    };

    fn settings(threads: usize, monitor: &Monitor) -> Settings<'_> {
        Settings {
            limits: BIG,
            threads,
            monitor,
            wait: false,
            arcs: Arcs::Store,
        }
    }

    /// Two independent two-place cycles with `n` tokens each: (n+1)² markings.
    fn cycles(n: u32) -> Net {
        let mut b = NetBuilder::new("cycles");
        for i in 0..2 {
            let a = b.place(format!("a{i}"), n);
            let c = b.place(format!("c{i}"), 0);
            let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
            let u = b.exponential(format!("u{i}"), 1.0, Servers::Single);
            b.input(a, t, 1);
            b.output(t, c, 1);
            b.input(c, u, 1);
            b.output(u, a, 1);
        }
        b.build().unwrap()
    }

    #[test]
    fn too_narrow_layout_grows_and_finds_every_marking() {
        let net = cycles(60);
        let exact = Layout::new(&[Some(60); 4], &[60, 0, 60, 0]);
        let narrow = Layout::new(&[Some(60), Some(1), Some(60), Some(1)], &[60, 0, 60, 0]);
        for threads in [1, 2] {
            let m = Monitor::new();
            let a = explore_with(&net, exact.clone(), settings(threads, &m)).unwrap();
            let b = explore_with(&net, narrow.clone(), settings(threads, &m)).unwrap();
            assert_eq!(a.store.len(), 61 * 61);
            assert_eq!(b.store.len(), a.store.len());
            assert_eq!(b.moves.total(), a.moves.total());
            let (mut x, mut y) = (vec![0; 4], vec![0; 4]);
            for id in (0..a.store.len()).step_by(37) {
                a.store.get(id, &mut x);
                b.store.get(id, &mut y);
                assert_eq!(x, y);
                assert_eq!(a.parent[id], b.parent[id]);
            }
        }
    }

    #[test]
    fn counting_the_arcs_gives_the_stored_graphs_counts() {
        // Too narrow a layout too: the search restarts a block, which must not count twice.
        let net = cycles(60);
        let narrow = Layout::new(&[Some(60), Some(1), Some(60), Some(1)], &[60, 0, 60, 0]);
        for threads in [1, 2] {
            let m = Monitor::new();
            let stored = explore_with(&net, narrow.clone(), settings(threads, &m)).unwrap();
            let counting = Settings {
                arcs: Arcs::Count,
                ..settings(threads, &m)
            };
            let counted = explore_with(&net, narrow.clone(), counting).unwrap();
            assert_eq!(counted.store.len(), 61 * 61);
            assert_eq!(counted.moves.total(), 0);
            // t_i fires while a_i > 0, u_i while c_i > 0: 4 arcs a marking, less one for
            // each of the 4 places in the 61 markings where it is empty.
            assert_eq!(counted.counted.arcs, stored.moves.total());
            assert_eq!(counted.counted.arcs, 4 * 61 * 61 - 4 * 61);
            assert_eq!(counted.counted.successor_pairs, counted.counted.arcs);
            assert!(counted.counted.dead.is_empty());
        }
    }

    #[test]
    fn the_monitor_counts_markings_and_a_cancel_stops_the_search() {
        let net = cycles(60);
        let exact = Layout::new(&[Some(60); 4], &[60, 0, 60, 0]);
        let m = Monitor::new();
        explore_with(&net, exact.clone(), settings(1, &m)).unwrap();
        assert_eq!(m.markings(), 61 * 61);
        let c = Monitor::new();
        c.cancel();
        // The first block (the initial marking) is expanded, then the flag is seen.
        match explore_with(&net, exact, settings(1, &c)) {
            Err(AnalysisError::Cancelled { markings }) => assert_eq!(markings, 3),
            other => panic!("expected a cancel, got {:?}", other.map(|r| r.store.len())),
        }
    }
}
