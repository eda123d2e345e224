//! The tangible reachability graph of a GSPN, vanishing markings eliminated.
//!
//! [`StateSpace::build`] searches every reachable marking breadth-first (packed markings in
//! a hash-indexed store, both cores when the frontier is large), then eliminates the
//! vanishing ones ([`vanishing`](crate::analysis::vanishing)): tangible states are numbered
//! `0..tangible_count()` and each carries its [`Move`]s, ready for a CTMC. The full graph
//! (vanishing markings included) stays available for [`properties`](crate::analysis::properties).
//!
//! Before searching, places without a structural bound (P-invariants, capacities) send the
//! net through [`karp_miller`](crate::analysis::coverability::karp_miller), so an unbounded
//! net ends with [`AnalysisError::Unbounded`] instead of running forever.
//!
//! ```
//! use gspn::analysis::state_space::{Options, StateSpace};
//! use gspn::net::{NetBuilder, Servers};
//! // cyc3: P1 (2 tokens) → T1 → P2 → t2 (immediate) → P3 → T3 → P1
//! let mut b = NetBuilder::new("cyc3");
//! let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
//! let t1 = b.exponential("T1", 1.0, Servers::Single);
//! let t2 = b.immediate("t2", 1.0, 1);
//! let t3 = b.exponential("T3", 2.0, Servers::Single);
//! b.input(p1, t1, 1); b.output(t1, p2, 1);
//! b.input(p2, t2, 1); b.output(t2, p3, 1);
//! b.input(p3, t3, 1); b.output(t3, p1, 1);
//! let net = b.build().unwrap();
//! let ss = StateSpace::build(&net, &Options::default()).unwrap();
//! assert_eq!((ss.tangible_count(), ss.vanishing_count()), (3, 2));
//! assert_eq!(ss.marking(0), vec![2, 0, 0]);
//! ```

mod census;
pub(crate) mod explore;
pub(crate) mod packing;
pub(crate) mod table;

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use thiserror::Error;

use crate::analysis::coverability::{Coverability, karp_miller};
use crate::analysis::invariants::structural_bounds;
use crate::analysis::vanishing::eliminate;
use crate::net::{MAX_TOKENS, Net, TransitionId};
use crate::policy::Policy;
pub use census::Census;
use packing::{Layout, MarkingStore};
use table::MoveTable;

/// How to build a state space.
#[derive(Clone, Debug)]
pub struct Options {
    /// Most markings (tangible and vanishing) to store before giving up (default 10,000,000).
    pub max_states: usize,
    /// Threads to use; 0 = all available cores.
    pub threads: usize,
    /// Most bytes the search may hold (markings, their index and their moves), estimated
    /// before each allocation (default 4 GiB).
    pub max_memory: usize,
    /// Watches the search from another thread: its progress ([`Monitor::markings`]) and a
    /// cancel that stops it with [`AnalysisError::Cancelled`] (default: none).
    pub monitor: Option<Arc<Monitor>>,
}

impl Options {
    /// The monitor the search reports to: [`Options::monitor`], or a fresh one nobody
    /// watches.
    pub(crate) fn watcher(&self) -> Arc<Monitor> {
        self.monitor.clone().unwrap_or_default()
    }
}

/// [`Options::max_memory`]'s default: 4 GiB.
pub const DEFAULT_MAX_MEMORY: usize = 4 << 30;

impl Default for Options {
    fn default() -> Self {
        Options {
            max_states: 10_000_000,
            threads: 0,
            max_memory: DEFAULT_MAX_MEMORY,
            monitor: None,
        }
    }
}

