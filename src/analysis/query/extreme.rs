//! `Pmax=?`, `Pmin=?`, `Tmax=?`, `Tmin=?` and `R{"name"}max=?`/`min=?`: the best and
//! worst a plan's controllable transitions can do, through the synthesis engine
//! ([`decision`](crate::analysis::decision): the same model and solvers as
//! `plan-runner synthesize`, with its sound interval).
//!
//! Answered: `P[F φ]` (reach), `T[F φ]` (time), `R[F φ]` (total reward), `R[S]` (long-run
//! average). Time bounds and `U` are refused with a message: the engine has no
//! time-bounded objective. The goal is read on the decision model's states (tangible and
//! decision markings; eliminated races are not states).

use super::{Kind, Query, QueryError};
use crate::analysis::decision::{
    BuildOptions, Controls, DecisionModel, Objective, RewardSpec, SolveOptions, solve,
};
use crate::net::Net;

/// The optimum of `query` (which has `max` or `min`) over the policies of `controls`, with
/// the reward structures `rewards` (those given to [`Query::parse`]).
pub fn evaluate(
    net: &Net,
    controls: &Controls,
    rewards: &[RewardSpec],
    query: &Query,
    build: &BuildOptions,
) -> Result<f64, QueryError> {
    let Some(max) = query.extreme else {
        return Err(QueryError::Unsupported(format!(
            "`{query}` has no `max` or `min`"
        )));
    };
    if !controls.controllable.iter().any(|&c| c) {
        return Err(QueryError::Unsupported(format!(
            "`{query}`: nothing is controllable (no `controllable` transitions in the plan, \
             no zero-weight immediate transition in the net): ask `=?` instead"
        )));
    }
    let unsupported = |what: &str| {
        Err(QueryError::Unsupported(format!(
            "`{query}`: {what} is not computed for max/min (the synthesis engine has reach, \
             time, total-reward and long-run objectives)"
        )))
    };
    // What the objective needs: a goal predicate and a reward structure (none: time).
    let (goal, reward) = match &query.kind {
        Kind::Until {
            safe: None,
            bound: None,
            goal,
        } => (Some(goal), None),
        Kind::Time { goal } => (Some(goal), None),
        Kind::RewardReach { reward, goal } => (Some(goal), Some(*reward)),
        Kind::RewardSteady { reward } => (None, Some(*reward)),
        Kind::Until { bound: Some(_), .. } => return unsupported("a time bound"),
        Kind::Until { .. } => return unsupported("until (`U`)"),
        Kind::Globally { .. } => return unsupported("globally (`G`)"),
        Kind::Steady { .. } => return unsupported("`S`"),
        Kind::RewardCumulative { .. } => return unsupported("cumulative reward (`C<=t`)"),
    };
    let model = DecisionModel::build(net, controls, build)?;
    let goal_flags = goal.map(|g| model.states_where(|m| g.eval(m)));
    let (rewards, objective) = match (goal_flags, reward) {
        // P[F φ]: reach.
        (Some(goal), None) if matches!(query.kind, Kind::Until { .. }) => (
            model.rewards(&RewardSpec::default()),
            Objective::Reach { max, goal },
        ),
        // T[F φ]: the total of time rewards.
        (Some(goal), None) => (model.time_rewards(), Objective::Total { max, goal }),
        (Some(goal), Some(r)) => (model.rewards(&rewards[r]), Objective::Total { max, goal }),
        (None, r) => (
            model.rewards(r.map_or(&RewardSpec::default(), |r| &rewards[r])),
            Objective::Lra { max },
        ),
    };
    Ok(solve(&model, &rewards, &objective, &SolveOptions::default())?.value)
}
