//! `plan-runner replay JOURNAL --net FILE [--web [ADDR]]`: play a run's journal back.
//!
//! The journal names its net by hash; `--net` gives the net (or plan) file it was run from.
//! A run that started from another marking than the file's (`run --robots N` scales the
//! robots' tokens) is recognised by the initial marking its journal's header records (older
//! journals: the marking before the first firing). Without `--web` the firings are printed
//! (time, transition, marking) — no feature needed; with it (feature `web`) the viewer shows
//! the run on the net with a time slider in model seconds, and the simulated world's map
//! when the journal recorded one.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::open;
use gspn::runtime::journal::{JournalError, Recording, read_recording, split_torn};

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
    #[cfg(feature = "web")]
    if let Some(addr) = args.web {
        crate::serve::check_bind(addr, args.allow_remote)?;
    }
    let net = open(&args.net, &args.net_args.read_options())?
        .into_plan()
        .net;
    let text = std::fs::read_to_string(&args.journal)
        .with_context(|| format!("cannot read {}", args.journal.display()))?;
    let (text, torn) = split_torn(&text);
    let recording = match read_recording(text, &net) {
        // A journal written before headers recorded the initial marking.
        Err(JournalError::OtherNet { .. })
            if let Some(scaled) = crate::conform::scaled_net(text, &net) =>
        {
            read_recording(text, &scaled)
        }
        r => r,
    }
    .map_err(|e| match e {
        JournalError::OtherNet { .. } => BadInput(format!(
            "{}: {e}, read from --net {}",
            args.journal.display(),
            args.net.display()
        )),
        e => BadInput(format!("{}: {e}", args.journal.display())),
    })?;
    if let Some(torn) = &torn {
        eprintln!(
            "warning: {}: {torn}: skipped (the run was killed while writing it)",
            args.journal.display()
        );
    }
    match args.web {
        Some(addr) => viewer(addr, &args.journal, recording),
        None => {
            let net = &recording.net;
            for f in &recording.frames() {
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
fn viewer(_: SocketAddr, _: &std::path::Path, _: Recording) -> anyhow::Result<ExitCode> {
    Err(BadInput("--web needs plan-runner built with the `web` feature".into()).into())
}

#[cfg(feature = "web")]
fn viewer(
    addr: SocketAddr,
    journal: &std::path::Path,
    recording: Recording,
) -> anyhow::Result<ExitCode> {
    use gspn::web::{WebState, serve};
    let mut signals = crate::common::StopSignals::new()?;
    let rt = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()?;
    let served = rt.block_on(async {
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .with_context(|| format!("cannot listen on {addr}"))?;
        let state = WebState::for_recording(recording);
        println!(
            "replay of {} ({} firings) at http://{}/",
            journal.display(),
            state.replay_firings(),
            listener.local_addr()?
        );
        crate::serve::serve_until_signal(serve(listener, state), &mut signals).await
    });
    rt.shutdown_background();
    served
}
