//! `simulate`: one run's trace, or Monte-Carlo estimates with 95% intervals, as
//! `plan-runner simulate --json`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use gspn::net::Net;
use gspn::plan::Plan;
use gspn::sim::{Horizon, MonteCarlo, Simulator};
use gspn::stats::Estimate;
use pyo3::prelude::*;
use serde_json::{Map, Value, json};

use crate::errors::{Failure, Outcome};
use crate::model::Model;
use crate::wait::interruptible;

/// The net (under the plan's policy, if any) simulated from its initial marking: with
/// `runs`, estimates of the time-average tokens and throughputs over `runs` runs; without,
/// the trace of one run. The horizon: `until` (model time), else `steps` firings, else the
/// plan's stop conditions, else 1000 time units (estimates) or 100 steps (trace).
#[pyfunction]
#[pyo3(signature = (model, seed = None, until = None, steps = None, runs = None))]
pub(crate) fn simulate(
    py: Python<'_>,
    model: &Model,
    seed: Option<u64>,
    until: Option<f64>,
    steps: Option<u64>,
    runs: Option<u64>,
) -> PyResult<String> {
    let plan = Arc::clone(&model.plan);
    let cancel = Arc::new(AtomicBool::new(false));
    let stop = Arc::clone(&cancel);
    interruptible(py, cancel, move || {
        if let Some(t) = until
            && !(t.is_finite() && t >= 0.0)
        {
            return Err(Failure::input(format!(
                "until {t}: must be a finite number ≥ 0"
            )));
        }
        if runs == Some(0) {
            return Err(Failure::input("runs 0: at least one run is needed"));
        }
        let seed = seed.or(plan.seed).unwrap_or(0);
        let horizon = match (until, steps) {
            (Some(t), _) => Horizon::Until(t),
            (None, Some(n)) => Horizon::Steps(n),
            (None, None) => match (plan.stop.time_limit, plan.stop.max_firings) {
                (Some(t), _) => Horizon::Until(t),
                (None, Some(n)) => Horizon::Steps(n),
                (None, None) if runs.is_some() => Horizon::Until(1000.0),
                (None, None) => Horizon::Steps(100),
            },
        };
        match runs {
            Some(runs) => estimates(&plan, runs, horizon, seed),
            None => trace(&plan, horizon, seed, &stop),
        }
    })
}

fn sim_error(e: impl std::fmt::Display) -> Failure {
    // A timeless trap is a defect of the net: bad input, as in the CLI.
    Failure::input(e.to_string())
}

fn named(names: impl Iterator<Item = String>, f: impl Fn(usize) -> Value) -> Value {
    Value::Object(
        names
            .enumerate()
            .map(|(i, n)| (n, f(i)))
            .collect::<Map<_, _>>(),
    )
}

fn marking(net: &Net, m: &[u32]) -> Value {
    named(net.places().iter().map(|p| p.name.clone()), |i| json!(m[i]))
}

fn trace(plan: &Plan, horizon: Horizon, seed: u64, stop: &AtomicBool) -> Outcome<String> {
    let net = &plan.net;
    let mut sim = Simulator::new(net.clone(), seed);
    if !plan.policy.is_empty() {
        sim = sim.with_policy(plan.policy.clone());
    }
    let (until, max_steps) = match horizon {
        Horizon::Until(t) => (t, u64::MAX),
        Horizon::Steps(n) => (f64::INFINITY, n),
    };
    let mut rows = Vec::new();
    let mut end = "limit";
    while sim.firings() < max_steps && !stop.load(Ordering::Relaxed) {
        if plan
            .stop
            .when
            .as_ref()
            .is_some_and(|p| p.eval(sim.marking()))
        {
            end = "stop_when";
            break;
        }
        match sim.step_until(until).map_err(sim_error)? {
            Some(step) => rows.push(json!({
                "time": step.time,
                "transition": net.transition(step.transition).name,
                "marking": marking(net, sim.marking()),
            })),
            None => {
                if sim.is_dead() {
                    end = "dead";
                }
                break;
            }
        }
    }
    Ok(json!({
        "seed": seed,
        "initial": marking(net, &net.initial_marking()),
        "steps": rows,
        "end": end,
        "time": sim.time(),
    })
    .to_string())
}

fn estimates(plan: &Plan, runs: u64, horizon: Horizon, seed: u64) -> Outcome<String> {
    let net = &plan.net;
    let mut mc = MonteCarlo::new(net, horizon).runs(runs).seed(seed);
    if !plan.policy.is_empty() {
        mc = mc.policy(&plan.policy);
    }
    let est = mc.run().map_err(sim_error)?;
    let pair = |e: &Estimate| {
        if e.half_width.is_nan() {
            json!({"mean": e.mean, "lo": null, "hi": null})
        } else {
            json!({"mean": e.mean, "lo": e.lo(), "hi": e.hi()})
        }
    };
    Ok(json!({
        "seed": seed,
        "runs": est.runs,
        "firings": est.firings,
        "dead_runs": est.dead_runs,
        "mean_time": est.mean_time,
        "mean_tokens": named(net.places().iter().map(|p| p.name.clone()), |i| pair(&est.mean_tokens[i])),
        "throughput": named(net.transitions().iter().map(|t| t.name.clone()), |i| pair(&est.throughput[i])),
    })
    .to_string())
}
