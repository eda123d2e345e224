//! The analysis panel's data: properties of the state space, steady-state measures, dead
//! markings with the firing sequence that reaches each — or why they cannot be computed.

use serde_json::{Value, json};

use crate::analysis::ctmc::SolveError;
use crate::analysis::decision::RewardSpec;
use crate::analysis::invariants::{p_invariants, t_invariants};
use crate::analysis::measures::SolverOptions;
use crate::analysis::properties::Properties;
use crate::analysis::report::{MeasuresReport, Panel};
use crate::analysis::state_space::{AnalysisError, Options, StateSpace};
use crate::analysis::under_policy::{self, Regime};
use crate::net::Net;
use crate::policy::Policy;
use crate::web::analysis_job::{Phase, Progress};

/// Invariants kept at most, as `plan-runner analyze` keeps them.
const INVARIANT_CAP: usize = 10_000;

/// Everything the panel shows for `net` under `policy` (the bare net when it is empty: the
/// same analysis as `plan-runner analyze`, [`under_policy`]), with the long-run rates of
/// `rewards`, as JSON; `{"error", "kind"}` when the state space cannot be built (unbounded
/// net, too many states, timeless trap) or the job was cancelled (`kind` `cancelled`: the
/// search stops within a block of markings, the later phases before they start).
pub(crate) fn analyse(
    net: &Net,
    policy: &Policy,
    rewards: &[RewardSpec],
    max_states: usize,
    progress: &Progress,
) -> Value {
    let opts = Options {
        max_states,
        progress: false,
        threads: 0,
        ..Options::default()
    };
    let cancelled = || json!({ "error": "cancelled", "kind": "cancelled" });
    if !progress.enter(Phase::StateSpace) {
        return cancelled();
    }
    let regime = if policy.is_empty() {
        Regime::BareNet
    } else {
        Regime::UnderPolicy
    };
    let ss = match StateSpace::build_under_policy(net, policy, &opts, &progress.monitor) {
        Ok(ss) => ss,
        Err(e) => {
            let kind = match &e {
                AnalysisError::Unbounded { .. } => "unbounded",
                AnalysisError::TooManyStates { .. } => "too_many_states",
                AnalysisError::TimelessTrap { .. } => "timeless_trap",
                AnalysisError::VanishingLoopTooLarge { .. } => "vanishing_loop_too_large",
                AnalysisError::Cancelled { .. } => "cancelled",
                AnalysisError::TooManyTokens { .. } => "too_many_tokens",
                AnalysisError::TooMuchMemory { .. } => "too_much_memory",
            };
            let message = match &e {
                // The CLI's message names its flag; the page has a field.
                AnalysisError::TooManyStates { limit } => format!(
                    "more than {limit} reachable markings: raise \"max states\" and analyse again"
                ),
                _ => e.to_string(),
            };
            let mut v = json!({ "error": message, "kind": kind, "analysed": regime.label() });
            if let AnalysisError::Unbounded { places } = &e {
                v["places"] = json!(places);
            }
            return v;
        }
    };
    if !progress.enter(Phase::Properties) {
        return cancelled();
    }
    let props = Properties::compute(net, &ss);
    let pinv = p_invariants(net, INVARIANT_CAP);
    let tinv = t_invariants(net, INVARIANT_CAP);
    let mut panel = Panel::new(net, regime, &props, &pinv, &tinv);
    let to_json = |p: &Panel| serde_json::to_value(p).unwrap_or(Value::Null);
    if ss.tangible_count() == 0 {
        panel.steady_error = Some("no tangible marking: time never passes".into());
        return to_json(&panel);
    }
    if !progress.enter(Phase::SteadyState) {
        return cancelled();
    }
    let opts = SolverOptions {
        cancel: Some(progress.monitor.cancel_flag()),
        ..SolverOptions::default()
    };
    match under_policy::solve(net, policy, ss, rewards, &opts) {
        Ok(a) => {
            panel.steady = Some(
                MeasuresReport::panel(net, a.limiting.ergodic, &a.measures)
                    .with_rewards(&a.rewards),
            );
        }
        Err(SolveError::Cancelled { .. }) => return cancelled(),
        Err(e) => panel.steady_error = Some(e.to_string()),
    }
    to_json(&panel)
}
