//! The viewer's token game: one seeded [`Simulator`] run that the page steps, fires by hand,
//! and resets.
//!
//! The session keeps its [`Simulator`] alive between requests (it shares the net), so a step
//! request costs its own steps only, however long the run already is. Steps after a reset
//! are exactly `plan-runner simulate --seed S --steps N`.
//!
//! Firing a transition by hand leaves the seeded run: a new *segment* — a simulator started
//! from the marking after that firing — draws from a seed derived from the session seed and
//! the number of hand firings so far, still reproducible from the same sequence of requests.

use std::collections::VecDeque;
use std::sync::Arc;

use serde::Serialize;

use crate::net::{Marking, Net, TransitionId};
use crate::policy::Policy;
use crate::sim::{SimError, Simulator};

/// Trace entries kept for the page (the oldest are dropped past this).
pub(crate) const TRACE_KEEP: usize = 10_000;

/// One firing of the session's run.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct TraceEntry {
    /// 1 for the first firing after a reset.
    pub(crate) step: u64,
    /// Virtual time of the firing.
    pub(crate) time: f64,
    /// Name of the transition.
    pub(crate) transition: String,
    /// Fired in a vanishing marking (no time passed).
    pub(crate) immediate: bool,
    /// Fired by hand (`/api/sim/fire`) rather than drawn by the token game.
    pub(crate) manual: bool,
    /// The marking after it, as `p=k,...`.
    pub(crate) marking: String,
}

/// Why a request to the session failed.
#[derive(Debug, thiserror::Error)]
pub(crate) enum SessionError {
    /// No transition of that name.
    #[error("no transition named `{0}`")]
    UnknownTransition(String),
    /// The transition exists but may not fire in the current marking.
    #[error("transition `{0}` cannot fire in the current marking")]
    NotFirable(String),
    /// The token game stopped (a timeless trap).
    #[error("{0}")]
    Sim(#[from] SimError),
}

/// The state of the viewer's run.
#[derive(Debug)]
pub(crate) struct Session {
    net: Arc<Net>,
    policy: Option<Arc<Policy>>,
    seed: u64,
    /// The run of the current segment (since the reset or the last hand firing).
    sim: Simulator,
    /// When the segment started (its simulator's clock starts at 0).
    segment_time: f64,
    manual: u64,
    firings: u64,
    trace: VecDeque<TraceEntry>,
}

impl Session {
    /// A run of `net` from its initial marking, drawing from `seed`.
    pub(crate) fn new(net: Arc<Net>, policy: Option<Arc<Policy>>, seed: u64) -> Session {
        let marking = net.initial_marking();
        Session {
            sim: Session::segment(&net, &policy, marking, seed),
            net,
            policy,
            seed,
            segment_time: 0.0,
            manual: 0,
            firings: 0,
            trace: VecDeque::new(),
        }
    }

    fn segment(
        net: &Arc<Net>,
        policy: &Option<Arc<Policy>>,
        marking: Marking,
        seed: u64,
    ) -> Simulator {
        let sim = Simulator::from_marking(Arc::clone(net), marking, seed);
        match policy {
            Some(p) => sim.with_policy(Arc::clone(p)),
            None => sim,
        }
    }

    /// Back to the initial marking at time 0, drawing from `seed` (the current one if `None`).
    pub(crate) fn reset(&mut self, seed: Option<u64>) {
        *self = Session::new(
            self.net.clone(),
            self.policy.clone(),
            seed.unwrap_or(self.seed),
        );
    }

    /// Plays `net` from now on (an edited version of the net) under `policy` (the plan's,
    /// resolved against it): back to its initial marking at time 0, with the same seed.
    pub(crate) fn replace_net(&mut self, net: Arc<Net>, policy: Option<Arc<Policy>>) {
        self.net = net;
        self.policy = policy;
        self.reset(None);
    }

    pub(crate) fn net(&self) -> &Arc<Net> {
        &self.net
    }

    pub(crate) fn policy(&self) -> Option<&Policy> {
        self.policy.as_deref()
    }

