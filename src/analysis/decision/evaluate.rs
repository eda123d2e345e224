//! Exact evaluation of a policy: the CTMC it induces, solved by the CTMC code.
//!
//! Under a fixed (possibly randomised) policy the instant states are an absorbing chain
//! ([`absorb`](super::absorb)): each leads to Markovian states with known probabilities and
//! expected impulses. What remains is a CTMC over the Markovian states; its limiting
//! distribution from the initial distribution ([`Ctmc::limiting`]) gives the long-run average
//! reward `Σ π(s)·(rate(s) + exit(s)·impulse(s))`.

use super::{DecisionError, DecisionModel, Kind, Rewards};
use crate::analysis::absorbing::{AbsorbError, Target, absorb};
use crate::analysis::ctmc::{Ctmc, SteadyOptions};

/// The long-run average reward of one policy.
#[derive(Clone, Debug, PartialEq)]
pub struct PolicyValue {
    /// Long-run average reward per unit of time, from the initial distribution.
    pub lra: f64,
    /// States of the induced CTMC (the Markovian states).
    pub ctmc_states: usize,
    /// Residual `‖πQ‖∞` of the limiting distribution's bottom components.
    pub residual: f64,
}

/// Evaluates the policy that takes, in state `s`, the choices `choose(s)` with their
/// probabilities (Markovian states have one choice and ignore it).
pub fn evaluate_lra(
    model: &DecisionModel,
    rewards: &Rewards,
    mut choose: impl FnMut(usize) -> Vec<(usize, f64)>,
) -> Result<PolicyValue, DecisionError> {
    let n = model.state_count();
    let mut index = vec![u32::MAX; n];
    let (mut markov, mut instant) = (Vec::new(), Vec::new());
    for (s, slot) in index.iter_mut().enumerate() {
        if model.kind(s) == Kind::Instant {
            *slot = instant.len() as u32;
            instant.push(s);
        } else {
            *slot = markov.len() as u32;
            markov.push(s);
        }
    }
    let target = |t: u32| {
        if model.kind(t as usize) == Kind::Instant {
            Target::In(index[t as usize])
        } else {
            Target::Out(index[t as usize])
        }
    };
    let picks: Vec<Vec<(usize, f64)>> = instant.iter().map(|&s| choose(s)).collect();
    let absorbed = absorb(
        instant.len(),
        |v, out| {
            for &(c, q) in &picks[v as usize] {
                for (t, p) in model.branches(c) {
                    out.push((target(t), q * p));
                }
            }
        },
        |v, out| {
            let imp: f64 = picks[v as usize]
                .iter()
                .map(|&(c, q)| q * rewards.impulse[c])
                .sum();
            out.push((0, imp));
        },
    )
    .map_err(|e| match e {
        AbsorbError::Trap(v) => DecisionError::TimelessPolicy {
            marking: format!("{:?}", model.marking(instant[v as usize])),
        },
        e => DecisionError::Analysis(e.into_analysis(|_| String::new())),
    })?;
    let mut triplets = Vec::new();
    let mut reward = vec![0.0; markov.len()];
    for (i, &s) in markov.iter().enumerate() {
        if model.kind(s) == Kind::Dead {
            continue;
        }
        let e = model.exit_rate(s);
        let c = model.choices(s).start;
        let mut imp = rewards.impulse[c];
        for (t, p) in model.branches(c) {
            match target(t) {
                Target::Out(k) => triplets.push((i as u32, k, e * p)),
                Target::In(w) => {
                    for &(k, q) in &absorbed.dist[w as usize] {
                        triplets.push((i as u32, k, e * p * q));
                    }
                    imp += p * absorbed.counts[w as usize]
                        .iter()
                        .map(|&(_, x)| x)
                        .sum::<f64>();
                }
            }
        }
        reward[i] = rewards.rate[s] + e * imp;
    }
    let mut initial: Vec<(u32, f64)> = Vec::new();
    for &(s, p) in model.initial() {
        match target(s) {
            Target::Out(k) => initial.push((k, p)),
            Target::In(w) => {
                for &(k, q) in &absorbed.dist[w as usize] {
                    initial.push((k, p * q));
                }
            }
        }
    }
    let ctmc = Ctmc::from_triplets(markov.len(), triplets);
    let opts = SteadyOptions {
        tolerance: 1e-13,
        ..SteadyOptions::default()
    };
    let lim = ctmc
        .limiting(&initial, &opts)
        .map_err(|e| DecisionError::Unsupported(format!("policy evaluation: {e}")))?;
    let lra = lim.pi.iter().zip(&reward).map(|(p, r)| p * r).sum();
    let residual = lim
        .bottom
        .iter()
        .map(|states| {
            let sub = ctmc.restrict(states);
            let total: f64 = states.iter().map(|&s| lim.pi[s as usize]).sum();
            if total <= 0.0 {
                return 0.0;
            }
            let pi: Vec<f64> = states.iter().map(|&s| lim.pi[s as usize] / total).collect();
            sub.residual(&pi)
        })
        .fold(0.0, f64::max);
    Ok(PolicyValue {
        lra,
        ctmc_states: markov.len(),
        residual,
    })
}
