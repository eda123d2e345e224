//! The Zenoh transport in the CLI (feature `zenoh`): `run --zenoh ENDPOINT` (or a plan's
//! `[ros2] transport = "zenoh"`), `robot --zenoh ENDPOINT`, `fleet` (many robots in one
//! process) and `router` (a Zenoh router from the crate, for users without `zenohd`).

use std::net::IpAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use gspn::plan::{Plan, read_plan};
use gspn::ros2::DdsConfig;
use gspn::ros2::settings::Transport;
use gspn::zenoh::keys::valid_robot_id;
use gspn::zenoh::presence::Liveness;
use gspn::zenoh::robot::{FleetOptions, FleetStats};
use gspn::zenoh::{ZenohBackend, ZenohConfig};

use crate::common::{BadInput, NetArgs};

/// The router a plan with `transport = "zenoh"` and no `zenoh` key connects to.
pub(crate) const DEFAULT_ENDPOINT: &str = "tcp/127.0.0.1:7447";

/// The Zenoh flag of `run`.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct ZenohRunArgs {
    /// Reach the robots over Zenoh through the router at ENDPOINT (`tcp/127.0.0.1:7447`)
    /// instead of DDS [default: DDS, unless the plan says `[ros2] transport = "zenoh"`].
    #[arg(long, value_name = "ENDPOINT")]
    zenoh: Option<String>,
}

impl ZenohRunArgs {
    /// `--zenoh`, when given.
    pub(crate) fn zenoh(&self) -> Option<&str> {
        self.zenoh.as_deref()
    }
}

/// The router to use, when the transport is Zenoh: the flag, else the plan's.
pub(crate) fn endpoint(plan: &Plan, flag: Option<&str>) -> Option<String> {
    match (flag, plan.ros2.transport) {
        (Some(e), _) => Some(e.to_string()),
        (None, Transport::Zenoh) => Some(
            plan.ros2
                .zenoh
                .clone()
                .unwrap_or_else(|| DEFAULT_ENDPOINT.into()),
        ),
        (None, Transport::Dds) => None,
    }
}

/// The domain and timings: the `[ros2]` table's, as DDS reads them (plan, then environment).
fn config(plan: &Plan, endpoint: &str) -> anyhow::Result<ZenohConfig> {
    let dds = DdsConfig::resolve(&plan.ros2).map_err(|e| BadInput(e.to_string()))?;
    check_endpoint(endpoint, false)?;
    Ok(ZenohConfig {
        endpoint: endpoint.to_string(),
        domain: dds.domain_id,
        lost_after: dds.lost_after,
        startup: dds.startup,
    })
}

/// Refuses an endpoint that is not `tcp/HOST:PORT` (the one transport built in) and, unless
/// `remote`, a listening one off the loopback.
fn check_endpoint(e: &str, listen_remote: bool) -> anyhow::Result<()> {
    let Some(addr) = e.strip_prefix("tcp/") else {
        return Err(BadInput(format!(
            "zenoh endpoint `{e}`: only tcp/HOST:PORT endpoints are built in"
        ))
        .into());
    };
    let Some((host, port)) = addr.rsplit_once(':') else {
        return Err(BadInput(format!("zenoh endpoint `{e}`: no :PORT")).into());
    };
    if port.parse::<u16>().is_err() {
        return Err(BadInput(format!("zenoh endpoint `{e}`: `{port}` is not a port")).into());
    }
    if listen_remote {
        let host = host.trim_matches(['[', ']']);
        let loopback =
            host == "localhost" || host.parse::<IpAddr>().is_ok_and(|ip| ip.is_loopback());
        if !loopback {
            return Err(BadInput(format!(
                "zenoh endpoint `{e}`: listening off the loopback needs --allow-remote"
            ))
            .into());
        }
    }
    Ok(())
}

/// Connects the supervisor to its robots over Zenoh.
pub(crate) async fn connect(
    plan: &Plan,
    endpoint: &str,
    ros2: &crate::ros2::RunArgs,
) -> anyhow::Result<ZenohRun> {
    let cfg = config(plan, endpoint)?;
    let robots = crate::ros2::robots(plan);
    if let Some(bad) = robots.iter().find(|r| !valid_robot_id(r)) {
        return Err(BadInput(format!(
            "{}: robot `{bad}` cannot be a Zenoh key chunk (letters, digits, _; not starting with a digit)",
            plan.path.display()
        ))
        .into());
    }
    eprintln!(
        "zenoh: router {endpoint}, domain {}, waiting for {} robot(s)",
        cfg.domain,
        robots.len()
    );
    let started = tokio::time::Instant::now();
    let session = gspn::zenoh::client(endpoint).await?;
    let backend = ZenohBackend::connect(
        session,
        &plan.net,
        &plan.ros2,
        &robots,
        &cfg,
        ros2.ros2_wait_subscribers,
    )
    .await?;
    eprintln!(
        "zenoh: robots ready after {:.2} s",
        started.elapsed().as_secs_f64()
    );
    let after = cfg.lost_after;
    crate::ros2::say_liveness(
        &robots,
        |r| backend.presence().liveness(r),
        move |r, l| match l {
            Liveness::Lost => Some(format!(
                "zenoh: robot `{r}` lost: no liveliness token for {after:?}"
            )),
            Liveness::Alive => Some(format!("zenoh: robot `{r}` is back")),
            Liveness::Unknown | Liveness::Gone => None,
        },
    );
    Ok(ZenohRun::new(backend, ros2.ros2_linger))
}

