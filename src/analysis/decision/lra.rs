//! Long-run average reward: maximal end components (MECs), the optimal average of each, then
//! the best MEC to reach.
//!
//! Inside a MEC every state can reach every other, so one value `g` holds for all of them.
//! It is found by value iteration on the MEC uniformised with `Λ` slightly above its largest
//! exit rate (a self-loop in every Markovian state: aperiodic): a step of the iteration is
//! `1/Λ` of time, instant states are resolved inside the step, and for any `v` the increments
//! bound the optimum, `min(Tv − v)·Λ ≤ g ≤ max(Tv − v)·Λ` (the MEC is communicating). The
//! iteration stops once the bounds are within the precision. Then every state chooses
//! between staying in its MEC (value `g`) and leaving it, solved by optimistic value
//! iteration with a stop option per MEC state; a MEC whose best is to leave steers each of
//! its states to the leaving state (an attractor), so the policy never cycles inside.

use super::policy_iteration::{mec_policy_iteration, steer};
use super::solve::{Algorithm, Equations, Method, Solution, SolveOptions};
use super::{DecisionError, DecisionModel, Kind, Rewards};
use crate::analysis::scc::{Members, tarjan};

/// The maximal end components: per state its MEC (`u32::MAX` outside any), per choice
/// whether it stays inside its state's MEC.
pub(super) struct Mecs {
    pub(super) of: Vec<u32>,
    pub(super) count: usize,
    pub(super) inside: Vec<bool>,
}

pub(super) fn mecs(model: &DecisionModel) -> Mecs {
    mecs_within(model, |_| true, |_| true)
}

/// The maximal end components of the sub-model of the states `state_ok` keeps and the
/// choices `choice_ok` keeps (a choice with a branch to a dropped state is dropped too).
pub(super) fn mecs_within(
    model: &DecisionModel,
    state_ok: impl Fn(usize) -> bool,
    choice_ok: impl Fn(usize) -> bool,
) -> Mecs {
    let n = model.state_count();
    let mut alive: Vec<bool> = (0..model.choice_count()).map(&choice_ok).collect();
    let mut live: Vec<bool> = (0..n).map(&state_ok).collect();
    let mut of = vec![u32::MAX; n];
    let mut count = 0u32;
    // Candidate sets, each closed off from the others: the components of the choices still
    // alive. A set whose components lose nothing is final; a component that loses a choice
    // or a state is searched again alone (only it can split).
    let mut work: Vec<Vec<u32>> = vec![(0..n as u32).filter(|&s| live[s as usize]).collect()];
    let mut local = vec![u32::MAX; n];
    while let Some(set) = work.pop() {
        for (i, &s) in set.iter().enumerate() {
            local[s as usize] = i as u32;
        }
        let sccs = tarjan(set.len(), |v, out| {
            for c in model.choices(set[v as usize] as usize) {
                if alive[c] {
                    out.extend(
                        model
                            .branches(c)
                            .map(|(t, _)| local[t as usize])
                            .filter(|&l| l != u32::MAX),
                    );
                }
            }
        });
        let comp = &sccs.component;
        let mut changed = vec![false; sccs.count];
        for (v, &s) in set.iter().enumerate() {
            let s = s as usize;
            let mut any = false;
            for c in model.choices(s) {
                if !alive[c] {
                    continue;
                }
                let leaves = model.branches(c).any(|(t, _)| {
                    let l = local[t as usize];
                    l == u32::MAX || comp[l as usize] != comp[v]
                });
                if leaves {
                    alive[c] = false;
                    changed[comp[v] as usize] = true;
                } else {
                    any = true;
                }
            }
            if !any {
                live[s] = false;
                changed[comp[v] as usize] = true;
            }
        }
        for &s in &set {
            local[s as usize] = u32::MAX;
        }
        for (c, members) in sccs.members().iter().enumerate() {
            let states = members.iter().map(|&v| set[v as usize]);
            if changed[c] {
                let rest: Vec<u32> = states.filter(|&s| live[s as usize]).collect();
                if !rest.is_empty() {
                    work.push(rest);
                }
            } else {
                for s in states {
                    of[s as usize] = count;
                }
                count += 1;
            }
        }
    }
    // A state outside every MEC lost all its choices on the way: none is `inside`.
    Mecs {
        of,
        count: count as usize,
        inside: alive,
    }
}

/// The optimal average of one MEC: bounds, iterations, and per state the best inside choice.
struct MecValue {
    lower: f64,
    upper: f64,
    iterations: usize,
}

