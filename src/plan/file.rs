//! A plan file as written ([`PlanFile`]): the TOML's types, from which the JSON Schema
//! (`docs/plan.schema.json`) is generated, and the parser. Names are still names here;
//! [`resolve`](super::resolve) turns them into ids.

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use schemars::JsonSchema;
use serde::Deserialize;
use toml::Spanned;

use super::map::MapFile;
use super::programs::{ActionFile, WorkerFile};
use super::rewards::RewardFile;
use super::ros2::Ros2File;
use crate::io::{LoadError, LoadErrorKind, Span};

/// A plan file as written, before it is checked against its net. The JSON Schema in
/// `docs/plan.schema.json` is generated from this type.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
#[schemars(title = "gspn plan")]
pub struct PlanFile {
    /// The net file (PIPE `.xml`, `.pnml` or `.PNPRO`), relative to the plan file.
    #[schemars(with = "String")]
    pub net: Spanned<String>,
    /// The page of the net file to read (PNPRO files may hold several).
    pub page: Option<String>,
    /// Template parameters of the net (PNPRO `<template>`), overriding the file's
    /// `last-binding`; `--param NAME=VALUE` on the command line overrides these.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, ParamValue>")]
    pub params: BTreeMap<Spanned<String>, ParamValue>,
    /// Seed for every random choice; the same seed repeats a run exactly.
    pub seed: Option<u64>,
    /// Scale of time: 0 = virtual time as fast as possible, 1 = real time, 0.5 = twice as fast.
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub time_scale: Option<Spanned<f64>>,
    /// Roles of places, by place name. Places not listed have no role: their exponential
    /// transitions are timed by the net.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, PlaceFile>")]
    pub places: BTreeMap<Spanned<String>, Spanned<PlaceFile>>,
    /// Policy rules, looked up as DESIGN.md says: an exact marking through a hash index
    /// first, then partial patterns in this order.
    #[serde(default)]
    #[schemars(with = "Vec<RuleFile>")]
    pub policy: Vec<Spanned<RuleFile>>,
    /// When the run ends.
    pub stop: Option<StopFile>,
    /// Robot names bound to the initial agents, in agent order: places in net order, then
    /// tokens. Every initial token outside resource places is an agent, so a non-empty list
    /// names exactly that many robots (another length is refused at this key). Each agent
    /// keeps its robot as it moves through the net; a net that can create or destroy robot
    /// tokens (outside resource places) is refused when the run starts.
    #[serde(default)]
    #[schemars(with = "Vec<String>")]
    pub robots: Vec<Spanned<String>>,
    /// The room for simulated robots (feature `sim`): locations, the topological map, walls,
    /// obstacles; see `docs/plans.md`.
    #[schemars(with = "Option<MapFile>")]
    pub map: Option<Spanned<MapFile>>,
    /// ROS 2 backend settings (feature `ros2`; see `docs/ros2.md`).
    pub ros2: Option<Ros2File>,
    /// Reward structures for policy synthesis and evaluation, by name (see
    /// `docs/synthesis.md`).
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, RewardFile>")]
    pub rewards: BTreeMap<Spanned<String>, Spanned<RewardFile>>,
    /// The immediate transitions a policy controls (default: the net's zero-weight ones).
    #[schemars(with = "Option<Vec<String>>")]
    pub controllable: Option<Vec<Spanned<String>>>,
    /// Long-lived worker programs, by name, that places use with
    /// `action = { worker = "NAME", name = "…" }` (see `docs/actions.md`).
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, WorkerFile>")]
    pub workers: BTreeMap<Spanned<String>, Spanned<WorkerFile>>,
    /// Let a policy WAIT in markings where exponential transitions are enabled besides the
    /// controllable ones (the GSPNR toolbox's `toMDP`); default false.
    pub wait: Option<bool>,
}

/// The value of a net parameter: a number or an expression the net reader evaluates.
#[derive(Clone, Debug, PartialEq, Deserialize, JsonSchema)]
#[serde(untagged)]
pub enum ParamValue {
    /// An integer, e.g. `N = 3`.
    Int(i64),
    /// A real number, e.g. `rate = 0.5`.
    Float(f64),
    /// An expression or any other text, passed to the reader as written.
    Text(String),
}

impl std::fmt::Display for ParamValue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ParamValue::Int(i) => write!(f, "{i}"),
            ParamValue::Float(x) => write!(f, "{x:?}"),
            ParamValue::Text(t) => f.write_str(t),
        }
    }
}

