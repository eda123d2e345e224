//! Decision models: a GSPN with controllable immediate transitions and rewards as a Markov
//! automaton, and the optimal policies of its objectives.
//!
//! [`DecisionModel::build`] searches the reachable markings with the state-space code
//! (packed markings, both cores) and keeps three kinds of states:
//!
//! - **Markovian** states: tangible markings, their enabled exponential transitions racing
//!   with their exit rate; a dead marking gets a self-loop of rate 1 and earns nothing.
//! - **Decision** states: vanishing markings whose enabled immediate transitions are all
//!   controllable. Each enabled controllable transition is its own choice
//!   ([`Action::Fire`]). With [`Controls::wait`], a marking where exponential transitions are
//!   enabled too also offers [`Action::Wait`], which leads to a *WAIT copy* of the marking: a
//!   Markovian state that races only those exponential transitions.
//! - Vanishing markings with an uncontrolled immediate transition enabled are a weighted race
//!   among their uncontrolled transitions ([`Action::Race`]); they are eliminated exactly
//!   (loops of them solved by LU, as in CTMC analysis) unless [`Controls::keep_races`] keeps
//!   them as states, or WAIT makes them a decision between the race and waiting.
//!
//! Every choice records how often each transition fires on the way (the controllable
//! transition, the exponential one, and the expected firings of the eliminated races after
//! it), so any [`RewardSpec`] turns into reward rates per state and impulses per choice
//! ([`DecisionModel::rewards`]). The objectives and their solvers are in [`Objective`] and
//! [`solve`].
//!
//! ```
//! use gspn::analysis::decision::{Controls, DecisionModel, Objective, RewardSpec, SolveOptions, solve};
//! use gspn::net::{NetBuilder, Servers};
//! // A robot at home chooses: clean (rate 1, earns 2 per unit of time) or charge (rate 2, 1).
//! let mut b = NetBuilder::new("choice");
//! let home = b.place("Home", 1);
//! let (cleaning, charging) = (b.place("Cleaning", 0), b.place("Charging", 0));
//! let (clean, charge) = (b.immediate("clean", 0.0, 1), b.immediate("charge", 0.0, 1));
//! let done = b.exponential("done", 1.0, Servers::Single);
//! let full = b.exponential("full", 2.0, Servers::Single);
//! b.input(home, clean, 1); b.output(clean, cleaning, 1);
//! b.input(home, charge, 1); b.output(charge, charging, 1);
//! b.input(cleaning, done, 1); b.output(done, home, 1);
//! b.input(charging, full, 1); b.output(full, home, 1);
//! let net = b.build().unwrap();
//! let model = DecisionModel::build(&net, &Controls::zero_weight(&net), &Default::default()).unwrap();
//! assert_eq!((model.state_count(), model.decision_count()), (3, 1));
//! let mut spec = RewardSpec::default();
//! spec.places.push((cleaning, 2.0, gspn::analysis::decision::PlaceMode::Marked));
//! spec.places.push((charging, 1.0, gspn::analysis::decision::PlaceMode::Marked));
//! let rewards = model.rewards(&spec);
//! let best = solve(&model, &rewards, &Objective::Lra { max: true }, &SolveOptions::default()).unwrap();
//! assert!((best.value - 2.0).abs() < 1e-8);
//! assert_eq!(model.action(best.policy[0] as usize), gspn::analysis::decision::Action::Fire(clean));
//! ```

mod build;
mod evaluate;
mod interval;
mod lra;
mod objectives;
mod policy_graph;
mod policy_iteration;
mod quotient;
mod solve;
mod tree;

use std::sync::Arc;

use thiserror::Error;

pub use evaluate::{PolicyValue, evaluate_lra};
pub use solve::{Algorithm, Method, Solution, SolveOptions, solve};
pub use tree::compress;

use crate::analysis::state_space::packing::MarkingStore;
use crate::analysis::state_space::{AnalysisError, Monitor};
use crate::net::{Net, PlaceId, Timing, TransitionId};

/// A policy where it decides ([`DecisionModel::policy_table`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PolicyTable {
    /// Each decision marking whose choice fires a transition, and that transition.
    pub fires: Vec<(Vec<u32>, TransitionId)>,
    /// How many decision states choose WAIT (no rule: the exponential race goes on).
    pub waits: usize,
}

/// What the decision-maker controls, and how the model is built.
#[derive(Clone, Debug, PartialEq)]
pub struct Controls {
    /// Controllable immediate transitions, one flag per transition of the net.
    pub controllable: Vec<bool>,
    /// Offer WAIT in vanishing markings where exponential transitions are enabled too.
    pub wait: bool,
    /// Keep uncontrolled vanishing markings as states with one [`Action::Race`] choice
    /// instead of eliminating them (the GSPNR toolbox's MDP; needed for its per-step
    /// discount, which counts every vanishing step).
    pub keep_races: bool,
}