#[allow(clippy::too_many_arguments)]
fn mec_value(
    model: &DecisionModel,
    rewards: &Rewards,
    mecs: &Mecs,
    states: &[u32],
    max: bool,
    opts: &SolveOptions,
    policy: &mut [u32],
    iterations_so_far: usize,
    start: Option<&[f64]>,
) -> Result<MecValue, DecisionError> {
    let Some(step) = MecStep::new(model, rewards, mecs, states, max) else {
        // Only instant states: time never passes here (a Zeno end component).
        let s = states[0] as usize;
        return Err(DecisionError::TimelessPolicy {
            marking: format!("{:?}", model.marking(s)),
        });
    };
    let mut x = match start {
        Some(v) => v.to_vec(),
        None => vec![0.0f64; model.state_count()],
    };
    let mut next = vec![0.0f64; step.markov.len()];
    let eps = opts.precision;
    let floor = step.gain_floor();
    let mut iterations = 0;
    loop {
        if opts.cancelled() {
            return Err(DecisionError::Cancelled {
                iterations: iterations_so_far + iterations,
            });
        }
        if iterations >= opts.max_iterations {
            return Err(DecisionError::NoConvergence {
                iterations: iterations_so_far + iterations,
                lower: f64::NAN,
                upper: f64::NAN,
            });
        }
        iterations += 1;
        step.instant_sweep(&mut x, policy);
        let (lo, hi) = step.markov_step(&x, &mut next, policy);
        let (glo, ghi) = (lo * step.lambda, hi * step.lambda);
        let reference = next[0];
        for (i, &s) in step.markov.iter().enumerate() {
            x[s as usize] = next[i] - reference;
        }
        if ghi - glo <= eps * glo.abs().max(ghi.abs()).max(floor) || ghi - glo <= 1e-300 {
            return Ok(MecValue {
                lower: glo,
                upper: ghi,
                iterations,
            });
        }
    }
}

/// One MEC's relative value iteration: its Markovian states uniformised at `lambda`, its
/// instant states solved in the order of their components (sinks first) after each step.
struct MecStep<'a> {
    model: &'a DecisionModel,
    rewards: &'a Rewards,
    mecs: &'a Mecs,
    max: bool,
    markov: Vec<u32>,
    instant: Vec<u32>,
    /// The instant states' components (local indices), sinks first.
    order: Members,
    lambda: f64,
}

impl<'a> MecStep<'a> {
    /// `None` when the MEC has no Markovian state.
    fn new(
        model: &'a DecisionModel,
        rewards: &'a Rewards,
        mecs: &'a Mecs,
        states: &[u32],
        max: bool,
    ) -> Option<MecStep<'a>> {
        let (instant, markov): (Vec<u32>, Vec<u32>) = states
            .iter()
            .partition(|&&s| model.kind(s as usize) == Kind::Instant);
        if markov.is_empty() {
            return None;
        }
        let lambda = markov
            .iter()
            .map(|&s| model.exit_rate(s as usize))
            .fold(0.0, f64::max)
            * 1.05;
        // Instant states sinks first (their inside choices only).
        let mut local = vec![u32::MAX; model.state_count()];
        for (i, &s) in instant.iter().enumerate() {
            local[s as usize] = i as u32;
        }
        let sccs = tarjan(instant.len(), |v, out| {
            for c in model.choices(instant[v as usize] as usize) {
                if mecs.inside[c] {
                    out.extend(
                        model
                            .branches(c)
                            .map(|(t, _)| local[t as usize])
                            .filter(|&l| l != u32::MAX),
                    );
                }
            }
        });
        let order = sccs.members();
        Some(MecStep {
            model,
            rewards,
            mecs,
            max,
            markov,
            instant,
            order,
            lambda,
        })
    }

    /// A gain near 0 (a minimum that avoids every reward) is bounded absolutely, relative to
    /// the largest reward rate a state of the MEC can earn.
    fn gain_floor(&self) -> f64 {
        let (model, rewards) = (self.model, self.rewards);
        self.markov
            .iter()
            .map(|&s| {
                let s = s as usize;
                let c = model.choices(s).start;
                rewards.rate[s].abs() + model.exit_rate(s) * rewards.impulse[c].abs()
            })
            .fold(0.0f64, f64::max)
            * 1e-3
    }

    /// The instant states' values from the current Markovian values, and their best inside
    /// choices.
    fn instant_sweep(&self, x: &mut [f64], policy: &mut [u32]) {
        let model = self.model;
        let better = |a: f64, b: f64| if self.max { a > b } else { a < b };
        let tiny = 1e-15
            * (1.0
                + self
                    .markov
                    .iter()
                    .fold(0.0f64, |m, &s| m.max(x[s as usize].abs())));
        for comp in &self.order {
            let rounds = if comp.len() == 1 { 1 } else { 10_000 };
            for _ in 0..rounds {
                let mut change = 0.0f64;
                for &v in comp {
                    let s = self.instant[v as usize] as usize;
                    let mut best: Option<f64> = None;
                    for c in model.choices(s) {
                        if !self.mecs.inside[c] {
                            continue;
                        }
                        let val = self.rewards.impulse[c]
                            + model
                                .branches(c)
                                .map(|(t, p)| p * x[t as usize])
                                .sum::<f64>();
                        if best.is_none_or(|b| better(val, b)) {
                            best = Some(val);
                            policy[s] = c as u32;
                        }
                    }
                    let val = best.unwrap_or(0.0);
                    change = change.max((val - x[s]).abs());
                    x[s] = val;
                }
                if change <= tiny {
                    break;
                }
            }
        }
    }

    /// One uniformised step of the Markovian states into `next`; the smallest and largest
    /// change, whose λ-multiples bound the gain.
    fn markov_step(&self, x: &[f64], next: &mut [f64], policy: &mut [u32]) -> (f64, f64) {
        let (model, rewards, lambda) = (self.model, self.rewards, self.lambda);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for (i, &s) in self.markov.iter().enumerate() {
            let s = s as usize;
            let c = model.choices(s).start;
            policy[s] = c as u32;
            let (e, rate) = if model.kind(s) == Kind::Dead {
                (0.0, 0.0)
            } else {
                (model.exit_rate(s), rewards.rate[s])
            };
            let sum: f64 = model.branches(c).map(|(t, p)| p * x[t as usize]).sum();
            let v =
                rate / lambda + e / lambda * (rewards.impulse[c] + sum) + (1.0 - e / lambda) * x[s];
            let d = v - x[s];
            lo = lo.min(d);
            hi = hi.max(d);
            next[i] = v;
        }
        (lo, hi)
    }
}

