//! The ROS 2 backend in the CLI (feature `ros2`): the DDS flags of `run` and `robot`, the
//! supervisor's side of `run` for plans with `ros2` places, and `plan-runner robot`.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::{Plan, read_plan};
use gspn::ros2::config::{parse_domain, parse_networks};
use gspn::ros2::heartbeat::Liveness;
use gspn::ros2::names::RosArgs;
use gspn::ros2::robot::{RobotOptions, serve};
use gspn::ros2::{DdsConfig, Ros2Backend};
use gspn::runtime::Role;

use crate::common::{BadInput, NetArgs};

#[cfg(feature = "sim")]
mod sim_nav2;
#[cfg(feature = "sim")]
pub(crate) use sim_nav2::{SimNav2Args, main as sim_nav2_main};

/// DDS flags (override the plan's `[ros2]` table and the `GSPN_ROS2_*` environment).
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct DdsArgs {
    /// DDS domain id (0–232) [default: the plan's, else $GSPN_ROS2_DOMAIN, else
    /// $ROS_DOMAIN_ID, else 0].
    #[arg(long, value_name = "ID", value_parser = domain)]
    ros2_domain: Option<u16>,
    /// The local IPv4 address every DDS socket binds to [default: the plan's, else
    /// $GSPN_ROS2_NETWORKS, else 127.0.0.1; 0.0.0.0 = every interface].
    #[arg(long, value_name = "ADDRS")]
    ros2_networks: Option<String>,
    /// Publish the ROS 2 layer's warnings and errors on /rosout (rcl_interfaces/msg/Log, as
    /// ROS 2 nodes do), besides stderr [default: the plan's `[ros2] rosout`, else off].
    #[arg(long)]
    ros2_rosout: bool,
    /// ROS arguments, last on the line (or ended by `--`): `-r __ns:=/NS` (every node,
    /// topic and action under /NS), `-r __node:=NAME`, `-p KEY:=VALUE` (domain_id,
    /// heartbeat, lost_after, startup, service_mapping, rosout; over the plan's and flags).
    #[arg(
        long = "ros-args",
        num_args = 0..,
        allow_hyphen_values = true,
        value_terminator = "--",
        value_name = "ARGS"
    )]
    ros_args: Option<Vec<String>>,
}

impl DdsArgs {
    /// What `--ros-args` says.
    fn ros(&self) -> anyhow::Result<RosArgs> {
        Ok(RosArgs::parse(self.ros_args.as_deref().unwrap_or_default())
            .map_err(|e| BadInput(e.to_string()))?)
    }
}

fn domain(s: &str) -> Result<u16, String> {
    parse_domain(s).map_err(str::to_string)
}

impl DdsArgs {
    fn config(&self, plan: &Plan) -> anyhow::Result<DdsConfig> {
        let mut c = DdsConfig::resolve(&plan.ros2).map_err(|e| BadInput(e.to_string()))?;
        if let Some(d) = self.ros2_domain {
            c.domain_id = d;
        }
        if let Some(n) = &self.ros2_networks {
            c.networks = parse_networks(n)
                .map_err(|why| BadInput(format!("--ros2-networks `{n}`: {why}")))?;
        }
        c.rosout |= self.ros2_rosout;
        c.apply_ros_args(&self.ros()?)
            .map_err(|e| BadInput(e.to_string()))?;
        c.bind_address().map_err(|e| BadInput(e.to_string()))?;
        // The supervisor, the robots and a viewer or two on one host: any start order.
        Ok(c.for_fleet(robots(plan).len() + 2))
    }
}

