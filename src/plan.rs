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
//!
//! - [`file`]: the TOML as written and its schema; [`resolve`]: names → ids.
//! - [`map`]: the `[map]` section (the room of simulated robots, `gspn::world::map`).
//! - [`programs`]: `action = { command | worker }`, `[workers.NAME]`, and the check that
//!   every action name is known ([`Plan::check_actions`]).
//! - [`ros2`]: the `[ros2]` table and the `server` keys of `ros2` places.
//! - [`thesis`]: `plan-runner import-thesis`, the thesis framework's inputs → a plan.

pub(crate) mod file;
pub(crate) mod map;
pub(crate) mod programs;
pub mod resolve;
pub(crate) mod rewards;
pub mod ros2;
pub mod thesis;

use std::path::{Path, PathBuf};

use crate::analysis::decision::{Controls, RewardSpec};
use crate::io::{Format, LoadError, LoadErrorKind, Loaded, ReadOptions, Span, read_net};
use crate::net::{Net, PlaceId};
use crate::policy::Policy;
use crate::ros2::Ros2Settings;
use crate::runtime::{Role, Runtime, RuntimeBuilder, StopConditions};
use crate::world::map::Map;
use file::locate;

pub use file::{ParamValue, PlaceFile, PlanFile, RuleFile, StopFile, json_schema};
pub use programs::{ActionFile, ProgramAction, ProgramFile, WorkerFile, WorkerRef};
pub use rewards::RewardFile;
pub use ros2::Ros2File;

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
    pub map: Option<Map>,
    /// The ROS 2 backend's settings and the places it serves (feature `ros2`).
    pub ros2: Ros2Settings,
    /// Reward structures (`[rewards.NAME]`), in name order.
    pub rewards: Vec<RewardSpec>,
    /// What a policy controls: `controllable` transitions and `wait`.
    pub controls: Controls,
    /// Actions run as programs (`action = { command = … }` / `{ worker = … }`), registered
    /// under the names their places' roles carry (`gspn::actions::ProgramActions`).
    pub programs: Vec<ProgramAction>,
    /// Where each place's `action` is written in the plan file, indexed by
    /// [`PlaceId::index`] (for [`Plan::check_actions`]).
    pub action_spans: Vec<Option<Span>>,
    /// Where each transition is defined in the net file ([`Loaded::transition_at`]).
    pub transition_at: Vec<Span>,
    /// The plan file's text as it was read, to check the plan again against an edited net
    /// ([`PlanText::check`]); `None` for a bare net ([`Plan::for_net`]).
    pub text: Option<PlanText>,
}

/// A plan file's text as [`read_plan`] read it, kept to check the plan again against
/// another version of its net (the viewer's editor does after every edit) with the reader's
/// own checks ([`PlanFile::resolve`]): every place and transition its roles, policy, stop
/// condition, rewards, map and ROS 2 places name must exist and be of the kind it needs.
#[derive(Clone, Debug)]
pub struct PlanText {
    path: PathBuf,
    text: std::sync::Arc<str>,
}

impl PlanText {
    /// The plan checked against `net` exactly as [`read_plan`] checks it against the net
    /// file it names, with its names resolved to `net`'s ids; or the reader's error, at the
    /// plan's line and column, naming what is missing (`transition `t3` does not exist`).
    ///
    /// ```
    /// use gspn::io::ReadOptions;
    /// use gspn::net::{NetBuilder, Servers};
    /// # let dir = tempfile::tempdir().unwrap();
    /// # let plan = dir.path().join("plan.toml");
    /// # std::fs::write(dir.path().join("n.PNPRO"), r#"<project name="n" version="121"><gspn name="n"><nodes>
    /// #   <place marking="1" name="p" x="1" y="1"/><transition name="go" type="IMM" weight="1" x="3" y="1"/>
    /// # </nodes><edges><arc head="go" kind="INPUT" tail="p"/></edges></gspn></project>"#).unwrap();
    /// std::fs::write(&plan, "net = \"n.PNPRO\"\n[[policy]]\nmarking = { p = 1 }\nchoose = { go = 1.0 }\n")
    ///     .unwrap();
    /// let read = gspn::plan::read_plan(&plan, &ReadOptions::default()).unwrap();
    /// let text = read.text.clone().unwrap();
    /// assert!(!text.check(read.net.clone()).unwrap().policy.is_empty());
    /// let mut b = NetBuilder::new("n");
    /// let p = b.place("p", 1);
    /// let stay = b.exponential("stay", 1.0, Servers::Single);
    /// b.input(p, stay, 1);
    /// let e = text.check(b.build().unwrap()).unwrap_err();
    /// assert!(e.to_string().ends_with(":4:12: transition `go` does not exist"), "{e}");
    /// ```
    pub fn check(&self, net: Net) -> Result<Plan, LoadError> {
        PlanFile::parse(&self.path, &self.text)?.resolve(&self.path, &self.text, net)
    }

