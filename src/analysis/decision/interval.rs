//! Interval iteration: a lower and an upper bound, each a sound start, both improved by the
//! same Bellman sweeps until they meet (Haddad & Monmege 2018; Baier et al., CAV 2017).
//!
//! Unlike a guessed upper bound, a start `U₀` with `T(U₀) ≤ U₀` stays above the answer at
//! every sweep, so the printed interval holds whenever the iteration stops. It converges
//! when the equations have one fixed point: for reachability once the end components are
//! collapsed ([`Quotient`](super::quotient::Quotient)) and the states that cannot reach the
//! goal fixed at 0; for the discounted objectives always (a contraction), whatever the
//! sign of the rewards, from the starts [`discount_start`] computes.

use super::solve::{Equations, Method, Solution, SolveOptions, initial_value};
use super::{DecisionError, DecisionModel};
use crate::analysis::scc::tarjan;

impl Equations {
    /// Interval iteration from `lo` and `up` (`T(lo) ≥ lo`, `T(up) ≤ up`; fixed states
    /// already set in both) until the relative width at the initial distribution is at
    /// most the precision.
    pub(super) fn solve_interval(
        &self,
        model: &DecisionModel,
        r: &[f64],
        mut lo: Vec<f64>,
        mut up: Vec<f64>,
        opts: &SolveOptions,
    ) -> Result<Solution, DecisionError> {
        let n = model.state_count();
        let mut policy = vec![u32::MAX; n];
        let mut spare = vec![u32::MAX; n];
        let mut exits = vec![u32::MAX; self.groups.members.len()];
        let mut spare_exits = exits.clone();
        let mut iterations = 0;
        // A value at 0 has no relative precision: the bounds meet there only to within the
        // rounding of sums of the problem's size (the starts'), which is where they stop.
        let start = initial_value(model, &lo)
            .abs()
            .max(initial_value(model, &up).abs());
        let rounding = 64.0 * f64::EPSILON * start;
        loop {
            let (lower, upper) = (initial_value(model, &lo), initial_value(model, &up));
            let scale = lower.abs().max(upper.abs());
            if upper - lower <= opts.precision * scale || upper - lower <= rounding.max(1e-300) {
                self.finish_policy(model, r, &lo, &mut policy, &exits);
                let values = lo.iter().zip(&up).map(|(a, b)| (a + b) / 2.0).collect();
                return Ok(Solution {
                    value: (lower + upper) / 2.0,
                    lower,
                    upper,
                    values,
                    policy,
                    iterations,
                    method: Method::IntervalIteration,
                });
            }
            if opts.cancelled() {
                return Err(DecisionError::Cancelled { iterations });
            }
            if iterations >= opts.max_iterations {
                return Err(DecisionError::NoConvergence {
                    iterations,
                    lower,
                    upper,
                });
            }
            iterations += 1;
            self.sweep(model, r, &mut lo, &mut policy, &mut exits);
            self.sweep(model, r, &mut up, &mut spare, &mut spare_exits);
        }
    }
}

/// Sound starts `(lower, upper)` of a discounted objective's equations: per state
/// `U₀(s) = C + d(s)`, where `d` bounds the positive rewards collected by steps that are not
/// discounted (instant states under a continuous discount) before a discounted one, and `C`
/// the rest, `C = max_c (r⁺_c + f_c·Σ p·d) / (1 − f_c − w_c)` over the discounted choices
/// (`f` the discount factor, `w` the self-loop weight); then `T(U₀) ≤ U₀`. The lower start
/// is the same for the negative rewards. With rewards of one sign the other start is 0.
/// `Err` when a loop of undiscounted steps earns something (no finite bound).
pub(super) fn discount_start(
    model: &DecisionModel,
    eq: &Equations,
    r: &[f64],
) -> Result<(Vec<f64>, Vec<f64>), DecisionError> {
    let pos: Vec<f64> = r.iter().map(|&x| x.max(0.0)).collect();
    let neg: Vec<f64> = r.iter().map(|&x| (-x).max(0.0)).collect();
    let up = upper_start(model, eq, &pos)?;
    let lo = upper_start(model, eq, &neg)?
        .into_iter()
        .map(|x| -x)
        .collect::<Vec<_>>();
    let fix = |v: Vec<f64>| -> Vec<f64> {
        v.into_iter()
            .enumerate()
            .map(|(s, x)| eq.fixed[s].unwrap_or(x))
            .collect()
    };
    Ok((fix(lo), fix(up)))
}

