//! `plan-runner run PLAN` for a plan with a `[map]`: the run on simulated robots (feature
//! `sim`). The world and the runtime share one tokio runtime; with time scale 0 its clock is
//! paused, so simulated time jumps from one physics step to the next as fast as the steps
//! compute. `--json` prints the summary with the world's metrics under `sim`.

use std::process::ExitCode;

use anyhow::Context as _;
use gspn::io::plan::Plan;
use gspn::sim::world::{Fleet, SimMetrics};

use crate::common::BadInput;
use crate::run::{Args, Backends, execute_with, print_summary};

pub(crate) fn main(plan: Plan, args: &Args) -> anyhow::Result<ExitCode> {
    let virtual_time = plan.time_scale.unwrap_or(0.0) == 0.0;
    let rt = if virtual_time {
        tokio::runtime::Builder::new_current_thread()
            .enable_all()
            .start_paused(true)
            .build()
    } else {
        tokio::runtime::Builder::new_multi_thread()
            .worker_threads(2)
            .enable_all()
            .build()
    }
    .context("starting tokio")?;
    let ((summary, code), metrics) = rt.block_on(async {
        let fleet = Fleet::new(plan, args.robots).map_err(|e| BadInput(e.to_string()))?;
        #[cfg_attr(not(feature = "web"), allow(unused_mut))]
        let mut backends = Backends::default();
        #[cfg(feature = "web")]
        if args.web.is_some() {
            backends.world = Some(world_feed(fleet.world.view()));
        }
        let signals = crate::common::StopSignals::new()?;
        let run = execute_with(fleet.builder, args, backends, signals).await;
        let metrics = fleet.world.metrics().await;
        fleet.world.stop();
        anyhow::Ok((run?, metrics))
    })?;
    if args.json {
        let mut v = serde_json::to_value(&summary)?;
        v["sim"] = serde_json::to_value(&metrics)?;
        println!("{}", serde_json::to_string_pretty(&v)?);
    } else {
        print_summary(&summary, false)?;
        if let Some(m) = &metrics {
            print_metrics(m);
        }
    }
    Ok(ExitCode::from(code))
}

fn print_metrics(m: &SimMetrics) {
    println!(
        "sim: {} robots, {:.1} s simulated ({:.1}× real time)",
        m.robots, m.sim_time_s, m.real_time_factor
    );
    println!(
        "  collisions {}  min separation {}  order violations {}  stuck {}",
        m.collisions,
        m.min_separation_m
            .map_or("-".to_string(), |s| format!("{s:.3} m")),
        m.order_violations,
        m.stuck_events
    );
    println!("  patrol cycles per robot {:?}", m.cycles_per_robot);
}

/// The world's view as JSON for the viewer's map: a task forwards each new view.
#[cfg(feature = "web")]
fn world_feed(
    mut view: tokio::sync::watch::Receiver<gspn::sim::world::WorldView>,
) -> tokio::sync::watch::Receiver<serde_json::Value> {
    let json = |v: &gspn::sim::world::WorldView| {
        serde_json::to_value(v).unwrap_or(serde_json::Value::Null)
    };
    let (tx, rx) = tokio::sync::watch::channel(json(&view.borrow_and_update()));
    tokio::spawn(async move {
        while view.changed().await.is_ok() {
            let v = json(&view.borrow_and_update());
            if tx.send(v).is_err() {
                break;
            }
        }
    });
    rx
}