/// The ROS 2 flags of `run`.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct RunArgs {
    #[command(flatten)]
    dds: DdsArgs,
    /// Wait (up to the startup time) for this many subscribers of /gspn/firings before the
    /// first firing.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub(crate) ros2_wait_subscribers: usize,
    /// At most this many seconds after the run for the subscribers to acknowledge the last
    /// firings, then as many for the end of the run (lost samples are repaired meanwhile).
    #[arg(long, value_name = "SECS", default_value_t = 0.5)]
    pub(crate) ros2_linger: f64,
    /// Accept time scale 0 (virtual time) with ros2 places: the robots still act in real
    /// time, so model times mean nothing.
    #[arg(long)]
    allow_virtual_time: bool,
    /// With simulated robots (`--robots N`, feature `sim`): every `goto` goes through Nav2's
    /// NavigateToPose over DDS to /<robot>/navigate_to_pose, which the simulated world
    /// serves for each robot, and the robots' poses are published on /<robot>/pose
    /// (geometry_msgs/PoseStamped, frame `map`). Needs a time scale > 0 (DDS is on the wall
    /// clock).
    #[cfg(feature = "sim")]
    #[arg(long, conflicts_with = "nav2")]
    pub(crate) ros2: bool,
    /// The plan's robots are real robots running Nav2 (feature `sim`): the same plan as
    /// with `--robots N` — every `goto L` of its built-in actions becomes a NavigateToPose
    /// goal to L's pose at /<robot>/navigate_to_pose, and nothing is simulated. The queues,
    /// turns and draws of the built-in actions are kept by a mirror of the map that shows
    /// each robot where Nav2's feedback says it is. Robots are r1..rN (`--robots N`) or the
    /// plan's `robots`, starting at the locations the net's initial marking puts them.
    /// Needs a time scale > 0. `plan-runner sim-nav2` stands in for such a fleet.
    #[cfg(feature = "sim")]
    #[arg(long)]
    pub(crate) nav2: bool,
}

/// Refuses a plan with ros2 places the supervisor cannot run: no robots to send goals to,
/// or virtual time (time scale 0, the default without one) without `--allow-virtual-time`
/// (robots act in real time).
pub(crate) fn check_plan(plan: &Plan, args: &RunArgs) -> anyhow::Result<()> {
    if !wanted(plan) {
        return Ok(());
    }
    if robots(plan).is_empty() {
        return Err(BadInput(format!(
            "{}: the plan has ros2 places but no `robots = [...]` (nor a place's `robot`) to send their goals to",
            plan.path.display()
        ))
        .into());
    }
    if plan.time_scale.unwrap_or(0.0) == 0.0 && !args.allow_virtual_time {
        return Err(BadInput(format!(
            "{}: time scale 0 (virtual time) with ros2 places: the robots act in real time, so \
             the run's model times would mean nothing; give --time-scale X > 0 (or the plan's \
             time_scale), or --allow-virtual-time",
            plan.path.display()
        ))
        .into());
    }
    Ok(())
}

/// Refuses `--ros2` on a run that cannot serve Nav2 from a simulated world: no `[map]`, or
/// virtual time (DDS runs on the wall clock, so the world must too).
#[cfg(feature = "sim")]
pub(crate) fn check_sim_nav2(plan: &Plan, args: &RunArgs) -> anyhow::Result<()> {
    let flag = match (args.ros2, args.nav2) {
        (true, _) => "--ros2 serves Nav2 for simulated robots",
        (_, true) => "--nav2 sends the built-in actions' `goto`s to Nav2 robots",
        _ => return Ok(()),
    };
    if plan.map.is_none() {
        return Err(BadInput(format!(
            "{}: {flag}: the plan needs a [map] (see docs/ros2.md, \"Nav2\")",
            plan.path.display()
        ))
        .into());
    }
    if plan.time_scale.unwrap_or(0.0) == 0.0 {
        return Err(BadInput(format!(
            "{}: {flag}, with time scale 0 (virtual time): DDS runs on the wall clock, so the \
             world must too; give --time-scale X > 0 (1 = real time, 0.05 = 20x faster)",
            plan.path.display()
        ))
        .into());
    }
    Ok(())
}

/// Serves Nav2 for `fleet`'s robots and makes its `goto`s go through it: the world's
/// servers (a backend of the run, which counts the goals) and the fleet, ready.
#[cfg(feature = "sim")]
pub(crate) async fn sim_nav2(
    fleet: gspn::world::Fleet,
    cfg: &DdsConfig,
) -> anyhow::Result<(gspn::world::Fleet, gspn::ros2::nav2::SimNav2)> {
    use gspn::ros2::nav2::{Nav2Navigator, SimNav2};
    let servers = SimNav2::serve(&fleet.world, std::sync::Arc::clone(&fleet.map), cfg)?;
    let robots = fleet.world.robots().to_vec();
    eprintln!(
        "ros2: domain {}, Nav2 NavigateToPose served for {} simulated robot(s)",
        cfg.domain_id,
        robots.len()
    );
    let nav = Nav2Navigator::connect(&robots, std::sync::Arc::clone(&fleet.map), cfg).await?;
    Ok((fleet.navigate_with(std::sync::Arc::new(nav)), servers))
}

