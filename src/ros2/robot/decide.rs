//! What a net-timed robot does with a goal, whatever carries it (DDS here, Zenoh in
//! `crate::zenoh::robot`): the race of the place's exponential outputs, drawn from the
//! robot's own stream.

use crate::net::{Net, PlaceId, Timing};
use crate::sample::{self, Rng};

/// The local decision for one goal: wait this long, then answer this transition.
#[derive(Clone, Debug, PartialEq)]
pub struct Decision {
    /// Seconds to wait.
    pub delay: f64,
    /// The transition's name; empty = let the policy decide.
    pub transition: String,
}

/// The net-timed decision for place `p`: the race of its exponential outputs, or at once
/// with no transition when it has an immediate output (or none at all).
pub fn decide(net: &Net, p: PlaceId, time_scale: f64, rng: &mut Rng) -> Decision {
    let outputs = net.consumers(p);
    let mut rates = Vec::new();
    for &t in outputs {
        match net.transition(t).timing {
            Timing::Immediate { .. } => {
                return Decision {
                    delay: 0.0,
                    transition: String::new(),
                };
            }
            Timing::Exponential { rate, .. } => rates.push((t, rate)),
        }
    }
    let total: f64 = rates.iter().map(|&(_, r)| r).sum();
    if rates.is_empty() || total <= 0.0 {
        return Decision {
            delay: 0.0,
            transition: String::new(),
        };
    }
    let delay = sample::exponential(rng, total) * time_scale;
    let chosen = sample::pick_weighted(rng, &rates).unwrap_or(rates[rates.len() - 1].0);
    Decision {
        delay,
        transition: net.transition(chosen).name.clone(),
    }
}

/// FNV-1a of the robot id, to give each robot its own stream of draws.
pub fn id_hash(id: &str) -> u64 {
    crate::sample::fnv::fnv1a(id.as_bytes())
}
