//! The objectives other than the long-run average, each set up as Bellman equations for
//! [`Equations`]: reachability, accumulated reward, the two discounted objectives, and the
//! graph searches that fix the states whose value is known before iterating (`Pmin = 0`,
//! `Pmax < 1`, …). [`solve`](super::solve::solve) dispatches here.

use super::interval::discount_start;
use super::quotient::Quotient;
use super::solve::{Equations, Solution, SolveOptions};
use super::{DecisionError, DecisionModel, Kind, Rewards};

/// The optimal probability of reaching `goal`.
pub(super) fn reach(
    model: &DecisionModel,
    goal: &[bool],
    max: bool,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    let mut eq = Equations::new(model, max);
    // States whose optimum is 0 are fixed; what remains has one fixed point once the
    // end components a maximiser could idle in are collapsed.
    let zero = if max {
        cannot_reach(model, goal)
    } else {
        avoidable(model, goal)
    };
    for s in 0..model.state_count() {
        eq.fixed[s] = if goal[s] {
            Some(1.0)
        } else if zero[s] {
            Some(0.0)
        } else {
            None
        };
    }
    if max {
        eq.groups = Quotient::new(model, |s| eq.fixed[s].is_none(), |_| true);
    }
    let lo: Vec<f64> = eq.fixed.iter().map(|f| f.unwrap_or(0.0)).collect();
    let up: Vec<f64> = eq.fixed.iter().map(|f| f.unwrap_or(1.0)).collect();
    eq.solve_interval(model, &vec![0.0; model.choice_count()], lo, up, opts)
}

/// The optimal reward accumulated until `goal` (infinite where the goal is not reached
/// almost surely).
pub(super) fn total(
    model: &DecisionModel,
    rewards: &Rewards,
    goal: &[bool],
    max: bool,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    if rewards
        .rate
        .iter()
        .chain(&rewards.impulse)
        .any(|&r| r < 0.0)
    {
        return Err(DecisionError::Unsupported(
            "accumulated rewards must be ≥ 0".into(),
        ));
    }
    let mut eq = Equations::new(model, max);
    let infinite = if max {
        min_below_one(model, goal)
    } else {
        not_max_one(model, goal)
    };
    for s in 0..model.state_count() {
        eq.fixed[s] = if goal[s] {
            Some(0.0)
        } else if infinite[s] {
            Some(f64::INFINITY)
        } else {
            None
        };
    }
    let r = sojourn_rewards(model, rewards, |_| 1.0);
    if !max {
        // A minimiser may idle for free in a zero-reward end component, which the
        // least fixed point counts as 0 though it never reaches the goal: collapsed.
        eq.groups = Quotient::new(model, |s| eq.fixed[s].is_none(), |c| r[c] == 0.0);
    }
    eq.solve(model, &r, opts, false)
}

/// The optimal reward discounted in time at `rate`.
pub(super) fn discounted(
    model: &DecisionModel,
    rewards: &Rewards,
    rate: f64,
    max: bool,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    if !(rate > 0.0 && rate.is_finite()) {
        return Err(DecisionError::Unsupported(format!(
            "the discount rate must be > 0, not {rate}"
        )));
    }
    let mut eq = Equations::new(model, max);
    let mut r = vec![0.0; model.choice_count()];
    for s in 0..model.state_count() {
        let e = model.exit_rate(s);
        for c in model.choices(s) {
            if model.kind(s) == Kind::Instant {
                r[c] = rewards.impulse[c];
            } else {
                eq.scale[c] = e / (e + rate);
                r[c] = (rewards.rate[s] + e * rewards.impulse[c]) / (e + rate);
            }
        }
    }
    let (lo, up) = discount_start(model, &eq, &r)?;
    // A loop of instant steps that time never leaves (a Zeno end component) earns
    // nothing (`discount_start` refuses one that earns): a policy may stay there
    // for ever, worth 0, which the equations `x = x` do not say. Each maximal one
    // becomes one state whose value is the best of its exits and staying.
    eq.groups = Quotient::new(model, |s| model.kind(s) == Kind::Instant, |c| r[c] == 0.0);
    eq.idle = Some(0.0);
    eq.solve_interval(model, &r, lo, up, opts)
}

