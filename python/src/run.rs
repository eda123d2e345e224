//! `run`: a plan executed on agents, some of whose actions are Python callables.

use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Duration;

use gspn::plan::Plan;
use gspn::runtime::{
    Action, ActionContext, ActionFuture, Backends, Outcome as Done, Role, RuntimeBuilder,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::errors::{Failure, Outcome};
use crate::model::Model;
use crate::wait::interruptible_with_grace;

/// How long Ctrl-C waits for the run to stop cleanly before KeyboardInterrupt is raised.
const STOP_GRACE: Duration = Duration::from_millis(500);

/// Runs the plan. `actions` maps a place name (that place's agents call it) or an action
/// name the plan uses (every place naming it) to a Python callable; the callable gets a
/// context and answers through `gspn._actions.call` (a transition name, None, a
/// `(name, seconds)` pair, or a coroutine of one). Answers the summary `plan-runner run
/// --json` prints (JSON). Ctrl-C stops the run cleanly (actions cancelled, journal
/// flushed) before KeyboardInterrupt reaches the caller.
#[pyfunction]
#[pyo3(signature = (model, actions, seed = None, until = None, max_firings = None, time_scale = None, journal = None, robots = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn run(
    py: Python<'_>,
    model: &Model,
    actions: Bound<'_, PyDict>,
    seed: Option<u64>,
    until: Option<f64>,
    max_firings: Option<u64>,
    time_scale: Option<f64>,
    journal: Option<PathBuf>,
    robots: Option<usize>,
) -> PyResult<String> {
    let mut plan = (*model.plan).clone();
    let call = py.import("gspn._actions")?.getattr("call")?.unbind();
    let call = Arc::new(call);
    let mut registered: Vec<(String, Py<PyAny>)> = Vec::new();
    for (key, func) in actions.iter() {
        let key: String = key.extract()?;
        if !func.is_callable() {
            return Err(Failure::input(format!("actions[{key:?}]: not callable")).into_py(py));
        }
        let name = bind(&mut plan, &key).map_err(|f| f.into_py(py))?;
        registered.push((name, func.unbind()));
    }
    if let Some(s) = seed {
        plan.seed = Some(s);
    }
    if let Some(x) = time_scale {
        plan.time_scale = Some(x);
    }
    if let Some(t) = until {
        plan.stop.time_limit = Some(t);
    }
    if let Some(n) = max_firings {
        plan.stop.max_firings = Some(n);
    }
    let names: Vec<&str> = registered.iter().map(|(n, _)| n.as_str()).collect();
    plan.check_actions(&names)
        .map_err(|e| Failure::from(e).into_py(py))?;
    let stop = Arc::new(AtomicBool::new(false));
    let watched = Arc::clone(&stop);
    interruptible_with_grace(py, stop, STOP_GRACE, move || {
        let rt = runtime(&plan).map_err(|e| Failure::Run(format!("starting tokio: {e}")))?;
        let r = rt.block_on(execute(plan, registered, call, journal, robots, watched));
        rt.shutdown_background();
        r
    })
}

/// The registered name for `key` in the plan: a place gets an action of its own
/// (`python:PLACE`, keeping its timeout and failure policy); an action name the plan uses
/// is registered as it is.
fn bind(plan: &mut Plan, key: &str) -> Outcome<String> {
    if let Some(p) = plan.net.place_by_name(key) {
        let name = format!("python:{key}");
        let role = match plan.roles[p.index()].take() {
            Some(Role::Resource) => {
                return Err(Failure::input(format!(
                    "actions[{key:?}]: place `{key}` is a resource, not an action place"
                )));
            }
            Some(Role::Action {
                timeout,
                on_failure,
                robot,
                ..
            }) => Role::Action {
                name: name.clone(),
                timeout,
                on_failure,
                robot,
            },
            None => Role::Action {
                name: name.clone(),
                timeout: None,
                on_failure: Default::default(),
                robot: None,
            },
        };
        plan.roles[p.index()] = Some(role);
        return Ok(name);
    }
    let used = plan
        .roles
        .iter()
        .any(|r| matches!(r, Some(Role::Action { name, .. }) if name == key));
    if used {
        Ok(key.to_string())
    } else {
        Err(Failure::input(format!(
            "actions[{key:?}]: the plan has no place `{key}` and no place whose action is `{key}`"
        )))
    }
}

fn runtime(plan: &Plan) -> std::io::Result<tokio::runtime::Runtime> {
    // A simulated world in virtual time runs on tokio's paused clock (as `plan-runner`).
    if plan.map.is_some() && plan.time_scale.unwrap_or(0.0) == 0.0 {
        return tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build();
    }
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
}