/// Why a state space could not be built.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[non_exhaustive]
pub enum AnalysisError {
    /// More markings than `Options::max_states`.
    #[error("more than {limit} reachable markings (raise --max-states)")]
    TooManyStates {
        /// The limit that was hit.
        limit: usize,
    },
    /// The net is unbounded: these places can hold arbitrarily many tokens.
    #[error("the net is unbounded: places {} can grow without limit", places.join(", "))]
    Unbounded {
        /// Names of the unbounded places.
        places: Vec<String>,
    },
    /// A loop of immediate transitions that time can never leave.
    #[error(
        "timeless trap: a loop of immediate transitions with no way out, through marking {marking}"
    )]
    TimelessTrap {
        /// One marking of the loop, as `p=k,...`.
        marking: String,
    },
    /// A loop of vanishing markings too large to solve exactly in memory: its exits and
    /// firing counts, one dense column each over the loop, would pass 512 MB.
    #[error(
        "a loop of {markings} vanishing markings is too large to solve exactly (its exits and firing counts would need more than 512 MB)"
    )]
    VanishingLoopTooLarge {
        /// Markings in the loop.
        markings: usize,
    },
    /// The LU factorisation of a loop of vanishing markings failed (numerically singular).
    #[error("the loop of {markings} vanishing markings could not be solved: {reason}")]
    VanishingLoopFailed {
        /// Markings in the loop.
        markings: usize,
        /// What the factorisation reported.
        reason: String,
    },
    /// A place can hold more tokens than a count can ([`MAX_TOKENS`]): refused before the
    /// search when a structural bound says so, or when the search first meets such a count.
    #[error(
        "place `{place}` can reach {tokens} tokens, which {}",
        crate::net::TOO_MANY_TOKENS
    )]
    TooManyTokens {
        /// The place.
        place: String,
        /// Its bound, or the count the search met.
        tokens: u64,
    },
    /// The search would need more memory than `Options::max_memory`: refused before the
    /// allocation, from the size of one packed marking and of its moves.
    #[error(
        "the state space needs more than {limit_mib} MiB: {markings} markings of {bytes_per_marking} bytes each so far (raise --max-memory or lower --max-states)"
    )]
    TooMuchMemory {
        /// The memory limit, in MiB.
        limit_mib: usize,
        /// Markings stored when the estimate crossed the limit.
        markings: usize,
        /// Estimated bytes per marking (packed words, index, parent, moves).
        bytes_per_marking: usize,
    },
    /// [`Monitor::cancel`] was called while the search ran.
    #[error("cancelled after {markings} markings")]
    Cancelled {
        /// Markings found when the search stopped.
        markings: usize,
    },
}

/// Watches a long computation from another thread — a state space search
/// ([`Options::monitor`], [`BuildOptions::monitor`](crate::analysis::decision::BuildOptions::monitor))
/// or a transient solution
/// ([`TransientOptions::monitor`](crate::analysis::ctmc::TransientOptions::monitor)) — and
/// stops it: how many markings the search has found so far, how far the transient
/// solver is (the time point it works towards, its iterations done of planned), and a flag
/// that makes either give up ([`AnalysisError::Cancelled`], [`SolveError::Cancelled`](crate::analysis::ctmc::SolveError::Cancelled)).
///
/// The search reads the flag and publishes its count once per block of about a thousand
/// markings, the transient solver once per iteration (one product with the generator), so a
/// cancel takes effect within milliseconds and costs nothing measurable.
///
/// ```
/// use std::sync::Arc;
/// use gspn::analysis::state_space::{AnalysisError, Monitor, Options, StateSpace};
/// use gspn::net::{NetBuilder, Servers};
/// let mut b = NetBuilder::new("loop");
/// let (p, q) = (b.place("p", 1), b.place("q", 0));
/// let t = b.exponential("t", 1.0, Servers::Single);
/// let u = b.exponential("u", 1.0, Servers::Single);
/// b.input(p, t, 1); b.output(t, q, 1); b.input(q, u, 1); b.output(u, p, 1);
/// let net = b.build().unwrap();
/// let monitor = Arc::new(Monitor::new());
/// let opts = Options { monitor: Some(Arc::clone(&monitor)), ..Options::default() };
/// let space = StateSpace::build(&net, &opts).unwrap();
/// assert_eq!(monitor.markings(), space.tangible_count());
/// monitor.cancel();
/// let r = StateSpace::build(&net, &opts);
/// assert!(matches!(r, Err(AnalysisError::Cancelled { .. })));
/// ```
#[derive(Debug, Default)]
pub struct Monitor {
    markings: AtomicUsize,
    cancelled: Arc<AtomicBool>,
    /// The transient solver's time point (index in increasing time order).
    point: AtomicUsize,
    /// Its iterations done, over all time points.
    iterations: AtomicUsize,
    /// Its iterations planned, over all time points.
    iterations_planned: AtomicUsize,
}

impl Monitor {
    /// A monitor that has seen nothing and is not cancelled.
    pub fn new() -> Monitor {
        Monitor::default()
    }

    /// Asks the search to stop as soon as it next looks.
    pub fn cancel(&self) {
        self.cancelled.store(true, Ordering::Relaxed);
    }

