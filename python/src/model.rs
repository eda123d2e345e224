//! Nets and plans as Python sees them: `load`, `build`, and the `Model` they return.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use gspn::io::{Format, Loaded, ReadOptions, Span};
use gspn::net::{ArcKind, NetBuilder, Servers, Timing};
use gspn::plan::{Plan, open};
use pyo3::prelude::*;
use serde::Deserialize;
use serde_json::{Value, json};

use crate::errors::{Failure, Outcome, raise};

/// A net, or a plan with its net (policy, rewards, roles, stop conditions): what the Python
/// `gspn.Net` wraps. Immutable: every call works on its own copy.
#[pyclass(frozen, module = "gspn._native")]
pub(crate) struct Model {
    pub(crate) plan: Arc<Plan>,
    /// Read from a plan file (`.toml`), not a bare net.
    pub(crate) is_plan: bool,
}

#[pymethods]
impl Model {
    /// The net as plain data (JSON): name, places, transitions, arcs, and for a plan its
    /// file, rewards, policy size and controllable transitions.
    fn describe(&self) -> String {
        let plan = &self.plan;
        let net = &plan.net;
        let places: Vec<Value> = net
            .places()
            .iter()
            .map(|p| json!({"name": p.name, "initial": p.initial, "capacity": p.capacity}))
            .collect();
        let transitions: Vec<Value> = net
            .transitions()
            .iter()
            .map(|t| match t.timing {
                Timing::Immediate { weight, priority } => json!({
                    "name": t.name, "kind": "immediate", "weight": weight, "priority": priority,
                }),
                Timing::Exponential { rate, servers } => json!({
                    "name": t.name, "kind": "exponential", "rate": rate,
                    "servers": match servers {
                        Servers::Single => json!(1),
                        Servers::Infinite => json!("infinite"),
                        Servers::K(k) => json!(k),
                    },
                }),
            })
            .collect();
        let arcs: Vec<Value> = net
            .arcs()
            .iter()
            .map(|a| {
                json!({
                    "kind": match a.kind {
                        ArcKind::Input => "input",
                        ArcKind::Output => "output",
                        ArcKind::Inhibitor => "inhibitor",
                    },
                    "place": net.place(a.place).name,
                    "transition": net.transition(a.transition).name,
                    "weight": a.weight,
                })
            })
            .collect();
        let controllable: Vec<&str> = net
            .transition_ids()
            .filter(|t| {
                plan.controls
                    .controllable
                    .get(t.index())
                    .copied()
                    .unwrap_or(false)
            })
            .map(|t| net.transition(t).name.as_str())
            .collect();
        json!({
            "name": net.name(),
            // The plan file, or the net file for a bare net (`Plan::for_net` sets both).
            "source": plan.path.display().to_string(),
            "is_plan": self.is_plan,
            "places": places,
            "transitions": transitions,
            "arcs": arcs,
            "rewards": plan.rewards.iter().map(|r| r.name.clone()).collect::<Vec<_>>(),
            "policy_rules": plan.policy.rules().len(),
            "controllable": controllable,
            "warnings": plan.warnings,
        })
        .to_string()
    }

    /// The net in a file format: `pnpro`, `pnml`, `pipe` or `dot`.
    fn to_text(&self, py: Python<'_>, format: &str) -> PyResult<String> {
        let net = &self.plan.net;
        let text = match format {
            "pnpro" => gspn::io::pnpro::write(net),
            "pnml" => gspn::io::pnml::write(net),
            "pipe" => gspn::io::pipe::write(net),
            "dot" => gspn::io::dot::write(net),
            other => {
                return raise(
                    py,
                    Err(Failure::input(format!(
                        "format `{other}`: expected pnpro, pnml, pipe or dot"
                    ))),
                );
            }
        };
        Ok(text)
    }

    /// Positions for a drawing (JSON): the file's when every node has one, else the viewer's
    /// layered layout.
    fn layout(&self) -> String {
        let l = gspn::web::layout::layout(&self.plan.net);
        let xy = |p: &gspn::net::Position| [p.x, p.y];
        json!({
            "places": l.places.iter().map(xy).collect::<Vec<_>>(),
            "transitions": l.transitions.iter().map(xy).collect::<Vec<_>>(),
            "arcs": l.arcs.iter().map(|a| a.iter().map(xy).collect::<Vec<_>>()).collect::<Vec<_>>(),
        })
        .to_string()
    }
}

