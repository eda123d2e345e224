//! End components collapsed: the quotient that makes reach and total-reward equations have
//! one fixed point, so that bounds from below *and* above converge to the answer.
//!
//! In an end component a policy may stay for ever. For maximal reachability every state of
//! a maximal end component (MEC) of non-goal states has the same value, the best way out;
//! value iteration from above never learns it (staying keeps any guess). For minimal total
//! reward, a MEC of zero-reward choices lets the iteration from below stay at 0 for ever,
//! while the true minimum must leave it (staying never reaches the goal, and a goal missed
//! with positive probability costs ∞). Both are solved as the literature does (Baier et al.,
//! "Ensuring the reliability of your model checker: interval iteration for Markov decision
//! processes", CAV 2017): each such MEC becomes one state whose choices are its members'
//! choices that leave it, `v_M = opt_c (r_c + Σ_out p·x) / (1 − p_in)`. The policy then
//! takes the best exit at its state and steers every other member to it
//! ([`steer`](super::policy_iteration::steer)).

use super::DecisionModel;
use super::lra::mecs_within;
use super::policy_iteration::steer;

/// Collapsed end components.
#[derive(Debug, Default)]
pub(super) struct Quotient {
    /// Per state: its group, `u32::MAX` outside every group.
    pub(super) of: Vec<u32>,
    /// Per group: its states (the first one updates the group in a sweep).
    pub(super) members: Vec<Vec<u32>>,
    /// Per choice: it stays inside its state's group (not an exit).
    pub(super) inside: Vec<bool>,
}

impl Quotient {
    /// The MECs of the states `state_ok` keeps and choices `choice_ok` keeps.
    pub(super) fn new(
        model: &DecisionModel,
        state_ok: impl Fn(usize) -> bool,
        choice_ok: impl Fn(usize) -> bool,
    ) -> Quotient {
        let mecs = mecs_within(model, state_ok, choice_ok);
        let mut members = vec![Vec::new(); mecs.count];
        for (s, &m) in mecs.of.iter().enumerate() {
            if m != u32::MAX {
                members[m as usize].push(s as u32);
            }
        }
        Quotient {
            of: mecs.of,
            members,
            inside: mecs.inside,
        }
    }

    /// No groups at all.
    pub(super) fn is_empty(&self) -> bool {
        self.members.is_empty()
    }

    /// The group's value from `x` and the exit choice that attains it (`u32::MAX` when the
    /// group has no exit, value `none`). `r` per choice; `better(a, b)` says a beats b.
    pub(super) fn update(
        &self,
        model: &DecisionModel,
        r: &[f64],
        x: &[f64],
        g: usize,
        better: impl Fn(f64, f64) -> bool,
        none: f64,
    ) -> (f64, u32) {
        let mut best: Option<f64> = None;
        let mut arg = u32::MAX;
        let gid = g as u32;
        for &s in &self.members[g] {
            for c in model.choices(s as usize) {
                if self.inside[c] {
                    continue;
                }
                let (mut p_in, mut sum) = (0.0, 0.0);
                for (t, p) in model.branches(c) {
                    if self.of[t as usize] == gid {
                        p_in += p;
                    } else {
                        sum += p * x[t as usize];
                    }
                }
                // A choice that never leaves but earns something: staying for ever
                // (a missed goal; ∞ for total reward, never chosen by a minimiser).
                let v = if p_in >= 1.0 - 1e-12 {
                    if r[c] > 0.0 { f64::INFINITY } else { continue }
                } else {
                    (r[c] + sum) / (1.0 - p_in)
                };
                if v.is_nan() {
                    continue;
                }
                if best.is_none_or(|b| better(v, b)) {
                    best = Some(v);
                    arg = c as u32;
                }
            }
        }
        (best.unwrap_or(none), arg)
    }

    /// Policy inside each group: the best exit (`exit[g]`, a choice) at its state, every
    /// other member steered to that state over inside choices.
    pub(super) fn steer_policy(&self, model: &DecisionModel, exit: &[u32], policy: &mut [u32]) {
        let mut target = vec![false; model.state_count()];
        for (g, states) in self.members.iter().enumerate() {
            let c = exit[g];
            if c == u32::MAX {
                // No way out: any inside choice keeps the policy in the group.
                for &s in states {
                    if let Some(c) = model.choices(s as usize).find(|&c| self.inside[c]) {
                        policy[s as usize] = c as u32;
                    }
                }
                continue;
            }
            let Some(&at) = states
                .iter()
                .find(|&&s| model.choices(s as usize).contains(&(c as usize)))
            else {
                continue;
            };
            let at = at as usize;
            policy[at] = c;
            target[at] = true;
            steer(model, &self.inside, states, &mut target, policy);
        }
    }
}