/// Links `fleet` (a mirror, [`gspn::world::Fleet::mirror`]) to its real robots' Nav2
/// servers (`--nav2`): every `goto` becomes a NavigateToPose goal and the mirror follows
/// the feedback. Returns the fleet and the backend that counts the goals.
#[cfg(feature = "sim")]
pub(crate) async fn real_nav2(
    fleet: gspn::world::Fleet,
    cfg: &DdsConfig,
) -> anyhow::Result<(gspn::world::Fleet, gspn::ros2::nav2::Nav2Goals)> {
    use gspn::ros2::nav2::Nav2Navigator;
    let robots = fleet.world.robots().to_vec();
    eprintln!(
        "ros2: domain {}, waiting for Nav2 (NavigateToPose) on robot(s) {}",
        cfg.domain_id,
        robots.join(", ")
    );
    let nav = Nav2Navigator::connect(&robots, std::sync::Arc::clone(&fleet.map), cfg)
        .await?
        .mirroring(fleet.world.clone());
    eprintln!("ros2: Nav2 ready on {} robot(s)", robots.len());
    let goals = nav.goals();
    Ok((fleet.navigate_with(std::sync::Arc::new(nav)), goals))
}

/// The DDS settings of a run with simulated robots served over ROS 2 (`--ros2`).
#[cfg(feature = "sim")]
pub(crate) fn sim_config(plan: &Plan, args: &RunArgs, robots: usize) -> anyhow::Result<DdsConfig> {
    Ok(args.dds.config(plan)?.for_fleet(robots + 4))
}

/// Whether the plan has `ros2` places (else the ROS 2 backend stays off).
pub(crate) fn wanted(plan: &Plan) -> bool {
    !plan.ros2.servers.is_empty()
}

/// The robots the supervisor links to: the plan's `robots`, then the `robot` of each `ros2`
/// place not among them (several places may name one robot: its server then gets their
/// goals concurrently).
pub(crate) fn robots(plan: &Plan) -> Vec<String> {
    let mut out = plan.robots.clone();
    for (p, _) in &plan.ros2.servers {
        if let Some(Some(Role::Action { robot: Some(r), .. })) = plan.roles.get(p.index())
            && !out.contains(r)
        {
            out.push(r.clone());
        }
    }
    out
}

/// Joins DDS and links to the plan's robots.
pub(crate) async fn connect(plan: &Plan, args: &RunArgs) -> anyhow::Result<Ros2Run> {
    let cfg = args.dds.config(plan)?;
    let robots = robots(plan);
    eprintln!(
        "ros2: domain {}, waiting for robot(s) {}",
        cfg.domain_id,
        robots.join(", ")
    );
    let backend = Ros2Backend::connect(
        &plan.net,
        &plan.ros2,
        &robots,
        &cfg,
        args.ros2_wait_subscribers,
    )
    .await?;
    eprintln!("ros2: robots ready");
    // Say when a robot is lost or back (the runs' errors say which action it failed).
    let after = cfg.lost_after;
    say_liveness(
        &robots,
        |r| backend.presence().liveness(r),
        move |r, l| match l {
            Liveness::Lost => Some(format!(
                "ros2: robot `{r}` lost: no heartbeat for {after:?}"
            )),
            Liveness::Gone => Some(format!(
                "ros2: robot `{r}` lost: its ExecPlace server left DDS discovery"
            )),
            Liveness::Alive => Some(format!("ros2: robot `{r}` is back")),
            Liveness::Unknown => None,
        },
    );
    Ok(Ros2Run::new(backend, args.ros2_linger))
}

/// Says on stderr when one of `robots` (its liveness from `liveness`) is lost or back: `say`
/// words each change for its transport (`None`: nothing to say). DDS and Zenoh alike.
pub(crate) fn say_liveness(
    robots: &[String],
    liveness: impl Fn(&str) -> Option<tokio::sync::watch::Receiver<Liveness>>,
    say: impl Fn(&str, Liveness) -> Option<String> + Clone + Send + 'static,
) {
    for r in robots {
        let Some(mut live) = liveness(r) else {
            continue;
        };
        let (r, say) = (r.clone(), say.clone());
        live.borrow_and_update();
        tokio::spawn(async move {
            while live.changed().await.is_ok() {
                let now = *live.borrow();
                if let Some(line) = say(&r, now) {
                    eprintln!("{line}");
                }
            }
        });
    }
}

/// The ROS 2 side of `run` over DDS.
pub(crate) type Ros2Run = crate::supervisor_run::SupervisorRun<Ros2Backend>;

