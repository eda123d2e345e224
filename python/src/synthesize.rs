//! `synthesize`: the optimal policy of a plan (or a net), as `plan-runner synthesize --json`.

use std::sync::Arc;

use gspn::analysis::decision::{
    Algorithm, BuildOptions, DecisionError, DecisionModel, Objective, PolicyTable, RewardSpec,
    SolveOptions, compress, solve,
};
use gspn::analysis::state_space::Monitor;
use gspn::net::predicate::Predicate;
use gspn::plan::Plan;
use gspn::policy::Pattern;
use pyo3::prelude::*;
use serde_json::{Value, json};

use crate::errors::{Failure, Outcome};
use crate::model::Model;
use crate::wait::interruptible;

/// The objective, as the CLI's `--objective NAME-max|min` with its `--goal`, `--discount`
/// or `--gamma`.
struct Request {
    objective: String,
    goal: Option<String>,
    discount: Option<f64>,
    gamma: Option<f64>,
    reward: Option<String>,
    wait: Option<bool>,
    precision: f64,
    method: String,
    max_states: usize,
}

/// Synthesises the policy optimising `objective` (lra, reach, total, time, discounted,
/// discounted-per-step; `-max` or `-min`) and answers the value, its interval, the model's
/// size and the policy's rules (JSON).
#[pyfunction]
#[pyo3(signature = (model, objective = "lra-max".to_string(), goal = None, discount = None, gamma = None, reward = None, wait = None, precision = 1e-9, method = "auto".to_string(), max_states = 10_000_000))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn synthesize(
    py: Python<'_>,
    model: &Model,
    objective: String,
    goal: Option<String>,
    discount: Option<f64>,
    gamma: Option<f64>,
    reward: Option<String>,
    wait: Option<bool>,
    precision: f64,
    method: String,
    max_states: usize,
) -> PyResult<String> {
    let plan = Arc::clone(&model.plan);
    let request = Request {
        objective,
        goal,
        discount,
        gamma,
        reward,
        wait,
        precision,
        method,
        max_states,
    };
    let monitor = Arc::new(Monitor::new());
    interruptible(py, monitor.cancel_flag(), move || {
        run(&plan, &request, &monitor)
    })
}

/// What to optimise.
enum Goal {
    Lra,
    Reach(Predicate),
    Total(Predicate),
    Time(Predicate),
    Discounted(f64),
    PerStep(f64),
}

const OBJECTIVES: &str = "lra, reach, total, time, discounted, discounted-per-step";

fn parse(r: &Request, plan: &Plan) -> Outcome<(Goal, bool)> {
    let o = r.objective.replace('_', "-");
    let (kind, max) = match o.rsplit_once('-') {
        Some((k, "max")) => (k, true),
        Some((k, "min")) => (k, false),
        _ => {
            return Err(Failure::input(format!(
                "objective `{}`: expected NAME-max or NAME-min ({OBJECTIVES})",
                r.objective
            )));
        }
    };
    let goal = || -> Outcome<Predicate> {
        let text = r.goal.as_deref().ok_or_else(|| {
            Failure::input(format!(
                "objective {o} needs goal=EXPR (e.g. 'P_done == 3')"
            ))
        })?;
        Predicate::parse(&plan.net, text).map_err(|e| Failure::input(format!("goal `{text}`: {e}")))
    };
    let g = match kind {
        "lra" => Goal::Lra,
        "reach" => Goal::Reach(goal()?),
        "total" => Goal::Total(goal()?),
        "time" => Goal::Time(goal()?),
        "discounted" => match r.discount {
            Some(d) if d > 0.0 && d.is_finite() => Goal::Discounted(d),
            Some(d) => return Err(Failure::input(format!("discount {d}: must be a rate > 0"))),
            None => return Err(Failure::input(format!("objective {o} needs discount=RATE"))),
        },
        "discounted-per-step" => match r.gamma {
            Some(g) if g > 0.0 && g < 1.0 => Goal::PerStep(g),
            Some(g) => return Err(Failure::input(format!("gamma {g}: must be in (0, 1)"))),
            None => return Err(Failure::input(format!("objective {o} needs gamma=G"))),
        },
        other => {
            return Err(Failure::input(format!(
                "objective `{}`: unknown objective `{other}` ({OBJECTIVES})",
                r.objective
            )));
        }
    };
    Ok((g, max))
}

fn reward_spec(r: &Request, plan: &Plan) -> Outcome<RewardSpec> {
    let names = || {
        let n: Vec<&str> = plan.rewards.iter().map(|r| r.name.as_str()).collect();
        if n.is_empty() {
            "none".into()
        } else {
            n.join(", ")
        }
    };
    match &r.reward {
        Some(name) => plan
            .rewards
            .iter()
            .find(|s| &s.name == name)
            .cloned()
            .ok_or_else(|| {
                Failure::input(format!(
                    "reward `{name}`: the plan has no [rewards.{name}] (it has: {})",
                    names()
                ))
            }),
        None => match plan.rewards.len() {
            0 => Ok(RewardSpec::default()),
            1 => Ok(plan.rewards[0].clone()),
            _ => Err(Failure::input(format!(
                "the plan has several reward structures ({}): pick one with reward=NAME",
                names()
            ))),
        },
    }
}