async fn execute(
    mut plan: Plan,
    registered: Vec<(String, Py<PyAny>)>,
    call: Arc<Py<PyAny>>,
    journal: Option<PathBuf>,
    robots: Option<usize>,
    stop: Arc<AtomicBool>,
) -> Outcome<String> {
    let mut backends = Backends::default();
    let programs = std::mem::take(&mut plan.programs);
    if !programs.is_empty() {
        backends.push(gspn::actions::ProgramActions::new(programs));
    }
    let builder: RuntimeBuilder = if plan.map.is_some() {
        let fleet =
            gspn::world::Fleet::new(plan, robots).map_err(|e| Failure::input(e.to_string()))?;
        backends.push(gspn::world::WorldBackend::new(fleet.world));
        fleet.builder
    } else {
        plan.runtime_builder()
    };
    let mut b = backends
        .attach(builder)
        .map_err(|e| Failure::Run(e.to_string()))?;
    for (name, func) in registered {
        b = b.action(
            name,
            PyAction {
                func: Arc::new(func),
                call: Arc::clone(&call),
            },
        );
    }
    if let Some(j) = journal {
        b = b.journal(j);
    }
    let handle = b.spawn().map_err(|e| Failure::input(e.to_string()))?;
    let handle = match backends.start(handle).await {
        Ok(h) => h,
        Err(e) => {
            backends.stop();
            return Err(Failure::Run(e.to_string()));
        }
    };
    let wait = handle.wait();
    tokio::pin!(wait);
    let mut tick = tokio::time::interval(Duration::from_millis(20));
    let mut interrupted = false;
    let summary = loop {
        tokio::select! {
            s = &mut wait => break s,
            _ = tick.tick(), if !interrupted => {
                if stop.load(Ordering::Relaxed) {
                    interrupted = true;
                    handle.interrupt();
                }
            }
        }
    };
    let sections = backends.finish(&summary).await;
    backends.stop();
    let mut v = serde_json::to_value(&summary).map_err(|e| Failure::Run(e.to_string()))?;
    for (name, s) in sections {
        v[name] = s.json;
    }
    v["seed"] = serde_json::json!(handle.seed());
    v["exit_code"] = serde_json::json!(summary.exit_code());
    Ok(v.to_string())
}

/// A Python callable as a place's action. It runs on tokio's blocking pool, holding the
/// GIL only while Python runs; the run (in virtual time too) waits for its answer like any
/// action's.
struct PyAction {
    func: Arc<Py<PyAny>>,
    call: Arc<Py<PyAny>>,
}

/// What the callable answered, normalised by `gspn._actions.call`.
type Answer = (Option<String>, f64);

impl Action for PyAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let func = Arc::clone(&self.func);
        let call = Arc::clone(&self.call);
        Box::pin(async move {
            let info = ctx.clone();
            let answer = tokio::task::spawn_blocking(move || {
                Python::attach(|py| -> PyResult<Answer> {
                    let c = context(py, &info)?;
                    call.bind(py).call1((func.bind(py), c))?.extract()
                })
                .map_err(|e| Python::attach(|py| describe(py, e)))
            });
            let answer = tokio::select! {
                a = answer => a,
                _ = ctx.cancel.cancelled() => return Done::Cancelled,
            };
            match answer {
                Err(join) => Done::Failed(format!("the Python action did not finish: {join}")),
                Ok(Err(message)) => Done::Failed(message),
                Ok(Ok((fire, after))) => {
                    if after > 0.0 {
                        tokio::select! {
                            _ = ctx.clock.sleep(after) => {}
                            _ = ctx.cancel.cancelled() => return Done::Cancelled,
                        }
                    }
                    match fire {
                        None => Done::Decide,
                        Some(name) => match ctx.transition(&name) {
                            Some(t) => Done::Fire(t),
                            None => Done::Failed(format!(
                                "the Python action of `{}` answered {name:?}, which is not a transition",
                                ctx.place_name()
                            )),
                        },
                    }
                }
            }
        })
    }
}

/// The context a Python action receives (a dict; `gspn._actions` makes it an object).
fn context<'py>(py: Python<'py>, ctx: &ActionContext) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let net = &ctx.net;
    d.set_item("agent", ctx.agent.0)?;
    d.set_item("robot", ctx.robot.as_deref())?;
    d.set_item("place", ctx.place_name())?;
    let marking = PyDict::new(py);
    for (p, &k) in net.places().iter().zip(ctx.marking.iter()) {
        if k > 0 {
            marking.set_item(&p.name, k)?;
        }
    }
    d.set_item("marking", marking)?;
    d.set_item("attempt", ctx.attempt)?;
    d.set_item("time", ctx.time)?;
    d.set_item("seed", ctx.seed)?;
    let outputs: Vec<&str> = ctx
        .outputs()
        .into_iter()
        .map(|t| net.transition(t).name.as_str())
        .collect();
    d.set_item("outputs", PyList::new(py, outputs)?)?;
    Ok(d)
}

/// A Python exception as an action's failure message: `Type: message`.
fn describe(py: Python<'_>, e: PyErr) -> String {
    let kind = e
        .get_type(py)
        .name()
        .map(|n| n.to_string())
        .unwrap_or_else(|_| "Exception".into());
    format!("{kind}: {}", e.value(py))
}
