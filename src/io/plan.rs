//! Plan files (TOML): the net, the roles of its places, the policy, the stop conditions.
//!
//! ```toml
//! net = "temperature_patrol.xml"      # relative to this file
//! page = "main"                       # optional (PNPRO pages)
//! seed = 42
//! time_scale = 0.0                    # 0 = virtual time, as fast as possible; 1 = real time
//!
//! [params]                            # PNPRO template parameters (--param overrides)
//! N = 3
//!
//! [places."p1:Check_Temperature_L1"]
//! action = "check_temperature"        # or: role = "resource"
//! timeout = 30.0
//! on_failure = "retry 3"              # "stop" | "retry N" | "fire T"
//!
//! [[policy]]
//! marking = { "p3:Decide_L1" = 1, "p5:Check_Temperature_L2" = 0 }
//! partial = true                      # listed places must match, the others are free
//! choose = { "t6:Go_Check_L2" = 1.0 }
//!
//! [stop]
//! when = "`p1:Check_Temperature_L1` == 0"
//! time_limit = 1000.0
//! max_firings = 100000
//! ```
//!
//! [`PlanFile`] is the TOML as written (its JSON Schema is `docs/plan.schema.json`);
//! [`PlanFile::resolve`] checks it against the net and gives a [`Plan`], where names have
//! become ids. Every mistake is a [`LoadError`] with the plan's line and column: unknown keys,
//! a place or transition that does not exist, a bad probability, a bad predicate.

pub mod map;

use std::collections::BTreeMap;
use std::ops::Range;
use std::path::{Path, PathBuf};

use schemars::JsonSchema;
use serde::Deserialize;
use toml::Spanned;

use super::{LoadError, LoadErrorKind, Loaded, ReadOptions, Span, read_net};

mod rewards;
mod ros2;

use crate::analysis::decision::{Controls, RewardSpec};
use crate::net::predicate::Predicate;
use crate::net::{Net, PlaceId, Timing, TransitionId};
use crate::policy::{Pattern, Policy, PolicyError, Rule};
pub use rewards::RewardFile;
use rewards::{resolve_controls, resolve_rewards};
use ros2::resolve_ros2;
pub use ros2::{DEFAULT_SERVER, ROS2_ACTION, Ros2File, Ros2Settings};

/// A plan ready to run: the net, what each place does, the policy and when to stop.
#[derive(Clone, Debug)]
pub struct Plan {
    /// The plan file.
    pub path: PathBuf,
    /// The net file, resolved relative to the plan's directory.
    pub net_path: PathBuf,
    /// The page of the net file that was read, when one was named.
    pub page: Option<String>,
    /// The net.
    pub net: Net,
    /// Seed for every random choice; `None` = the caller picks one.
    pub seed: Option<u64>,
    /// Scale of time: 0 = virtual time as fast as possible, 1 = real time.
    pub time_scale: Option<f64>,
    /// Role of each place, indexed by [`PlaceId::index`]; `None` = no role (net-timed).
    pub roles: Vec<Option<Role>>,
    /// The policy over immediate transitions.
    pub policy: Policy,
    /// Where each policy rule is in the plan file, in rule order.
    pub rule_spans: Vec<Span>,
    /// When the run ends (besides "nothing can fire any more").
    pub stop: StopConditions,
    /// Robots bound to the initial agents, in agent order (places in net order, then
    /// tokens); empty when the plan names none.
    pub robots: Vec<String>,
    /// Things accepted but worth saying (from the net reader and from the plan).
    pub warnings: Vec<String>,
    /// The room simulated robots drive in (`[map]`), when the plan has one.
    pub map: Option<map::Map>,
    /// The ROS 2 backend's settings and the places it serves (feature `ros2`).
    pub ros2: Ros2Settings,
    /// Reward structures (`[rewards.NAME]`), in name order.
    pub rewards: Vec<RewardSpec>,
    /// What a policy controls: `controllable` transitions and `wait`.
    pub controls: Controls,
}

