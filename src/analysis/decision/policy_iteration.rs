//! Policy iteration for the long-run average reward inside one maximal end component.
//!
//! A MEC is communicating, so its optimal average `g` is one number. Each round evaluates the
//! current policy exactly — gain `g` and bias `h` from the linear system (sparse LU)
//!
//! - Markovian state `s` (exit rate `E`): `g + E·h(s) − E·Σ p·h(s') = rate(s) + E·impulse`,
//! - instant state `s`: `h(s) − Σ p·h(s') = impulse`,
//! - `h(ref) = 0` for one recurrent Markovian state,
//!
//! then improves it: an instant state switches to a choice whose `impulse + Σ p·h(s')` is
//! strictly better (Markovian states have one choice). A policy whose chain has several
//! bottom components is repaired first: each bottom component's gain is evaluated alone, and
//! every state outside the best one is steered to it ([`steer`]: almost surely, through
//! choices that stay in the MEC), which makes it unichain with that best gain. The gain never
//! gets worse from round to round; the rounds stop when no state switches.
//!
//! The result is not trusted as such: the caller ([`lra`](super::lra)) starts its value
//! iteration from the final bias, whose one Bellman step gives the sound interval
//! `min(Tv − v)·Λ ≤ g ≤ max(Tv − v)·Λ` — tight at once when the policy is optimal.

use super::lra::Mecs;
use super::solve::SolveOptions;
use super::{DecisionError, DecisionModel, Kind, Rewards};
use crate::analysis::scc::tarjan;
use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};

/// Most rounds before giving up (each round at least improves the bias).
const MAX_ROUNDS: usize = 1000;

/// Runs policy iteration on the MEC `states`; writes the policy of its instant states into
/// `policy` and returns the bias per state (indexed globally; 0 outside the MEC) and the
/// number of rounds.
pub(super) fn mec_policy_iteration(
    model: &DecisionModel,
    rewards: &Rewards,
    mecs: &Mecs,
    states: &[u32],
    max: bool,
    opts: &SolveOptions,
    policy: &mut [u32],
) -> Result<(Vec<f64>, usize), DecisionError> {
    let n = model.state_count();
    let mut h = vec![0.0f64; n];
    // A dead state is a MEC alone: gain 0, nothing to choose.
    if states.iter().any(|&s| model.kind(s as usize) == Kind::Dead) {
        return Ok((h, 0));
    }
    let mut local = vec![u32::MAX; n];
    for (i, &s) in states.iter().enumerate() {
        local[s as usize] = i as u32;
    }
    let better = |a: f64, b: f64| if max { a > b } else { a < b };
    // Start with the first inside choice that time can leave: an instant state prefers a
    // choice reaching a Markovian state, so the start has no timeless loop when avoidable.
    for &s in states {
        let s = s as usize;
        let inside: Vec<usize> = model.choices(s).filter(|&c| mecs.inside[c]).collect();
        policy[s] = inside
            .iter()
            .copied()
            .find(|&c| {
                model
                    .branches(c)
                    .any(|(t, _)| model.kind(t as usize) != Kind::Instant)
            })
            .unwrap_or(inside[0]) as u32;
    }
    let mut rounds = 0;
    loop {
        if opts.cancelled() {
            return Err(DecisionError::Cancelled { iterations: rounds });
        }
        if rounds >= MAX_ROUNDS {
            return Err(DecisionError::NoConvergence {
                iterations: rounds,
                lower: f64::NAN,
                upper: f64::NAN,
            });
        }
        rounds += 1;
        let reference = make_unichain(model, rewards, mecs, states, &local, max, policy)?;
        let x = evaluate(model, rewards, states, &local, policy, reference)?;
        for (i, &s) in states.iter().enumerate() {
            h[s as usize] = if i == reference { 0.0 } else { x[i] };
        }
        // Improvement: instant states only (a Markovian state has one choice).
        let mut changed = false;
        for &s in states {
            let s = s as usize;
            if model.kind(s) != Kind::Instant || model.choices(s).len() < 2 {
                continue;
            }
            let value = |c: usize| {
                rewards.impulse[c]
                    + model
                        .branches(c)
                        .map(|(t, p)| p * h[t as usize])
                        .sum::<f64>()
            };
            let current = value(policy[s] as usize);
            let tol = 1e-10 * (1.0 + current.abs());
            let mut best = (current, policy[s] as usize);
            for c in model.choices(s) {
                if !mecs.inside[c] || c == policy[s] as usize {
                    continue;
                }
                let v = value(c);
                if better(v, best.0) && (v - current).abs() > tol {
                    best = (v, c);
                }
            }
            if best.1 != policy[s] as usize {
                policy[s] = best.1 as u32;
                changed = true;
            }
        }
        if !changed {
            return Ok((h, rounds));
        }
    }
}

