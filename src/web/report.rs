//! The analysis panel's data: properties of the state space, steady-state measures, dead
//! markings with the firing sequence that reaches each — or why they cannot be computed.

use serde_json::{Value, json};

use crate::analysis::ctmc::SolveError;
use crate::analysis::measures::{Solver, SolverOptions};
use crate::analysis::properties::Properties;
use crate::analysis::report::{MeasuresReport, Panel};
use crate::analysis::state_space::{AnalysisError, Options, StateSpace};
use crate::net::Net;
use crate::web::analysis_job::{Phase, Progress};

/// Everything the panel shows, as JSON; `{"error", "kind"}` when the state space cannot be
/// built (unbounded net, too many states, timeless trap) or the job was cancelled (`kind`
/// `cancelled`: the search stops within a block of markings, the later phases before they
/// start).
pub(crate) fn analyse(net: &Net, max_states: usize, progress: &Progress) -> Value {
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
    let ss = match StateSpace::build_monitored(net, &opts, &progress.monitor) {
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
            let mut v = json!({ "error": e.to_string(), "kind": kind });
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
    let mut panel = Panel::new(net, &props);
    let to_json = |p: &Panel| serde_json::to_value(p).unwrap_or(Value::Null);
    if ss.tangible_count() == 0 {
        panel.steady_error = Some("no tangible marking: time never passes".into());
        return to_json(&panel);
    }
    if !progress.enter(Phase::SteadyState) {
        return cancelled();
    }
    let solver = Solver::new(net, &ss);
    let opts = SolverOptions {
        cancel: Some(progress.monitor.cancel_flag()),
        ..SolverOptions::default()
    };
    match solver.steady_state(&opts) {
        Ok(lim) => {
            let m = solver.measures(&lim.pi);
            panel.steady = Some(MeasuresReport::panel(net, lim.ergodic, &m));
        }
        Err(SolveError::Cancelled { .. }) => return cancelled(),
        Err(e) => panel.steady_error = Some(e.to_string()),
    }
    to_json(&panel)
}