/// What a place does when tokens enter it.
#[derive(Clone, Debug, PartialEq)]
pub enum Role {
    /// Each token is an agent running this action.
    Action {
        /// The registered action's name.
        name: String,
        /// Seconds the action may run before it fails; `None` = no limit.
        timeout: Option<f64>,
        /// What to do when it fails.
        on_failure: FailurePolicy,
        /// The robot the place's agents are bound to, when there is one.
        robot: Option<String>,
    },
    /// Tokens are plain counters (a shared resource).
    Resource,
}

/// What to do when an action fails.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum FailurePolicy {
    /// Stop the plan (the default).
    #[default]
    Stop,
    /// Run the action again, at most this many more times, then stop.
    Retry(u32),
    /// Fire this transition (an output of the place) as if the action had chosen it.
    Fire(TransitionId),
}

/// When a run ends, besides "nothing can ever fire again".
#[derive(Clone, Debug, Default)]
pub struct StopConditions {
    /// Stop as soon as the marking satisfies this predicate.
    pub when: Option<Predicate>,
    /// Stop at this (model) time.
    pub time_limit: Option<f64>,
    /// Stop after this many firings.
    pub max_firings: Option<u64>,
}

impl Plan {
    /// The plan for a bare net: no roles (every place net-timed), no policy, no stop
    /// condition. `plan-runner run NET` uses it.
    pub fn for_net(net_path: &Path, loaded: Loaded) -> Plan {
        let n = loaded.net.place_count();
        let controls = Controls::zero_weight(&loaded.net);
        Plan {
            path: net_path.to_path_buf(),
            net_path: net_path.to_path_buf(),
            page: None,
            net: loaded.net,
            seed: None,
            time_scale: None,
            roles: vec![None; n],
            policy: Policy::empty(),
            rule_spans: Vec::new(),
            stop: StopConditions::default(),
            robots: Vec::new(),
            warnings: loaded.warnings,
            map: None,
            ros2: Ros2Settings::default(),
            rewards: Vec::new(),
            controls,
        }
    }

    /// The role of place `p`.
    pub fn role(&self, p: PlaceId) -> Option<&Role> {
        self.roles.get(p.index()).and_then(Option::as_ref)
    }
}

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
    pub params: BTreeMap<String, ParamValue>,
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
    /// tokens. Each agent keeps its robot as it moves through the net; a net that can create
    /// or destroy robot tokens (outside resource places) is refused when the run starts.
    #[serde(default)]
    #[schemars(with = "Vec<String>")]
    pub robots: Vec<Spanned<String>>,
    /// The room for simulated robots (feature `sim`): locations, the topological map, walls,
    /// obstacles; see `docs/plans.md`.
    #[schemars(with = "Option<map::MapFile>")]
    pub map: Option<Spanned<map::MapFile>>,
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
    /// The action each token entering the place runs (a name registered with the runtime).
    pub action: Option<String>,
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
    /// Stop after this many firings.
    #[schemars(range(min = 1))]
    pub max_firings: Option<u64>,
}

/// The JSON Schema of plan files, as committed in `docs/plan.schema.json`.
pub fn json_schema() -> String {
    let schema = schemars::schema_for!(PlanFile);
    let mut s = serde_json::to_string_pretty(&schema).unwrap_or_default();
    s.push('\n');
    s
}

/// Reads and checks the plan in `path`, and the net it names. `opts.page` (the CLI's
/// `--page`) overrides the plan's `page`; `opts.params` override the plan's `params` of the
/// same name, and both go to the net reader.
pub fn read_plan(path: &Path, opts: &ReadOptions) -> Result<Plan, LoadError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| LoadError::file(path, LoadErrorKind::Io(e.to_string())))?;
    if text.trim().is_empty() {
        return Err(LoadError::file(path, LoadErrorKind::Empty));
    }
    let file = PlanFile::parse(path, &text)?;
    let net_path = file.net_path(path);
    let page = opts.page.clone().or_else(|| file.page.clone());
    let mut params: Vec<(String, String)> = file
        .params
        .iter()
        .filter(|(k, _)| !opts.params.iter().any(|(o, _)| o == *k))
        .map(|(k, v)| (k.clone(), v.to_string()))
        .collect();
    params.extend(opts.params.iter().cloned());
    let net_opts = ReadOptions {
        page: page.clone(),
        params,
    };
    if !net_path.is_file() {
        return Err(LoadError::at(
            path,
            locate(&text, file.net.span()),
            LoadErrorKind::Invalid(format!(
                "net file `{}` not found (looked at {})",
                file.net.get_ref(),
                net_path.display()
            )),
        ));
    }
    let loaded = read_net(&net_path, &net_opts)?;
    let mut plan = file.resolve(path, &text, loaded.net)?;
    plan.net_path = net_path;
    plan.page = page;
    let mut warnings = loaded.warnings;
    warnings.append(&mut plan.warnings);
    plan.warnings = warnings;
    Ok(plan)
}

