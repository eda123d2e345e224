//! Behavioural properties of a net, read off its [`StateSpace`]: counts, dead markings with a
//! shortest firing sequence to each, place bounds, safety, reversibility, liveness per
//! transition, deadlock freedom.
//!
//! Properties are about the *full* reachability graph (vanishing markings included, fired
//! under GSPN rules: in a vanishing marking only the highest-priority immediate transitions).
//!
//! ```
//! use gspn::analysis::properties::{Liveness, Properties};
//! use gspn::analysis::state_space::{Options, StateSpace};
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("chain");
//! let (p1, p2) = (b.place("p1", 1), b.place("p2", 0));
//! let t = b.exponential("t", 1.0, Servers::Single);
//! b.input(p1, t, 1);
//! b.output(t, p2, 1);
//! let net = b.build().unwrap();
//! let ss = StateSpace::build(&net, &Options::default()).unwrap();
//! let props = Properties::compute(&net, &ss);
//! assert_eq!(props.reachable, 2);
//! assert_eq!(props.dead_markings[0].marking, vec![0, 1]);
//! assert_eq!(props.dead_markings[0].path, vec![t]);
//! assert!(props.safe && !props.reversible && !props.deadlock_free);
//! assert_eq!(props.liveness, vec![Liveness::QuasiLive]);
//! ```

use serde::Serialize;

use crate::analysis::scc::tarjan;
use crate::analysis::state_space::StateSpace;
use crate::net::{Net, TransitionId};

/// How alive a transition is.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Liveness {
    /// Never fires from any reachable marking.
    Dead,
    /// Fires from some reachable marking, but not from every one eventually.
    QuasiLive,
    /// From every reachable marking it can eventually fire (it fires inside every bottom
    /// strongly connected component).
    Live,
}

/// A reachable marking where nothing can fire.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct DeadMarking {
    /// Tokens per place.
    pub marking: Vec<u32>,
    /// One shortest firing sequence from the initial marking to it.
    pub path: Vec<TransitionId>,
}

/// What the state space says about the net.
#[derive(Clone, Debug, PartialEq)]
pub struct Properties {
    /// Reachable markings, tangible and vanishing.
    pub reachable: usize,
    /// Tangible markings.
    pub tangible: usize,
    /// Vanishing markings.
    pub vanishing: usize,
    /// Labelled arcs, one per (marking, fired transition) — the `TRANSITIONS` of the Model
    /// Checking Contest's state-space oracles in `fixtures/mcc`; for nets with immediate
    /// transitions, arcs between tangible states after elimination.
    pub edges: usize,
    /// Distinct (marking, successor) pairs of the reachability graph (vanishing markings
    /// included): two transitions from one marking to the same marking count once, as tools
    /// that count the graph's edges rather than its firings do.
    pub successor_pairs: usize,
    /// Dead markings, in breadth-first order.
    pub dead_markings: Vec<DeadMarking>,
    /// Most tokens each place holds in a reachable marking.
    pub place_bounds: Vec<u32>,
    /// Every place holds at most one token.
    pub safe: bool,
    /// Most tokens in one place in one marking.
    pub max_tokens_in_place: u32,
    /// Most tokens in one marking (all places).
    pub max_tokens_per_marking: u64,
    /// The initial marking can be reached again from every reachable marking (home state).
    pub reversible: bool,
    /// No reachable marking is dead.
    pub deadlock_free: bool,
    /// Liveness of each transition, by [`TransitionId`].
    pub liveness: Vec<Liveness>,
}

impl Properties {
    /// Reads the properties off `ss` (built from `net`).
    pub fn compute(net: &Net, ss: &StateSpace) -> Properties {
        let n = ss.reachable_count();
        let mut bounds = vec![0u32; net.place_count()];
        let mut max_total = 0u64;
        let mut m = vec![0u32; net.place_count()];
        for g in 0..n {
            ss.marking_into(g, &mut m);
            let mut total = 0u64;
            for (b, &k) in bounds.iter_mut().zip(&m) {
                *b = (*b).max(k);
                total += k as u64;
            }
            max_total = max_total.max(total);
        }
        let dead_markings = ss
            .dead_states()
            .iter()
            .map(|&s| DeadMarking {
                marking: ss.marking(s as usize),
                path: ss.path_to(s as usize),
            })
            .collect();
        let sccs = tarjan(n, |v, out| {
            out.extend(ss.successors(v as usize).map(|(_, to)| to))
        });
        let bottom = sccs.bottom(|v, out| out.extend(ss.successors(v as usize).map(|(_, to)| to)));
        let bottoms = bottom.iter().filter(|&&b| b).count();
        let reversible = bottoms == 1 && bottom[sccs.component[ss.initial_global()] as usize];
        // Liveness: fires somewhere (quasi-live); fires inside every bottom component (live).
        let nt = net.transition_count();
        let mut fires = vec![false; nt];
        let mut fires_in_bottom = vec![0usize; nt];
        let mut last_bottom = vec![u32::MAX; nt];
        let mut successor_pairs = 0;
        let mut targets = Vec::new();
        for g in 0..n {
            let c = sccs.component[g];
            let in_bottom = bottom[c as usize];
            targets.clear();
            targets.extend(ss.successors(g).map(|(_, to)| to));
            targets.sort_unstable();
            targets.dedup();
            successor_pairs += targets.len();
            for (t, _) in ss.successors(g) {
                fires[t.index()] = true;
                if in_bottom && last_bottom[t.index()] != c {
                    last_bottom[t.index()] = c;
                    fires_in_bottom[t.index()] += 1;
                }
            }
        }
        let liveness = (0..nt)
            .map(|t| {
                if !fires[t] {
                    Liveness::Dead
                } else if fires_in_bottom[t] == bottoms {
                    Liveness::Live
                } else {
                    Liveness::QuasiLive
                }
            })
            .collect();
        let edges = if ss.vanishing_count() > 0 {
            ss.tangible_edge_count()
        } else {
            ss.edge_count()
        };
        Properties {
            reachable: n,
            tangible: ss.tangible_count(),
            vanishing: ss.vanishing_count(),
            edges,
            successor_pairs,
            deadlock_free: ss.dead_states().is_empty(),
            dead_markings,
            safe: bounds.iter().all(|&b| b <= 1),
            max_tokens_in_place: bounds.iter().copied().max().unwrap_or(0),
            max_tokens_per_marking: max_total,
            place_bounds: bounds,
            reversible,
            liveness,
        }
    }

    /// Transitions that are live.
    pub fn live_transitions(&self) -> Vec<TransitionId> {
        self.with(Liveness::Live)
    }

    /// Transitions that never fire.
    pub fn dead_transitions(&self) -> Vec<TransitionId> {
        self.with(Liveness::Dead)
    }

    fn with(&self, l: Liveness) -> Vec<TransitionId> {
        (0..self.liveness.len() as u32)
            .map(TransitionId)
            .filter(|t| self.liveness[t.index()] == l)
            .collect()
    }
}
