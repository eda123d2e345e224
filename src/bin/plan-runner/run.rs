//! `plan-runner run PLAN|NET`: execute a plan (or a bare net, every place net-timed) on agents.
//!
//! Places whose action is not registered in this binary run net-timed (the CLI has no user
//! code); a live one-line progress display on a terminal; a summary at the end (`--json`:
//! `stopped, firings, time, agents_spawned, agents_ended, final_marking, mean_tokens,
//! throughput, errors`). Ctrl-C stops the run cleanly (journal flushed) with exit code 130.
//!
//! A plan with a `[map]` runs on simulated robots (feature `sim`): `--robots N` scales the
//! net's initial robot tokens to N; with time scale 0 the run uses tokio's paused clock, so the
//! world runs faster than real time; `--json` adds the key `sim` (see
//! `gspn::sim::world::SimMetrics`).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

use anyhow::Context as _;
use gspn::io::plan::{Plan, read_plan};
use gspn::runtime::{Runtime, RuntimeBuilder, Summary};

use crate::common::{BadInput, NetArgs, load_net};

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A plan (`.toml`) or a net file (every place net-timed).
    file: PathBuf,
    /// Seed of every random choice (default: the plan's, else from the clock).
    #[arg(long)]
    seed: Option<u64>,
    /// 0 = virtual time, as fast as possible; 1 = real time (default: the plan's, else 0).
    #[arg(long, value_name = "X")]
    time_scale: Option<f64>,
    /// Stop at this model time.
    #[arg(long, value_name = "T")]
    until: Option<f64>,
    /// Stop after this many firings.
    #[arg(long, value_name = "N")]
    max_firings: Option<u64>,
    /// Write every event to this file (JSON Lines).
    #[arg(long, value_name = "FILE")]
    journal: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    pub(crate) json: bool,
    /// Watch the run in the browser: serve the viewer at ADDR [default: 127.0.0.1:8080]
    /// (feature `web`); after the run it stays up until Ctrl-C.
    #[cfg(feature = "web")]
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    pub(crate) web: Option<std::net::SocketAddr>,
    /// Run the plan's map with N simulated robots (the net's initial robot tokens scaled to
    /// N; feature `sim`).
    #[cfg(feature = "sim")]
    #[arg(long, value_name = "N")]
    pub(crate) robots: Option<usize>,
    #[command(flatten)]
    net: NetArgs,
    /// ROS 2 flags, used when the plan has `ros2` places (feature `ros2`).
    #[cfg(feature = "ros2")]
    #[command(flatten)]
    ros2: crate::ros2::RunArgs,
}

fn load(args: &Args) -> anyhow::Result<Plan> {
    let is_plan = args
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("toml"));
    if is_plan {
        Ok(read_plan(&args.file, &args.net.read_options())?)
    } else {
        let loaded = load_net(&args.file, &args.net)?;
        Ok(Plan::for_net(&args.file, loaded))
    }
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let mut plan = load(&args)?;
    if let Some(x) = args.time_scale {
        if !(x.is_finite() && x >= 0.0) {
            return Err(BadInput(format!("--time-scale {x}: must be ≥ 0")).into());
        }
        plan.time_scale = Some(x);
    }
    if let Some(s) = args.seed {
        plan.seed = Some(s);
    }
    if let Some(t) = args.until {
        plan.stop.time_limit = Some(t);
    }
    if let Some(n) = args.max_firings {
        plan.stop.max_firings = Some(n);
    }
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    #[cfg(feature = "sim")]
    if plan.map.is_some() {
        return crate::robots::main(plan, &args);
    } else if args.robots.is_some() {
        return Err(
            BadInput("--robots needs a plan with a [map] (see docs/plans.md)".into()).into(),
        );
    }
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
        .context("starting tokio")?;
    let summary = rt.block_on(execute(plan, &args))?;
    print_summary(&summary, args.json)?;
    Ok(ExitCode::from(summary.exit_code()))
}

