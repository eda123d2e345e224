//! The analysis panel's data: properties of the state space, steady-state measures, dead
//! markings with the firing sequence that reaches each — or why they cannot be computed —
//! and, on the state space kept from it ([`Kept`]), transient points, `--prob` predicates
//! and `--query` queries computed by the same library calls as `plan-runner analyze`
//! ([`query`]).

use std::sync::Arc;

use serde_json::{Value, json};

use crate::analysis::ctmc::{Limiting, SolveError, TransientOptions};
use crate::analysis::decision::RewardSpec;
use crate::analysis::invariants::{p_invariants, t_invariants};
use crate::analysis::measures::{Solver, SolverOptions, bad_time};
use crate::analysis::properties::Properties;
use crate::analysis::query::{Evaluator, Query};
use crate::analysis::report::{MeasuresReport, Panel, QueryAnswer};
use crate::analysis::state_space::{AnalysisError, Monitor, Options, StateSpace};
use crate::analysis::under_policy::{self, Regime};
use crate::net::Net;
use crate::net::predicate::Predicate;
use crate::policy::Policy;
use crate::web::analysis_job::{Phase, Progress};

/// Invariants kept at most, as `plan-runner analyze` keeps them.
const INVARIANT_CAP: usize = 10_000;

/// What a finished analysis keeps for later questions: the state space and its limiting
/// distribution.
#[derive(Debug)]
pub(crate) struct Kept {
    /// The state space (under the plan's policy, if any).
    pub(crate) space: StateSpace,
    /// The limiting distribution over its tangible markings.
    pub(crate) limiting: Limiting,
    /// The plan's reward structures, for `R{"name"}` queries.
    pub(crate) rewards: Vec<RewardSpec>,
}

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
) -> (Value, Option<Kept>) {
    let opts = Options {
        max_states,
        threads: 0,
        monitor: Some(Arc::clone(&progress.monitor)),
        ..Options::default()
    };
    let cancelled = || (json!({ "error": "cancelled", "kind": "cancelled" }), None);
    if !progress.enter(Phase::StateSpace) {
        return cancelled();
    }
    let regime = if policy.is_empty() {
        Regime::BareNet
    } else {
        Regime::UnderPolicy
    };
    let ss = match StateSpace::build_under_policy(net, policy, &opts) {
        Ok(ss) => ss,
        Err(e) => {
            let kind = match &e {
                AnalysisError::Unbounded { .. } => "unbounded",
                AnalysisError::TooManyStates { .. } => "too_many_states",
                AnalysisError::TimelessTrap { .. } => "timeless_trap",
                AnalysisError::VanishingLoopTooLarge { .. } => "vanishing_loop_too_large",
                AnalysisError::VanishingLoopFailed { .. } => "vanishing_loop_failed",
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
            return (v, None);
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
        return (to_json(&panel), None);
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
            let kept = Kept {
                space: a.space,
                limiting: a.limiting,
                rewards: rewards.to_vec(),
            };
            (to_json(&panel), Some(kept))
        }
        Err(SolveError::Cancelled { .. }) => cancelled(),
        // As `plan-runner analyze` stops there, no transient point or predicate either.
        Err(e) => {
            panel.steady_error = Some(e.to_string());
            (to_json(&panel), None)
        }
    }
}

/// Why a question got no answer.
#[derive(Debug)]
pub(crate) enum QueryError {
    /// A bad time or predicate: the message names it.
    Bad(String),
    /// Its monitor was cancelled.
    Cancelled,
}

/// The panel's questions on a finished analysis (`POST /api/analysis/query`): the
/// predicates' steady-state probabilities and the state at each of `times`, computed as
/// `plan-runner analyze --prob EXPR --transient T --json` computes them
/// ([`Solver::probabilities`], [`Solver::transient_points`]) and in its JSON form
/// (`steady_state.probability`, `transient`), watched by `monitor` (progress, cancel).
pub(crate) fn query(
    net: &Net,
    kept: &Kept,
    times: &[f64],
    exprs: &[String],
    queries: &[String],
    monitor: &Arc<Monitor>,
) -> Result<Value, QueryError> {
    if let Some(t) = bad_time(times) {
        return Err(QueryError::Bad(format!("transient: {t} is not a time ≥ 0")));
    }
    let predicates = exprs
        .iter()
        .map(|p| {
            Predicate::parse(net, p)
                .map_err(|e| QueryError::Bad(format!("prob `{}`: {e}", crate::io::excerpt(p, 80))))
        })
        .collect::<Result<Vec<_>, _>>()?;
    let solver = Solver::new(net, &kept.space);
    if let Some(e) = solver.too_far(times) {
        return Err(QueryError::Bad(format!("transient: {e}")));
    }
    let transient: Vec<MeasuresReport> = solver
        .transient_points(
            times,
            &predicates,
            &TransientOptions {
                monitor: Some(Arc::clone(monitor)),
                ..TransientOptions::default()
            },
        )
        .map_err(|e| match e {
            SolveError::Cancelled { .. } => QueryError::Cancelled,
            e => QueryError::Bad(e.to_string()),
        })?
        .iter()
        .map(|p| MeasuresReport::point(net, p, exprs))
        .collect();
    let steady = solver.probabilities(&kept.limiting.pi, &predicates);
    let queries = answers(net, kept, queries)?;
    let probability: serde_json::Map<String, Value> = exprs
        .iter()
        .zip(steady)
        .map(|(e, p)| (e.clone(), json!(p)))
        .collect();
    Ok(json!({
        "steady_state": { "probability": probability },
        "transient": transient,
        "queries": queries,
    }))
}

/// The panel's Storm/PRISM queries (`plan-runner analyze --query`), each `{query, value}`
/// (an infinite value as `"inf"`), on the kept state space; `max`/`min` ones are refused
/// (the panel has no synthesis: `plan-runner analyze PLAN --query`).
fn answers(net: &Net, kept: &Kept, texts: &[String]) -> Result<Vec<QueryAnswer>, QueryError> {
    let ev = Evaluator::new(net, &kept.space, &kept.rewards).with_limiting(kept.limiting.clone());
    texts
        .iter()
        .map(|text| {
            let bad = |e: &dyn std::fmt::Display| {
                QueryError::Bad(format!("query `{}`: {e}", crate::io::excerpt(text, 200)))
            };
            let q = Query::parse(net, &kept.rewards, text).map_err(|e| bad(&e))?;
            if q.extreme.is_some() {
                return Err(bad(
                    &"max and min are answered by `plan-runner analyze PLAN --query`",
                ));
            }
            let value = ev.evaluate(&q).map_err(|e| bad(&e))?;
            Ok(QueryAnswer {
                query: text.clone(),
                value,
            })
        })
        .collect()
}