    pub(crate) fn seed(&self) -> u64 {
        self.seed
    }

    pub(crate) fn marking(&self) -> &[u32] {
        self.sim.marking()
    }

    pub(crate) fn time(&self) -> f64 {
        self.segment_time + self.sim.time()
    }

    pub(crate) fn firings(&self) -> u64 {
        self.firings
    }

    /// The most recent `limit` trace entries, oldest first, and how many were fired in all.
    pub(crate) fn trace_tail(&self, limit: usize) -> Vec<TraceEntry> {
        let skip = self.trace.len().saturating_sub(limit);
        self.trace.iter().skip(skip).cloned().collect()
    }

    /// Fires up to `n` transitions drawn by the token game; returns how many fired (fewer
    /// when a dead marking is reached).
    pub(crate) fn step(&mut self, n: u64) -> Result<u64, SessionError> {
        let mut fired = 0;
        while fired < n {
            let Some(step) = self.sim.step()? else { break };
            fired += 1;
            self.firings += 1;
            self.record(step.transition, step.immediate, false);
        }
        Ok(fired)
    }

    /// Fires `name` by hand; it must be firable now ([`Net::firable`]).
    pub(crate) fn fire(&mut self, name: &str) -> Result<(), SessionError> {
        let t = self
            .net
            .transition_by_name(name)
            .ok_or_else(|| SessionError::UnknownTransition(name.to_string()))?;
        if !self.net.firable(self.sim.marking()).contains(&t) {
            return Err(SessionError::NotFirable(name.to_string()));
        }
        let mut marking = self.sim.marking().clone();
        self.net.fire(&mut marking, t).map_err(|o| {
            SessionError::Sim(SimError::TokenOverflow {
                time: self.time(),
                message: self.net.describe_overflow(&o),
            })
        })?;
        self.manual += 1;
        self.firings += 1;
        self.segment_time = self.time();
        let seed = self
            .seed
            .wrapping_add(self.manual.wrapping_mul(0x9E37_79B9_7F4A_7C15));
        self.sim = Session::segment(&self.net, &self.policy, marking, seed);
        let immediate = self.net.transition(t).is_immediate();
        self.record(t, immediate, true);
        Ok(())
    }

    fn record(&mut self, t: TransitionId, immediate: bool, manual: bool) {
        if self.trace.len() == TRACE_KEEP {
            self.trace.pop_front();
        }
        self.trace.push_back(TraceEntry {
            step: self.firings,
            time: self.time(),
            transition: self.net.transition(t).name.clone(),
            immediate,
            manual,
            marking: self.net.format_marking(self.sim.marking()),
        });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::Servers;

    fn cyc3() -> Arc<Net> {
        Arc::new(crate::net::cyc3(Servers::Single))
    }

    #[test]
    fn steps_in_pieces_equal_one_run() {
        let net = cyc3();
        let mut s = Session::new(net.clone(), None, 7);
        for n in [1, 3, 2, 10] {
            assert_eq!(s.step(n).unwrap(), n);
        }
        let mut sim = Simulator::new(net.clone(), 7);
        sim.run_steps(16).unwrap();
        assert_eq!(s.marking(), sim.marking().as_slice());
        assert_eq!(s.time(), sim.time());
        assert_eq!(s.firings(), 16);
    }

    #[test]
    fn hand_firing_checks_firability_and_moves_tokens() {
        let net = cyc3();
        let mut s = Session::new(net, None, 1);
        assert!(matches!(s.fire("t2"), Err(SessionError::NotFirable(_))));
        assert!(matches!(
            s.fire("nope"),
            Err(SessionError::UnknownTransition(_))
        ));
        s.fire("T1").unwrap();
        assert_eq!(s.marking(), &[1, 1, 0]);
        assert_eq!(s.step(1).unwrap(), 1); // t2 is the only firable one
        assert_eq!(s.marking(), &[1, 0, 1]);
        assert_eq!(s.time(), 0.0);
        s.reset(Some(3));
        assert_eq!((s.marking(), s.seed(), s.firings()), (&[2, 0, 0][..], 3, 0));
    }
}