fn algorithm(r: &Request, goal: &Goal) -> Outcome<Algorithm> {
    let lra = matches!(goal, Goal::Lra);
    match r.method.as_str() {
        "value" => Ok(Algorithm::ValueIteration),
        "auto" | "policy" if lra => Ok(Algorithm::PolicyIteration),
        "auto" => Ok(Algorithm::ValueIteration),
        "policy" => Err(Failure::input(format!(
            "method policy: policy iteration is implemented for lra-max and lra-min only, not {}",
            r.objective
        ))),
        other => Err(Failure::input(format!(
            "method `{other}`: expected auto, value or policy"
        ))),
    }
}

fn decision(e: DecisionError) -> Failure {
    Failure::Analysis(e.to_string())
}

fn run(plan: &Plan, r: &Request, monitor: &Arc<Monitor>) -> Outcome<String> {
    if !plan.policy.is_empty() {
        return Err(Failure::input(format!(
            "{}: the plan already has [[policy]] rules; synthesize from a plan without them",
            plan.path.display()
        )));
    }
    let net = &plan.net;
    let (goal, max) = parse(r, plan)?;
    let spec = reward_spec(r, plan)?;
    let mut controls = plan.controls.clone();
    if let Some(w) = r.wait {
        controls.wait = w;
    }
    if matches!(goal, Goal::PerStep(_)) {
        // The GSPNR toolbox counts every vanishing step, races included.
        controls.keep_races = true;
    }
    let t0 = std::time::Instant::now();
    let model = DecisionModel::build(
        net,
        &controls,
        &BuildOptions {
            max_states: r.max_states,
            threads: 0,
            monitor: Some(Arc::clone(monitor)),
        },
    )
    .map_err(decision)?;
    let build_s = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let flags = |p: &Predicate| model.states_where(|m| p.eval(m));
    let (rewards, objective) = match &goal {
        Goal::Lra => (model.rewards(&spec), Objective::Lra { max }),
        Goal::Reach(p) => (
            model.rewards(&spec),
            Objective::Reach {
                max,
                goal: flags(p),
            },
        ),
        Goal::Total(p) => (
            model.rewards(&spec),
            Objective::Total {
                max,
                goal: flags(p),
            },
        ),
        Goal::Time(p) => (
            model.time_rewards(),
            Objective::Total {
                max,
                goal: flags(p),
            },
        ),
        Goal::Discounted(rate) => (
            model.rewards(&spec),
            Objective::Discounted { max, rate: *rate },
        ),
        Goal::PerStep(gamma) => (
            model.rewards(&spec),
            Objective::DiscountedPerStep { max, gamma: *gamma },
        ),
    };
    let sol = solve(
        &model,
        &rewards,
        &objective,
        &SolveOptions {
            precision: r.precision,
            algorithm: algorithm(r, &goal)?,
            cancel: Some(monitor.cancel_flag()),
            ..SolveOptions::default()
        },
    )
    .map_err(decision)?;
    let solve_s = t1.elapsed().as_secs_f64();
    // The decision markings and what the policy fires there (WAIT: no rule).
    let PolicyTable {
        fires: table,
        waits,
    } = model.policy_table(&sol.policy);
    let marking = |pairs: Vec<(usize, u32)>| -> serde_json::Map<String, Value> {
        pairs
            .into_iter()
            .map(|(i, k)| (net.places()[i].name.clone(), json!(k)))
            .collect()
    };
    let exact = |m: &[u32]| -> Vec<(usize, u32)> {
        m.iter()
            .enumerate()
            .filter(|&(_, &k)| k > 0)
            .map(|(i, &k)| (i, k))
            .collect()
    };
    let rules: Vec<Value> = table
        .iter()
        .map(|(m, t)| json!({"marking": marking(exact(m)), "choose": net.transition(*t).name}))
        .collect();
    let compressed: Vec<Value> = compress(&table)
        .iter()
        .map(|rule| {
            let (pairs, partial) = match &rule.pattern {
                Pattern::Exact(m) => (exact(m), false),
                Pattern::Partial(v) => (v.iter().map(|&(p, k)| (p.index(), k)).collect(), true),
            };
            let choose: serde_json::Map<String, Value> = rule
                .choose
                .iter()
                .map(|&(t, p)| (net.transition(t).name.clone(), json!(p)))
                .collect();
            json!({"marking": marking(pairs), "partial": partial, "choose": choose})
        })
        .collect();
    let finite = |x: f64| {
        if x.is_finite() {
            json!(x)
        } else {
            json!(x.to_string())
        }
    };
    Ok(json!({
        "objective": r.objective,
        "reward": spec.name,
        "value": finite(sol.value),
        "lower": finite(sol.lower),
        "upper": finite(sol.upper),
        "method": format!("{:?}", sol.method),
        "iterations": sol.iterations,
        "states": model.state_count(),
        "choices": model.choice_count(),
        "markings": model.marking_count(),
        "wait_copies": model.wait_copies(),
        "wait_markings": waits,
        "build_s": build_s,
        "solve_s": solve_s,
        "rules": rules,
        "compressed_rules": compressed,
        "net_hash": gspn::runtime::journal::net_hash(net),
    })
    .to_string())
}
