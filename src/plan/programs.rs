//! Actions as programs in a plan file: `action = { command = [...] }` (a process per
//! action), `action = { worker = [...] | "NAME", name = "…" }` (requests to one long-lived
//! process) and the `[workers.NAME]` table a worker can be named from; and the check that
//! every action name of a plan is known ([`Plan::check_actions`]). The programs run through
//! `gspn::actions` (unix); the protocol is in `docs/actions.md`.

use std::collections::BTreeMap;
use std::fmt;
use std::ops::Range;
use std::path::{Path, PathBuf};

use schemars::JsonSchema;
use serde::Deserialize;
use serde::de::{self, Deserializer, MapAccess, SeqAccess, Visitor};
use toml::Spanned;

use super::Plan;
use crate::io::{LoadError, LoadErrorKind};
use crate::ros2::settings::ROS2_ACTION;
use crate::runtime::{BUILTIN_WORDS, Builtin, Role};

/// A place's `action`: a name, or a program.
#[derive(Debug, JsonSchema)]
#[serde(untagged)]
pub enum ActionFile {
    /// A built-in (`wait [S]`, `log MSG`, `fire T [after S]`), a robot program with a
    /// `[map]`, `ros2`, or a name a library user registers.
    Name(String),
    /// `{ command = [...] }` or `{ worker = ..., name = "…" }`.
    Program(ProgramFile),
}

impl ActionFile {
    /// The name, when the action is one.
    pub fn name(&self) -> Option<&str> {
        match self {
            ActionFile::Name(n) => Some(n),
            ActionFile::Program(_) => None,
        }
    }
}

impl<'de> Deserialize<'de> for ActionFile {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ActionFile;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str(
                    "an action name (a string) or a program: { command = [...] } or { worker = [...], name = \"...\" }",
                )
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<ActionFile, E> {
                Ok(ActionFile::Name(s.to_owned()))
            }
            fn visit_map<A: MapAccess<'de>>(self, m: A) -> Result<ActionFile, A::Error> {
                ProgramFile::deserialize(de::value::MapAccessDeserializer::new(m))
                    .map(ActionFile::Program)
            }
        }
        d.deserialize_any(V)
    }
}

/// `{ command = [...] }` (a program per action) or `{ worker = [...] | "NAME", name = "…" }`
/// (requests to one long-lived program).
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct ProgramFile {
    /// Program and arguments, run once per action; `{place}`, `{agent}`, `{robot}`,
    /// `{transition_choices}` are replaced.
    pub command: Option<Vec<String>>,
    /// A worker: its program and arguments, or the name of a `[workers.NAME]` entry.
    pub worker: Option<WorkerRef>,
    /// With `worker`: the action name the requests carry.
    pub name: Option<String>,
    /// Working directory, relative to the plan's directory (the default; not with a named
    /// worker).
    pub cwd: Option<String>,
    /// Extra environment variables (not with a named worker).
    #[serde(default)]
    pub env: BTreeMap<String, String>,
    /// With `command`: seconds before the program is stopped and the action fails.
    #[schemars(range(min = 0.0))]
    pub timeout: Option<f64>,
    /// Seconds between SIGTERM and SIGKILL when the program must stop (default 2; not with a
    /// named worker).
    #[schemars(range(min = 0.0))]
    pub kill_grace: Option<f64>,
}

/// A worker, written inline (`worker = ["python3", "robot_actions.py"]`) or by the name of
/// a `[workers.NAME]` entry (`worker = "robot"`).
#[derive(Debug, JsonSchema)]
#[serde(untagged)]
pub enum WorkerRef {
    /// Program and arguments.
    Argv(Vec<String>),
    /// The name of a `[workers.NAME]` entry.
    Named(String),
}

impl<'de> Deserialize<'de> for WorkerRef {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = WorkerRef;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a program and its arguments (a list of strings) or the name of a [workers.NAME] entry")
            }
            fn visit_str<E: de::Error>(self, s: &str) -> Result<WorkerRef, E> {
                Ok(WorkerRef::Named(s.to_owned()))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, s: A) -> Result<WorkerRef, A::Error> {
                Vec::<String>::deserialize(de::value::SeqAccessDeserializer::new(s))
                    .map(WorkerRef::Argv)
            }
        }
        d.deserialize_any(V)
    }
}