/// The role of one place.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct PlaceFile {
    /// The action each token entering the place runs: a name (a built-in `wait [S]`,
    /// `log MSG`, `fire T [after S]`; a robot program with a `[map]`; `ros2`; or an action a
    /// library user registers), or a program: `{ command = [...] }`,
    /// `{ worker = [...] | "NAME", name = "…" }` (see `docs/actions.md`).
    #[schemars(with = "Option<ActionFile>")]
    pub action: Option<Spanned<ActionFile>>,
    /// `"resource"`: the tokens are counters, not agents. (`"action"` is implied by `action`.)
    #[schemars(with = "Option<String>")]
    pub role: Option<Spanned<String>>,
    /// Seconds the action may run before it counts as failed.
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub timeout: Option<Spanned<f64>>,
    /// What to do when the action fails: `"stop"` (default), `"retry N"` or `"fire T"` (T an
    /// output transition of this place).
    #[schemars(with = "Option<String>")]
    pub on_failure: Option<Spanned<String>>,
    /// The robot this place's agents are bound to.
    pub robot: Option<String>,
    /// With `action = "ros2"`: the ExecPlace action server of the robots, reached at
    /// `/<robot>/<server>` (default `"exec_place"`).
    #[schemars(with = "Option<String>")]
    pub server: Option<Spanned<String>>,
    /// With `action = "ros2"`: the target pose sent in the ExecPlace goal (frame `map`):
    /// `[x, y]` or `[x, y, yaw]` (metres, radians).
    #[schemars(with = "Option<Vec<f64>>")]
    pub target: Option<Spanned<Vec<f64>>>,
    /// With `action = "ros2"`: text arguments sent in the ExecPlace goal
    /// (`diagnostic_msgs/KeyValue` pairs).
    #[schemars(with = "Option<BTreeMap<String, String>>")]
    pub args: Option<Spanned<BTreeMap<String, String>>>,
}

/// One policy rule.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RuleFile {
    /// Token counts by place name. With `partial = false` (the default) this is the whole
    /// marking: places not listed hold 0 tokens.
    #[schemars(with = "BTreeMap<String, u32>")]
    pub marking: BTreeMap<Spanned<String>, Spanned<u32>>,
    /// `true`: only the listed places must match; the others are free (the thesis's `'-'`).
    #[serde(default)]
    pub partial: bool,
    /// Probabilities of immediate transitions, by name (each in [0, 1], summing to 1).
    #[schemars(with = "BTreeMap<String, f64>")]
    pub choose: BTreeMap<Spanned<String>, Spanned<f64>>,
}

/// Stop conditions.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct StopFile {
    /// A marking predicate (see `docs/plans.md`), e.g. `"P_done >= 3 && Busy == 0"`.
    #[schemars(with = "Option<String>")]
    pub when: Option<Spanned<String>>,
    /// Stop at this model time (seconds).
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub time_limit: Option<Spanned<f64>>,
    /// Stop after this many firings (≥ 1).
    #[schemars(with = "Option<u64>", range(min = 1))]
    pub max_firings: Option<Spanned<u64>>,
}

/// The JSON Schema of plan files, as committed in `docs/plan.schema.json`.
pub fn json_schema() -> String {
    let schema = schemars::schema_for!(PlanFile);
    let mut s = serde_json::to_string_pretty(&schema).unwrap_or_default();
    s.push('\n');
    s
}

impl PlanFile {
    /// Parses the TOML text of `path` (no net needed yet). Unknown keys and wrong types are
    /// refused with their line and column.
    pub fn parse(path: &Path, text: &str) -> Result<PlanFile, LoadError> {
        toml::from_str::<PlanFile>(text).map_err(|e| {
            let message = misplaced_map_key(e.message().trim());
            match e.span() {
                Some(s) => LoadError::at(path, locate(text, s), LoadErrorKind::Invalid(message)),
                None => LoadError::file(path, LoadErrorKind::Invalid(message)),
            }
        })
    }

    /// The net file, resolved against the directory of the plan at `plan_path`.
    pub fn net_path(&self, plan_path: &Path) -> PathBuf {
        let dir = plan_path.parent().unwrap_or(Path::new(""));
        dir.join(self.net.get_ref())
    }
}

/// TOML puts a key into the last table header above it: a `[map]` key (`edges = …`, `patrol`,
/// `walls`, …) written after a `[map.locations.NAME]` header lands in that location, whose
/// reader then says "unknown field". Says where the key belongs.
fn misplaced_map_key(message: &str) -> String {
    const MAP_KEYS: [&str; 8] = [
        "edges",
        "patrol",
        "walls",
        "obstacles",
        "step_hz",
        "robot",
        "stuck_after",
        "locations",
    ];
    let in_location = message.contains("expected one of `x`, `y`, `queue`, `places`");
    let key = MAP_KEYS
        .iter()
        .find(|k| message.starts_with(&format!("unknown field `{k}`")));
    match key {
        Some(k) if in_location => format!(
            "{message}: `{k}` belongs to [map], and this line is under a [map.locations.…] \
             header (TOML puts a key into the last table above it) — move it above the first \
             [map.locations.…] table"
        ),
        _ => message.to_string(),
    }
}

/// The line and column of the start of `span` in `text`.
pub(super) fn locate(text: &str, span: Range<usize>) -> Span {
    Span::locate(text.as_bytes(), span.start)
}
