//! A plan's net analysed under its policy, with its rewards: what `plan-runner analyze PLAN`
//! prints, and what the viewer and `conform` compare a run against.
//!
//! The policy replaces the net's weights in vanishing markings
//! ([`StateSpace::build_under_policy`]: a rule's distribution where one applies, else the
//! weights — the same lookup `run` uses, [`Policy::distribution_or_weights`]); an empty policy
//! gives the bare net. The long-run measures come from the limiting distribution of the
//! tangible chain from the initial marking ([`Solver::steady_state`]), and each reward
//! structure's long-run rate is
//!
//! `Σ_s π(s)·rate(s) + Σ_t throughput(t)·impulse(t)`
//!
//! with place rates earned in tangible markings where time passes (dead markings earn
//! nothing, as in [`DecisionModel::rewards`](crate::analysis::decision::DecisionModel::rewards)),
//! so a synthesised policy's optimal value and the analysis of the policy it wrote agree.
//!
//! ```
//! use gspn::analysis::state_space::Options;
//! use gspn::analysis::under_policy::{Regime, analyse};
//! use gspn::analysis::decision::{PlaceMode, RewardSpec};
//! use gspn::analysis::measures::SolverOptions;
//! use gspn::net::{NetBuilder, Servers};
//! use gspn::policy::{Pattern, Policy, Rule};
//! // At home, a robot cleans (rate 1 back, earns 2 per unit of time) or charges (rate 2 back).
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
//! let spec = RewardSpec {
//!     name: "work".into(),
//!     places: vec![(cleaning, 2.0, PlaceMode::Marked)],
//!     transitions: vec![(full, 1.0)],
//! };
//! let (opts, solver) = (Options::default(), SolverOptions::default());
//! // Bare net: a fair coin at Home; π(Cleaning) = 2/3, π(Charging) = 1/3.
//! let bare = analyse(&net, &Policy::empty(), &[spec.clone()], &opts, &solver).unwrap();
//! assert_eq!(bare.regime, Regime::BareNet);
//! assert!((bare.rewards[0].rate - (2.0 * 2.0 / 3.0 + 2.0 / 3.0)).abs() < 1e-12);
//! // Always clean: 2 per unit of time, no charging.
//! let always = Policy::new(&net, vec![Rule { pattern: Pattern::Exact(vec![1, 0, 0]), choose: vec![(clean, 1.0)] }]).unwrap();
//! let a = analyse(&net, &always, &[spec], &opts, &solver).unwrap();
//! assert_eq!(a.regime, Regime::UnderPolicy);
//! assert!((a.rewards[0].rate - 2.0).abs() < 1e-12);
//! ```

use std::fmt;

use thiserror::Error;

use crate::analysis::ctmc::{Limiting, SolveError};
use crate::analysis::decision::RewardSpec;
use crate::analysis::measures::{Measures, Solver, SolverOptions};
use crate::analysis::state_space::{AnalysisError, Options, StateSpace};
use crate::net::Net;
use crate::policy::Policy;

/// What was analysed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Regime {
    /// The net with its own weights (no policy rule).
    BareNet,
    /// The net with the plan's policy choosing in vanishing markings.
    UnderPolicy,
}

impl Regime {
    /// The words the CLI and the viewer print: "bare net" or "net under plan policy".
    pub fn label(self) -> &'static str {
        match self {
            Regime::BareNet => "bare net",
            Regime::UnderPolicy => "net under plan policy",
        }
    }
}

impl fmt::Display for Regime {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.label())
    }
}

/// The long-run rate of one reward structure.
#[derive(Clone, Debug, PartialEq)]
pub struct RewardRate {
    /// The structure's name (`[rewards.NAME]`).
    pub name: String,
    /// Reward per unit of time in the long run: `places + transitions`.
    pub rate: f64,
    /// The part earned by place rates.
    pub places: f64,
    /// The part earned by transition impulses.
    pub transitions: f64,
}

/// The net analysed under a policy.
#[derive(Debug)]
pub struct PolicyAnalysis {
    /// Bare net or under the policy.
    pub regime: Regime,
    /// The state space, its vanishing markings resolved by the policy
    /// (`Solver::new(net, &space)` measures other distributions on it).
    pub space: StateSpace,
    /// The limiting distribution from the initial marking.
    pub limiting: Limiting,
    /// The long-run measures.
    pub measures: Measures,
    /// The long-run rate of each reward structure, in the order given.
    pub rewards: Vec<RewardRate>,
}

/// Why the analysis failed.
#[derive(Debug, Clone, PartialEq, Error)]
#[non_exhaustive]
pub enum PolicyAnalysisError {
    /// The state space could not be built (too large, unbounded, a timeless trap under the
    /// policy, cancelled).
    #[error(transparent)]
    StateSpace(#[from] AnalysisError),
    /// The steady-state solver failed.
    #[error(transparent)]
    Solve(#[from] SolveError),
}

/// Analyses `net` under `policy` (the bare net when it is empty) and evaluates `rewards`.
pub fn analyse(
    net: &Net,
    policy: &Policy,
    rewards: &[RewardSpec],
    opts: &Options,
    solver_opts: &SolverOptions,
) -> Result<PolicyAnalysis, PolicyAnalysisError> {
    let space = StateSpace::build_under_policy(net, policy, opts)?;
    Ok(solve(net, policy, space, rewards, solver_opts)?)
}

/// The second half of [`analyse`]: the long-run measures and reward rates on `space`, the
/// state space [`StateSpace::build_under_policy`] built for `net` under `policy` (a caller
/// that reports its phases, like the viewer, builds it first).
pub fn solve(
    net: &Net,
    policy: &Policy,
    space: StateSpace,
    rewards: &[RewardSpec],
    solver_opts: &SolverOptions,
) -> Result<PolicyAnalysis, SolveError> {
    let solver = Solver::new(net, &space);
    let limiting = solver.steady_state(solver_opts)?;
    let measures = solver.measures(&limiting.pi);
    drop(solver);
    let rewards = rewards
        .iter()
        .map(|spec| reward_rate(net, &space, &limiting.pi, &measures, spec))
        .collect();
    Ok(PolicyAnalysis {
        regime: if policy.is_empty() {
            Regime::BareNet
        } else {
            Regime::UnderPolicy
        },
        space,
        limiting,
        measures,
        rewards,
    })
}

/// The long-run rate of `spec` under the distribution `pi` over the tangible states of
/// `space`, with `measures` its measures (for the throughputs).
pub fn reward_rate(
    net: &Net,
    space: &StateSpace,
    pi: &[f64],
    measures: &Measures,
    spec: &RewardSpec,
) -> RewardRate {
    let mut dead = vec![false; space.tangible_count()];
    for &s in space.dead_states() {
        dead[s as usize] = true;
    }
    let mut m = vec![0u32; net.place_count()];
    let mut places = 0.0;
    for (s, &p) in pi.iter().enumerate() {
        if p == 0.0 || dead[s] {
            continue;
        }
        space.marking_into(s, &mut m);
        places += p * spec.place_rate(&m);
    }
    let transitions: f64 = spec
        .transitions
        .iter()
        .map(|&(t, r)| r * measures.throughput[t.index()])
        .sum();
    RewardRate {
        name: spec.name.clone(),
        rate: places + transitions,
        places,
        transitions,
    }
}