/// The gain of every MEC ([`mec_value`]'s bounds), each started from policy iteration's
/// bias unless the algorithm is value iteration.
struct MecGains {
    /// Per MEC: lower and upper bound of its optimal gain.
    bounds: Vec<(f64, f64)>,
    /// Sweeps and rounds over all MECs.
    iterations: usize,
    /// Whether every MEC went through policy iteration (the method reported).
    all_pi: bool,
}

fn mec_gains(
    model: &DecisionModel,
    rewards: &Rewards,
    mecs: &Mecs,
    members: &[Vec<u32>],
    max: bool,
    opts: &SolveOptions,
    policy: &mut [u32],
) -> Result<MecGains, DecisionError> {
    let pi = matches!(opts.algorithm, Algorithm::PolicyIteration | Algorithm::Auto);
    let mut gains = MecGains {
        bounds: Vec::with_capacity(members.len()),
        iterations: 0,
        all_pi: true,
    };
    for states in members {
        // Policy iteration finds the MEC's optimal policy and its bias; value iteration then
        // starts from that bias, so its first step already bounds the gain. Under `Auto` a
        // MEC whose evaluation would be a large LU goes to value iteration alone.
        let start = if pi {
            match mec_policy_iteration(model, rewards, mecs, states, max, opts, policy)? {
                Some((h, rounds)) => {
                    gains.iterations += rounds;
                    Some(h)
                }
                None => {
                    gains.all_pi = false;
                    None
                }
            }
        } else {
            None
        };
        let v = mec_value(
            model,
            rewards,
            mecs,
            states,
            max,
            opts,
            policy,
            gains.iterations,
            start.as_deref(),
        )?;
        gains.iterations += v.iterations;
        gains.bounds.push((v.lower, v.upper));
    }
    Ok(gains)
}

/// The policy outside the MECs' own choices: a state outside every MEC takes its best
/// choice towards the best MEC (`y`, the values of reaching it, with `eq`'s stop values);
/// a MEC whose best is to leave steers all its states to its best exit by an attractor;
/// a MEC whose best is to stay keeps the choices [`mec_value`] gave it.
fn exit_policy(
    model: &DecisionModel,
    mecs: &Mecs,
    members: &[Vec<u32>],
    eq: &Equations,
    y: &[f64],
    policy: &mut [u32],
) {
    let zero = vec![0.0; model.choice_count()];
    let mut leave_best: Vec<Option<(f64, u32)>> = vec![None; mecs.count];
    for (s, slot) in policy.iter_mut().enumerate() {
        let m = mecs.of[s];
        if m == u32::MAX {
            let c = eq.update(model, &zero, y, s).1;
            *slot = if c == u32::MAX {
                model.choices(s).start as u32
            } else {
                c
            };
            continue;
        }
        for c in model.choices(s) {
            if mecs.inside[c] {
                continue;
            }
            let val: f64 = model.branches(c).map(|(t, p)| p * y[t as usize]).sum();
            let stop = eq.stop[s].unwrap_or(0.0);
            if val > stop + 1e-12 * stop.abs().max(1.0)
                && leave_best[m as usize].is_none_or(|(b, _)| val > b)
            {
                leave_best[m as usize] = Some((val, c as u32));
            }
        }
    }
    for (m, best) in leave_best.iter().enumerate() {
        let Some((_, c)) = *best else { continue };
        attract(model, mecs, &members[m], c as usize, policy);
    }
}

