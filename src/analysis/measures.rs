//! Performance measures of a GSPN from a distribution over its tangible states: mean tokens
//! and token distribution per place, P(place non-empty), throughput of every transition
//! (immediate ones through the vanishing paths), mean waiting time per place (Little's law)
//! and the probability of a marking predicate — in steady state or at transient times.
//!
//! ```
//! use gspn::analysis::measures::{Solver, SolverOptions};
//! use gspn::analysis::state_space::{Options, StateSpace};
//! use gspn::net::{NetBuilder, Servers, predicate::Predicate};
//! // cyc3 (single server): π over (2,0,0), (1,0,1), (0,0,2) is (4,2,1)/7.
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
//! let solver = Solver::new(&net, &ss);
//! let steady = solver.steady_state(&SolverOptions::default()).unwrap();
//! assert!(steady.ergodic);
//! let m = solver.measures(&steady.pi);
//! assert!((m.mean_tokens[0] - 10.0 / 7.0).abs() < 1e-12);
//! assert!((m.throughput[1] - 6.0 / 7.0).abs() < 1e-12); // t2, immediate
//! let busy = Predicate::parse(&net, "P3 > 0").unwrap();
//! assert!((solver.probability(&steady.pi, &busy) - 3.0 / 7.0).abs() < 1e-12);
//! let at = solver.transient(&[0.0, 1.0], &Default::default()).unwrap();
//! assert_eq!(at[0][0], 1.0);
//! ```

use std::sync::OnceLock;

use crate::analysis::ctmc::{Columns, Ctmc, Limiting, Method, SolveError, SteadyOptions};
use crate::analysis::state_space::StateSpace;
use crate::net::Net;
use crate::net::predicate::Predicate;

/// Options of [`Solver::steady_state`] and [`Solver::transient`].
pub type SolverOptions = SteadyOptions;

/// The CTMC of a state space, with the net, ready to solve and measure.
#[derive(Debug)]
pub struct Solver<'a> {
    net: &'a Net,
    space: &'a StateSpace,
    /// The row form, built on first use.
    chain: OnceLock<Ctmc>,
}

/// The measures of one distribution over tangible states. Vectors are indexed by
/// [`PlaceId::index`](crate::net::PlaceId::index) or
/// [`TransitionId::index`](crate::net::TransitionId::index).
#[derive(Clone, Debug, PartialEq)]
pub struct Measures {
    /// E[tokens] per place.
    pub mean_tokens: Vec<f64>,
    /// `token_distribution[p].get(k)` = P(place p holds k tokens).
    pub token_distribution: Vec<TokenDistribution>,
    /// P(place holds at least one token).
    pub prob_nonempty: Vec<f64>,
    /// Firings per unit time of each transition.
    pub throughput: Vec<f64>,
    /// Mean time a token spends in each place: E[tokens] / Σ throughput of the place's output
    /// transitions (`None` when that sum is 0).
    pub mean_wait: Vec<Option<f64>>,
}

/// The distribution of one place's token count: P(k tokens) for each count seen. Its size
/// follows the counts that occur, not the largest one (one state with 2³¹ tokens asked for
/// a 16 GiB table when it was a dense vector).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct TokenDistribution {
    /// P(k) for k < `DENSE`, by k.
    dense: Vec<f64>,
    /// P(k) for larger counts.
    sparse: std::collections::BTreeMap<u32, f64>,
}

impl TokenDistribution {
    /// Counts below this live in a plain vector.
    const DENSE: u32 = 1024;

    fn add(&mut self, k: u32, p: f64) {
        if k < Self::DENSE {
            let k = k as usize;
            if self.dense.len() <= k {
                self.dense.resize(k + 1, 0.0);
            }
            self.dense[k] += p;
        } else {
            *self.sparse.entry(k).or_insert(0.0) += p;
        }
    }

    /// P(k tokens); `None` for a count never seen.
    pub fn get(&self, k: usize) -> Option<&f64> {
        if k < Self::DENSE as usize {
            self.dense.get(k)
        } else {
            self.sparse.get(&u32::try_from(k).ok()?)
        }
    }

