//! The backends of `plan-runner run`, built in one place: program actions (a plan with
//! `action = { command | worker }`), the simulated world (feature `sim`, a plan with a
//! `[map]`), ROS 2 (feature `ros2`, a plan with `ros2` places) and the
//! live viewer (feature `web`, `--web`). Every feature switch of `run` is in this file;
//! `run.rs` attaches, starts and finishes the list it gets.

use gspn::plan::Plan;
use gspn::runtime::{Backends, RuntimeBuilder};

use crate::common::StopSignals;

#[cfg(feature = "sim")]
use crate::common::BadInput;
#[cfg(feature = "ros2")]
use anyhow::Context as _;

/// The flags of `run` that belong to a backend.
#[derive(clap::Args, Debug)]
pub(crate) struct BackendArgs {
    /// Watch the run in the browser: serve the viewer at ADDR [default: 127.0.0.1:8080]
    /// (feature `web`). A signal (Ctrl-C, SIGTERM) during the run ends the run and the viewer
    /// together; after a run that ended on its own the viewer stays up until one.
    #[cfg(feature = "web")]
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    web: Option<std::net::SocketAddr>,
    /// Let `--web` listen on a non-loopback address (the viewer has no login: anyone who
    /// can reach it can stop the run).
    #[cfg(feature = "web")]
    #[arg(long)]
    allow_remote: bool,
    /// Run the plan's map with N simulated robots (the net's initial robot tokens scaled to
    /// N; feature `sim`).
    #[cfg(feature = "sim")]
    #[arg(long, value_name = "N")]
    robots: Option<usize>,
    /// The run's monitor (`run --monitor`), set once it is made, for the viewer's table.
    #[cfg(feature = "web")]
    #[arg(skip)]
    pub(crate) monitor: crate::serve::MonitorSlot,
    /// ROS 2 flags, used when the plan has `ros2` places (feature `ros2`).
    #[cfg(feature = "ros2")]
    #[command(flatten)]
    ros2: crate::ros2::RunArgs,
    /// `--zenoh ENDPOINT`: the same over Zenoh (feature `zenoh`).
    #[cfg(feature = "zenoh")]
    #[command(flatten)]
    zenoh: crate::zenoh::ZenohRunArgs,
}

/// Refuses flags the plan cannot honour, before anything starts.
pub(crate) fn check(plan: &Plan, args: &BackendArgs) -> anyhow::Result<()> {
    #[cfg(feature = "web")]
    if let Some(addr) = args.web {
        crate::serve::check_bind(addr, args.allow_remote)?;
    }
    #[cfg(feature = "sim")]
    if plan.map.is_none() && args.robots.is_some() {
        return Err(
            BadInput("--robots needs a plan with a [map] (see docs/plans.md)".into()).into(),
        );
    }
    #[cfg(feature = "ros2")]
    crate::ros2::check_plan(plan, &args.ros2)?;
    #[cfg(all(feature = "ros2", feature = "sim"))]
    crate::ros2::check_sim_nav2(plan, &args.ros2)?;
    #[cfg(not(feature = "ros2"))]
    if !plan.ros2.servers.is_empty() {
        return Err(crate::common::BadInput(format!(
            "{}: places with action = \"ros2\" need a plan-runner built with the `ros2` feature (cargo build --features ros2)",
            plan.path.display()
        ))
        .into());
    }
    let _ = (plan, args);
    Ok(())
}

/// The tokio runtime of a run. A simulated world on virtual time (time scale 0) gets a
/// paused clock on one thread, so simulated time jumps from one physics step to the next as
/// fast as the steps compute; everything else two worker threads.
pub(crate) fn tokio_runtime(plan: &Plan) -> std::io::Result<tokio::runtime::Runtime> {
    #[cfg(feature = "sim")]
    if plan.map.is_some() && plan.time_scale.unwrap_or(0.0) == 0.0 {
        return tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build();
    }
    let _ = plan;
    crate::common::two_threads()
}