/// The Zenoh side of `run`.
pub(crate) type ZenohRun = crate::supervisor_run::SupervisorRun<ZenohBackend>;

/// Serves robots `opts.ids` of `plan` over Zenoh until the run is over (or Ctrl-C).
pub(crate) fn serve_robots(
    plan: &Plan,
    endpoint: &str,
    opts: FleetOptions,
) -> anyhow::Result<ExitCode> {
    if let Some(bad) = opts.ids.iter().find(|r| !valid_robot_id(r)) {
        return Err(BadInput(format!(
            "robot `{bad}` cannot be a Zenoh key chunk (letters, digits, _; not starting with a digit)"
        ))
        .into());
    }
    let cfg = config(plan, endpoint)?;
    let rt = crate::common::two_threads().context("starting tokio")?;
    let n = opts.ids.len();
    let stats: FleetStats = rt.block_on(async {
        let session = gspn::zenoh::client(endpoint).await?;
        eprintln!(
            "zenoh: {n} robot(s) serving via {endpoint} on domain {} ({} ros2 places)",
            cfg.domain,
            plan.ros2.servers.len()
        );
        let stats = gspn::zenoh::robot::serve(
            &session,
            &plan.net,
            &plan.ros2,
            &cfg,
            opts,
            crate::ros2::shutdown(),
        )
        .await;
        let _ = session.close().await;
        anyhow::Ok(stats?)
    })?;
    if let Some(left) = &stats.left {
        eprintln!("zenoh: {left}: leaving");
    }
    let goals: u64 = stats.robots.iter().map(|(_, s)| s.goals).sum();
    let cancelled: u64 = stats.robots.iter().map(|(_, s)| s.cancelled).sum();
    if let [(id, _)] = stats.robots.as_slice() {
        eprintln!(
            "robot {id}: {goals} goals, {cancelled} cancelled, {} firings received",
            stats.firings
        );
    } else {
        eprintln!(
            "fleet: {n} robots, {goals} goals, {cancelled} cancelled, {} firings received",
            stats.firings
        );
    }
    Ok(ExitCode::SUCCESS)
}

/// Arguments of `fleet`.
#[derive(clap::Args, Debug)]
pub(crate) struct FleetArgs {
    /// The plan.
    #[arg(long)]
    plan: PathBuf,
    /// Which of the plan's robots this process hosts: `A..B` (positions in the plan's robot
    /// list, B excluded) or ids separated by commas [default: all].
    #[arg(long, value_name = "A..B|IDS")]
    robots: Option<String>,
    /// The router [default: the plan's `[ros2] zenoh`, else tcp/127.0.0.1:7447].
    #[arg(long, value_name = "ENDPOINT")]
    zenoh: Option<String>,
    /// Seed of the robots' draws (each mixes in its id) [default: the plan's, else 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Seconds per unit of model time [default: the plan's time_scale, else 1].
    #[arg(long, value_name = "X")]
    time_scale: Option<f64>,
    /// Keep serving after the run is over.
    #[arg(long)]
    stay: bool,
    #[command(flatten)]
    net: NetArgs,
}

/// The robots `spec` picks out of `all`.
fn pick_robots(all: &[String], spec: Option<&str>) -> Result<Vec<String>, String> {
    let Some(spec) = spec else {
        return Ok(all.to_vec());
    };
    if let Some((a, b)) = spec.split_once("..") {
        let a: usize = a
            .trim()
            .parse()
            .map_err(|_| format!("`{a}` is not a position"))?;
        let b: usize = b
            .trim()
            .parse()
            .map_err(|_| format!("`{b}` is not a position"))?;
        if a >= b || b > all.len() {
            return Err(format!(
                "{a}..{b} is not a range within the plan's {} robots",
                all.len()
            ));
        }
        return Ok(all[a..b].to_vec());
    }
    let ids: Vec<String> = spec.split(',').map(|s| s.trim().to_string()).collect();
    if let Some(unknown) = ids.iter().find(|id| !all.contains(id)) {
        return Err(format!("robot `{unknown}` is not one of the plan's robots"));
    }
    Ok(ids)
}