    /// `(k, P(k))` for every count seen (and the zero-probability counts below the largest
    /// small one), by increasing k.
    pub fn iter(&self) -> impl Iterator<Item = (u32, f64)> + '_ {
        self.dense
            .iter()
            .enumerate()
            .map(|(k, &p)| (k as u32, p))
            .chain(self.sparse.iter().map(|(&k, &p)| (k, p)))
    }
}

pub use crate::analysis::ctmc::{TRANSIENT_EPS, TransientOptions};

/// The state at one time: its measures and the probabilities of the asked predicates.
#[derive(Clone, Debug)]
pub struct TransientPoint {
    /// The time.
    pub t: f64,
    /// The measures of the distribution at `t`.
    pub measures: Measures,
    /// P(predicate) at `t`, in the order asked.
    pub probabilities: Vec<f64>,
}

/// Most iterations of uniformisation (Λ·t, Λ the largest exit rate) a transient point may
/// need: 10^11 products with the generator, hours even on the smallest chain, with Poisson
/// weights over about 14·√(Λ·t) counts. A time past it is refused ([`Solver::too_far`])
/// rather than left to run for days or, for t = 1e300, to fill the memory.
pub const MAX_UNIFORMISATION: f64 = 1e11;

/// A transient time past [`MAX_UNIFORMISATION`] ([`Solver::too_far`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TooFar {
    /// The time.
    pub t: f64,
    /// The chain's uniformisation rate Λ (its largest exit rate).
    pub lambda: f64,
}

impl std::fmt::Display for TooFar {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "t = {:e} needs about {:.3e} iterations of uniformisation (Λ·t, Λ = {}, the largest \
             exit rate); at most {MAX_UNIFORMISATION:e}: ask a smaller time, or the steady state",
            self.t,
            self.lambda * self.t,
            self.lambda
        )
    }
}

impl std::error::Error for TooFar {}

/// The first of `times` that is not a time ≥ 0 (a transient point needs one).
pub fn bad_time(times: &[f64]) -> Option<f64> {
    times
        .iter()
        .copied()
        .find(|t| !(t.is_finite() && *t >= 0.0))
}

impl<'a> Solver<'a> {
    /// A solver over the tangible states of `space`. Nothing is built yet: the row form of
    /// the generator ([`Solver::chain`]) is made on first use, and a large ergodic chain is
    /// solved from its columns alone (see [`Solver::steady_state`]).
    pub fn new(net: &'a Net, space: &'a StateSpace) -> Self {
        Solver {
            net,
            space,
            chain: OnceLock::new(),
        }
    }

    /// The generator in rows: `Q[s][to] += rate·prob` for every move (self-loops dropped),
    /// built row by row straight from the moves (no triplet list), on first use.
    pub fn chain(&self) -> &Ctmc {
        self.chain.get_or_init(|| {
            let space = self.space;
            let n = space.tangible_count();
            let mut row_ptr = Vec::with_capacity(n + 1);
            row_ptr.push(0);
            let mut cols = Vec::new();
            let mut rates = Vec::new();
            let mut row: Vec<(u32, f64)> = Vec::new();
            for s in 0..n {
                row.clear();
                self.row(s, &mut row);
                row.sort_unstable_by_key(|e| e.0);
                let start = cols.len();
                for &(to, q) in &row {
                    if cols.len() > start && cols.last() == Some(&to) {
                        *rates.last_mut().expect("an entry was pushed") += q;
                    } else {
                        cols.push(to);
                        rates.push(q);
                    }
                }
                row_ptr.push(cols.len());
            }
            cols.shrink_to_fit();
            rates.shrink_to_fit();
            Ctmc {
                n,
                row_ptr,
                cols,
                rates,
            }
        })
    }

    /// Appends the off-diagonal entries `(to, rate·prob)` of state `s` (unmerged).
    fn row(&self, s: usize, out: &mut Vec<(u32, f64)>) {
        out.extend(
            self.space
                .moves(s)
                .iter()
                .filter(|m| m.to as usize != s && m.rate * m.prob > 0.0)
                .map(|m| (m.to, m.rate * m.prob)),
        );
    }