/// Makes the policy unichain: when its chain on the MEC has several bottom components (or one
/// where time never passes), evaluates each and steers every state to the best. Returns the
/// local index of a Markovian state of the remaining bottom component.
fn make_unichain(
    model: &DecisionModel,
    rewards: &Rewards,
    mecs: &Mecs,
    states: &[u32],
    local: &[u32],
    max: bool,
    policy: &mut [u32],
) -> Result<usize, DecisionError> {
    let succ = |policy: &[u32], v: u32, out: &mut Vec<u32>| {
        let s = states[v as usize] as usize;
        out.extend(
            model
                .branches(policy[s] as usize)
                .filter(|&(_, p)| p > 0.0)
                .map(|(t, _)| local[t as usize]),
        );
    };
    let sccs = tarjan(states.len(), |v, out| succ(policy, v, out));
    let bottom = sccs.bottom(|v, out| succ(policy, v, out));
    let members = sccs.members();
    let markovian = |comp: &Vec<u32>| {
        comp.iter()
            .copied()
            .find(|&v| model.kind(states[v as usize] as usize) == Kind::Markovian)
    };
    let bottoms: Vec<usize> = (0..sccs.count).filter(|&c| bottom[c]).collect();
    if let [only] = bottoms[..]
        && let Some(r) = markovian(&members[only])
    {
        return Ok(r as usize);
    }
    // Several bottom components: the gain of each (timeless ones are worst).
    let better = |a: f64, b: f64| if max { a > b } else { a < b };
    let mut best: Option<(f64, usize, u32)> = None;
    for &c in &bottoms {
        let Some(r) = markovian(&members[c]) else {
            continue;
        };
        let comp: Vec<u32> = members[c].iter().map(|&v| states[v as usize]).collect();
        let mut sub_local = vec![u32::MAX; model.state_count()];
        for (i, &s) in comp.iter().enumerate() {
            sub_local[s as usize] = i as u32;
        }
        let r_sub = sub_local[states[r as usize] as usize] as usize;
        let x = evaluate(model, rewards, &comp, &sub_local, policy, r_sub)?;
        let g = x[r_sub];
        if best.is_none_or(|(b, _, _)| better(g, b)) {
            best = Some((g, c, r));
        }
    }
    let Some((_, c, r)) = best else {
        return Err(DecisionError::TimelessPolicy {
            marking: format!("{:?}", model.marking(states[0] as usize)),
        });
    };
    let mut target = vec![false; model.state_count()];
    for &v in &members[c] {
        target[states[v as usize] as usize] = true;
    }
    steer(model, &mecs.inside, states, &mut target, policy);
    Ok(r as usize)
}

/// Steers every state of `states` not in `target` towards it, almost surely: a backward
/// search over the choices flagged `inside`, each state taking a choice with a branch into
/// the states already steered (Markovian states have one choice, which then qualifies).
/// `target` grows to every state steered.
pub(super) fn steer(
    model: &DecisionModel,
    inside: &[bool],
    states: &[u32],
    target: &mut [bool],
    policy: &mut [u32],
) {
    // Predecessors (state, choice) of each state, over inside choices.
    let mut local = vec![u32::MAX; model.state_count()];
    for (i, &s) in states.iter().enumerate() {
        local[s as usize] = i as u32;
    }
    let mut start = vec![0u32; states.len() + 1];
    for &s in states {
        for c in model.choices(s as usize).filter(|&c| inside[c]) {
            for (t, _) in model.branches(c) {
                if local[t as usize] != u32::MAX {
                    start[local[t as usize] as usize + 1] += 1;
                }
            }
        }
    }
    for i in 0..states.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut pred = vec![(0u32, 0u32); start[states.len()] as usize];
    for &s in states {
        for c in model.choices(s as usize).filter(|&c| inside[c]) {
            for (t, _) in model.branches(c) {
                let l = local[t as usize];
                if l != u32::MAX {
                    pred[fill[l as usize] as usize] = (s, c as u32);
                    fill[l as usize] += 1;
                }
            }
        }
    }
    let mut queue: Vec<u32> = states
        .iter()
        .copied()
        .filter(|&s| target[s as usize])
        .collect();
    let mut head = 0;
    while head < queue.len() {
        let t = local[queue[head] as usize] as usize;
        head += 1;
        for &(s, c) in &pred[start[t] as usize..start[t + 1] as usize] {
            if !target[s as usize] {
                target[s as usize] = true;
                policy[s as usize] = c;
                queue.push(s);
            }
        }
    }
}

