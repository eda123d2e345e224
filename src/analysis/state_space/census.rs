//! The cheapest question about a state space: how many markings and arcs, how many tokens
//! each place can hold, which markings are dead — answered by a search that stores no arc
//! ([`Arcs::Count`]). Arcs are most of a stored state space (24 bytes each, about ten per
//! marking on the Model Checking Contest's models), so this takes the markings' packed words,
//! their hash index and one parent each: Kanban-PT-00005's 2.5 million markings in a few tens
//! of bytes each, where the full graph needs over 250.

use super::explore::Arcs;
use super::{AnalysisError, Options, search};
use crate::analysis::properties::DeadMarking;
use crate::net::{Net, TransitionId};

/// A state space's counts, bounds and dead markings, without its arcs.
#[derive(Clone, Debug, PartialEq)]
pub struct Census {
    /// Reachable markings, tangible and vanishing.
    pub reachable: usize,
    /// Tangible markings (no immediate transition enabled).
    pub tangible: usize,
    /// Vanishing markings.
    pub vanishing: usize,
    /// Labelled arcs of the reachability graph, vanishing markings included: one per
    /// (marking, fired transition) — the Model Checking Contest's `TRANSITIONS` for nets
    /// without immediate transitions ([`Properties::edges`](crate::analysis::properties::Properties::edges)
    /// counts the arcs left after eliminating vanishing markings instead, which needs them
    /// stored).
    pub arcs: usize,
    /// Distinct (marking, successor) pairs, as
    /// [`Properties::successor_pairs`](crate::analysis::properties::Properties::successor_pairs).
    pub successor_pairs: usize,
    /// Most tokens each place holds in a reachable marking.
    pub place_bounds: Vec<u32>,
    /// Most tokens in one marking (all places).
    pub max_tokens_per_marking: u64,
    /// Markings where nothing can fire, in breadth-first order, each with one shortest
    /// firing sequence to it.
    pub dead_markings: Vec<DeadMarking>,
    /// Heap bytes the search held at its end (markings and parents), for the record.
    pub heap_bytes: usize,
}

impl Census {
    /// Searches every reachable marking of `net`, counting arcs instead of storing them.
    ///
    /// ```
    /// use gspn::analysis::state_space::{Census, Options, StateSpace};
    /// use gspn::net::{NetBuilder, Servers};
    /// let mut b = NetBuilder::new("drain");
    /// let (p, q) = (b.place("p", 2), b.place("q", 0));
    /// let t = b.exponential("t", 1.0, Servers::Single);
    /// b.input(p, t, 1); b.output(t, q, 1);
    /// let net = b.build().unwrap();
    /// let c = Census::build(&net, &Options::default()).unwrap();
    /// assert_eq!((c.reachable, c.arcs, c.place_bounds.clone()), (3, 2, vec![2, 2]));
    /// assert_eq!(c.dead_markings[0].marking, vec![0, 2]);
    /// assert_eq!(c.arcs, StateSpace::build(&net, &Options::default()).unwrap().edge_count());
    /// ```
    pub fn build(net: &Net, opts: &Options) -> Result<Census, AnalysisError> {
        let raw = search(net, opts, &opts.watcher(), false, Arcs::Count)?;
        let n = raw.store.len();
        let mut bounds = vec![0u32; net.place_count()];
        let mut max_total = 0u64;
        let mut m = vec![0u32; net.place_count()];
        for g in 0..n {
            raw.store.get(g, &mut m);
            let mut total = 0u64;
            for (b, &k) in bounds.iter_mut().zip(&m) {
                *b = (*b).max(k);
                total += k as u64;
            }
            max_total = max_total.max(total);
        }
        let dead_markings = raw
            .counted
            .dead
            .iter()
            .map(|&g| {
                let mut marking = vec![0u32; net.place_count()];
                raw.store.get(g as usize, &mut marking);
                let mut path = Vec::new();
                let mut v = g;
                while raw.parent[v as usize].0 != u32::MAX {
                    let (p, t) = raw.parent[v as usize];
                    path.push(TransitionId(t));
                    v = p;
                }
                path.reverse();
                DeadMarking { marking, path }
            })
            .collect();
        let tangible = raw.tangible.iter().filter(|&&t| t).count();
        Ok(Census {
            reachable: n,
            tangible,
            vanishing: n - tangible,
            arcs: raw.counted.arcs,
            successor_pairs: raw.counted.successor_pairs,
            place_bounds: bounds,
            max_tokens_per_marking: max_total,
            dead_markings,
            heap_bytes: raw.store.heap_bytes()
                + raw.parent.capacity() * 8
                + raw.tangible.capacity(),
        })
    }
}