/// Reads a net file (PNPRO, PNML, PIPE) or a plan (`.toml`): what `plan-runner` reads.
#[pyfunction]
#[pyo3(signature = (path, params = None, page = None))]
pub(crate) fn load(
    py: Python<'_>,
    path: PathBuf,
    params: Option<Vec<(String, String)>>,
    page: Option<String>,
) -> PyResult<Model> {
    let opts = ReadOptions {
        page,
        params: params.unwrap_or_default(),
    };
    let is_plan = Format::from_extension(&path) == Some(Format::Plan);
    let plan = py
        .detach(|| open(&path, &opts))
        .map_err(|e| Failure::from(e).into_py(py))?
        .into_plan();
    Ok(Model {
        plan: Arc::new(plan),
        is_plan,
    })
}

#[derive(Deserialize)]
struct Spec {
    name: String,
    places: Vec<PlaceSpec>,
    transitions: Vec<TransitionSpec>,
    arcs: Vec<ArcSpec>,
}

#[derive(Deserialize)]
struct PlaceSpec {
    name: String,
    initial: u32,
    capacity: Option<u32>,
}

#[derive(Deserialize)]
struct TransitionSpec {
    name: String,
    rate: Option<f64>,
    weight: Option<f64>,
    priority: Option<u32>,
    servers: Option<Value>,
}

#[derive(Deserialize)]
struct ArcSpec {
    kind: String,
    place: String,
    transition: String,
    weight: u32,
}

/// Builds a net from plain data (JSON of `gspn.Net.build`'s arguments), with the library's
/// checks: names unique, rates > 0 and finite, weights ≥ 0, priorities ≥ 1.
#[pyfunction]
pub(crate) fn build(py: Python<'_>, spec: &str) -> PyResult<Model> {
    raise(py, build_net(spec))
}

fn build_net(spec: &str) -> Outcome<Model> {
    let spec: Spec = serde_json::from_str(spec).map_err(|e| Failure::input(e.to_string()))?;
    let mut b = NetBuilder::new(spec.name.clone());
    for p in &spec.places {
        b.place_with_capacity(p.name.clone(), p.initial, p.capacity);
    }
    for t in &spec.transitions {
        match (t.rate, t.weight) {
            (Some(rate), None) => {
                let servers = match &t.servers {
                    None => Servers::Single,
                    Some(Value::String(s)) if s == "infinite" => Servers::Infinite,
                    Some(v) => match v.as_u64() {
                        Some(1) => Servers::Single,
                        Some(k) if k > 1 && k <= u64::from(u32::MAX) => Servers::K(k as u32),
                        _ => {
                            return Err(Failure::input(format!(
                                "transition `{}`: servers {v}: expected a count ≥ 1 or \"infinite\"",
                                t.name
                            )));
                        }
                    },
                };
                b.exponential(t.name.clone(), rate, servers);
            }
            (None, Some(weight)) => {
                b.immediate(t.name.clone(), weight, t.priority.unwrap_or(1));
            }
            _ => {
                return Err(Failure::input(format!(
                    "transition `{}`: give a rate (exponential) or a weight (immediate), not both or neither",
                    t.name
                )));
            }
        }
    }
    for a in &spec.arcs {
        let p = b
            .find_place(&a.place)
            .ok_or_else(|| Failure::input(format!("arc: no place `{}`", a.place)))?;
        let t = b
            .find_transition(&a.transition)
            .ok_or_else(|| Failure::input(format!("arc: no transition `{}`", a.transition)))?;
        let kind = match a.kind.as_str() {
            "input" => ArcKind::Input,
            "output" => ArcKind::Output,
            "inhibitor" => ArcKind::Inhibitor,
            other => {
                return Err(Failure::input(format!(
                    "arc `{}`–`{}`: kind `{other}`: expected input, output or inhibitor",
                    a.place, a.transition
                )));
            }
        };
        b.arc(kind, p, t, a.weight, Vec::new());
    }
    let net = b.build().map_err(|e| Failure::input(e.to_string()))?;
    let transitions = net.transition_count();
    let loaded = Loaded {
        net,
        format: Format::Pnpro,
        warnings: Vec::new(),
        transition_at: vec![Span { line: 1, column: 1 }; transitions],
    };
    Ok(Model {
        plan: Arc::new(Plan::for_net(Path::new(&spec.name), loaded)),
        is_plan: false,
    })
}