    /// The limiting distribution from the initial marking: the steady state when the chain
    /// is ergodic, else absorption into each bottom component times its steady state.
    ///
    /// A chain above `opts.direct_limit` states (under [`Method::Auto`] or
    /// [`Method::GaussSeidel`]) is checked for irreducibility on the moves and, when
    /// irreducible, solved by Gauss–Seidel on its columns only — the row form is never built,
    /// which keeps the peak memory near the state space's own size.
    pub fn steady_state(&self, opts: &SolverOptions) -> Result<Limiting, SolveError> {
        let n = self.space.tangible_count();
        let iterative = match opts.method {
            Method::Auto => n > opts.direct_limit,
            Method::GaussSeidel => n > 1,
            Method::Direct | Method::Power => false,
        };
        if iterative && self.chain.get().is_none() && self.all_reachable_from_0() {
            let columns = Columns::from_rows(n, |s, out| self.row(s, out));
            if !columns.all_reach(0) {
                drop(columns);
                return self.chain().limiting(self.space.initial(), opts);
            }
            let scale = columns.exit.iter().fold(1.0f64, |m, &x| m.max(x));
            let solved = columns.gauss_seidel(
                opts.tolerance * scale,
                opts.max_iterations,
                opts.method == Method::Auto,
                opts.cancel.as_deref(),
            );
            drop(columns);
            match solved {
                Ok(pi) => {
                    return Ok(Limiting {
                        pi,
                        ergodic: true,
                        bottom: vec![(0..n as u32).collect()],
                        absorption: vec![1.0],
                    });
                }
                Err(e @ SolveError::Cancelled { .. }) => return Err(e),
                Err(e) if opts.method != Method::Auto => return Err(e),
                // Auto goes on to the other solvers on the row form.
                Err(_) => {}
            }
        }
        self.chain().limiting(self.space.initial(), opts)
    }

    /// Every tangible state is reachable from state 0 through the moves (half of
    /// irreducibility; [`Columns::all_reach`] is the other half). A breadth-first search: a
    /// queue and a flag per state, where Tarjan's depth-first stack would grow with the
    /// longest path.
    fn all_reachable_from_0(&self) -> bool {
        let n = self.space.tangible_count();
        let mut seen = vec![false; n];
        let mut queue: Vec<u32> = Vec::with_capacity(n);
        seen[0] = true;
        queue.push(0);
        let mut head = 0;
        while head < queue.len() {
            let s = queue[head] as usize;
            head += 1;
            for m in self.space.moves(s) {
                if m.rate * m.prob > 0.0 && !seen[m.to as usize] {
                    seen[m.to as usize] = true;
                    queue.push(m.to);
                }
            }
        }
        queue.len() == n
    }

    /// `‖πQ‖∞` from the moves (no generator is built): how far `pi` is from stationary.
    pub fn residual(&self, pi: &[f64]) -> f64 {
        let mut r = vec![0.0; pi.len()];
        let mut row = Vec::new();
        for (s, &p) in pi.iter().enumerate() {
            row.clear();
            self.row(s, &mut row);
            for &(to, q) in &row {
                r[to as usize] += p * q;
                r[s] -= p * q;
            }
        }
        r.iter().fold(0.0f64, |m, x| m.max(x.abs()))
    }

    /// π(t) at each time, from the initial marking (uniformization; [`Ctmc::transient`]).
    pub fn transient(
        &self,
        times: &[f64],
        opts: &TransientOptions,
    ) -> Result<Vec<Vec<f64>>, SolveError> {
        self.chain().transient(self.space.initial(), times, opts)
    }

    /// The largest of `times` when uniformisation would need more than
    /// [`MAX_UNIFORMISATION`] iterations to reach it (ask before [`Solver::transient`]:
    /// past it the Poisson weights alone may not fit in memory).
    pub fn too_far(&self, times: &[f64]) -> Option<TooFar> {
        let t = times.iter().copied().max_by(f64::total_cmp)?;
        let chain = self.chain();
        let lambda = (0..chain.n).map(|s| chain.exit_rate(s)).fold(0.0, f64::max);
        (lambda * t > MAX_UNIFORMISATION).then_some(TooFar { t, lambda })
    }

