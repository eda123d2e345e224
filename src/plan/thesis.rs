//! The thesis framework's execution inputs, turned into plans.
//!
//! The 2020 framework took a JSON file whose values are Python literals in strings:
//!
//! ```json
//! { "gspn": "example_gspn.xml",
//!   "place_to_client_mapping": "{'p1': ['ExecGSPN', 'action_server_1'], ...}",
//!   "resources_list": "['p4']",
//!   "places_tuple": "('p1','p2','p3','p4','p5','p6','p7')",
//!   "policy_dictionary": "{('-','-','-','-','-','-',1): {'t5':1}, ...}" }
//! ```
//!
//! [`read_input`] parses it, keeping the line and column of every name; [`import`] checks it
//! against its net and writes a plan (`plan.toml`) next to a copy of the net:
//!
//! - `places_tuple` orders the places of each `policy_dictionary` key; `'-'` (free) places
//!   make a partial pattern. A key with no `'-'` over every place of the net is an exact
//!   marking (looked up through the hash index); any other key is a partial pattern, in the
//!   order written. `'1'` (a string, which the thesis code never matched against the integer
//!   1) is read as 1, with a warning.
//! - `place_to_function_mapping` (`'p1': 'functions.work_p1'`): each place's action goes to
//!   one Python worker, `thesis_functions.py` (written beside the plan; it runs on the gspn
//!   Python package's `gspn.worker`), which imports `functions` from the input's `project_path` and calls
//!   `work_p1(agent_id)`: a returned transition name fires it, `None` lets the policy decide.
//!   So the thesis's functions run unchanged, from the command line.
//! - `place_to_client_mapping` (`'p1': ['ExecGSPN', 'action_server_1']`): the place's action
//!   is `ros2`, the ExecPlace server named after the thesis's action server.
//! - `resources_list` places get `role = "resource"`.
//!
//! A place that is not in the net is a [`LoadError`] at its position in the JSON file. A
//! policy choice of a transition the net lacks (the standalone example's `t4` and `t5`) or
//! of an exponential transition — which the thesis code never consulted — is dropped with a
//! warning naming the entry, its line and column, so the thesis's inputs import as shipped.

mod cursor;
mod input;
mod json;
mod pylit;
mod write;

use std::path::{Path, PathBuf};

use super::{Plan, read_plan_with};
use crate::io::{LoadError, LoadErrorKind, ReadOptions, Span, read_net};

pub use write::plan_text;

/// A name in the input and where it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Named {
    /// The name as written.
    pub name: String,
    /// Its position in the JSON file.
    pub span: Span,
}

/// One element of a policy key: a token count or `'-'` (free).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum KeyItem {
    /// `'-'`: any count.
    Free,
    /// Exactly this many tokens.
    Count(u32),
}

/// One `policy_dictionary` entry: a marking key and the transitions' probabilities.
#[derive(Clone, Debug, PartialEq)]
pub struct PolicyEntry {
    /// Where the key starts.
    pub span: Span,
    /// The key, one item per place of `places_tuple`.
    pub key: Vec<KeyItem>,
    /// Transitions and probabilities, in the order written.
    pub choose: Vec<(Named, f64)>,
}

/// The action of a place.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionEntry {
    /// The place.
    pub place: Named,
    /// The function (`place_to_function_mapping`) or action server (`place_to_client_mapping`).
    pub action: String,
    /// The ROS action type for a client mapping (`ExecGSPN`), `None` for a function.
    pub action_type: Option<String>,
}

/// A thesis execution input, parsed but not yet checked against its net.
#[derive(Clone, Debug, PartialEq)]
pub struct ThesisInput {
    /// The JSON file.
    pub path: PathBuf,
    /// The `gspn` value: the net file as the thesis named it (often an absolute path on the
    /// author's machine).
    pub net: Named,
    /// `places_tuple`.
    pub places: Vec<Named>,
    /// `policy_dictionary`, in the order written.
    pub policy: Vec<PolicyEntry>,
    /// `place_to_function_mapping` and `place_to_client_mapping` entries.
    pub actions: Vec<ActionEntry>,
    /// `resources_list`.
    pub resources: Vec<Named>,
    /// `full_synchronization`, when given.
    pub full_synchronization: Option<bool>,
    /// `project_path`: the directory the `place_to_function_mapping` modules are imported
    /// from, when given.
    pub project_path: Option<Named>,
    /// Remarks: ignored keys, values read leniently.
    pub warnings: Vec<String>,
}