fn locate(text: &str, span: Range<usize>) -> Span {
    Span::locate(text.as_bytes(), span.start)
}

impl PlanFile {
    /// Parses the TOML text of `path` (no net needed yet). Unknown keys and wrong types are
    /// refused with their line and column.
    pub fn parse(path: &Path, text: &str) -> Result<PlanFile, LoadError> {
        toml::from_str::<PlanFile>(text).map_err(|e| {
            let message = e.message().trim().to_string();
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

    /// Checks the plan against `net` (read from [`PlanFile::net_path`]) and resolves names
    /// to ids. `text` is the plan's text, for line and column numbers.
    pub fn resolve(self, path: &Path, text: &str, net: Net) -> Result<Plan, LoadError> {
        let at =
            |span: Range<usize>, kind: LoadErrorKind| LoadError::at(path, locate(text, span), kind);
        let mut warnings = Vec::new();

        if let Some(ts) = &self.time_scale {
            let v = *ts.get_ref();
            if !(v.is_finite() && v >= 0.0) {
                return Err(at(
                    ts.span(),
                    out_of_range("time_scale", "plan", v, "must be a finite number ≥ 0"),
                ));
            }
        }

        let mut roles: Vec<Option<Role>> = vec![None; net.place_count()];
        for (name, role) in &self.places {
            let p = net
                .place_by_name(name.get_ref())
                .ok_or_else(|| at(name.span(), unknown("place", name.get_ref())))?;
            roles[p.index()] = Some(resolve_role(&net, p, role, &at)?);
            if matches!(roles[p.index()], Some(Role::Action { .. }))
                && net_outputs(&net, p).is_empty()
            {
                warnings.push(format!(
                    "place `{}` has an action but no output transition: its agents end Inactive",
                    name.get_ref()
                ));
            }
        }

        let ros2 = resolve_ros2(&net, self.ros2.as_ref(), &self.places, &at)?;

        let mut rules = Vec::with_capacity(self.policy.len());
        let mut rule_spans = Vec::with_capacity(self.policy.len());
        for rule in &self.policy {
            rules.push(resolve_rule(&net, rule.get_ref(), &at)?);
            rule_spans.push(locate(text, rule.span()));
        }
        let policy = Policy::new(&net, rules).map_err(|e| {
            let rule = self.policy[e.rule()].get_ref();
            let span = policy_error_span(&e, rule).unwrap_or_else(|| self.policy[e.rule()].span());
            at(span, LoadErrorKind::Invalid(format!("policy {e}")))
        })?;

        let mut stop = StopConditions::default();
        if let Some(s) = &self.stop {
            if let Some(w) = &s.when {
                let pred = Predicate::parse(&net, w.get_ref()).map_err(|e| {
                    let span = w.span();
                    let start = span.start + string_content_offset(text, span.start);
                    // Columns count characters; the content starts after the opening quote.
                    let byte = w
                        .get_ref()
                        .char_indices()
                        .nth(e.column.saturating_sub(1))
                        .map_or(w.get_ref().len(), |(i, _)| i);
                    let kind = match e.name {
                        Some(n) if e.message.contains("does not exist") => unknown("place", &n),
                        _ => LoadErrorKind::Invalid(format!("stop.when: {}", e.message)),
                    };
                    at(start + byte..start + byte, kind)
                })?;
                stop.when = Some(pred);
            }
            if let Some(t) = &s.time_limit {
                let v = *t.get_ref();
                if !(v.is_finite() && v > 0.0) {
                    return Err(at(
                        t.span(),
                        out_of_range("time_limit", "stop", v, "must be a finite number > 0"),
                    ));
                }
                stop.time_limit = Some(v);
            }
            if s.max_firings == Some(0) {
                warnings.push("stop.max_firings = 0: the run stops before any firing".into());
            }
            stop.max_firings = s.max_firings;
        }

        let mut robots: Vec<String> = Vec::with_capacity(self.robots.len());
        for r in &self.robots {
            let name = r.get_ref();
            if name.is_empty() || name.contains(char::is_whitespace) {
                return Err(at(
                    r.span(),
                    LoadErrorKind::Invalid(format!(
                        "robot name `{name}` must be non-empty and without spaces"
                    )),
                ));
            }
            if robots.iter().any(|n| n == name) {
                return Err(at(
                    r.span(),
                    LoadErrorKind::Invalid(format!("robot `{name}` is listed twice")),
                ));
            }
            robots.push(name.clone());
        }

        let map = match &self.map {
            Some(m) => Some(m.get_ref().resolve(&net, m.span(), &at)?),
            None => None,
        };
        if let Some(m) = &map {
            // Built-in robot actions (`goto L2; measure`) name locations: check them now.
            for (name, role) in &self.places {
                if let Some(a) = &role.get_ref().action {
                    m.program(a).map_err(|e| {
                        at(
                            role.span(),
                            LoadErrorKind::Invalid(format!("place `{}`: {e}", name.get_ref())),
                        )
                    })?;
                }
            }
        }

        let rewards = resolve_rewards(&net, &self.rewards, &at)?;
        let controls = resolve_controls(&net, self.controllable.as_ref(), self.wait, &at)?;

        Ok(Plan {
            path: path.to_path_buf(),
            net_path: self.net_path(path),
            page: self.page,
            net,
            seed: self.seed,
            time_scale: self.time_scale.map(Spanned::into_inner),
            roles,
            policy,
            rule_spans,
            stop,
            robots,
            warnings,
            map,
            ros2,
            rewards,
            controls,
        })
    }
}

/// Bytes between the start of a TOML string value and its content (its opening quotes).
fn string_content_offset(text: &str, start: usize) -> usize {
    let rest = &text[start.min(text.len())..];
    if rest.starts_with("\"\"\"") || rest.starts_with("'''") {
        3
    } else if rest.starts_with('"') || rest.starts_with('\'') {
        1
    } else {
        0
    }
}

fn unknown(what: &'static str, name: &str) -> LoadErrorKind {
    LoadErrorKind::UnknownNode {
        what,
        name: name.to_string(),
    }
}

fn out_of_range(what: &'static str, name: &str, v: f64, expected: &'static str) -> LoadErrorKind {
    LoadErrorKind::OutOfRange {
        what,
        name: name.to_string(),
        value: v.to_string(),
        expected,
    }
}

fn net_outputs(net: &Net, p: PlaceId) -> Vec<TransitionId> {
    net.transition_ids()
        .filter(|&t| net.inputs(t).iter().any(|&(q, _)| q == p))
        .collect()
}

fn resolve_role(
    net: &Net,
    p: PlaceId,
    role: &Spanned<PlaceFile>,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Role, LoadError> {
    let place = &net.place(p).name;
    let f = role.get_ref();
    let resource = match &f.role {
        None => false,
        Some(r) if r.get_ref() == "resource" => true,
        Some(r) if r.get_ref() == "action" => false,
        Some(r) => {
            return Err(at(
                r.span(),
                LoadErrorKind::Invalid(format!(
                    "role `{}` of place `{place}`: expected \"resource\" or \"action\"",
                    r.get_ref()
                )),
            ));
        }
    };
    if resource {
        if let Some(a) = &f.action {
            return Err(at(
                role.span(),
                LoadErrorKind::Invalid(format!(
                    "place `{place}` is a resource and also has action `{a}`: choose one"
                )),
            ));
        }
        for (key, span) in [
            ("timeout", f.timeout.as_ref().map(Spanned::span)),
            ("on_failure", f.on_failure.as_ref().map(Spanned::span)),
        ] {
            if let Some(span) = span {
                return Err(at(
                    span,
                    LoadErrorKind::Invalid(format!(
                        "place `{place}` is a resource: `{key}` applies to actions only"
                    )),
                ));
            }
        }
        if f.robot.is_some() {
            return Err(at(
                role.span(),
                LoadErrorKind::Invalid(format!(
                    "place `{place}` is a resource: `robot` applies to action places only"
                )),
            ));
        }
        return Ok(Role::Resource);
    }
    let Some(name) = f.action.clone() else {
        return Err(at(
            role.span(),
            LoadErrorKind::Missing {
                what: "`action` (or `role = \"resource\"`)".into(),
                name: Some(place.clone()),
            },
        ));
    };
    if name.trim().is_empty() {
        return Err(at(
            role.span(),
            LoadErrorKind::Invalid(format!("place `{place}`: the action name is empty")),
        ));
    }
    let timeout = match &f.timeout {
        None => None,
        Some(t) => {
            let v = *t.get_ref();
            if !(v.is_finite() && v > 0.0) {
                return Err(at(
                    t.span(),
                    out_of_range("timeout", place, v, "must be a finite number > 0"),
                ));
            }
            Some(v)
        }
    };
    let on_failure = match &f.on_failure {
        None => FailurePolicy::Stop,
        Some(s) => parse_failure(net, p, s.get_ref()).map_err(|kind| at(s.span(), kind))?,
    };
    Ok(Role::Action {
        name,
        timeout,
        on_failure,
        robot: f.robot.clone(),
    })
}

/// Parses `stop`, `retry N` or `fire T` for place `p`.
fn parse_failure(net: &Net, p: PlaceId, s: &str) -> Result<FailurePolicy, LoadErrorKind> {
    let place = &net.place(p).name;
    let s = s.trim();
    let (word, rest) = s.split_once(char::is_whitespace).unwrap_or((s, ""));
    let rest = rest.trim();
    match (word, rest) {
        ("stop", "") => Ok(FailurePolicy::Stop),
        ("retry", n) => {
            n.parse::<u32>()
                .map(FailurePolicy::Retry)
                .map_err(|_| LoadErrorKind::NotANumber {
                    what: "retry count",
                    name: place.clone(),
                    value: n.to_string(),
                })
        }
        ("fire", t) if !t.is_empty() => {
            let t = t.trim_matches('`');
            let id = net
                .transition_by_name(t)
                .ok_or_else(|| unknown("transition", t))?;
            if !net.inputs(id).iter().any(|&(q, _)| q == p) {
                return Err(LoadErrorKind::Invalid(format!(
                    "on_failure of `{place}`: transition `{t}` is not an output of the place"
                )));
            }
            Ok(FailurePolicy::Fire(id))
        }
        _ => Err(LoadErrorKind::Invalid(format!(
            "on_failure of `{place}`: `{s}` is not \"stop\", \"retry N\" or \"fire T\""
        ))),
    }
}

fn resolve_rule(
    net: &Net,
    r: &RuleFile,
    at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
) -> Result<Rule, LoadError> {
    let mut listed = Vec::with_capacity(r.marking.len());
    for (name, k) in &r.marking {
        let p = net
            .place_by_name(name.get_ref())
            .ok_or_else(|| at(name.span(), unknown("place", name.get_ref())))?;
        if let Some(cap) = net.place(p).capacity
            && *k.get_ref() > cap
        {
            return Err(at(
                k.span(),
                LoadErrorKind::Invalid(format!(
                    "policy marking of `{}` is {}, above its capacity {cap}: the rule could never apply",
                    name.get_ref(),
                    k.get_ref()
                )),
            ));
        }
        listed.push((p, *k.get_ref()));
    }
    listed.sort_by_key(|&(p, _)| p);
    let pattern = if r.partial {
        Pattern::Partial(listed)
    } else {
        let mut m = vec![0; net.place_count()];
        for (p, k) in listed {
            m[p.index()] = k;
        }
        Pattern::Exact(m)
    };
    let mut choose = Vec::with_capacity(r.choose.len());
    for (name, prob) in &r.choose {
        let t = net
            .transition_by_name(name.get_ref())
            .ok_or_else(|| at(name.span(), unknown("transition", name.get_ref())))?;
        if !matches!(net.transition(t).timing, Timing::Immediate { .. }) {
            return Err(at(
                name.span(),
                LoadErrorKind::Invalid(format!(
                    "policy chooses `{}`, an exponential transition: a policy chooses among immediate transitions",
                    name.get_ref()
                )),
            ));
        }
        choose.push((t, *prob.get_ref()));
    }
    Ok(Rule { pattern, choose })
}

/// The most precise span for a policy error: the offending transition's value or key.
fn policy_error_span(e: &PolicyError, rule: &RuleFile) -> Option<Range<usize>> {
    match e {
        PolicyError::BadProbability { name, .. } => rule
            .choose
            .iter()
            .find(|(k, _)| k.get_ref() == name)
            .map(|(_, v)| v.span()),
        PolicyError::NotImmediate { name, .. } | PolicyError::DuplicateTransition { name, .. } => {
            rule.choose
                .keys()
                .find(|k| k.get_ref() == name)
                .map(Spanned::span)
        }
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    /// P1 -T1-> P2 -t2|t3-> P3|P1 ; P3 -T4-> P1. Names with `:` as in the thesis.
    fn net() -> Net {
        let mut b = NetBuilder::new("n");
        let p1 = b.place("p1:Start", 2);
        let p2 = b.place("P2", 0);
        let p3 = b.place("P3", 0);
        let t1 = b.exponential("T1", 1.0, Servers::Single);
        let t2 = b.immediate("t2", 1.0, 1);
        let t3 = b.immediate("t3", 1.0, 1);
        let t4 = b.exponential("T4", 2.0, Servers::Single);
        b.input(p1, t1, 1);
        b.output(t1, p2, 1);
        b.input(p2, t2, 1);
        b.output(t2, p3, 1);
        b.input(p2, t3, 1);
        b.output(t3, p1, 1);
        b.input(p3, t4, 1);
        b.output(t4, p1, 1);
        b.build().unwrap()
    }

    fn load(text: &str) -> Result<Plan, LoadError> {
        let path = Path::new("dir/plan.toml");
        PlanFile::parse(path, text)?.resolve(path, text, net())
    }

    fn err_at(text: &str) -> (u32, u32, String) {
        let e = load(text).unwrap_err();
        let s = e.span.expect("a span");
        (s.line, s.column, e.kind.to_string())
    }

    #[test]
    fn a_full_plan_resolves_to_ids() {
        let plan = load(
            r#"net = "n.xml"
seed = 7
time_scale = 0.0
[places."p1:Start"]
action = "work"
timeout = 5.0
on_failure = "fire T1"
robot = "r1"
[places.P3]
role = "resource"
[[policy]]
marking = { P2 = 1 }
partial = true
choose = { t2 = 0.25, t3 = 0.75 }
[[policy]]
marking = { "p1:Start" = 1, P2 = 1 }
choose = { t3 = 1 }
[stop]
when = "P3 >= 2 || `p1:Start` == 0"
time_limit = 100.0
max_firings = 500
"#,
        )
        .unwrap();
        assert_eq!(plan.net_path, Path::new("dir/n.xml"));
        assert_eq!(plan.seed, Some(7));
        assert_eq!(plan.time_scale, Some(0.0));
        assert_eq!(
            plan.roles[0],
            Some(Role::Action {
                name: "work".into(),
                timeout: Some(5.0),
                on_failure: FailurePolicy::Fire(TransitionId(0)),
                robot: Some("r1".into()),
            })
        );
        assert_eq!(plan.roles[1], None);
        assert_eq!(plan.roles[2], Some(Role::Resource));
        let rules = plan.policy.rules();
        assert_eq!(rules[0].pattern, Pattern::Partial(vec![(PlaceId(1), 1)]));
        assert_eq!(rules[1].pattern, Pattern::Exact(vec![1, 1, 0]));
        assert_eq!(rules[1].choose, vec![(TransitionId(2), 1.0)]);
        assert_eq!(plan.rule_spans[0].line, 11);
        assert_eq!(plan.rule_spans[1].line, 15);
        // Exact rule first: marking (1,1,0) → t3 only.
        let t = [TransitionId(1), TransitionId(2)];
        assert_eq!(
            plan.policy.distribution(&plan.net, &[1, 1, 0], &t),
            Some(vec![(TransitionId(2), 1.0)])
        );
        assert_eq!(
            plan.policy.distribution(&plan.net, &[0, 1, 1], &t),
            Some(vec![(TransitionId(1), 0.25), (TransitionId(2), 0.75)])
        );
        let when = plan.stop.when.as_ref().unwrap();
        assert!(when.eval(&[1, 0, 2]) && when.eval(&[0, 1, 0]) && !when.eval(&[1, 1, 0]));
        assert_eq!(plan.stop.time_limit, Some(100.0));
        assert_eq!(plan.stop.max_firings, Some(500));
    }

    #[test]
    fn unknown_keys_are_refused_with_line_and_column() {
        let (l, c, m) = err_at("net = \"n.xml\"\nsede = 3\n");
        assert_eq!((l, c), (2, 1));
        assert!(m.contains("sede"), "{m}");
        let (l, c, m) = err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\ntimeot = 3\n");
        assert_eq!((l, c), (4, 1));
        assert!(m.contains("timeot"), "{m}");
    }

    #[test]
    fn unknown_names_are_load_errors_at_their_position() {
        let (l, c, m) = err_at("net = \"n.xml\"\n[places.P9]\naction = \"a\"\n");
        assert_eq!((l, c), (2, 9));
        assert_eq!(m, "place `P9` does not exist");
        let (l, c, m) = err_at(
            "net = \"n.xml\"\n[[policy]]\nmarking = { P2 = 1, Q = 0 }\nchoose = { t2 = 1 }\n",
        );
        assert_eq!((l, c), (3, 21));
        assert_eq!(m, "place `Q` does not exist");
        let (l, c, m) =
            err_at("net = \"n.xml\"\n[[policy]]\nmarking = { P2 = 1 }\nchoose = { t9 = 1 }\n");
        assert_eq!((l, c), (4, 12));
        assert_eq!(m, "transition `t9` does not exist");
        let (l, c, m) =
            err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"fire t9\"\n");
        assert_eq!((l, c), (4, 14));
        assert_eq!(m, "transition `t9` does not exist");
    }

    #[test]
    fn predicate_errors_point_inside_the_string() {
        let (l, c, m) = err_at("net = \"n.xml\"\n[stop]\nwhen = \"P2 > 0 && Nope == 1\"\n");
        assert_eq!((l, c), (3, 19));
        assert_eq!(m, "place `Nope` does not exist");
        let (l, c, m) = err_at("net = \"n.xml\"\n[stop]\nwhen = \"P2 = 0\"\n");
        assert_eq!((l, c), (3, 12));
        assert!(m.starts_with("stop.when:"), "{m}");
    }

    #[test]
    fn bad_probabilities_and_exponential_choices_are_refused() {
        let (l, c, m) = err_at(
            "net = \"n.xml\"\n[[policy]]\nmarking = {}\npartial = true\nchoose = { t2 = 0.5, t3 = 0.6 }\n",
        );
        assert_eq!((l, c), (2, 1));
        assert!(m.contains("sum to 1.1"), "{m}");
        let (l, c, m) = err_at(
            "net = \"n.xml\"\n[[policy]]\nmarking = {}\npartial = true\nchoose = { t2 = 1.5 }\n",
        );
        assert_eq!((l, c), (5, 17));
        assert!(m.contains("must be in [0, 1]"), "{m}");
        let (l, c, m) = err_at("net = \"n.xml\"\n[[policy]]\nmarking = {}\nchoose = { T1 = 1 }\n");
        assert_eq!((l, c), (4, 12));
        assert!(m.contains("exponential"), "{m}");
    }

    #[test]
    fn role_mistakes_are_refused() {
        let (l, _, m) = err_at("net = \"n.xml\"\n[places.P2]\ntimeout = 3.0\n");
        assert_eq!(l, 2);
        assert!(m.contains("`action`"), "{m}");
        let (l, c, m) =
            err_at("net = \"n.xml\"\n[places.P2]\nrole = \"resource\"\ntimeout = 3.0\n");
        assert_eq!((l, c), (4, 11));
        assert!(m.contains("resource"), "{m}");
        let (l, c, _) = err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\ntimeout = -1.0\n");
        assert_eq!((l, c), (4, 11));
        let (_, _, m) =
            err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"fire T4\"\n");
        assert!(m.contains("not an output"), "{m}");
        let (_, _, m) =
            err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"retry x\"\n");
        assert!(m.contains("`x` is not a number"), "{m}");
        let plan = load("net = \"n.xml\"\n[places.P2]\naction = \"a\"\non_failure = \"retry 3\"\n")
            .unwrap();
        assert!(matches!(
            plan.roles[1],
            Some(Role::Action {
                on_failure: FailurePolicy::Retry(3),
                ..
            })
        ));
    }

    #[test]
    fn ros2_places_and_settings_resolve() {
        let plan = load(
            "net = \"n.xml\"\n[ros2]\ndomain_id = 42\nnetworks = [\"127.0.0.1\"]\nlost_after = 0.5\n\
             [places.P2]\naction = \"ros2\"\nserver = \"exec_p2\"\n[places.P3]\naction = \"ros2\"\n",
        )
        .unwrap();
        assert_eq!(plan.ros2.domain_id, Some(42));
        assert_eq!(
            plan.ros2.networks,
            vec![std::net::IpAddr::from([127, 0, 0, 1])]
        );
        assert_eq!(plan.ros2.lost_after, Some(0.5));
        assert_eq!(plan.ros2.heartbeat, None);
        assert_eq!(
            plan.ros2.servers,
            vec![
                (PlaceId(1), "exec_p2".to_string()),
                (PlaceId(2), DEFAULT_SERVER.to_string())
            ]
        );
    }

    #[test]
    fn ros2_mistakes_are_refused_at_their_position() {
        let (l, c, m) = err_at("net = \"n.xml\"\n[places.P2]\naction = \"a\"\nserver = \"s\"\n");
        assert_eq!((l, c), (4, 10));
        assert!(
            m.contains("`server` applies to places with action = \"ros2\""),
            "{m}"
        );
        let (l, c, m) =
            err_at("net = \"n.xml\"\n[places.P2]\naction = \"ros2\"\nserver = \"a b\"\n");
        assert_eq!((l, c), (4, 10));
        assert!(m.contains("server `a b` is not a ROS 2 name"), "{m}");
        let (l, c, m) = err_at("net = \"n.xml\"\n[ros2]\nnetworks = [\"127.0.0.1\", \"lo\"]\n");
        assert_eq!((l, c), (3, 26));
        assert!(m.contains("`lo` is not an IP address"), "{m}");
        let (l, c, _) = err_at("net = \"n.xml\"\n[ros2]\ndomain_id = 300\n");
        assert_eq!((l, c), (3, 13));
        let (l, c, _) = err_at("net = \"n.xml\"\n[ros2]\nlost_after = 0.0\n");
        assert_eq!((l, c), (3, 14));
        let (l, c, m) = err_at("net = \"n.xml\"\n[ros2]\ndomian_id = 3\n");
        assert_eq!((l, c), (3, 1));
        assert!(m.contains("domian_id"), "{m}");
    }

    #[test]
    fn time_values_are_checked() {
        let (l, c, _) = err_at("net = \"n.xml\"\ntime_scale = -1.0\n");
        assert_eq!((l, c), (2, 14));
        let (l, c, _) = err_at("net = \"n.xml\"\n[stop]\ntime_limit = 0.0\n");
        assert_eq!((l, c), (3, 14));
    }
}
