//! `plan-runner serve FILE [--addr 127.0.0.1:PORT] [--seed S] [--save-to [PATH]]`: the
//! viewer (and editor) for a net or a plan.
//!
//! Draws the net in the browser (positions from the file, else an automatic layout), plays
//! its seeded token game (a plan's policy and seed apply) and shows its analysis. Every asset
//! is inside the binary; nothing is fetched from the network.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use std::sync::Arc;

use anyhow::Context as _;

use gspn::runtime::{Backend, BackendError, BackendFuture, Section, Start, Started, Summary};
use gspn::web::{LiveRun, WebState, serve};

use crate::common::{BadInput, NetArgs, StopSignals};

/// Arguments of `serve`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A net (.xml, .pnml, .PNPRO) or a plan (.toml: its policy and seed apply).
    file: PathBuf,
    /// Address to listen on (port 0 picks a free one; the URL is printed).
    #[arg(long, default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    /// Let `--addr` be a non-loopback address (the viewer has no login: anyone who can
    /// reach it can drive it).
    #[arg(long)]
    allow_remote: bool,
    /// Seed of the token game [default: the plan's seed, else 0].
    #[arg(long)]
    seed: Option<u64>,
    /// Most reachable markings the analysis panel explores before it gives up (the page's
    /// "max states" field starts at this value).
    #[arg(long, value_name = "N", default_value_t = gspn::web::DEFAULT_MAX_STATES)]
    max_states: usize,
    /// Where the editor's "save" writes the edited net: a GreatSPN project (.PNPRO) or a
    /// PIPE net (.xml), replaced whole (expressions, constants and templates of the opened
    /// file are written as their values). `--save-to` without PATH: the net file opened —
    /// for a plan, the net file it names. Without it the page downloads the net.
    #[arg(long, value_name = "PATH", num_args = 0..=1)]
    save_to: Option<Option<PathBuf>>,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    check_bind(args.addr, args.allow_remote)?;
    let plan = crate::common::open_checked(&args.file, &args.net)?.into_plan();
    let save_to = args
        .save_to
        .map(|path| path.unwrap_or_else(|| plan.net_path.clone()));
    if let Some(path) = &save_to
        && !args.addr.ip().is_loopback()
    {
        return Err(BadInput(format!(
            "--save-to with a non-loopback --addr: anyone who can reach {} could overwrite {}",
            args.addr,
            path.display()
        ))
        .into());
    }
    for w in &plan.warnings {
        eprintln!("warning: {w}");
    }
    let seed = args.seed.or(plan.seed).unwrap_or(0);
    if args.max_states == 0 {
        return Err(BadInput(
            "--max-states 0: the analysis needs at least the initial marking".into(),
        )
        .into());
    }
    // The panel analyses the net under the plan's policy, with its rewards (the bare net
    // for a net file), as `plan-runner analyze` does; the editor checks every edit against
    // the plan as the plan reader does.
    let text = plan.text;
    let state = WebState::for_plan(
        plan.net,
        Some(plan.policy),
        plan.rewards,
        seed,
        args.max_states,
    )
    .with_source(&plan.net_path);
    let state = match text {
        Some(text) => state.with_plan(text),
        None => state,
    };
    let state = match save_to {
        Some(path) => {
            let real = |p: &std::path::Path| std::fs::canonicalize(p).ok();
            if real(&path).is_some() && real(&path) == real(&plan.net_path) {
                eprintln!(
                    "warning: `save` replaces {} itself: its constants, templates and \
                     expressions are written as their values",
                    path.display()
                );
            }
            state.saving_to(path).map_err(|e| BadInput(e.to_string()))?
        }
        None => state,
    };
    let mut signals = StopSignals::new()?;
    let rt = crate::common::two_threads()?;
    let served = rt.block_on(async {
        let listener = tokio::net::TcpListener::bind(args.addr)
            .await
            .with_context(|| format!("cannot listen on {}", args.addr))?;
        let addr = listener.local_addr()?;
        println!("viewer for {} at http://{addr}/", args.file.display());
        serve_until_signal(serve(listener, state), &mut signals).await
    });
    // An analysis still running on a blocking thread must not hold the exit up.
    rt.shutdown_background();
    served
}