/// Arguments of `robot`.
#[derive(clap::Args, Debug)]
pub(crate) struct RobotArgs {
    /// The robot's id, as in the plan's `robots` (its servers are `/<ID>/<server>`)
    /// [default: the node name of `--ros-args -r __node:=ID`].
    #[arg(long)]
    id: Option<String>,
    /// The plan.
    #[arg(long)]
    plan: PathBuf,
    /// Seed of the robot's draws [default: the plan's, else 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Seconds of real time per unit of model time for the local delays (larger = slower)
    /// [default: the plan's time_scale, else 1].
    #[arg(long, value_name = "X")]
    time_scale: Option<f64>,
    /// Append `seq stamp_ns received_ns` for every firing received to this file.
    #[arg(long, value_name = "FILE")]
    latency_log: Option<PathBuf>,
    /// Keep serving after the supervisor says its run is over or its heartbeat stops
    /// (default: exit then).
    #[arg(long)]
    stay: bool,
    #[command(flatten)]
    dds: DdsArgs,
    #[command(flatten)]
    net: NetArgs,
    /// Serve over Zenoh through the router at ENDPOINT (`tcp/127.0.0.1:7447`) instead of
    /// DDS [default: DDS, unless the plan says `[ros2] transport = "zenoh"`] (feature `zenoh`).
    #[cfg(feature = "zenoh")]
    #[arg(long, value_name = "ENDPOINT")]
    zenoh: Option<String>,
}

/// `plan-runner robot`: serve until the supervisor's run is over (with `--stay`: until
/// Ctrl-C or SIGTERM).
pub(crate) fn robot(args: RobotArgs) -> anyhow::Result<ExitCode> {
    let plan = read_plan(&args.plan, &args.net.read_options())?;
    if !wanted(&plan) {
        return Err(BadInput(format!(
            "{}: no place has action = \"ros2\": nothing to serve",
            args.plan.display()
        ))
        .into());
    }
    let id = match (&args.id, args.dds.ros()?.node) {
        (Some(id), _) => id.clone(),
        (None, Some(node)) => node,
        (None, None) => {
            return Err(
                BadInput("robot: give --id ID (or --ros-args -r __node:=ID)".to_string()).into(),
            );
        }
    };
    let robots = robots(&plan);
    if !robots.contains(&id) {
        eprintln!(
            "warning: robot `{}` is not in the plan's robots ({})",
            id,
            robots.join(", ")
        );
    }
    let scale = args
        .time_scale
        .or(plan.time_scale.filter(|&x| x > 0.0))
        .unwrap_or(1.0);
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(BadInput(format!("--time-scale {scale}: must be ≥ 0")).into());
    }
    #[cfg(feature = "zenoh")]
    if let Some(endpoint) = crate::zenoh::endpoint(&plan, args.zenoh.as_deref()) {
        let opts = gspn::zenoh::robot::FleetOptions {
            ids: vec![id.clone()],
            seed: args.seed.or(plan.seed).unwrap_or(0),
            time_scale: scale,
            stay: args.stay,
        };
        return crate::zenoh::serve_robots(&plan, &endpoint, opts);
    }
    let cfg = args.dds.config(&plan)?;
    let opts = RobotOptions {
        id: id.clone(),
        seed: args.seed.or(plan.seed).unwrap_or(0),
        time_scale: scale,
        latency_log: args.latency_log.clone(),
        stay: args.stay,
    };
    let rt = crate::common::two_threads().context("starting tokio")?;
    let stats = rt.block_on(async {
        eprintln!(
            "robot {}: serving on domain {} ({} ros2 places)",
            opts.id,
            cfg.domain_id,
            plan.ros2.servers.len()
        );
        serve(&plan.net, &plan.ros2, &cfg, opts, shutdown()).await
    })?;
    if let Some(left) = &stats.left {
        eprintln!("robot {id}: {left}: leaving");
    }
    eprintln!(
        "robot {}: {} goals, {} cancelled, {} firings received",
        id, stats.goals, stats.cancelled, stats.firings
    );
    Ok(ExitCode::SUCCESS)
}

/// Completes on Ctrl-C or SIGTERM.
pub(crate) async fn shutdown() {
    #[cfg(unix)]
    {
        use tokio::signal::unix::{SignalKind, signal};
        if let Ok(mut term) = signal(SignalKind::terminate()) {
            tokio::select! {
                _ = tokio::signal::ctrl_c() => {}
                _ = term.recv() => {}
            }
            return;
        }
    }
    let _ = tokio::signal::ctrl_c().await;
}