    /// The plan file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Line `line` (from 1) of the plan, without its indentation: the entry an error of
    /// [`PlanText::check`] points at.
    pub fn line(&self, line: u32) -> Option<&str> {
        let i = usize::try_from(line).ok()?.checked_sub(1)?;
        self.text.lines().nth(i).map(str::trim)
    }
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
            programs: Vec::new(),
            action_spans: vec![None; n],
            transition_at: loaded.transition_at,
            text: None,
        }
    }

    /// Refuses a time scale under which some exponential transition would wait longer than
    /// 10 years of real time on average, pointing at the transition in the net file: for a
    /// time scale given on the command line (`what`, e.g. `--time-scale 1`), which the plan
    /// reader did not see. Plans check their own `time_scale` when they are read.
    pub fn check_time_scale(&self, what: &str, scale: f64) -> Result<(), LoadError> {
        let Some((t, rate)) = crate::limits::too_slow_for_real_time(&self.net, scale) else {
            return Ok(());
        };
        let kind = LoadErrorKind::Invalid(resolve::real_time_wait(what, &self.net, t, rate, scale));
        Err(match self.transition_at.get(t.index()) {
            Some(&span) => LoadError::at(&self.net_path, span, kind),
            None => LoadError::file(&self.net_path, kind),
        })
    }

    /// The role of place `p`.
    pub fn role(&self, p: PlaceId) -> Option<&Role> {
        self.roles.get(p.index()).and_then(Option::as_ref)
    }

    /// A runtime builder for this plan: its net, roles, policy, rewards, stop conditions,
    /// seed, time scale and robots. Register actions on it, then spawn.
    pub fn runtime_builder(self) -> RuntimeBuilder {
        let places: Vec<PlaceId> = self.net.place_ids().collect();
        let mut b = Runtime::builder(self.net)
            .policy(self.policy)
            .rewards(self.rewards)
            .stop_conditions(self.stop)
            .robots(self.robots)
            .source(self.path);
        for (p, role) in places.into_iter().zip(self.roles) {
            if let Some(role) = role {
                b = b.role(p, role);
            }
        }
        if let Some(seed) = self.seed {
            b = b.seed(seed);
        }
        b.time_scale(self.time_scale.unwrap_or(0.0))
    }
}

#[cfg(feature = "sim")]
impl From<Plan> for crate::world::fleet::FleetPlan {
    fn from(plan: Plan) -> Self {
        let map = plan.map.clone();
        crate::world::fleet::FleetPlan {
            run: plan.runtime_builder(),
            map,
        }
    }
}

/// Reads and checks the plan in `path`, and the net it names. `opts.page` (the CLI's
/// `--page`) overrides the plan's `page`; `opts.params` override the plan's `params` of the
/// same name, and both go to the net reader.
pub fn read_plan(path: &Path, opts: &ReadOptions) -> Result<Plan, LoadError> {
    read_plan_with(path, opts, None)
}

