//! Solving an [`Objective`]: value iteration with sound bounds.
//!
//! Reachability, accumulated reward and the two discounted objectives are Bellman equations
//! `x(s) = opt_c [r_c + f_c·Σ p·x(s') + w_c·x(s)]` over every state (instant states take no
//! time: `f_c = 1` except under the per-step discount). Reachability and the discounted
//! objectives run *interval iteration* ([`interval`](super::interval)): a lower and an upper
//! bound from sound starts, improved together until they meet. Accumulated reward runs
//! *optimistic value iteration* (Hartmanns & Kaminski, CAV 2020): Gauss–Seidel sweeps from 0
//! give a lower bound (the value is the least fixed point); a guessed upper bound `U` is
//! accepted only once one Bellman step does not raise it anywhere (`T(U) ≤ U`, so `U` is
//! above the least fixed point). End components that would give the equations a wrong least
//! fixed point (reach-max, zero-reward ones in total-min) are collapsed first
//! ([`quotient`](super::quotient)). The result is an interval `[lower, upper]` at the initial
//! distribution, of relative width at most [`SolveOptions::precision`].
//!
//! The long-run average reward is solved in [`lra`](super::lra): maximal end components, the
//! value of each, then the best one to reach.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::quotient::Quotient;
use super::{DecisionError, DecisionModel, Objective, Rewards};
use super::{lra, objectives};

/// Relative slack of the bound checks: floating-point sums of probabilities are off by a
/// few ulps.
pub(super) const ROUNDING: f64 = 16.0 * f64::EPSILON;

/// How to solve.
#[derive(Clone, Debug)]
pub struct SolveOptions {
    /// Relative width of the result interval (default 1e-9).
    pub precision: f64,
    /// Most sweeps before giving up with [`DecisionError::NoConvergence`].
    pub max_iterations: usize,
    /// Set from another thread to stop ([`DecisionError::Cancelled`]).
    pub cancel: Option<Arc<AtomicBool>>,
    /// Which algorithm to run.
    pub algorithm: Algorithm,
}

/// The algorithm [`solve`] runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Algorithm {
    /// Value iteration with sound bounds ([`Method::OptimisticValueIteration`],
    /// [`Method::RelativeValueIteration`]).
    #[default]
    ValueIteration,
    /// Policy iteration with exact policy evaluation (sparse LU), then one bounding step of
    /// value iteration from its values ([`Method::PolicyIteration`]). For the long-run
    /// average only; the other objectives refuse it ([`DecisionError::Unsupported`]).
    PolicyIteration,
    /// Policy iteration per MEC while its evaluations stay cheap, value iteration for a MEC
    /// whose policy has a strongly connected component above
    /// [`AUTO_COMPONENT_LIMIT`](Algorithm::AUTO_COMPONENT_LIMIT) states (each round would
    /// be a large sparse LU); value iteration for the objectives other than the long-run
    /// average.
    Auto,
}

impl Algorithm {
    /// Under [`Algorithm::Auto`], the largest component of a policy's graph that policy
    /// iteration evaluates before handing the MEC to value iteration. The home models'
    /// policies have components of at most 3 states.
    pub const AUTO_COMPONENT_LIMIT: usize = 2_000;
}

impl Default for SolveOptions {
    fn default() -> Self {
        SolveOptions {
            precision: 1e-9,
            max_iterations: 1_000_000,
            cancel: None,
            algorithm: Algorithm::default(),
        }
    }
}

impl SolveOptions {
    pub(super) fn cancelled(&self) -> bool {
        self.cancel
            .as_ref()
            .is_some_and(|c| c.load(Ordering::Relaxed))
    }
}

/// Which algorithm produced a [`Solution`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Method {
    /// Optimistic value iteration: a lower bound by Gauss–Seidel sweeps, an upper bound
    /// verified by one Bellman step.
    OptimisticValueIteration,
    /// Long-run average: value iteration on the uniformised end components with the
    /// span bounds `min(Tv − v) ≤ g ≤ max(Tv − v)`, then optimistic value iteration to reach
    /// the best component.
    RelativeValueIteration,
    /// Interval iteration: a lower and an upper bound, each from a sound start, improved by
    /// the same sweeps until they meet (reachability with end components collapsed, the
    /// discounted objectives with rewards of any sign).
    IntervalIteration,
    /// Policy iteration (long-run average): each policy evaluated exactly (gain and bias by
    /// sparse LU), improved until stable; the interval from one Bellman step on its bias, as
    /// value iteration checks its own.
    PolicyIteration,
}

/// An optimal value with its bound, and a policy that attains it.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// The value at the initial distribution (middle of the interval).
    pub value: f64,
    /// Lower end of the interval that holds the exact optimum.
    pub lower: f64,
    /// Upper end.
    pub upper: f64,
    /// Per state: the value (middle of its interval; `inf` where infinite).
    pub values: Vec<f64>,
    /// Per state: the chosen choice (a global choice id of that state).
    pub policy: Vec<u32>,
    /// Sweeps done.
    pub iterations: usize,
    /// The algorithm.
    pub method: Method,
}

