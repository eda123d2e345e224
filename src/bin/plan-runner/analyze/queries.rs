//! `analyze --query Q`: Storm/PRISM queries read against the plan (its places and reward
//! structures), answered on the analysed state space or, for `max`/`min`, by the synthesis
//! engine over the plan's controllable transitions.

use gspn::analysis::ctmc::Limiting;
use gspn::analysis::decision::BuildOptions;
use gspn::analysis::query::{Evaluator, Query, QueryError};
use gspn::analysis::report::QueryAnswer;
use gspn::analysis::state_space::StateSpace;
use gspn::plan::Plan;

use crate::common::BadInput;

/// Reads every `--query`, refusing the first bad one with its column and a caret under it.
pub(super) fn parse(plan: &Plan, texts: &[String]) -> Result<Vec<Query>, BadInput> {
    texts
        .iter()
        .map(|text| {
            Query::parse(&plan.net, &plan.rewards, text).map_err(|e| BadInput(pointed(text, &e)))
        })
        .collect()
}

/// `--query `TEXT`: column C: MESSAGE`, then the query and a caret under column C.
fn pointed(text: &str, e: &QueryError) -> String {
    let shown = gspn::io::excerpt(text, 200);
    match e.column() {
        Some(col) if col <= 201 => format!(
            "--query `{shown}`: {e}\n  {shown}\n  {}^",
            " ".repeat(col - 1)
        ),
        _ => format!("--query `{shown}`: {e}"),
    }
}

/// The value of each query, in order.
pub(super) fn answer(
    plan: &Plan,
    space: &StateSpace,
    limiting: Option<Limiting>,
    queries: &[Query],
    max_states: usize,
) -> anyhow::Result<Vec<QueryAnswer>> {
    let mut ev = Evaluator::new(&plan.net, space, &plan.rewards).with_controls(
        &plan.controls,
        BuildOptions {
            max_states,
            ..BuildOptions::default()
        },
    );
    if let Some(l) = limiting {
        ev = ev.with_limiting(l);
    }
    queries
        .iter()
        .map(|q| match ev.evaluate(q) {
            Ok(value) => Ok(QueryAnswer {
                query: q.source().to_string(),
                value,
            }),
            Err(e @ QueryError::Unsupported(_)) => Err(BadInput(format!("--query: {e}")).into()),
            Err(e) => Err(anyhow::Error::new(e).context(format!("--query `{q}`"))),
        })
        .collect()
}
