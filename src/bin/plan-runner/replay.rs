//! `plan-runner replay JOURNAL --net FILE [--web [ADDR]]`: play a run's journal back.
//!
//! The journal names its net by hash; `--net` gives the net (or plan) file it was run from.
//! Without `--web` the firings are printed (time, transition, marking) — no feature needed;
//! with it (feature `web`) the viewer shows the run on the net with a time slider.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::open;
use gspn::runtime::journal::{Frame, read_journal, split_torn};

use crate::common::{BadInput, NetArgs};

/// Arguments of `replay`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// The journal (`plan-runner run --journal FILE`).
    journal: PathBuf,
    /// The net or plan file the run was made from.
    #[arg(long, value_name = "FILE")]
    net: PathBuf,
    /// Show it in the browser: serve the viewer at ADDR [default: 127.0.0.1:8080].
    #[arg(long, value_name = "ADDR", num_args = 0..=1, default_missing_value = "127.0.0.1:8080")]
    web: Option<SocketAddr>,
    /// Let `--web` listen on a non-loopback address (the viewer has no login).
    #[arg(long)]
    allow_remote: bool,
    #[command(flatten)]
    net_args: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    if let Some(addr) = args.web {
        crate::serve::check_bind(addr, args.allow_remote)?;
    }
    let net = open(&args.net, &args.net_args.read_options())?
        .into_plan()
        .net;
    let text = std::fs::read_to_string(&args.journal)
        .with_context(|| format!("cannot read {}", args.journal.display()))?;
    let (text, torn) = split_torn(&text);
    let frames = read_journal(text, &net)
        .map_err(|e| BadInput(format!("{}: {e}", args.journal.display())))?;
    if let Some(torn) = &torn {
        eprintln!(
            "warning: {}: {torn}: skipped (the run was killed while writing it)",
            args.journal.display()
        );
    }
    match args.web {
        Some(addr) => viewer(addr, &args.journal, net, frames),
        None => {
            for f in &frames {
                println!(
                    "{:>14.6}  {:<24}  {}",
                    f.time,
                    f.transition.as_deref().unwrap_or("(initial)"),
                    net.format_marking(&f.tokens)
                );
            }
            Ok(ExitCode::SUCCESS)
        }
    }
}

/// Without the viewer compiled in, `--web` is refused (exit code 2).
#[cfg(not(feature = "web"))]
fn viewer(
    _: SocketAddr,
    _: &std::path::Path,
    _: gspn::net::Net,
    _: Vec<Frame>,
) -> anyhow::Result<ExitCode> {
    Err(BadInput("--web needs plan-runner built with the `web` feature".into()).into())
}

#[cfg(feature = "web")]
fn viewer(
    addr: SocketAddr,
    journal: &std::path::Path,
    net: gspn::net::Net,
    frames: Vec<Frame>,
) -> anyhow::Result<ExitCode> {
    use gspn::web::{WebState, serve};
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    rt.block_on(async {
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .with_context(|| format!("cannot listen on {addr}"))?;
        println!(
            "replay of {} ({} firings) at http://{}/",
            journal.display(),
            frames.len() - 1,
            listener.local_addr()?
        );
        tokio::select! {
            r = serve(listener, WebState::for_replay(net, frames)) => r.context("viewer server")?,
            _ = tokio::signal::ctrl_c() => return Ok(ExitCode::from(130)),
        }
        Ok(ExitCode::SUCCESS)
    })
}