/// Solves the long-run average reward, maximal or minimal.
pub(super) fn solve(
    model: &DecisionModel,
    rewards: &Rewards,
    max: bool,
    opts: &SolveOptions,
) -> Result<Solution, DecisionError> {
    let n = model.state_count();
    let mecs = mecs(model);
    let mut members: Vec<Vec<u32>> = vec![Vec::new(); mecs.count];
    for s in 0..n {
        if mecs.of[s] != u32::MAX {
            members[mecs.of[s] as usize].push(s as u32);
        }
    }
    let mut policy = vec![u32::MAX; n];
    let pi = matches!(opts.algorithm, Algorithm::PolicyIteration | Algorithm::Auto);
    let gains = mec_gains(model, rewards, &mecs, &members, max, opts, &mut policy)?;
    let (g, all_pi) = (gains.bounds, gains.all_pi);
    let mut iterations = gains.iterations;
    // Reaching the best MEC, as a maximisation with non-negative stop values: for max,
    // y = g − gmin; for min, y = gmax − g.
    let gmin = g.iter().map(|v| v.0).fold(f64::INFINITY, f64::min);
    let gmax = g.iter().map(|v| v.1).fold(f64::NEG_INFINITY, f64::max);
    let shift = |v: f64| if max { v - gmin } else { gmax - v };
    let unshift = |y: f64| if max { y + gmin } else { gmax - y };
    let zero = vec![0.0; model.choice_count()];
    let stop_of = |pick: fn(&(f64, f64)) -> f64, max_side: bool| {
        let mut eq = Equations::new(model, true);
        for s in 0..n {
            if mecs.of[s] != u32::MAX {
                let v = g[mecs.of[s] as usize];
                // For min the lower y comes from the upper g and vice versa.
                let gv = if max_side {
                    pick(&v)
                } else {
                    pick(&(v.1, v.0))
                };
                eq.stop[s] = Some(shift(gv));
            }
        }
        eq
    };
    let eq_lo = stop_of(|v| v.0, max);
    let eq_hi = stop_of(|v| v.1, max);
    // With one MEC every policy ends in it almost surely (the choices visited infinitely
    // often form an end component), so its value holds everywhere and any choice of a state
    // outside it will do.
    let single = mecs.count == 1;
    let (sol_lo, sol_hi) = if single {
        (None, None)
    } else {
        let a = eq_lo.solve(model, &zero, opts, false)?;
        let b = eq_hi.solve(model, &zero, opts, false)?;
        iterations += a.iterations + b.iterations;
        (Some(a), Some(b))
    };
    let (values, lower, upper) = match (&sol_lo, &sol_hi) {
        (Some(a), Some(b)) => {
            let values: Vec<f64> = (0..n)
                .map(|s| (unshift(a.values[s]) + unshift(b.values[s])) / 2.0)
                .collect();
            // y-lower of the lower run and y-upper of the upper run bound the value.
            let (y_lo, y_hi) = (a.lower, b.upper);
            let (l, u) = if max {
                (unshift(y_lo), unshift(y_hi))
            } else {
                (unshift(y_hi), unshift(y_lo))
            };
            (values, l, u)
        }
        _ => {
            let (l, u) = g[0];
            (vec![(l + u) / 2.0; n], l, u)
        }
    };
    if let Some(a) = &sol_lo {
        exit_policy(model, &mecs, &members, &eq_lo, &a.values, &mut policy);
    }
    for (s, slot) in policy.iter_mut().enumerate() {
        if *slot == u32::MAX {
            *slot = model.choices(s).start as u32;
        }
    }
    let value = match (&sol_lo, &sol_hi) {
        (Some(_), Some(_)) => {
            let v: f64 = model
                .initial()
                .iter()
                .map(|&(s, p)| p * values[s as usize])
                .sum();
            v.clamp(lower, upper)
        }
        _ => (lower + upper) / 2.0,
    };
    Ok(Solution {
        value,
        lower,
        upper,
        values,
        policy,
        iterations,
        method: if pi && all_pi {
            Method::PolicyIteration
        } else {
            Method::RelativeValueIteration
        },
    })
}

/// Steers every state of a MEC to the state owning `exit` (a choice leaving the MEC), through
/// its inside choices ([`steer`]).
fn attract(model: &DecisionModel, mecs: &Mecs, states: &[u32], exit: usize, policy: &mut [u32]) {
    let owner = states
        .iter()
        .copied()
        .find(|&s| model.choices(s as usize).contains(&exit))
        .expect("the exit belongs to a state of the MEC") as usize;
    let mut done = vec![false; model.state_count()];
    done[owner] = true;
    policy[owner] = exit as u32;
    steer(model, &mecs.inside, states, &mut done, policy);
}