    /// The state at each of `times` from the initial marking: its measures and the
    /// probability of each predicate — what `plan-runner analyze --transient T --prob EXPR`
    /// reports and the viewer's panel shows (which watches it through
    /// [`TransientOptions::monitor`]).
    pub fn transient_points(
        &self,
        times: &[f64],
        predicates: &[Predicate],
        opts: &TransientOptions,
    ) -> Result<Vec<TransientPoint>, SolveError> {
        let at = self.transient(times, opts)?;
        Ok(self.points(at, times, predicates))
    }

    fn points(
        &self,
        at: Vec<Vec<f64>>,
        times: &[f64],
        predicates: &[Predicate],
    ) -> Vec<TransientPoint> {
        at.into_iter()
            .zip(times)
            .map(|(pi, &t)| TransientPoint {
                t,
                measures: self.measures(&pi),
                probabilities: self.probabilities(&pi, predicates),
            })
            .collect()
    }

    /// P(the marking satisfies each predicate) under distribution `pi`, in order.
    pub fn probabilities(&self, pi: &[f64], predicates: &[Predicate]) -> Vec<f64> {
        predicates.iter().map(|p| self.probability(pi, p)).collect()
    }

    /// Every measure of distribution `pi` over tangible states.
    pub fn measures(&self, pi: &[f64]) -> Measures {
        let net = self.net;
        let places = net.place_count();
        let mut mean = vec![0.0; places];
        let mut dist: Vec<TokenDistribution> = vec![TokenDistribution::default(); places];
        let mut throughput = vec![0.0; net.transition_count()];
        let mut m = vec![0u32; places];
        for (s, &p) in pi.iter().enumerate() {
            self.space.marking_into(s, &mut m);
            for (i, &k) in m.iter().enumerate() {
                dist[i].add(k, p);
                mean[i] += p * k as f64;
            }
            if p == 0.0 {
                continue;
            }
            for mv in self.space.moves(s) {
                throughput[mv.transition.index()] += p * mv.rate * mv.prob;
            }
        }
        if !self.space.immediate_flows().is_empty() {
            let mut rate_of = rustc_hash::FxHashMap::default();
            for (s, &p) in pi.iter().enumerate() {
                if p == 0.0 {
                    continue;
                }
                for mv in self.space.moves(s) {
                    rate_of.insert((s as u32, mv.transition), mv.rate);
                }
            }
            for f in self.space.immediate_flows() {
                let p = pi[f.state as usize];
                if p == 0.0 {
                    continue;
                }
                let rate = rate_of
                    .get(&(f.state, f.transition))
                    .copied()
                    .unwrap_or_else(|| {
                        self.space.marking_into(f.state as usize, &mut m);
                        net.exp_rate(&m, f.transition)
                    });
                throughput[f.immediate.index()] += p * rate * f.expected;
            }
        }
        let prob_nonempty = dist
            .iter()
            .map(|d| {
                d.iter()
                    .filter(|&(k, _)| k > 0)
                    .fold(0.0, |a, (_, p)| a + p)
            })
            .collect();
        let mut out_rate = vec![0.0; places];
        for t in net.transition_ids() {
            for &(p, _) in net.inputs(t) {
                out_rate[p.index()] += throughput[t.index()];
            }
        }
        let mean_wait = mean
            .iter()
            .zip(&out_rate)
            .map(|(&e, &x)| (x > 0.0).then(|| e / x))
            .collect();
        Measures {
            mean_tokens: mean,
            token_distribution: dist,
            prob_nonempty,
            throughput,
            mean_wait,
        }
    }

    /// P(the marking satisfies `predicate`) under distribution `pi`.
    pub fn probability(&self, pi: &[f64], predicate: &Predicate) -> f64 {
        let mut m = vec![0u32; self.net.place_count()];
        let mut total = 0.0;
        for (s, &p) in pi.iter().enumerate() {
            if p == 0.0 {
                continue;
            }
            self.space.marking_into(s, &mut m);
            if predicate.eval(&m) {
                total += p;
            }
        }
        total
    }
}