    /// The cancel flag itself, to hand to the steady-state solver
    /// ([`SteadyOptions::cancel`](crate::analysis::ctmc::SteadyOptions::cancel)) so one
    /// cancel stops the whole analysis.
    pub fn cancel_flag(&self) -> Arc<AtomicBool> {
        Arc::clone(&self.cancelled)
    }

    /// Whether [`Monitor::cancel`] was called.
    pub fn is_cancelled(&self) -> bool {
        self.cancelled.load(Ordering::Relaxed)
    }

    /// Markings (tangible and vanishing) the search has stored so far.
    pub fn markings(&self) -> usize {
        self.markings.load(Ordering::Relaxed)
    }

    fn set_markings(&self, n: usize) {
        self.markings.store(n, Ordering::Relaxed);
    }

    /// The transient solver's progress: the time point it works towards (0 for the
    /// earliest of the times asked), and its iterations (products with the generator) done
    /// and planned over all the time points.
    pub fn transient_progress(&self) -> (usize, usize, usize) {
        (
            self.point.load(Ordering::Relaxed),
            self.iterations.load(Ordering::Relaxed),
            self.iterations_planned.load(Ordering::Relaxed),
        )
    }

    pub(crate) fn set_transient_plan(&self, iterations: usize) {
        self.iterations_planned.store(iterations, Ordering::Relaxed);
    }

    pub(crate) fn set_transient_point(&self, point: usize) {
        self.point.store(point, Ordering::Relaxed);
    }

    pub(crate) fn set_transient_iterations(&self, done: usize) {
        self.iterations.store(done, Ordering::Relaxed);
    }
}

/// One way out of a tangible state: exponential `transition` fires at `rate`, and the
/// vanishing markings after it (if any) lead to tangible state `to` with probability `prob`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Move {
    /// The exponential transition that fires.
    pub transition: TransitionId,
    /// Its rate in the source state (`Net::exp_rate`).
    pub rate: f64,
    /// The tangible state reached.
    pub to: u32,
    /// Probability of reaching `to` (1 without vanishing markings in between).
    pub prob: f64,
}

/// Expected firings of an immediate transition on the vanishing paths after a tangible state
/// fires an exponential transition.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ImmediateFlow {
    /// The tangible state.
    pub state: u32,
    /// The exponential transition fired from it.
    pub transition: TransitionId,
    /// The immediate transition.
    pub immediate: TransitionId,
    /// Expected number of its firings before the next tangible state.
    pub expected: f64,
}

/// The tangible reachability graph, and the full graph it came from.
///
/// Markings are numbered tangible first (`0..tangible_count()`, the CTMC's states), then
/// vanishing (`tangible_count()..reachable_count()`); "global" ids range over both.
#[derive(Debug)]
pub struct StateSpace {
    places: usize,
    store: MarkingStore,
    tangible: usize,
    moves: MoveTable,
    /// Full graph over global ids; `None` when there are no vanishing markings (then it is
    /// `moves`).
    graph: Option<MoveTable>,
    initial: Vec<(u32, f64)>,
    initial_global: u32,
    flows: Vec<ImmediateFlow>,
    parent: Vec<(u32, u32)>,
    dead: Vec<u32>,
}

/// Coverability nodes to try before searching a net that has places without a structural
/// bound: scaled so the Karp–Miller tree (each node a marking, stored twice) stays around
/// 40 MB whatever the number of places. A million-place net gets 5 nodes, not 1000 (which
/// took 8 GB).
fn km_limit(places: usize) -> usize {
    (5_000_000 / places.max(1)).clamp(1, 200_000)
}