/// A `[workers.NAME]` entry: one long-lived program that places name with
/// `action = { worker = "NAME", name = "…" }`.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct WorkerFile {
    /// Program and arguments.
    pub command: Vec<String>,
    /// Working directory, relative to the plan's directory (the default).
    pub cwd: Option<String>,
    /// Extra environment variables.
    #[serde(default)]
    pub env: BTreeMap<String, String>,
    /// Seconds between SIGTERM and SIGKILL when the program must stop (default 2).
    #[schemars(range(min = 0.0))]
    pub kill_grace: Option<f64>,
}

/// An action the plan runs as a program; the runtime registers it under `name`, the name
/// its place's [`Role::Action`] carries.
#[derive(Clone, Debug, PartialEq)]
pub struct ProgramAction {
    /// The name the place's [`Role::Action`] refers to.
    pub name: String,
    /// Program and arguments.
    pub argv: Vec<String>,
    /// `Some(action)`: a worker answering requests for `action`; `None`: a command.
    pub worker_action: Option<String>,
    /// Working directory: the plan's directory, or `cwd` resolved against it.
    pub cwd: Option<PathBuf>,
    /// Extra environment variables.
    pub env: Vec<(String, String)>,
    /// Seconds a command may run (commands only).
    pub timeout: Option<f64>,
    /// Seconds between SIGTERM and SIGKILL.
    pub kill_grace: Option<f64>,
}

/// The program parts of a plan file, checked as places name them.
pub(super) struct Programs<'a> {
    workers: &'a BTreeMap<Spanned<String>, Spanned<WorkerFile>>,
    dir: PathBuf,
    /// The programs the places use, in the order first named.
    pub(super) list: Vec<ProgramAction>,
    /// Index of each program in `list`, by name.
    by_name: std::collections::HashMap<String, usize>,
}

impl<'a> Programs<'a> {
    /// Checks the `[workers]` table; the programs of the plan at `plan_path`.
    pub(super) fn new(
        workers: &'a BTreeMap<Spanned<String>, Spanned<WorkerFile>>,
        plan_path: &Path,
        at: &impl Fn(Range<usize>, LoadErrorKind) -> LoadError,
    ) -> Result<Self, LoadError> {
        for (name, w) in workers {
            let bad = |m: String| {
                at(
                    w.span(),
                    LoadErrorKind::Invalid(format!("workers.{}: {m}", name.get_ref())),
                )
            };
            if name.get_ref().trim().is_empty() {
                return Err(at(
                    name.span(),
                    LoadErrorKind::Invalid("a worker's name is empty".into()),
                ));
            }
            let f = w.get_ref();
            check_argv(&f.command).map_err(|e| bad(e.to_string()))?;
            check_seconds("kill_grace", f.kill_grace).map_err(|e| bad(e.to_string()))?;
        }
        Ok(Programs {
            workers,
            dir: plan_path.parent().unwrap_or(Path::new("")).to_path_buf(),
            list: Vec::new(),
            by_name: std::collections::HashMap::new(),
        })
    }