/// `C + d(s)` for rewards `r ≥ 0` (see [`discount_start`]).
fn upper_start(
    model: &DecisionModel,
    eq: &Equations,
    r: &[f64],
) -> Result<Vec<f64>, DecisionError> {
    let n = model.state_count();
    // Undiscounted states: some choice keeps the whole value (factor 1).
    let free = |s: usize| {
        eq.fixed[s].is_none()
            && model
                .choices(s)
                .any(|c| eq.scale[c] + eq.stay[c] >= 1.0 - 1e-12)
    };
    let mut d = vec![0.0f64; n];
    let local: Vec<u32> = {
        let mut next = 0u32;
        (0..n)
            .map(|s| {
                if free(s) {
                    next += 1;
                    next - 1
                } else {
                    u32::MAX
                }
            })
            .collect()
    };
    let states: Vec<usize> = (0..n).filter(|&s| local[s] != u32::MAX).collect();
    let sccs = tarjan(states.len(), |v, out| {
        for c in model.choices(states[v as usize]) {
            out.extend(
                model
                    .branches(c)
                    .map(|(t, _)| local[t as usize])
                    .filter(|&l| l != u32::MAX),
            );
        }
    });
    for comp in sccs.members().iter() {
        let id = sccs.component[comp[0] as usize];
        let inside = |t: u32| {
            local[t as usize] != u32::MAX && sccs.component[local[t as usize] as usize] == id
        };
        // One value for the whole component: the best way out, a loop that earns nothing
        // repeated at no cost.
        let mut best = 0.0f64;
        let mut earns_inside = false;
        for &v in comp {
            for c in model.choices(states[v as usize]) {
                let (mut p_in, mut out) = (0.0, 0.0);
                for (t, p) in model.branches(c) {
                    if inside(t) {
                        p_in += p;
                    } else {
                        out += p * d[t as usize];
                    }
                }
                let f = eq.scale[c];
                let gain = r[c] + f * out;
                if f * p_in >= 1.0 - 1e-12 {
                    earns_inside |= r[c] > 0.0;
                    continue;
                }
                best = best.max(gain / (1.0 - f * p_in));
            }
        }
        if earns_inside {
            // A choice that earns and stays in the component: the one value above does not
            // bound it. Values per state instead, checked; none where a loop earns for ever.
            let members: Vec<usize> = comp.iter().map(|&v| states[v as usize]).collect();
            if !component_bound(model, eq, r, &members, &mut d) {
                return Err(DecisionError::Unsupported(
                    "a loop of instant steps earns a reward at no cost of time: the discounted value has no bound"
                        .into(),
                ));
            }
            continue;
        }
        for &v in comp {
            d[states[v as usize]] = best;
        }
    }
    let mut c_max = 0.0f64;
    for (s, &l) in local.iter().enumerate().take(n) {
        if eq.fixed[s].is_some() || l != u32::MAX {
            continue;
        }
        for c in model.choices(s) {
            let f = eq.scale[c] + eq.stay[c];
            if f >= 1.0 - 1e-12 {
                continue;
            }
            let out: f64 = model.branches(c).map(|(t, p)| p * d[t as usize]).sum();
            c_max = c_max.max((r[c] + eq.scale[c] * out) / (1.0 - f));
        }
    }
    // A little above the bound: the check `T(U₀) ≤ U₀` must survive rounding.
    let c_max = c_max * (1.0 + 1e-9);
    Ok((0..n).map(|s| c_max + d[s] * (1.0 + 1e-9)).collect())
}

/// Per-state bounds `d` on a strongly connected set of undiscounted states, for rewards
/// `r ≥ 0`, where a choice that earns stays inside (so no single value bounds the set):
/// Gauss–Seidel value iteration of `d = max_c (r_c + ε + f_c·Σ p·d + w_c·d)` from 0 (the
/// states below already in `d`, discounted ones 0). The ε added to every step makes the
/// fixed point a strict super-solution, so once the sweeps change `d` by less than ε/4 the
/// iterate passes the check `max_c (r_c + f_c·Σ p·d + w_c·d) ≤ d`, which is then verified.
/// `false` when the values do not settle (a loop that earns for ever, or one of zero
/// reward that ε makes grow) or the check fails.
fn component_bound(
    model: &DecisionModel,
    eq: &Equations,
    r: &[f64],
    members: &[usize],
    d: &mut [f64],
) -> bool {
    const SWEEPS: usize = 10_000;
    let scale = members
        .iter()
        .flat_map(|&s| model.choices(s))
        .map(|c| r[c])
        .fold(0.0f64, f64::max);
    let eps = 1e-9 * scale.max(f64::MIN_POSITIVE);
    let step = |d: &[f64], s: usize, extra: f64| {
        model
            .choices(s)
            .map(|c| {
                let sum: f64 = model.branches(c).map(|(t, p)| p * d[t as usize]).sum();
                r[c] + extra + eq.scale[c] * sum + eq.stay[c] * d[s]
            })
            .fold(0.0f64, f64::max)
    };
    for &s in members {
        d[s] = 0.0;
    }
    let mut settled = false;
    for _ in 0..SWEEPS {
        let mut change = 0.0f64;
        for &s in members.iter().rev() {
            let v = step(d, s, eps);
            change = change.max(v - d[s]);
            d[s] = v;
        }
        if !members.iter().all(|&s| d[s].is_finite()) {
            return false;
        }
        if change <= eps / 4.0 {
            settled = true;
            break;
        }
    }
    settled
        && members
            .iter()
            .all(|&s| step(d, s, 0.0) <= d[s] + super::solve::ROUNDING * d[s].abs())
}