/// Searches every reachable marking of `net` (structural bounds first, Karp–Miller when they
/// do not bound every place). With `wait`, vanishing markings also list their enabled
/// exponential transitions and those targets are searched ([`explore::explore_with`]);
/// `arcs` says whether the arcs are stored or only counted.
pub(crate) fn search(
    net: &Net,
    opts: &Options,
    monitor: &Monitor,
    wait: bool,
    arcs: explore::Arcs,
) -> Result<explore::Raw, AnalysisError> {
    if monitor.is_cancelled() {
        return Err(AnalysisError::Cancelled { markings: 0 });
    }
    let mut bounds = structural_bounds(net);
    if bounds.iter().any(Option::is_none) {
        match karp_miller(net, km_limit(net.place_count()).min(opts.max_states)) {
            Coverability::Unbounded(places) => {
                return Err(AnalysisError::Unbounded {
                    places: places
                        .into_iter()
                        .map(|p| net.place(p).name.clone())
                        .collect(),
                });
            }
            Coverability::Bounded(max) => {
                bounds = max.into_iter().map(|b| Some(b as u64)).collect();
            }
            Coverability::Undecided => {}
        }
    }
    if let Some((p, &Some(b))) = bounds
        .iter()
        .enumerate()
        .find(|(_, b)| b.is_some_and(|b| b > MAX_TOKENS as u64))
    {
        return Err(AnalysisError::TooManyTokens {
            place: net.places()[p].name.clone(),
            tokens: b,
        });
    }
    let initial: Vec<u32> = net.places().iter().map(|p| p.initial).collect();
    let layout = Layout::new(&bounds, &initial);
    let threads = match opts.threads {
        0 => std::thread::available_parallelism().map_or(1, |n| n.get()),
        n => n,
    };
    explore::explore_with(
        net,
        layout,
        explore::Settings {
            limits: explore::Limits {
                states: opts.max_states,
                memory: opts.max_memory,
            },
            threads,
            monitor,
            wait,
            arcs,
        },
    )
}

impl StateSpace {
    /// Builds the state space of `net`, reporting to [`Options::monitor`] if there is one.
    pub fn build(net: &Net, opts: &Options) -> Result<StateSpace, AnalysisError> {
        let raw = search(net, opts, &opts.watcher(), false, explore::Arcs::Store)?;
        Self::from_raw(net, raw)
    }

    /// Like [`StateSpace::build`], with `policy` choosing in vanishing markings:
    /// each one's immediate transitions fire with [`Policy::distribution_or_weights`] (the
    /// policy's rule when one applies, else the net's weights) instead of the weights. The
    /// markings are the net's (a transition the policy never picks still has its target
    /// searched); the tangible chain and its measures are those of the net under the policy.
    pub fn build_under_policy(
        net: &Net,
        policy: &Policy,
        opts: &Options,
    ) -> Result<StateSpace, AnalysisError> {
        let mut raw = search(net, opts, &opts.watcher(), false, explore::Arcs::Store)?;
        if !policy.is_empty() {
            let mut m = vec![0u32; net.place_count()];
            let mut firable = Vec::new();
            for g in 0..raw.store.len() {
                if raw.tangible[g] {
                    continue;
                }
                raw.store.get(g, &mut m);
                let group = raw.moves.group_mut(g);
                firable.clear();
                firable.extend(group.iter().map(|mv| mv.transition));
                let dist = policy.distribution_or_weights(net, &m, &firable);
                for mv in group.iter_mut() {
                    mv.prob = dist
                        .iter()
                        .find(|&&(t, _)| t == mv.transition)
                        .map_or(0.0, |&(_, p)| p);
                }
            }
        }
        Self::from_raw(net, raw)
    }

    fn from_raw(net: &Net, raw: explore::Raw) -> Result<StateSpace, AnalysisError> {
        let n = raw.store.len();
        let places = net.place_count();
        let tangible = raw.tangible.iter().filter(|&&t| t).count();
        if tangible == n {
            let dead = (0..n as u32)
                .filter(|&s| raw.moves.group(s as usize).is_empty())
                .collect();
            return Ok(StateSpace {
                places,
                store: raw.store,
                tangible,
                moves: raw.moves,
                graph: None,
                initial: vec![(0, 1.0)],
                initial_global: 0,
                flows: Vec::new(),
                parent: raw.parent,
                dead,
            });
        }
        let mut order: Vec<u32> = Vec::with_capacity(n);
        order.extend((0..n as u32).filter(|&i| raw.tangible[i as usize]));
        order.extend((0..n as u32).filter(|&i| !raw.tangible[i as usize]));
        let mut new_id = vec![0u32; n];
        for (new, &old) in order.iter().enumerate() {
            new_id[old as usize] = new as u32;
        }
        let elim = eliminate(net, &raw, &order, &new_id, tangible)?;
        let explore::Raw {
            mut store,
            mut moves,
            parent,
            ..
        } = raw;
        store.permute(&order);
        moves.renumber(&order, &new_id);
        let parent = order
            .iter()
            .map(|&old| {
                let (p, t) = parent[old as usize];
                (if p == u32::MAX { p } else { new_id[p as usize] }, t)
            })
            .collect();
        let dead = (0..tangible as u32)
            .filter(|&s| moves.group(s as usize).is_empty())
            .collect();
        Ok(StateSpace {
            places,
            store,
            tangible,
            moves: elim.moves,
            graph: Some(moves),
            initial: elim.initial,
            initial_global: new_id[0],
            flows: elim.flows,
            parent,
            dead,
        })
    }