/// `plan-runner fleet`.
pub(crate) fn fleet(args: FleetArgs) -> anyhow::Result<ExitCode> {
    let plan = read_plan(&args.plan, &args.net.read_options())?;
    if !crate::ros2::wanted(&plan) {
        return Err(BadInput(format!(
            "{}: no place has action = \"ros2\": nothing to serve",
            args.plan.display()
        ))
        .into());
    }
    let ids = pick_robots(&crate::ros2::robots(&plan), args.robots.as_deref())
        .map_err(|why| BadInput(format!("--robots: {why}")))?;
    let scale = args
        .time_scale
        .or(plan.time_scale.filter(|&x| x > 0.0))
        .unwrap_or(1.0);
    if !(scale.is_finite() && scale >= 0.0) {
        return Err(BadInput(format!("--time-scale {scale}: must be ≥ 0")).into());
    }
    let endpoint =
        endpoint(&plan, args.zenoh.as_deref()).unwrap_or_else(|| DEFAULT_ENDPOINT.to_string());
    let opts = FleetOptions {
        ids,
        seed: args.seed.or(plan.seed).unwrap_or(0),
        time_scale: scale,
        stay: args.stay,
    };
    serve_robots(&plan, &endpoint, opts)
}

/// Arguments of `router`.
#[derive(clap::Args, Debug)]
pub(crate) struct RouterArgs {
    /// Where to listen (repeatable) [default: tcp/127.0.0.1:7447].
    #[arg(long, value_name = "ENDPOINT")]
    listen: Vec<String>,
    /// Other routers to join (another site's; repeatable; retried until they answer).
    #[arg(long, value_name = "ENDPOINT")]
    connect: Vec<String>,
    /// Let --listen use an address off the loopback.
    #[arg(long)]
    allow_remote: bool,
    /// Seconds another router or a client may hear nothing from this one before it drops
    /// the link [default: Zenoh's, 10]; a cut between sites is noticed after the far
    /// router's lease.
    #[arg(long, value_name = "SECS")]
    lease: Option<f64>,
}

/// `plan-runner router`: routes until Ctrl-C or SIGTERM.
pub(crate) fn router(args: RouterArgs) -> anyhow::Result<ExitCode> {
    let listen = if args.listen.is_empty() {
        vec![DEFAULT_ENDPOINT.to_string()]
    } else {
        args.listen
    };
    for e in &listen {
        check_endpoint(e, !args.allow_remote)?;
    }
    for e in &args.connect {
        check_endpoint(e, false)?;
    }
    let lease = match args.lease {
        None => None,
        Some(s) if s.is_finite() && (0.001..=3600.0).contains(&s) => {
            Some(Duration::from_secs_f64(s))
        }
        Some(s) => {
            return Err(BadInput(format!("--lease {s}: must be in 0.001..=3600 seconds")).into());
        }
    };
    let rt = crate::common::two_threads().context("starting tokio")?;
    rt.block_on(async {
        let session = gspn::zenoh::router(&listen, &args.connect, lease).await?;
        eprintln!(
            "router {}: listening on {}{}",
            session.zid(),
            listen.join(", "),
            if args.connect.is_empty() {
                String::new()
            } else {
                format!(", joining {}", args.connect.join(", "))
            }
        );
        crate::ros2::shutdown().await;
        let _ = session.close().await;
        anyhow::Ok(())
    })?;
    Ok(ExitCode::SUCCESS)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fleet_ranges_pick_positions() {
        let all: Vec<String> = (0..5).map(|i| format!("r{i}")).collect();
        assert_eq!(pick_robots(&all, Some("1..3")).unwrap(), ["r1", "r2"]);
        assert_eq!(pick_robots(&all, Some("r4,r0")).unwrap(), ["r4", "r0"]);
        assert!(
            pick_robots(&all, Some("3..9"))
                .unwrap_err()
                .contains("5 robots")
        );
        assert!(pick_robots(&all, Some("r9")).unwrap_err().contains("`r9`"));
        assert_eq!(pick_robots(&all, None).unwrap().len(), 5);
    }

    #[test]
    fn endpoints_are_tcp_and_listen_on_the_loopback() {
        assert!(check_endpoint("tcp/127.0.0.1:7447", true).is_ok());
        assert!(check_endpoint("tcp/localhost:1", true).is_ok());
        assert!(check_endpoint("tcp/10.0.0.1:7447", true).is_err());
        assert!(check_endpoint("tcp/10.0.0.1:7447", false).is_ok());
        assert!(check_endpoint("udp/127.0.0.1:7447", false).is_err());
        assert!(check_endpoint("tcp/127.0.0.1", false).is_err());
    }
}