/// Options of [`import`].
#[derive(Clone, Debug, Default)]
pub struct ImportOptions {
    /// Directory to write `plan.toml` and the net's copy into (created when missing).
    pub out: PathBuf,
    /// The net file, when the input's `gspn` path does not lead to it.
    pub net: Option<PathBuf>,
    /// The directory of the `place_to_function_mapping` modules, when the input's
    /// `project_path` does not lead to it.
    pub project_path: Option<PathBuf>,
}

/// The result of [`import`].
#[derive(Debug)]
pub struct Imported {
    /// The plan written.
    pub plan_path: PathBuf,
    /// The copy of the net next to it.
    pub net_path: PathBuf,
    /// The plan, read back with [`read_plan`].
    pub plan: Plan,
    /// Remarks from reading the input and translating it.
    pub warnings: Vec<String>,
}

/// Reads a thesis execution input (JSON with Python-literal values).
pub fn read_input(path: &Path) -> Result<ThesisInput, LoadError> {
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::file(path, LoadErrorKind::Io(e.into())))?;
    parse_input(path, &bytes)
}

/// Reads the thesis execution input in `bytes`, the contents of `path` (named in errors).
pub fn parse_input(path: &Path, bytes: &[u8]) -> Result<ThesisInput, LoadError> {
    let bytes = bytes.to_vec();
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::empty(path));
    }
    let text = String::from_utf8(bytes).map_err(|e| {
        let at = Span::locate(e.as_bytes(), e.utf8_error().valid_up_to());
        LoadError::at(
            path,
            at,
            LoadErrorKind::Invalid("the file is not UTF-8".into()),
        )
    })?;
    input::Reader {
        path,
        text: &text,
        lines: Default::default(),
    }
    .input()
}

/// Reads the input at `path`, checks it against its net, and writes `plan.toml` and a copy of
/// the net into `opts.out`. The plan is read back, so what is written always loads.
pub fn import(path: &Path, opts: &ImportOptions) -> Result<Imported, LoadError> {
    let input = read_input(path)?;
    let source = match &opts.net {
        Some(n) => n.clone(),
        None => locate_net(&input)?,
    };
    let loaded = read_net(&source, &ReadOptions::default())?;
    let file_name = source
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_else(|| "net.xml".into());
    let io_err = |p: &Path, e: std::io::Error| LoadError::file(p, LoadErrorKind::Io(e.into()));
    std::fs::create_dir_all(&opts.out).map_err(|e| io_err(&opts.out, e))?;
    let functions = input.actions.iter().any(|a| a.action_type.is_none());
    let mut project_warning = None;
    let project = if functions {
        let (dir, warning) = locate_project(&input, opts.project_path.as_deref())?;
        project_warning = warning;
        let p = opts.out.join("thesis_functions.py");
        std::fs::write(&p, THESIS_FUNCTIONS_PY).map_err(|e| io_err(&p, e))?;
        relative_to(&dir, &opts.out)
    } else {
        ".".into()
    };
    let (text, mut warnings) = plan_text(&input, &loaded.net, &file_name, &project)?;
    let net_path = opts.out.join(&file_name);
    let same = match (source.canonicalize(), net_path.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => false,
    };
    if !same {
        std::fs::copy(&source, &net_path).map_err(|e| io_err(&net_path, e))?;
    }
    let plan_path = opts.out.join("plan.toml");
    std::fs::write(&plan_path, text).map_err(|e| io_err(&plan_path, e))?;
    // The copy is the file just read, byte for byte: its net need not be parsed again.
    let plan = read_plan_with(&plan_path, &ReadOptions::default(), Some(loaded))?;
    let mut all = input.warnings;
    all.append(&mut warnings);
    all.extend(project_warning);
    Ok(Imported {
        plan_path,
        net_path,
        plan,
        warnings: all,
    })
}