    /// Checks the program action of `place` and records it; the name its role refers to.
    pub(super) fn add(&mut self, place: &str, f: &ProgramFile) -> Result<String, LoadErrorKind> {
        let bad = |m: String| LoadErrorKind::Invalid(format!("action of `{place}`: {m}"));
        if f.timeout.is_some() && f.command.is_none() {
            return Err(bad(
                "`timeout` goes with `command`; a worker's actions use the place's `timeout`"
                    .into(),
            ));
        }
        check_seconds("timeout", f.timeout).map_err(|e| bad(e.to_string()))?;
        check_seconds("kill_grace", f.kill_grace).map_err(|e| bad(e.to_string()))?;
        let env = |e: &BTreeMap<String, String>| -> Vec<(String, String)> {
            e.iter().map(|(k, v)| (k.clone(), v.clone())).collect()
        };
        let action = match (&f.command, &f.worker) {
            (Some(argv), None) => {
                if f.name.is_some() {
                    return Err(bad("`name` goes with `worker`, not `command`".into()));
                }
                check_argv(argv).map_err(|e| bad(e.to_string()))?;
                ProgramAction {
                    name: format!("command `{}`", argv.join(" ")),
                    argv: argv.clone(),
                    worker_action: None,
                    cwd: Some(self.dir.join(f.cwd.as_deref().unwrap_or("."))),
                    env: env(&f.env),
                    timeout: f.timeout,
                    kill_grace: f.kill_grace,
                }
            }
            (None, Some(w)) => {
                let action = match &f.name {
                    Some(n) if !n.trim().is_empty() => n.clone(),
                    _ => return Err(bad("a `worker` needs the `name` of its action".into())),
                };
                match w {
                    WorkerRef::Argv(argv) => {
                        check_argv(argv).map_err(|e| bad(e.to_string()))?;
                        ProgramAction {
                            name: format!("worker `{}` action `{action}`", argv.join(" ")),
                            argv: argv.clone(),
                            worker_action: Some(action),
                            cwd: Some(self.dir.join(f.cwd.as_deref().unwrap_or("."))),
                            env: env(&f.env),
                            timeout: None,
                            kill_grace: f.kill_grace,
                        }
                    }
                    WorkerRef::Named(w) => {
                        if f.cwd.is_some() || !f.env.is_empty() || f.kill_grace.is_some() {
                            return Err(bad(format!(
                                "`cwd`, `env` and `kill_grace` of a named worker go in [workers.{w}]"
                            )));
                        }
                        let Some(entry) = self.workers.iter().find(|(k, _)| k.get_ref() == w)
                        else {
                            let known: Vec<&str> =
                                self.workers.keys().map(|k| k.get_ref().as_str()).collect();
                            return Err(bad(format!(
                                "worker `{w}` is not in [workers] (known: {})",
                                if known.is_empty() {
                                    "none".into()
                                } else {
                                    known.join(", ")
                                }
                            )));
                        };
                        let entry = entry.1.get_ref();
                        ProgramAction {
                            name: format!("worker `{w}` action `{action}`"),
                            argv: entry.command.clone(),
                            worker_action: Some(action),
                            cwd: Some(self.dir.join(entry.cwd.as_deref().unwrap_or("."))),
                            env: env(&entry.env),
                            timeout: None,
                            kill_grace: entry.kill_grace,
                        }
                    }
                }
            }
            _ => return Err(bad("expected exactly one of `command` and `worker`".into())),
        };
        let name = action.name.clone();
        match self.by_name.get(&name).map(|&i| &self.list[i]) {
            Some(same) if *same == action => {}
            Some(_) => {
                return Err(bad(format!(
                    "{name} appears twice with different settings (cwd, env, timeout, kill_grace)"
                )));
            }
            None => {
                self.by_name.insert(name.clone(), self.list.len());
                self.list.push(action);
            }
        }
        Ok(name)
    }
}