async fn execute(plan: Plan, args: &Args) -> anyhow::Result<Summary> {
    #[cfg_attr(not(feature = "ros2"), allow(unused_mut))]
    let mut backends = Backends::default();
    #[cfg(feature = "ros2")]
    if crate::ros2::wanted(&plan) {
        backends.ros2 = Some(crate::ros2::connect(&plan, &args.ros2).await?);
    }
    let programs = plan.programs.clone();
    let b = Runtime::from_plan(plan);
    #[cfg(unix)]
    let b = gspn::actions::register(b, &programs);
    #[cfg(not(unix))]
    if !programs.is_empty() {
        return Err(
            BadInput("program actions (`command`, `worker`) need a unix system".into()).into(),
        );
    }
    execute_with(b, args, backends).await
}

/// What a run drives besides the runtime itself.
#[derive(Default)]
pub(crate) struct Backends {
    /// The ROS 2 connection (plans with `ros2` places).
    #[cfg(feature = "ros2")]
    pub(crate) ros2: Option<gspn::ros2::Ros2Backend>,
    /// The simulated world's view, for the viewer's map (`run --web` on a plan with a map).
    #[cfg(feature = "web")]
    pub(crate) world: Option<tokio::sync::watch::Receiver<serde_json::Value>>,
}

/// Runs a configured builder: journal, viewer, backends, progress, Ctrl-C, summary.
pub(crate) async fn execute_with(
    b: RuntimeBuilder,
    args: &Args,
    #[cfg_attr(not(any(feature = "web", feature = "ros2")), allow(unused_variables))]
    backends: Backends,
) -> anyhow::Result<Summary> {
    #[cfg(feature = "web")]
    let watched = args.web.is_some();
    #[cfg(not(feature = "web"))]
    let watched = false;
    #[cfg(feature = "ros2")]
    let mut ros2 = backends.ros2;
    #[cfg(feature = "ros2")]
    let watched = watched || ros2.is_some();
    let mut b = b.subscribe_at_start(watched);
    #[cfg(feature = "ros2")]
    if let Some(r) = &ros2 {
        b = r.attach(b);
    }
    if let Some(j) = &args.journal {
        b = b.journal(j);
    }
    #[cfg_attr(not(feature = "ros2"), allow(unused_mut))]
    let mut handle = b.spawn().map_err(|e| BadInput(e.to_string()))?;
    #[cfg(feature = "ros2")]
    if let Some(r) = &mut ros2 {
        r.publish(handle.events());
    }
    #[cfg(feature = "web")]
    let (handle, viewer) = crate::serve::follow(handle, args.web, backends.world).await?;
    for w in handle.warnings() {
        eprintln!("warning: {w}");
    }
    let live = !args.json && std::io::stderr().is_terminal();
    let progress = handle.progress();
    let bar = live.then(|| {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(100));
        bar
    });
    let wait = handle.wait();
    tokio::pin!(wait);
    let mut ticker = tokio::time::interval(Duration::from_millis(200));
    let mut interrupted = false;
    let summary = loop {
        tokio::select! {
            s = &mut wait => break s,
            r = tokio::signal::ctrl_c(), if !interrupted => {
                if r.is_ok() {
                    interrupted = true;
                    handle.interrupt();
                }
            }
            _ = ticker.tick() => {
                if let Some(bar) = &bar {
                    bar.set_message(format!(
                        "firings {}  time {:.3}",
                        progress.firings(),
                        progress.time()
                    ));
                }
            }
        }
    };
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    eprintln!("seed {}", handle.seed());
    #[cfg(feature = "ros2")]
    if let Some(r) = ros2 {
        crate::ros2::finish(r, &args.ros2).await;
    }
    #[cfg(feature = "web")]
    crate::serve::linger(viewer, &summary).await;
    Ok(summary)
}

pub(crate) fn print_summary(s: &Summary, json: bool) -> anyhow::Result<()> {
    if json {
        println!("{}", serde_json::to_string_pretty(s)?);
        return Ok(());
    }
    println!(
        "stopped: {} after {} firings at time {:.4}",
        s.stopped, s.firings, s.time
    );
    println!(
        "agents: {} spawned, {} ended",
        s.agents_spawned, s.agents_ended
    );
    println!("place                          final    mean tokens");
    for (p, k) in &s.final_marking {
        println!("  {p:<28} {k:>6}   {:>12.6}", s.mean_tokens[p]);
    }
    println!("transition                     throughput");
    for (t, x) in &s.throughput {
        println!("  {t:<28} {x:>12.6}");
    }
    for e in &s.errors {
        println!("error: {e}");
    }
    Ok(())
}