/// [`read_plan`], with the plan's net already read (`net`, read with default options from
/// the file the plan names): a caller that has just written both, as `import-thesis` does,
/// need not parse the net a second time.
pub(crate) fn read_plan_with(
    path: &Path,
    opts: &ReadOptions,
    net: Option<Loaded>,
) -> Result<Plan, LoadError> {
    let bytes =
        std::fs::read(path).map_err(|e| LoadError::file(path, LoadErrorKind::Io(e.into())))?;
    let text = String::from_utf8(bytes).map_err(|e| {
        let bytes = e.as_bytes();
        let at = e.utf8_error().valid_up_to();
        LoadError::at(
            path,
            crate::io::Span::locate(bytes, at),
            LoadErrorKind::Invalid(format!(
                "the file is not UTF-8: byte 0x{:02x} cannot start a character here",
                bytes[at]
            )),
        )
    })?;
    if text.trim().is_empty() {
        return Err(LoadError::empty(path));
    }
    let file = PlanFile::parse(path, &text)?;
    let net_path = file.net_path(path);
    let page = opts.page.clone().or_else(|| file.page.clone());
    let mut params: Vec<(String, String)> = file
        .params
        .iter()
        .filter(|(k, _)| !opts.params.iter().any(|(o, _)| o == k.get_ref()))
        .map(|(k, v)| (k.get_ref().clone(), v.to_string()))
        .collect();
    params.extend(opts.params.iter().cloned());
    let net_opts = ReadOptions {
        page: page.clone(),
        params,
    };
    let loaded = match net {
        Some(loaded) => loaded,
        None => read_plan_net(path, opts, &text, &file, &net_path, &net_opts)?,
    };
    let mut plan = file.resolve(path, &text, loaded.net)?;
    plan.text = Some(PlanText {
        path: path.to_path_buf(),
        text: text.into(),
    });
    plan.net_path = net_path;
    plan.transition_at = loaded.transition_at;
    plan.page = page;
    let mut warnings = loaded.warnings;
    warnings.append(&mut plan.warnings);
    plan.warnings = warnings;
    Ok(plan)
}

/// Reads the net a plan names, with the plan's page and parameters.
fn read_plan_net(
    path: &Path,
    opts: &ReadOptions,
    text: &str,
    file: &PlanFile,
    net_path: &Path,
    net_opts: &ReadOptions,
) -> Result<Loaded, LoadError> {
    if !net_path.is_file() {
        return Err(LoadError::at(
            path,
            locate(text, file.net.span()),
            LoadErrorKind::Invalid(format!(
                "net file `{}` not found (looked at {})",
                file.net.get_ref(),
                net_path.display()
            )),
        ));
    }
    read_net(net_path, net_opts).map_err(|e| {
        // A bad `[params]` entry is the plan's mistake: point at it, not at the net file.
        let entry = e.template_parameter().and_then(|name| {
            let from_cli = opts.params.iter().any(|(o, _)| o == name);
            let key = file.params.keys().find(|k| k.get_ref() == name)?;
            (!from_cli && e.span.is_none()).then(|| key.span())
        });
        if let Some(span) = entry {
            return LoadError::at(path, locate(text, span), e.kind);
        }
        // A file that is no net at all (`net = "/etc/passwd"`: unknown kind, empty, a plan or
        // a DOT file, unreadable) is the plan's mistake too: its `net = …` line, naming it.
        let not_a_net = match &e.kind {
            LoadErrorKind::Empty => true,
            LoadErrorKind::UnknownFormat(_) | LoadErrorKind::Io(_) => e.span.is_none(),
            LoadErrorKind::Invalid(why) => e.span.is_none() && why.ends_with("is not a net file"),
            _ => false,
        };
        if not_a_net {
            return LoadError::at(
                path,
                locate(text, file.net.span()),
                LoadErrorKind::Invalid(format!(
                    "net file `{}` ({}): {}",
                    file.net.get_ref(),
                    net_path.display(),
                    e.kind
                )),
            );
        }
        e
    })
}

/// A file opened by [`open`]: a plan, or a bare net.
#[derive(Clone, Debug)]
pub enum Opened {
    /// A plan file (`.toml`) with the net it names.
    Plan(Box<Plan>),
    /// A net file (PIPE, PNML, PNPRO).
    Net {
        /// The file.
        path: PathBuf,
        /// The net, its format and the reader's warnings.
        loaded: Box<Loaded>,
    },
}

impl Opened {
    /// The plan to run: the plan itself, or [`Plan::for_net`] for a bare net (every place
    /// net-timed, no policy, no stop condition).
    pub fn into_plan(self) -> Plan {
        match self {
            Opened::Plan(plan) => *plan,
            Opened::Net { path, loaded } => Plan::for_net(&path, *loaded),
        }
    }
}

/// Opens `path` as a plan when its extension is `.toml` (in any case), else as a net file.
/// Every command that accepts "a plan or a net" goes through here.
pub fn open(path: &Path, opts: &ReadOptions) -> Result<Opened, LoadError> {
    if Format::from_extension(path) == Some(Format::Plan) {
        Ok(Opened::Plan(Box::new(read_plan(path, opts)?)))
    } else {
        Ok(Opened::Net {
            path: path.to_path_buf(),
            loaded: Box::new(read_net(path, opts)?),
        })
    }
}