impl Controls {
    /// The toolbox's and Storm's convention: the net's zero-weight immediate transitions are
    /// controllable; no WAIT; races eliminated.
    pub fn zero_weight(net: &Net) -> Controls {
        let controllable = net
            .transitions()
            .iter()
            .map(|t| matches!(t.timing, Timing::Immediate { weight, .. } if weight == 0.0))
            .collect();
        Controls {
            controllable,
            wait: false,
            keep_races: false,
        }
    }

    /// Exactly `transitions` are controllable (immediate ones; others are refused by the
    /// caller).
    pub fn of(net: &Net, transitions: &[TransitionId]) -> Controls {
        let mut controllable = vec![false; net.transition_count()];
        for t in transitions {
            controllable[t.index()] = true;
        }
        Controls {
            controllable,
            wait: false,
            keep_races: false,
        }
    }
}

/// How a decision model is searched.
#[derive(Clone, Debug)]
pub struct BuildOptions {
    /// Most markings to store before giving up.
    pub max_states: usize,
    /// Threads for the search; 0 = all cores.
    pub threads: usize,
    /// Watches the search from another thread: its progress and a cancel that stops it
    /// (default: none).
    pub monitor: Option<Arc<Monitor>>,
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions {
            max_states: 10_000_000,
            threads: 0,
            monitor: None,
        }
    }
}

/// Why a decision model could not be built or solved.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum DecisionError {
    /// The search failed (too many states, unbounded, timeless trap, cancelled).
    #[error(transparent)]
    Analysis(#[from] AnalysisError),
    /// A policy loops forever through decision markings without letting time pass.
    #[error("the policy loops through vanishing markings forever, e.g. at {marking}")]
    TimelessPolicy {
        /// One marking of the loop, as `p=k,...`.
        marking: String,
    },
    /// The solver was cancelled.
    #[error("cancelled after {iterations} iterations")]
    Cancelled {
        /// Iterations done.
        iterations: usize,
    },
    /// The solver did not reach the precision within its iteration limit.
    #[error(
        "no convergence after {iterations} iterations (interval [{lower}, {upper}]); raise the limit or the precision"
    )]
    NoConvergence {
        /// Iterations done.
        iterations: usize,
        /// Lower bound reached.
        lower: f64,
        /// Upper bound reached.
        upper: f64,
    },
    /// The objective does not suit the model (e.g. a per-step discount ≥ 1).
    #[error("{0}")]
    Unsupported(String),
}

/// What a choice does.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Action {
    /// Fire this controllable immediate transition.
    Fire(TransitionId),
    /// Let the uncontrolled immediate transitions race by weight.
    Race,
    /// Wait: go to the WAIT copy, where only exponential transitions fire.
    Wait,
    /// Time passes: the enabled exponential transitions race (the one choice of a Markovian
    /// state).
    Delay,
}

/// The kind of a state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Kind {
    /// Exponential transitions race (exit rate > 0).
    Markovian,
    /// A dead marking: a self-loop of rate 1 that earns nothing.
    Dead,
    /// Time does not pass; one of the choices is taken at once.
    Instant,
}

/// Place rewards: per token, or per marked place (the toolbox's indicator).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlaceMode {
    /// Rate × tokens in the place.
    PerToken,
    /// Rate while the place holds at least one token.
    Marked,
}

/// One reward structure over the net: rates earned per unit of time in Markovian states,
/// impulses earned per firing.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RewardSpec {
    /// Name (the plan's `[rewards.NAME]`).
    pub name: String,
    /// Per-time rewards of places.
    pub places: Vec<(PlaceId, f64, PlaceMode)>,
    /// Impulse rewards of transitions.
    pub transitions: Vec<(TransitionId, f64)>,
}

impl RewardSpec {
    /// The impulse each transition of `net` earns when it fires (repeated entries add up).
    pub fn impulses(&self, net: &Net) -> Vec<f64> {
        let mut v = vec![0.0; net.transition_count()];
        for &(t, r) in &self.transitions {
            v[t.index()] += r;
        }
        v
    }

    /// The rate its places earn per unit of time in marking `m` (where time passes).
    pub fn place_rate(&self, m: &[u32]) -> f64 {
        self.places
            .iter()
            .map(|&(p, r, mode)| match mode {
                PlaceMode::PerToken => r * m[p.index()] as f64,
                PlaceMode::Marked if m[p.index()] > 0 => r,
                PlaceMode::Marked => 0.0,
            })
            .sum()
    }
}

