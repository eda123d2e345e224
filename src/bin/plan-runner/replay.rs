//! `plan-runner replay JOURNAL [--net FILE] [--web [ADDR]]`: play a run's journal back.
//!
//! The journal names its net by hash and records the file the run read it from; `--net`
//! gives that net (or plan) file when the recorded one is not where it was (without `--net`
//! the recorded path is tried as written, then relative to the journal's directory; either
//! way the net must hash as the journal says).
//! A run that started from another marking than the file's (`run --robots N` scales the
//! robots' tokens) is recognised by the initial marking its journal's header records (older
//! journals: the marking before the first firing). Without `--web` the firings are printed
//! (time, transition, marking) — no feature needed; with it (feature `web`) the viewer shows
//! the run on the net with a time slider in model seconds, and the simulated world's map
//! when the journal recorded one.

use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::plan::open;
use gspn::runtime::journal::{JournalError, JournalHeader, Recording, read_recording, split_torn};

use crate::common::{BadInput, NetArgs};

/// Arguments of `replay`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// The journal (`plan-runner run --journal FILE`).
    journal: PathBuf,
    /// The net or plan file the run was made from [default: the file the journal records].
    #[arg(long, value_name = "FILE")]
    net: Option<PathBuf>,
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
    let text = std::fs::read_to_string(&args.journal)
        .with_context(|| format!("cannot read {}", args.journal.display()))?;
    let (text, torn) = split_torn(&text);
    let net_file = match &args.net {
        Some(f) => f.clone(),
        None => recorded_net(&args.journal, text)?,
    };
    let net = open(&net_file, &args.net_args.read_options())?
        .into_plan()
        .net;
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
            "{}: {e}, read from {}{}",
            args.journal.display(),
            if args.net.is_some() {
                "--net "
            } else {
                "the recorded "
            },
            net_file.display()
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

/// The net file the journal's header records (`"file"`): as written (relative to the
/// directory the run was started in), else relative to the journal's own directory.
fn recorded_net(journal: &Path, text: &str) -> anyhow::Result<PathBuf> {
    let first = text.lines().find(|l| !l.trim().is_empty()).unwrap_or("");
    let header: JournalHeader<'_> = serde_json::from_str(first).map_err(|e| {
        BadInput(format!(
            "{}:1: not a journal header: {e}",
            journal.display()
        ))
    })?;
    let Some(file) = header.file else {
        return Err(BadInput(format!(
            "{}: the journal does not record its net file (a run from a library caller \
             without `source`): give it with --net FILE",
            journal.display()
        ))
        .into());
    };
    let recorded = PathBuf::from(file.into_owned());
    let beside = journal.parent().map(|d| d.join(&recorded));
    [Some(recorded.clone()), beside]
        .into_iter()
        .flatten()
        .find(|p| p.is_file())
        .ok_or_else(|| {
            BadInput(format!(
                "{}: the journal's net file `{}` is not there (nor beside the journal): give \
                 it with --net FILE",
                journal.display(),
                recorded.display()
            ))
            .into()
        })
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
