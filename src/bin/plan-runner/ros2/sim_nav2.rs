//! `plan-runner sim-nav2`: a plan's map with N simulated robots that serve Nav2's
//! `NavigateToPose` and publish their poses over DDS, in a process of their own — the
//! stand-in for a fleet of real Nav2 robots (or Gazebo with Nav2) that a supervisor
//! (`run --nav2`) drives without knowing the difference.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::read_plan;

use super::{DdsArgs, shutdown};
use crate::common::{BadInput, NetArgs};

/// The flags of `plan-runner sim-nav2`.
#[derive(clap::Args, Debug)]
pub(crate) struct SimNav2Args {
    /// The plan (its `[map]` and the robots of the net's initial marking).
    plan: PathBuf,
    /// N simulated robots (the net's initial robot tokens scaled to N, named r1..rN).
    #[arg(long, value_name = "N")]
    robots: Option<usize>,
    /// Seconds of real time per simulated second (larger = slower) [default: the plan's
    /// time_scale, else 1]. Must be > 0: DDS runs on the wall clock.
    #[arg(long, value_name = "X")]
    time_scale: Option<f64>,
    /// Seed of the world's draws [default: the plan's, else 0].
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    dds: DdsArgs,
    #[command(flatten)]
    net: NetArgs,
}

/// Serves the simulated robots until Ctrl-C or SIGTERM.
pub(crate) fn main(args: SimNav2Args) -> anyhow::Result<ExitCode> {
    let mut plan = read_plan(&args.plan, &args.net.read_options())?;
    if plan.map.is_none() {
        return Err(BadInput(format!(
            "{}: sim-nav2 needs a plan with a [map] (see docs/plans.md)",
            plan.path.display()
        ))
        .into());
    }
    let scale = args
        .time_scale
        .or(plan.time_scale.filter(|&x| x > 0.0))
        .unwrap_or(1.0);
    if !(scale.is_finite() && scale > 0.0) {
        return Err(BadInput(format!(
            "--time-scale {scale}: must be > 0 (DDS runs on the wall clock, so the world must too)"
        ))
        .into());
    }
    plan.check_time_scale(&format!("--time-scale {scale}"), scale)?;
    plan.time_scale = Some(scale);
    plan.seed = Some(args.seed.or(plan.seed).unwrap_or(0));
    let robots = args.robots.unwrap_or(plan.robots.len());
    let cfg = args.dds.config(&plan)?.for_fleet(robots + 4);
    let rt = crate::common::two_threads().context("starting tokio")?;
    rt.block_on(async {
        let fleet =
            gspn::world::Fleet::new(plan, args.robots).map_err(|e| BadInput(e.to_string()))?;
        let servers = gspn::ros2::nav2::SimNav2::serve(
            &fleet.world,
            std::sync::Arc::clone(&fleet.map),
            &cfg,
        )?;
        eprintln!(
            "sim-nav2: domain {}, NavigateToPose served for {} simulated robot(s): {}",
            cfg.domain_id,
            fleet.world.robots().len(),
            fleet.world.robots().join(", ")
        );
        shutdown().await;
        fleet.world.stop();
        eprintln!("sim-nav2: stopped");
        // The process ends here: its DDS entities go with it. Dropping them one by one
        // after their participant only makes RustDDS log errors.
        std::mem::forget(servers);
        anyhow::Ok(())
    })?;
    Ok(ExitCode::SUCCESS)
}