/// Solves `objective` on `model` with `rewards`.
pub fn solve(
    model: &DecisionModel,
    rewards: &Rewards,
    objective: &Objective,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    let max = objective.maximises();
    if opts.algorithm == Algorithm::PolicyIteration && !matches!(objective, Objective::Lra { .. }) {
        return Err(DecisionError::Unsupported(
            "policy iteration is implemented for the long-run average only".into(),
        ));
    }
    match objective {
        Objective::Lra { .. } => lra::solve(model, rewards, max, opts),
        Objective::Reach { goal, .. } => objectives::reach(model, goal, max, opts),
        Objective::Total { goal, .. } => objectives::total(model, rewards, goal, max, opts),
        Objective::Discounted { rate, .. } => {
            objectives::discounted(model, rewards, *rate, max, opts)
        }
        Objective::DiscountedPerStep { gamma, .. } => {
            objectives::discounted_per_step(model, rewards, *gamma, max, opts)
        }
    }
}

/// Bellman equations over the model's choices.
pub(super) struct Equations {
    pub(super) max: bool,
    /// Per state: a value fixed in advance (goal, infinite, dead).
    pub(super) fixed: Vec<Option<f64>>,
    /// Per state: an extra option "stop here and get this" (end components in LRA).
    pub(super) stop: Vec<Option<f64>>,
    /// Per choice: factor on `Σ p·x(s')`.
    pub(super) scale: Vec<f64>,
    /// Per choice: weight on the state's own value (uniformisation self-loop).
    pub(super) stay: Vec<f64>,
    /// End components solved as one state each (reach-max, total-min, instant loops under a
    /// continuous discount).
    pub(super) groups: Quotient,
    /// What staying in a group for ever is worth, where that is an option: `None` where it
    /// is not (a total-min minimiser must leave), `Some(0.0)` where it earns nothing more
    /// (a loop of instant steps under a continuous discount).
    pub(super) idle: Option<f64>,
}

impl Equations {
    pub(super) fn new(model: &DecisionModel, max: bool) -> Equations {
        Equations {
            max,
            fixed: vec![None; model.state_count()],
            stop: vec![None; model.state_count()],
            scale: vec![1.0; model.choice_count()],
            stay: vec![0.0; model.choice_count()],
            groups: Quotient::default(),
            idle: None,
        }
    }

    fn better(&self, a: f64, b: f64) -> bool {
        if self.max { a > b } else { a < b }
    }

    /// One Bellman update of state `s` from `x`: (value, best choice; `u32::MAX` when the
    /// stop option is best).
    #[inline]
    pub(super) fn update(
        &self,
        model: &DecisionModel,
        r: &[f64],
        x: &[f64],
        s: usize,
    ) -> (f64, u32) {
        let mut best = self.stop[s];
        let mut arg = u32::MAX;
        for c in model.choices(s) {
            let mut sum = 0.0;
            for (t, p) in model.branches(c) {
                sum += p * x[t as usize];
            }
            let v = r[c] + self.scale[c] * sum + self.stay[c] * x[s];
            if v.is_nan() {
                continue;
            }
            if best.is_none_or(|b| self.better(v, b)) {
                best = Some(v);
                arg = c as u32;
            }
        }
        (best.unwrap_or(0.0), arg)
    }

    /// One Bellman update of every state that is not fixed, in place (Gauss–Seidel, states
    /// in reverse order); a group is updated at its first member and all its members take
    /// the value. The choices go to `policy` (states) and `exits` (groups). Returns the
    /// largest relative change.
    pub(super) fn sweep(
        &self,
        model: &DecisionModel,
        r: &[f64],
        x: &mut [f64],
        policy: &mut [u32],
        exits: &mut [u32],
    ) -> f64 {
        let mut delta = 0.0f64;
        let mut note = |old: f64, v: f64| {
            let d = (v - old).abs() / v.abs().max(1e-300);
            if d > delta && (v - old).abs() > 1e-300 {
                delta = d;
            }
        };
        for s in (0..model.state_count()).rev() {
            if self.fixed[s].is_some() {
                continue;
            }
            let g = self.groups.of.get(s).copied().unwrap_or(u32::MAX);
            if g != u32::MAX {
                let members = &self.groups.members[g as usize];
                if members[0] as usize != s {
                    continue;
                }
                let (v, c) = self.group_update(model, r, x, g as usize);
                note(x[s], v);
                for &m in members {
                    x[m as usize] = v;
                }
                exits[g as usize] = c;
                continue;
            }
            let (v, c) = self.update(model, r, x, s);
            note(x[s], v);
            x[s] = v;
            policy[s] = c;
        }
        delta
    }

    /// A group's value from `x`: its best exit, or staying where that is an option and
    /// better (`u32::MAX`: no exit taken); no exit is worth 0 (a reach objective's missed
    /// goal).
    fn group_update(&self, model: &DecisionModel, r: &[f64], x: &[f64], g: usize) -> (f64, u32) {
        let (v, c) = self
            .groups
            .update(model, r, x, g, |a, b| self.better(a, b), f64::NAN);
        match self.idle {
            Some(idle) if v.is_nan() || self.better(idle, v) => (idle, u32::MAX),
            _ if v.is_nan() => (0.0, u32::MAX),
            _ => (v, c),
        }
    }

