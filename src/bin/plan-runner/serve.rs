//! `plan-runner serve FILE [--addr 127.0.0.1:PORT] [--seed S]`: the viewer for a net or a plan.
//!
//! Draws the net in the browser (positions from the file, else an automatic layout), plays
//! its seeded token game (a plan's policy and seed apply) and shows its analysis. Every asset
//! is inside the binary; nothing is fetched from the network.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::open;
use std::sync::Arc;

use gspn::runtime::{RuntimeHandle, Summary};
use gspn::web::{LiveRun, WebState, serve};

use crate::common::NetArgs;

/// Arguments of `serve`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO) or a plan (.toml: its policy and seed apply).
    file: PathBuf,
    /// Address to listen on (port 0 picks a free one; the URL is printed).
    #[arg(long, default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    /// Seed of the token game [default: the plan's seed, else 0].
    #[arg(long)]
    seed: Option<u64>,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let plan = open(&args.file, &args.net.read_options())?.into_plan();
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    let seed = args.seed.or(plan.seed).unwrap_or(0);
    let policy = (!plan.policy.is_empty()).then_some(plan.policy);
    let state = WebState::new(plan.net, policy, seed);
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    rt.block_on(async {
        let listener = tokio::net::TcpListener::bind(args.addr)
            .await
            .with_context(|| format!("cannot listen on {}", args.addr))?;
        let addr = listener.local_addr()?;
        println!("viewer for {} at http://{addr}/", args.file.display());
        tokio::select! {
            r = serve(listener, state) => r.context("viewer server")?,
            _ = tokio::signal::ctrl_c() => return Ok(ExitCode::from(130)),
        }
        Ok(ExitCode::SUCCESS)
    })
}

/// A viewer following a run (`plan-runner run --web`).
pub(crate) struct Viewer {
    addr: SocketAddr,
    task: tokio::task::JoinHandle<std::io::Result<()>>,
}

/// Serves the live view of `handle`'s run at `addr` (nothing when `None`). Call right after
/// spawning the run (with `subscribe_at_start(true)`), so the viewer sees every event.
pub(crate) async fn follow(
    mut handle: RuntimeHandle,
    addr: Option<SocketAddr>,
    world: Option<tokio::sync::watch::Receiver<serde_json::Value>>,
) -> anyhow::Result<(Arc<RuntimeHandle>, Option<Viewer>)> {
    let Some(addr) = addr else {
        return Ok((Arc::new(handle), None));
    };
    let events = handle.events();
    let handle = Arc::new(handle);
    let mut live = LiveRun::start(handle.clone(), events);
    if let Some(world) = world {
        live = live.with_world(world);
    }
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on {addr}"))?;
    let addr = listener.local_addr()?;
    eprintln!("watch the run at http://{addr}/");
    let task = tokio::spawn(serve(listener, WebState::for_live(live)));
    Ok((handle, Some(Viewer { addr, task })))
}

/// After the run: keeps the viewer up until Ctrl-C, so the final state can be looked at.
pub(crate) async fn linger(viewer: Option<Viewer>, summary: &Summary) {
    let Some(v) = viewer else { return };
    eprintln!(
        "run over ({}); the viewer stays at http://{}/ until Ctrl-C",
        summary.stopped, v.addr
    );
    let _ = tokio::signal::ctrl_c().await;
    v.task.abort();
}