/// The run's builder and its backends, in order: the simulated world (a plan with a map)
/// or ROS 2 (a plan with `ros2` places), then the viewer. Call inside the run's tokio
/// runtime.
pub(crate) async fn setup(
    mut plan: Plan,
    args: &BackendArgs,
    signals: &StopSignals,
) -> anyhow::Result<(RuntimeBuilder, Backends)> {
    let mut backends = Backends::default();
    // Program actions (`action = { command | worker }`) first: the names they register are
    // the plan's own.
    let programs = std::mem::take(&mut plan.programs);
    #[cfg(unix)]
    if !programs.is_empty() {
        backends.push(gspn::actions::ProgramActions::new(programs));
    }
    #[cfg(not(unix))]
    if !programs.is_empty() {
        return Err(crate::common::BadInput(
            "program actions (`command`, `worker`) need a unix system".into(),
        )
        .into());
    }
    #[cfg(feature = "sim")]
    if plan.map.is_some() {
        #[cfg(feature = "ros2")]
        let nav2 = match args.ros2.ros2 || args.ros2.nav2 {
            true => Some(crate::ros2::sim_config(
                &plan,
                &args.ros2,
                args.robots.unwrap_or(plan.robots.len()),
            )?),
            false => None,
        };
        #[cfg(feature = "ros2")]
        let mirror = args.ros2.nav2;
        #[cfg(not(feature = "ros2"))]
        let mirror = false;
        let fleet = match mirror {
            true => gspn::world::Fleet::mirror(plan, args.robots),
            false => gspn::world::Fleet::new(plan, args.robots),
        }
        .map_err(|e| BadInput(e.to_string()))?;
        #[cfg(feature = "ros2")]
        let fleet = match nav2 {
            Some(cfg) if mirror => {
                let (fleet, goals) = crate::ros2::real_nav2(fleet, &cfg).await?;
                backends.push(goals);
                fleet
            }
            Some(cfg) => {
                let (fleet, servers) = crate::ros2::sim_nav2(fleet, &cfg).await?;
                backends.push(servers);
                fleet
            }
            None => fleet,
        };
        #[cfg(feature = "web")]
        if let Some(addr) = args.web {
            let feed = gspn::world::WorldView::json_feed(fleet.world.view());
            backends.push(gspn::world::WorldBackend::new(fleet.world));
            backends.push(crate::serve::LiveViewer::new(
                addr,
                Some(feed),
                args.monitor.clone(),
                signals.clone(),
            ));
            return Ok((fleet.builder, backends));
        }
        backends.push(gspn::world::WorldBackend::new(fleet.world));
        return Ok((fleet.builder, backends));
    }
    #[cfg(feature = "ros2")]
    if crate::ros2::wanted(&plan) {
        // Ctrl-C while waiting for the robots ends at once (exit 130). The handler is
        // installed before joining DDS (which blocks a while), so no Ctrl-C is missed.
        #[cfg(unix)]
        let mut int = tokio::signal::unix::signal(tokio::signal::unix::SignalKind::interrupt())
            .context("installing the Ctrl-C handler")?;
        #[cfg(unix)]
        let interrupted = int.recv();
        #[cfg(not(unix))]
        let interrupted = tokio::signal::ctrl_c();
        tokio::select! {
            b = connect_ros2(&plan, args) => backends.push(b?),
            _ = interrupted => {
                return Err(crate::common::Interrupted {
                    what: "waiting for the robots",
                    signal: "SIGINT",
                    code: 130,
                }
                .into());
            }
        }
    }
    #[cfg(feature = "web")]
    if let Some(addr) = args.web {
        backends.push(crate::serve::LiveViewer::new(
            addr,
            None,
            args.monitor.clone(),
            signals.clone(),
        ));
    }
    let _ = (args, signals);
    Ok((plan.runtime_builder(), backends))
}

/// The supervisor's ROS 2 side: over Zenoh when the flag or the plan says so (feature
/// `zenoh`), else over DDS.
#[cfg(feature = "ros2")]
async fn connect_ros2(plan: &Plan, args: &BackendArgs) -> anyhow::Result<Ros2Side> {
    #[cfg(feature = "zenoh")]
    if let Some(e) = crate::zenoh::endpoint(plan, args.zenoh.zenoh()) {
        return Ok(Ros2Side::Zenoh(
            crate::zenoh::connect(plan, &e, &args.ros2).await?,
        ));
    }
    Ok(Ros2Side::Dds(Box::new(
        crate::ros2::connect(plan, &args.ros2).await?,
    )))
}

/// The ROS 2 backend of a run, on either transport.
#[cfg(feature = "ros2")]
#[derive(Debug)]
enum Ros2Side {
    Dds(Box<crate::ros2::Ros2Run>),
    #[cfg(feature = "zenoh")]
    Zenoh(crate::zenoh::ZenohRun),
}

#[cfg(feature = "ros2")]
impl Ros2Side {
    fn inner(&mut self) -> &mut dyn gspn::runtime::Backend {
        match self {
            Ros2Side::Dds(b) => b.as_mut(),
            #[cfg(feature = "zenoh")]
            Ros2Side::Zenoh(b) => b,
        }
    }
}

#[cfg(feature = "ros2")]
impl gspn::runtime::Backend for Ros2Side {
    fn name(&self) -> &'static str {
        match self {
            Ros2Side::Dds(b) => b.name(),
            #[cfg(feature = "zenoh")]
            Ros2Side::Zenoh(b) => b.name(),
        }
    }
    fn attach(
        &mut self,
        run: RuntimeBuilder,
    ) -> Result<RuntimeBuilder, gspn::runtime::BackendError> {
        self.inner().attach(run)
    }
    fn observes_events(&self) -> bool {
        true
    }
    fn started<'a>(&'a mut self, start: gspn::runtime::Start<'a>) -> gspn::runtime::Started<'a> {
        self.inner().started(start)
    }
    fn finish<'a>(
        &'a mut self,
        summary: &'a gspn::runtime::Summary,
    ) -> gspn::runtime::BackendFuture<'a, Option<gspn::runtime::Section>> {
        self.inner().finish(summary)
    }
}