    /// Number of tangible states (the CTMC's states `0..tangible_count()`).
    pub fn tangible_count(&self) -> usize {
        self.tangible
    }

    /// Number of vanishing markings met during the search.
    pub fn vanishing_count(&self) -> usize {
        self.store.len() - self.tangible
    }

    /// Number of reachable markings, tangible and vanishing.
    pub fn reachable_count(&self) -> usize {
        self.store.len()
    }

    /// Arcs of the full reachability graph: one per (marking, fired transition), vanishing
    /// markings included (the Model Checking Contest's count for nets without immediates).
    pub fn edge_count(&self) -> usize {
        self.graph().total()
    }

    /// Arcs between tangible states after elimination: one per (state, exponential
    /// transition, tangible target).
    pub fn tangible_edge_count(&self) -> usize {
        self.moves.total()
    }

    /// The marking of tangible state `s`.
    pub fn marking(&self, s: usize) -> Vec<u32> {
        self.global_marking(s)
    }

    /// The marking with global id `g` (tangible `0..tangible_count()`, then vanishing).
    pub fn global_marking(&self, g: usize) -> Vec<u32> {
        let mut m = vec![0u32; self.places];
        self.store.get(g, &mut m);
        m
    }

    /// Unpacks the marking with global id `g` into `out` (one count per place).
    pub fn marking_into(&self, g: usize, out: &mut [u32]) {
        self.store.get(g, out);
    }

    /// Initial distribution over tangible states (a vanishing initial marking is resolved).
    pub fn initial(&self) -> &[(u32, f64)] {
        &self.initial
    }

    /// Global id of the initial marking (0 when it is tangible).
    pub fn initial_global(&self) -> usize {
        self.initial_global as usize
    }

    /// Moves out of tangible state `s`. Several moves per (s, transition) when vanishing
    /// markings lie between; their `prob` then sum to 1.
    pub fn moves(&self, s: usize) -> &[Move] {
        self.moves.group(s)
    }

    /// Expected immediate firings after each (tangible state, exponential transition); empty
    /// for nets without immediate transitions.
    pub fn immediate_flows(&self) -> &[ImmediateFlow] {
        &self.flows
    }

    /// Tangible states where nothing can fire (dead markings), ascending.
    pub fn dead_states(&self) -> &[u32] {
        &self.dead
    }

    /// Arcs out of global marking `g` in the full graph: (transition fired, global target).
    /// For vanishing markings these are the firable immediate transitions (weight 0 ones
    /// included).
    pub fn successors(&self, g: usize) -> impl Iterator<Item = (TransitionId, u32)> + '_ {
        self.graph().group(g).iter().map(|m| (m.transition, m.to))
    }

    /// Probability of each arc out of vanishing marking `g` (global id), in the order of
    /// [`successors`](Self::successors).
    pub fn vanishing_probabilities(&self, g: usize) -> impl Iterator<Item = f64> + '_ {
        self.graph().group(g).iter().map(|m| m.prob)
    }

    /// Arcs out of global marking `g` in the full graph, as moves: from a tangible marking an
    /// exponential transition with its rate (`prob` 1), from a vanishing one an immediate
    /// transition with its probability (`rate` 0). Queries read paths on this graph
    /// ([`query`](crate::analysis::query)): a vanishing marking on the way counts.
    pub fn arcs(&self, g: usize) -> &[Move] {
        self.graph().group(g)
    }

    /// One shortest firing sequence from the initial marking to global marking `g`.
    pub fn path_to(&self, g: usize) -> Vec<TransitionId> {
        let mut path = Vec::new();
        let mut v = g as u32;
        while self.parent[v as usize].0 != u32::MAX {
            let (p, t) = self.parent[v as usize];
            path.push(TransitionId(t));
            v = p;
        }
        path.reverse();
        path
    }

    /// Approximate heap bytes held (markings and arcs).
    pub fn heap_bytes(&self) -> usize {
        self.moves.heap_bytes()
            + self.graph.as_ref().map_or(0, MoveTable::heap_bytes)
            + self.store.len() * 8 * self.store.layout.words()
            + self.parent.len() * 8
    }

    fn graph(&self) -> &MoveTable {
        self.graph.as_ref().unwrap_or(&self.moves)
    }
}