/// Serves until a signal (SIGINT, SIGTERM, SIGHUP) ends the server: exit code 128 + the
/// signal's number. For `serve` and `replay --web`.
pub(crate) async fn serve_until_signal(
    server: impl std::future::Future<Output = std::io::Result<()>>,
    signals: &mut StopSignals,
) -> anyhow::Result<ExitCode> {
    tokio::select! {
        r = server => {
            r.context("viewer server")?;
            Ok(ExitCode::SUCCESS)
        }
        caught = signals.recv() => Ok(ExitCode::from(caught.code)),
    }
}

/// Refuses to serve the viewer on a non-loopback `addr` unless `allow_remote` (exit code 2);
/// with it, warns that anyone who can reach the address can drive the viewer.
pub(crate) fn check_bind(addr: SocketAddr, allow_remote: bool) -> Result<(), BadInput> {
    if addr.ip().is_loopback() {
        return Ok(());
    }
    if !allow_remote {
        return Err(BadInput(format!(
            "{addr} is not a loopback address: the viewer has no login, so anyone who can \
             reach it could drive it; pass --allow-remote to listen there anyway"
        )));
    }
    eprintln!(
        "warning: the viewer listens on {addr}, reachable from other machines; it has no \
         login, so anyone who can reach it can drive it"
    );
    Ok(())
}

/// The viewer of `plan-runner run --web` as a backend: serves the live run from its first
/// event (and the simulated world's map when there is one). After a run that ended on its
/// own it stays up until a signal (Ctrl-C, SIGTERM, SIGHUP), so the final state can be
/// looked at; a run a signal stopped takes the viewer with it.
#[derive(Debug)]
pub(crate) struct LiveViewer {
    addr: SocketAddr,
    world: Option<tokio::sync::watch::Receiver<serde_json::Value>>,
    monitor: MonitorSlot,
    signals: StopSignals,
    served: Option<(SocketAddr, tokio::task::JoinHandle<std::io::Result<()>>)>,
}

/// Where `run --monitor` leaves its monitor for the viewer (set before the run starts).
pub(crate) type MonitorSlot = Arc<std::sync::OnceLock<gspn::conform::SharedMonitor>>;

impl LiveViewer {
    /// A viewer to serve at `addr`, with the world's view when the run has one and the
    /// monitor's table when `monitor` is set by the time the run starts; it stays up after
    /// the run until one of `signals` has come.
    pub(crate) fn new(
        addr: SocketAddr,
        world: Option<tokio::sync::watch::Receiver<serde_json::Value>>,
        monitor: MonitorSlot,
        signals: StopSignals,
    ) -> Self {
        LiveViewer {
            addr,
            world,
            monitor,
            signals,
            served: None,
        }
    }
}

impl Backend for LiveViewer {
    fn name(&self) -> &'static str {
        "web"
    }

    fn observes_events(&self) -> bool {
        true
    }

    fn started<'a>(&'a mut self, start: Start<'a>) -> Started<'a> {
        Box::pin(async move {
            let Some(events) = start.events else {
                return Ok(());
            };
            let mut live = LiveRun::start(Arc::clone(start.run), events);
            if let Some(world) = self.world.take() {
                live = live.with_world(world);
            }
            if let Some(m) = self.monitor.get() {
                live = live.with_monitor(m.clone());
            }
            let addr = self.addr;
            let listener = tokio::net::TcpListener::bind(addr)
                .await
                .map_err(|e| BackendError::new("web", format!("cannot listen on {addr}: {e}")))?;
            let addr = listener
                .local_addr()
                .map_err(|e| BackendError::new("web", e))?;
            eprintln!("watch the run at http://{addr}/");
            let task = tokio::spawn(serve(listener, WebState::for_live(live)));
            self.served = Some((addr, task));
            Ok(())
        })
    }

    /// Keeps the viewer up until a signal, unless one already stopped the run.
    fn finish<'a>(&'a mut self, summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        Box::pin(async move {
            if let Some((addr, _)) = &self.served
                && self.signals.caught().is_none()
            {
                eprintln!(
                    "run over ({}); the viewer stays at http://{addr}/ until Ctrl-C or SIGTERM",
                    summary.stopped
                );
                self.signals.recv().await;
            }
            None
        })
    }

    fn stop(&mut self) {
        if let Some((_, task)) = self.served.take() {
            task.abort();
        }
    }
}