/// The gain and bias of the policy on `states` (closed under it), `h(reference) = 0`: the
/// local solution vector, whose entry `reference` is the gain.
///
/// The gain would be a dense column of the system (every Markovian row has it), which makes a
/// sparse LU fill in; so the reference row and column are left out instead: with `M` the
/// rows and columns of the other states, `M·u = b` (rewards) and `M·w = τ` (time: 1 in each
/// Markovian row) give `h = u − g·w` (expected reward and time to reach the reference), and
/// the reference's own row then gives `g`. `M` is regular when the reference is recurrent and
/// reached from every state — the policy is unichain ([`make_unichain`]).
fn evaluate(
    model: &DecisionModel,
    rewards: &Rewards,
    states: &[u32],
    local: &[u32],
    policy: &[u32],
    reference: usize,
) -> Result<Vec<f64>, DecisionError> {
    let k = states.len();
    // Local index without the reference.
    let at = |i: usize| if i > reference { i - 1 } else { i };
    let mut triplets: Vec<Triplet<usize, usize, f64>> = Vec::with_capacity(4 * k);
    let mut b = vec![0.0f64; k];
    let mut tau = vec![0.0f64; k];
    // The reference's row: (column, coefficient) over the other states.
    let mut ref_row: Vec<(usize, f64)> = Vec::new();
    for (i, &s) in states.iter().enumerate() {
        let s = s as usize;
        let c = policy[s] as usize;
        let (scale, timed) = match model.kind(s) {
            Kind::Instant => (1.0, false),
            Kind::Markovian => (model.exit_rate(s), true),
            Kind::Dead => (1.0, true),
        };
        if timed {
            tau[i] = 1.0;
            b[i] = rewards.rate[s] + scale * rewards.impulse[c];
        } else {
            b[i] = rewards.impulse[c];
        }
        if i == reference {
            for (t, p) in model.branches(c) {
                let j = local[t as usize] as usize;
                if j != reference {
                    ref_row.push((at(j), -scale * p));
                }
            }
            continue;
        }
        triplets.push(Triplet::new(at(i), at(i), scale));
        for (t, p) in model.branches(c) {
            let j = local[t as usize] as usize;
            if j != reference {
                triplets.push(Triplet::new(at(i), at(j), -scale * p));
            }
        }
    }
    let fail = |e: String| {
        DecisionError::Unsupported(format!("policy evaluation (sparse LU on {k} states): {e}"))
    };
    let m = k - 1;
    let (u, w) = if m == 0 {
        (Vec::new(), Vec::new())
    } else {
        let a = SparseColMat::<usize, f64>::try_new_from_triplets(m, m, &triplets)
            .map_err(|e| fail(format!("{e:?}")))?;
        let lu = a.sp_lu().map_err(|e| fail(format!("{e:?}")))?;
        let rhs = Mat::from_fn(m, 2, |r, col| {
            let i = if r >= reference { r + 1 } else { r };
            if col == 0 { b[i] } else { tau[i] }
        });
        let x = lu.solve(&rhs);
        let u: Vec<f64> = (0..m).map(|r| x[(r, 0)]).collect();
        let w: Vec<f64> = (0..m).map(|r| x[(r, 1)]).collect();
        (u, w)
    };
    // The reference's row, h(reference) = 0: g·τ + Σ a_j·(u_j − g·w_j) = b.
    let (au, aw) = ref_row
        .iter()
        .fold((0.0, 0.0), |(x, y), &(j, a)| (x + a * u[j], y + a * w[j]));
    let g = (b[reference] - au) / (tau[reference] - aw);
    let mut x = vec![0.0f64; k];
    for i in 0..k {
        x[i] = if i == reference {
            g
        } else {
            u[at(i)] - g * w[at(i)]
        };
    }
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err(fail("singular matrix".into()))
    }
}