/// A reward structure evaluated on a model.
#[derive(Clone, Debug, PartialEq)]
pub struct Rewards {
    /// Per state: reward per unit of time (Markovian states and WAIT copies; 0 elsewhere).
    pub rate: Vec<f64>,
    /// Per choice: expected impulse reward earned when it is taken.
    pub impulse: Vec<f64>,
}

/// A Markov automaton built from a GSPN. States `0..state_count()`; choices numbered
/// globally, state `s` owning [`choices(s)`](Self::choices).
#[derive(Debug)]
pub struct DecisionModel {
    places: usize,
    store: MarkingStore,
    /// Per state: the marking (store id).
    marking: Vec<u32>,
    /// Per state: a WAIT copy.
    copy: Vec<bool>,
    kind: Vec<Kind>,
    /// Per state: exit rate (Markovian; 1 for dead; 0 for instant).
    exit: Vec<f64>,
    choice_start: Vec<u32>,
    action: Vec<Action>,
    branch_start: Vec<u32>,
    to: Vec<u32>,
    prob: Vec<f64>,
    count_start: Vec<u32>,
    count_t: Vec<u32>,
    count_x: Vec<f64>,
    initial: Vec<(u32, f64)>,
    copies: usize,
    eliminated: usize,
    total_markings: usize,
}

impl DecisionModel {
    /// Builds the decision model of `net` under `controls`, reporting the search's progress
    /// to [`BuildOptions::monitor`] if there is one.
    pub fn build(
        net: &Net,
        controls: &Controls,
        opts: &BuildOptions,
    ) -> Result<DecisionModel, DecisionError> {
        build::build(net, controls, opts)
    }

    /// Number of states (Markovian, dead, decision, WAIT copies).
    pub fn state_count(&self) -> usize {
        self.kind.len()
    }

    /// Number of reachable markings the search stored (eliminated ones included).
    pub fn marking_count(&self) -> usize {
        self.total_markings
    }

    /// Number of WAIT copies.
    pub fn wait_copies(&self) -> usize {
        self.copies
    }

    /// Number of vanishing markings eliminated.
    pub fn eliminated_count(&self) -> usize {
        self.eliminated
    }

    /// The GSPNR toolbox's MDP size: every reachable marking plus the WAIT copies.
    pub fn toolbox_state_count(&self) -> usize {
        self.total_markings + self.copies
    }

    /// States with a real decision (instant states with more than one choice).
    pub fn decision_count(&self) -> usize {
        (0..self.state_count())
            .filter(|&s| self.kind[s] == Kind::Instant && self.choices(s).len() > 1)
            .count()
    }

    /// Total number of choices.
    pub fn choice_count(&self) -> usize {
        self.action.len()
    }

    /// Total number of probabilistic branches.
    pub fn branch_count(&self) -> usize {
        self.to.len()
    }

    /// The kind of state `s`.
    pub fn kind(&self, s: usize) -> Kind {
        self.kind[s]
    }

    /// Exit rate of state `s` (0 for instant states, 1 for dead ones).
    pub fn exit_rate(&self, s: usize) -> f64 {
        self.exit[s]
    }

    /// Whether state `s` is a WAIT copy.
    pub fn is_wait_copy(&self, s: usize) -> bool {
        self.copy[s]
    }

    /// The marking of state `s` (a WAIT copy has its original's marking).
    pub fn marking(&self, s: usize) -> Vec<u32> {
        let mut m = vec![0u32; self.places];
        self.store.get(self.marking[s] as usize, &mut m);
        m
    }

    /// What `policy` (one choice per state, as [`Solution::policy`]) does where there is a
    /// decision: the marking and transition of every state with two or more choices whose
    /// choice fires a transition, and how many choose WAIT. The table a plan's policy is
    /// written from ([`compress`] turns it into rules; each row is also an exact rule).
    pub fn policy_table(&self, policy: &[u32]) -> PolicyTable {
        let mut table = PolicyTable::default();
        for (s, &choice) in policy.iter().enumerate().take(self.state_count()) {
            if self.choices(s).len() < 2 {
                continue;
            }
            match self.action(choice as usize) {
                Action::Fire(t) => table.fires.push((self.marking(s), t)),
                Action::Wait => table.waits += 1,
                Action::Race | Action::Delay => {}
            }
        }
        table
    }

    /// The global ids of the choices of state `s`.
    pub fn choices(&self, s: usize) -> std::ops::Range<usize> {
        self.choice_start[s] as usize..self.choice_start[s + 1] as usize
    }

    /// What choice `c` does.
    pub fn action(&self, c: usize) -> Action {
        self.action[c]
    }

    /// The branches `(state, probability)` of choice `c`.
    pub fn branches(&self, c: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.branch_start[c] as usize..self.branch_start[c + 1] as usize;
        self.to[r.clone()]
            .iter()
            .copied()
            .zip(self.prob[r].iter().copied())
    }