/// `python/thesis_functions.py`: the worker that imports and calls the thesis's functions.
const THESIS_FUNCTIONS_PY: &str = include_str!("../../python/thesis_functions.py");

/// The directory the input's functions are imported from: `explicit` (`--project-path`),
/// else the input's `project_path` relative to the JSON file when the module of the first
/// function is there, else the JSON file's directory (the thesis inputs hold absolute paths
/// from the author's machine) — with a warning when the module is not there either.
pub fn locate_project(
    input: &ThesisInput,
    explicit: Option<&Path>,
) -> Result<(PathBuf, Option<String>), LoadError> {
    let dir = input.path.parent().unwrap_or(Path::new(""));
    if let Some(p) = explicit {
        if p.is_dir() {
            return Ok((p.to_path_buf(), None));
        }
        return Err(LoadError::file(
            p,
            LoadErrorKind::Invalid("--project-path: not a directory".into()),
        ));
    }
    let module = input
        .actions
        .iter()
        .find(|a| a.action_type.is_none())
        .and_then(|a| a.action.rsplit_once('.'))
        .map(|(m, _)| m.replace('.', "/"));
    let has_module = |d: &Path| match &module {
        Some(m) => d.join(format!("{m}.py")).is_file() || d.join(m).join("__init__.py").is_file(),
        None => d.is_dir(),
    };
    let mut tried = Vec::new();
    if let Some(pp) = &input.project_path {
        tried.push(dir.join(&pp.name));
    }
    tried.push(dir.to_path_buf());
    if let Some(found) = tried.iter().find(|d| has_module(d)) {
        return Ok((found.clone(), None));
    }
    let looked: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
    let what = module.map_or_else(String::new, |m| format!("`{m}.py` "));
    Ok((
        dir.to_path_buf(),
        Some(format!(
            "the functions' module {what}is not in {}: the worker will import it from {} (put it there, or import again with --project-path DIR)",
            looked.join(" nor in "),
            dir.display()
        )),
    ))
}

/// `target` as a path relative to directory `base` (both made absolute first); `target`
/// itself when they share no prefix.
fn relative_to(target: &Path, base: &Path) -> String {
    let abs = |p: &Path| p.canonicalize().unwrap_or_else(|_| p.to_path_buf());
    let (t, b) = (abs(target), abs(base));
    let common = t
        .components()
        .zip(b.components())
        .take_while(|(x, y)| x == y)
        .count();
    if common == 0 {
        return t.display().to_string();
    }
    let mut rel = PathBuf::new();
    for _ in b.components().skip(common) {
        rel.push("..");
    }
    for c in t.components().skip(common) {
        rel.push(c);
    }
    if rel.as_os_str().is_empty() {
        ".".into()
    } else {
        rel.display().to_string()
    }
}

/// Where the input's net is: its `gspn` path (relative to the JSON file), else a file of the
/// same name beside the JSON file (the thesis inputs hold absolute paths from the author's
/// machine).
pub fn locate_net(input: &ThesisInput) -> Result<PathBuf, LoadError> {
    let dir = input.path.parent().unwrap_or(Path::new(""));
    let written = Path::new(&input.net.name);
    let mut tried = vec![dir.join(written)];
    if let Some(name) = written.file_name() {
        tried.push(dir.join(name));
    }
    tried.dedup();
    if let Some(found) = tried.iter().find(|p| p.is_file()) {
        return Ok(found.clone());
    }
    let looked: Vec<String> = tried.iter().map(|p| p.display().to_string()).collect();
    Err(LoadError::at(
        &input.path,
        input.net.span,
        LoadErrorKind::Invalid(format!(
            "net file `{}` not found (looked at {}); name it with --net",
            input.net.name,
            looked.join(" and ")
        )),
    ))
}