/// Why a program's entry is refused (the plan reader adds where).
#[derive(Debug, thiserror::Error)]
enum ProgramError {
    /// No program, or an empty first word.
    #[error("the program is empty")]
    Empty,
    /// A duration that is not a number of seconds.
    #[error("`{key}` = {value}: {}", crate::limits::SECONDS_EXPECTED)]
    Seconds { key: &'static str, value: f64 },
}

fn check_argv(argv: &[String]) -> Result<(), ProgramError> {
    if argv.first().is_none_or(|a| a.trim().is_empty()) {
        return Err(ProgramError::Empty);
    }
    Ok(())
}

fn check_seconds(key: &'static str, v: Option<f64>) -> Result<(), ProgramError> {
    match v {
        Some(value) if !crate::limits::valid_seconds(value) => {
            Err(ProgramError::Seconds { key, value })
        }
        _ => Ok(()),
    }
}

impl Plan {
    /// Checks that every action the plan names is known: a built-in (`wait [S]`, `log MSG`,
    /// `fire T [after S]`), a program of the plan (`command`, `worker`), a robot program of
    /// its `[map]`, `ros2`, or one of `registered` (names a library user registers on the
    /// runtime). The first unknown one is an error at its line and column, with the nearest
    /// known name and the list of known actions. `plan-runner` calls it with none registered.
    pub fn check_actions(&self, registered: &[&str]) -> Result<(), LoadError> {
        for p in self.net.place_ids() {
            let Some(Role::Action { name, .. }) = self.role(p) else {
                continue;
            };
            if registered.contains(&name.as_str())
                || self.programs.iter().any(|a| &a.name == name)
                || name == ROS2_ACTION
                || Builtin::parse(name, &self.net, p).is_some()
                || self
                    .map
                    .as_ref()
                    .is_some_and(|m| matches!(m.program(name), Ok(Some(_))))
            {
                continue;
            }
            let mut known: Vec<&str> = vec!["wait [S]", "log MSG", "fire T [after S]"];
            if self.map.is_some() {
                known.extend(["goto L", "measure [S]", "decide"]);
            }
            known.push(ROS2_ACTION);
            known.extend(registered.iter().copied());
            let mut words: Vec<&str> = BUILTIN_WORDS.to_vec();
            if self.map.is_some() {
                words.extend(["goto", "measure", "decide"]);
            }
            words.push(ROS2_ACTION);
            words.extend(registered.iter().copied());
            let hint = match nearest(name, &words) {
                Some(n) => format!(" (did you mean `{n}`?)"),
                None => String::new(),
            };
            let message = format!(
                "place `{}`: unknown action `{name}`{hint}; known actions: {}, a program (`{{ command = [...] }}` or `{{ worker = ..., name = \"...\" }}`, see docs/actions.md){}",
                self.net.place(p).name,
                known
                    .iter()
                    .map(|k| format!("`{k}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                if registered.is_empty() {
                    ", or a name a library user registers on the runtime"
                } else {
                    ""
                }
            );
            let kind = LoadErrorKind::Invalid(message);
            return Err(match self.action_spans.get(p.index()).copied().flatten() {
                Some(span) => LoadError::at(&self.path, span, kind),
                None => LoadError::file(&self.path, kind),
            });
        }
        Ok(())
    }
}

/// The candidate closest to `name` (or to its first word), when it is close: at most a third
/// of its letters differ, rounded up.
fn nearest<'a>(name: &str, candidates: &[&'a str]) -> Option<&'a str> {
    let first = name.split_whitespace().next().unwrap_or(name);
    candidates
        .iter()
        .flat_map(|&c| [(edit_distance(name, c), c), (edit_distance(first, c), c)])
        .filter(|&(d, c)| d <= c.chars().count().div_ceil(3))
        .min_by_key(|&(d, _)| d)
        .map(|(_, c)| c)
}

/// Levenshtein distance between `a` and `b`, in characters.
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut row: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut prev = row[0];
        row[0] = i + 1;
        for (j, &cb) in b.iter().enumerate() {
            let cur = row[j + 1];
            row[j + 1] = if ca == cb {
                prev
            } else {
                1 + prev.min(row[j]).min(row[j + 1])
            };
            prev = cur;
        }
    }
    row[b.len()]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_names_a_close_word_only() {
        assert_eq!(edit_distance("wiat", "wait"), 2);
        assert_eq!(edit_distance("", "log"), 3);
        assert_eq!(nearest("wiat 2", &["wait", "log", "fire"]), Some("wait"));
        assert_eq!(nearest("lgo hello", &["wait", "log", "fire"]), None);
        assert_eq!(nearest("lg hello", &["wait", "log", "fire"]), Some("log"));
        assert_eq!(nearest("plan_route", &["wait", "log", "fire"]), None);
        assert_eq!(nearest("ros", &["wait", "ros2"]), Some("ros2"));
    }
}