    /// Expected firings of each transition when choice `c` is taken (the transition chosen or
    /// raced, then the eliminated races after it).
    pub fn firings(&self, c: usize) -> impl Iterator<Item = (TransitionId, f64)> + '_ {
        let r = self.count_start[c] as usize..self.count_start[c + 1] as usize;
        self.count_t[r.clone()]
            .iter()
            .map(|&t| TransitionId(t))
            .zip(self.count_x[r].iter().copied())
    }

    /// The initial distribution over states (a vanishing initial marking is resolved).
    pub fn initial(&self) -> &[(u32, f64)] {
        &self.initial
    }

    /// Flags the states whose marking satisfies `goal`.
    pub fn states_where(&self, mut goal: impl FnMut(&[u32]) -> bool) -> Vec<bool> {
        let mut m = vec![0u32; self.places];
        (0..self.state_count())
            .map(|s| {
                self.store.get(self.marking[s] as usize, &mut m);
                goal(&m)
            })
            .collect()
    }

    /// Evaluates a reward structure: place rewards in Markovian states (dead and instant
    /// states earn no rate), impulses per choice from its expected firings.
    pub fn rewards(&self, spec: &RewardSpec) -> Rewards {
        let mut m = vec![0u32; self.places];
        let rate = (0..self.state_count())
            .map(|s| {
                if self.kind[s] != Kind::Markovian {
                    return 0.0;
                }
                self.store.get(self.marking[s] as usize, &mut m);
                spec.place_rate(&m)
            })
            .collect();
        let mut per_t = vec![0.0; self.count_t.iter().max().map_or(0, |&t| t as usize + 1)];
        for &(t, r) in &spec.transitions {
            if t.index() < per_t.len() {
                per_t[t.index()] += r;
            }
        }
        let impulse = (0..self.choice_count())
            .map(|c| self.firings(c).map(|(t, x)| x * per_t[t.index()]).sum())
            .collect();
        Rewards { rate, impulse }
    }

    /// Rewards that measure time: rate 1 in every Markovian state, no impulses.
    pub fn time_rewards(&self) -> Rewards {
        Rewards {
            rate: self
                .kind
                .iter()
                .map(|&k| if k == Kind::Markovian { 1.0 } else { 0.0 })
                .collect(),
            impulse: vec![0.0; self.choice_count()],
        }
    }

    /// The largest exit rate of a Markovian state (WAIT copies included, dead states not).
    pub fn max_exit_rate(&self) -> f64 {
        (0..self.state_count())
            .filter(|&s| self.kind[s] == Kind::Markovian)
            .map(|s| self.exit[s])
            .fold(0.0, f64::max)
    }

    /// The toolbox's uniformisation constant: the largest exit rate plus one.
    pub fn eta(&self) -> f64 {
        self.max_exit_rate() + 1.0
    }
}

/// The objectives a policy can optimise. `max` says maximise (else minimise).
#[derive(Clone, Debug, PartialEq)]
pub enum Objective {
    /// Long-run average reward per unit of time.
    Lra {
        /// Maximise.
        max: bool,
    },
    /// Probability of ever reaching a goal state.
    Reach {
        /// Maximise.
        max: bool,
        /// Goal flag per state ([`DecisionModel::states_where`]).
        goal: Vec<bool>,
    },
    /// Expected reward accumulated until a goal state is reached (infinite where the goal is
    /// missed with positive probability). With [`DecisionModel::time_rewards`]: the expected
    /// time. Rewards must be ≥ 0.
    Total {
        /// Maximise.
        max: bool,
        /// Goal flag per state.
        goal: Vec<bool>,
    },
    /// Expected reward discounted continuously: a reward at time t counts `e^(−rate·t)`.
    Discounted {
        /// Maximise.
        max: bool,
        /// Discount rate per unit of time (> 0).
        rate: f64,
    },
    /// The GSPNR toolbox's objective: `R + γ·ΣPV` per step of the MDP uniformised with
    /// [`DecisionModel::eta`], every vanishing step discounted too (build with
    /// [`Controls::keep_races`] to count race markings as steps, as the toolbox does).
    DiscountedPerStep {
        /// Maximise.
        max: bool,
        /// γ in (0, 1).
        gamma: f64,
    },
}

impl Objective {
    /// Whether the objective maximises.
    pub fn maximises(&self) -> bool {
        match *self {
            Objective::Lra { max }
            | Objective::Reach { max, .. }
            | Objective::Total { max, .. }
            | Objective::Discounted { max, .. }
            | Objective::DiscountedPerStep { max, .. } => max,
        }
    }
}
