//! `analyze`: what `plan-runner analyze FILE --json` prints, from the same library calls.

use std::sync::Arc;

use gspn::analysis::decision::BuildOptions;
use gspn::analysis::invariants::{p_invariants, t_invariants};
use gspn::analysis::measures::{Solver, SolverOptions, TransientOptions, bad_time};
use gspn::analysis::properties::Properties;
use gspn::analysis::query::{Evaluator, Query, QueryError};
use gspn::analysis::report::{MeasuresReport, Report, StateSpaceReport};
use gspn::analysis::state_space::{AnalysisError, Monitor, Options, StateSpace};
use gspn::analysis::under_policy::{PolicyAnalysisError, Regime, analyse};
use gspn::net::predicate::Predicate;
use gspn::plan::Plan;
use pyo3::prelude::*;

use crate::errors::{Failure, Outcome};
use crate::model::Model;
use crate::wait::interruptible;

/// State space, properties, invariants, steady state (with the plan's rewards and the
/// probabilities of `prob`'s predicates) and transient measures at `transient`'s times,
/// as the JSON report of `plan-runner analyze --json`.
#[pyfunction]
#[pyo3(signature = (model, steady = true, transient = Vec::new(), prob = Vec::new(), max_states = 10_000_000, max_memory_mib = 4096))]
pub(crate) fn analyze(
    py: Python<'_>,
    model: &Model,
    steady: bool,
    transient: Vec<f64>,
    prob: Vec<String>,
    max_states: usize,
    max_memory_mib: usize,
) -> PyResult<String> {
    let plan = Arc::clone(&model.plan);
    let monitor = Arc::new(Monitor::new());
    let cancel = monitor.cancel_flag();
    interruptible(py, cancel, move || {
        let opts = Options {
            max_states,
            threads: 0,
            max_memory: max_memory_mib.saturating_mul(1 << 20),
            monitor: Some(monitor),
        };
        report(&plan, steady, &transient, &prob, &opts)
    })
}

fn report(
    plan: &Plan,
    steady: bool,
    transient: &[f64],
    prob: &[String],
    opts: &Options,
) -> Outcome<String> {
    let net = &plan.net;
    let regime = if plan.policy.is_empty() {
        Regime::BareNet
    } else {
        Regime::UnderPolicy
    };
    if let Some(t) = bad_time(transient) {
        return Err(Failure::input(format!("transient: {t} is not a time ≥ 0")));
    }
    let predicates = prob
        .iter()
        .map(|p| Predicate::parse(net, p).map_err(|e| Failure::input(format!("prob `{p}`: {e}"))))
        .collect::<Outcome<Vec<_>>>()?;
    let want_steady = steady || !prob.is_empty() || transient.is_empty();
    let unbounded = |e: AnalysisError| match e {
        AnalysisError::Unbounded { places } => Ok(Report {
            analysed: regime.label().to_string(),
            state_space: StateSpaceReport::unbounded(&places),
            steady_state: None,
            transient: Vec::new(),
            queries: Vec::new(),
        }),
        e => Err(Failure::Analysis(e.to_string())),
    };
    let (space, analysed) = if want_steady {
        match analyse(
            net,
            &plan.policy,
            &plan.rewards,
            opts,
            &SolverOptions::default(),
        ) {
            Ok(a) => (a.space, Some((a.limiting, a.measures, a.rewards))),
            Err(PolicyAnalysisError::StateSpace(e)) => return json(&unbounded(e)?),
            Err(e) => return Err(Failure::Analysis(format!("steady state: {e}"))),
        }
    } else {
        match StateSpace::build_under_policy(net, &plan.policy, opts) {
            Ok(s) => (s, None),
            Err(e) => return json(&unbounded(e)?),
        }
    };
    let props = Properties::compute(net, &space);
    let pinv = p_invariants(net, 10_000);
    let tinv = t_invariants(net, 10_000);
    let solver = Solver::new(net, &space);
    if let Some(e) = solver.too_far(transient) {
        return Err(Failure::input(format!("transient: {e}")));
    }
    let steady_state = analysed.map(|(l, m, rewards)| {
        let probs = solver.probabilities(&l.pi, &predicates);
        MeasuresReport::steady(net, l.ergodic, &m)
            .with_probabilities(prob, &probs)
            .with_rewards(&rewards)
    });
    // Ctrl-C stops the transient solver too (the same monitor).
    let points = solver
        .transient_points(
            transient,
            &predicates,
            &TransientOptions {
                monitor: opts.monitor.clone(),
                ..TransientOptions::default()
            },
        )
        .map_err(|e| Failure::Analysis(format!("transient: {e}")))?;
    json(&Report {
        analysed: regime.label().to_string(),
        state_space: StateSpaceReport::new(net, &props, &pinv, &tinv),
        steady_state,
        transient: points
            .iter()
            .map(|p| MeasuresReport::point(net, p, prob))
            .collect(),
        queries: Vec::new(),
    })
}

fn json(report: &Report) -> Outcome<String> {
    serde_json::to_string(report).map_err(|e| Failure::Analysis(e.to_string()))
}

/// The value of each of `queries` (Storm/PRISM syntax: `P=? [F<=600 done=1]`, `T=? [F φ]`,
/// `S=? [φ]`, `R{"name"}=? [S]`, `Pmax=? [F φ]`, …), as `plan-runner analyze --query`
/// answers them: on the plan's net under its policy, `max`/`min` over its controllable
/// transitions.
#[pyfunction]
#[pyo3(signature = (model, queries, max_states = 10_000_000, max_memory_mib = 4096))]
pub(crate) fn query(
    py: Python<'_>,
    model: &Model,
    queries: Vec<String>,
    max_states: usize,
    max_memory_mib: usize,
) -> PyResult<Vec<f64>> {
    let plan = Arc::clone(&model.plan);
    let monitor = Arc::new(Monitor::new());
    let cancel = monitor.cancel_flag();
    interruptible(py, cancel, move || {
        let parsed = queries
            .iter()
            .map(|text| {
                Query::parse(&plan.net, &plan.rewards, text).map_err(|e| Failure::Input {
                    message: format!("query `{text}`: {e}"),
                    file: None,
                    line: None,
                    column: e.column().map(|c| c as u32),
                })
            })
            .collect::<Outcome<Vec<_>>>()?;
        let opts = Options {
            max_states,
            threads: 0,
            max_memory: max_memory_mib.saturating_mul(1 << 20),
            monitor: Some(monitor),
        };
        let space = StateSpace::build_under_policy(&plan.net, &plan.policy, &opts)
            .map_err(|e| Failure::Analysis(e.to_string()))?;
        let ev = Evaluator::new(&plan.net, &space, &plan.rewards).with_controls(
            &plan.controls,
            BuildOptions {
                max_states,
                ..BuildOptions::default()
            },
        );
        parsed
            .iter()
            .map(|q| match ev.evaluate(q) {
                Ok(v) => Ok(v),
                Err(e @ QueryError::Unsupported(_)) => Err(Failure::input(format!("query: {e}"))),
                Err(e) => Err(Failure::Analysis(format!("query `{q}`: {e}"))),
            })
            .collect()
    })
}