/// The optimal reward discounted by `gamma` per step (the GSPNR toolbox's objective).
pub(super) fn discounted_per_step(
    model: &DecisionModel,
    rewards: &Rewards,
    gamma: f64,
    max: bool,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    if !(gamma > 0.0 && gamma < 1.0) {
        return Err(DecisionError::Unsupported(format!(
            "the per-step discount must be in (0, 1), not {gamma}"
        )));
    }
    let eta = model.eta();
    let mut eq = Equations::new(model, max);
    let mut r = vec![0.0; model.choice_count()];
    for s in 0..model.state_count() {
        let e = model.exit_rate(s);
        match model.kind(s) {
            Kind::Dead => eq.fixed[s] = Some(0.0),
            Kind::Instant => {
                for c in model.choices(s) {
                    eq.scale[c] = gamma;
                    r[c] = rewards.impulse[c];
                }
            }
            Kind::Markovian => {
                for c in model.choices(s) {
                    eq.scale[c] = gamma * e / eta;
                    eq.stay[c] = gamma * (1.0 - e / eta);
                    r[c] = (rewards.rate[s] + e * rewards.impulse[c]) / eta;
                }
            }
        }
    }
    let (lo, up) = discount_start(model, &eq, &r)?;
    eq.solve_interval(model, &r, lo, up, opts)
}

/// Per choice: the reward of one step — the rate earned over the expected sojourn
/// `1/exit` (times `factor(s)`) plus the impulse.
pub(super) fn sojourn_rewards(
    model: &DecisionModel,
    rewards: &Rewards,
    factor: impl Fn(usize) -> f64,
) -> Vec<f64> {
    let mut r = rewards.impulse.clone();
    for s in 0..model.state_count() {
        if model.kind(s) == Kind::Markovian {
            for c in model.choices(s) {
                r[c] += factor(s) * rewards.rate[s] / model.exit_rate(s);
            }
        }
    }
    r
}

/// States where some policy misses the goal with positive probability (`Pmin < 1`): those
/// that can reach, avoiding the goal, a state where some policy avoids it for ever.
fn min_below_one(model: &DecisionModel, goal: &[bool]) -> Vec<bool> {
    backward_closure(model, avoidable(model, goal), goal)
}

/// States where some policy avoids the goal for ever (`Pmin = 0`, Prob0E): the greatest set
/// of non-goal states where some choice stays inside.
fn avoidable(model: &DecisionModel, goal: &[bool]) -> Vec<bool> {
    let n = model.state_count();
    // Prob0E: the greatest set of non-goal states where some choice stays inside.
    let mut avoid: Vec<bool> = goal.iter().map(|&g| !g).collect();
    loop {
        let mut changed = false;
        for s in 0..n {
            if avoid[s]
                && !model
                    .choices(s)
                    .any(|c| model.branches(c).all(|(t, _)| avoid[t as usize]))
            {
                avoid[s] = false;
                changed = true;
            }
        }
        if !changed {
            return avoid;
        }
    }
}

/// States from which no path reaches the goal (`Pmax = 0`).
fn cannot_reach(model: &DecisionModel, goal: &[bool]) -> Vec<bool> {
    let none = vec![false; model.state_count()];
    let reach = backward_closure(model, goal.to_vec(), &none);
    reach.iter().map(|&x| !x).collect()
}

/// States from which no policy reaches the goal with probability 1 (`Pmax < 1`).
fn not_max_one(model: &DecisionModel, goal: &[bool]) -> Vec<bool> {
    let n = model.state_count();
    let mut u = vec![true; n];
    loop {
        let mut r: Vec<bool> = goal.to_vec();
        loop {
            let mut changed = false;
            for s in 0..n {
                if !r[s]
                    && u[s]
                    && model.choices(s).any(|c| {
                        model.branches(c).all(|(t, _)| u[t as usize])
                            && model.branches(c).any(|(t, _)| r[t as usize])
                    })
                {
                    r[s] = true;
                    changed = true;
                }
            }
            if !changed {
                break;
            }
        }
        if r == u {
            return u.iter().map(|&x| !x).collect();
        }
        u = r;
    }
}

/// `set` plus every non-goal state with a choice that can reach it.
fn backward_closure(model: &DecisionModel, mut set: Vec<bool>, goal: &[bool]) -> Vec<bool> {
    let n = model.state_count();
    loop {
        let mut changed = false;
        for s in (0..n).rev() {
            if !set[s]
                && !goal[s]
                && model
                    .choices(s)
                    .any(|c| model.branches(c).any(|(t, _)| set[t as usize]))
            {
                set[s] = true;
                changed = true;
            }
        }
        if !changed {
            return set;
        }
    }
}