    /// One Bellman step of every state from `x` (Jacobi), groups included.
    fn step(&self, model: &DecisionModel, r: &[f64], x: &[f64], s: usize) -> f64 {
        let g = self.groups.of.get(s).copied().unwrap_or(u32::MAX);
        if g == u32::MAX {
            self.update(model, r, x, s).0
        } else {
            self.group_update(model, r, x, g as usize).0
        }
    }

    /// The policy of the last sweep completed: states without a choice yet take their
    /// best from `x`, groups steer to their exit.
    pub(super) fn finish_policy(
        &self,
        model: &DecisionModel,
        r: &[f64],
        x: &[f64],
        policy: &mut [u32],
        exits: &[u32],
    ) {
        for (s, slot) in policy.iter_mut().enumerate() {
            if *slot == u32::MAX {
                *slot = self.update(model, r, x, s).1;
                if *slot == u32::MAX {
                    *slot = model.choices(s).start as u32;
                }
            }
        }
        if !self.groups.is_empty() {
            self.groups.steer_policy(model, exits, policy);
        }
    }

    /// Optimistic value iteration; `contraction` also verifies the lower bound.
    pub(super) fn solve(
        &self,
        model: &DecisionModel,
        r: &[f64],
        opts: &SolveOptions,
        contraction: bool,
    ) -> Result<Solution, DecisionError> {
        let n = model.state_count();
        let fixed_or = |s: usize, v: f64| self.fixed[s].unwrap_or(v);
        let mut lo: Vec<f64> = (0..n).map(|s| fixed_or(s, 0.0)).collect();
        let mut policy = vec![u32::MAX; n];
        let mut exits = vec![u32::MAX; self.groups.members.len()];
        let eps = opts.precision;
        let mut threshold = eps;
        let mut iterations = 0;
        loop {
            // Gauss–Seidel sweeps until the relative change is below the threshold.
            loop {
                if opts.cancelled() {
                    return Err(DecisionError::Cancelled { iterations });
                }
                if iterations >= opts.max_iterations {
                    let v = initial_value(model, &lo);
                    return Err(DecisionError::NoConvergence {
                        iterations,
                        lower: v,
                        upper: f64::INFINITY,
                    });
                }
                iterations += 1;
                let delta = self.sweep(model, r, &mut lo, &mut policy, &mut exits);
                if delta <= threshold {
                    break;
                }
            }
            // Guess bounds around the iterate and check them with one Bellman step.
            let scale = lo
                .iter()
                .filter(|v| v.is_finite())
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let width = |v: f64| (eps * v.abs() / 4.0).max(eps * scale * 1e-3);
            let up: Vec<f64> = (0..n)
                .map(|s| self.fixed[s].unwrap_or(lo[s] + width(lo[s])))
                .collect();
            let down: Vec<f64> = (0..n)
                .map(|s| self.fixed[s].unwrap_or(lo[s] - width(lo[s])))
                .collect();
            let mut ok = true;
            let mut up2 = up.clone();
            let mut down2 = down.clone();
            for s in 0..n {
                if self.fixed[s].is_some() {
                    continue;
                }
                let v = self.step(model, r, &up, s);
                // Probabilities that sum to 1 give sums off by a few ulps: tolerate those.
                if v > up[s] + ROUNDING * up[s].abs() {
                    ok = false;
                    break;
                }
                up2[s] = v;
                if contraction {
                    let w = self.step(model, r, &down, s);
                    if w < down[s] - ROUNDING * down[s].abs() {
                        ok = false;
                        break;
                    }
                    down2[s] = w;
                }
            }
            iterations += 1;
            if ok {
                let lower_vec = if contraction { down2 } else { lo.clone() };
                let lower = initial_value(model, &lower_vec);
                let upper = initial_value(model, &up2);
                let values = (0..n)
                    .map(|s| (lower_vec[s] + up2[s]) / 2.0)
                    .map(|v| if v.is_nan() { f64::INFINITY } else { v })
                    .collect();
                self.finish_policy(model, r, &lo, &mut policy, &exits);
                return Ok(Solution {
                    value: (lower + upper) / 2.0,
                    lower,
                    upper,
                    values,
                    policy,
                    iterations,
                    method: Method::OptimisticValueIteration,
                });
            }
            threshold /= 10.0;
            if threshold < 1e-300 {
                return Err(DecisionError::NoConvergence {
                    iterations,
                    lower: initial_value(model, &lo),
                    upper: f64::INFINITY,
                });
            }
        }
    }
}

/// `Σ p·x(s)` over the initial distribution.
pub(super) fn initial_value(model: &DecisionModel, x: &[f64]) -> f64 {
    model
        .initial()
        .iter()
        .map(|&(s, p)| p * x[s as usize])
        .sum()
}
