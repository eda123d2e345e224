//! `plan-runner replay JOURNAL --net FILE [--web [ADDR]]`: play a run's journal back.
//!
//! The journal names its net by hash; `--net` gives the net (or plan) file it was run from.
//! A run that started from another marking than the file's (`run --robots N` scales the
//! robots' tokens) is recognised by the initial marking its journal's header records (older
//! journals: the marking before the first firing). Without `--web` the firings are printed
//! (time, transition, marking) — no feature needed; with it (feature `web`) the viewer shows
//! the run on the net with a time slider in model seconds, and the simulated world's map
//! when the journal recorded one.

use std::fs::File;
use std::io::{BufReader, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::net::Net;
use gspn::plan::open;
use gspn::runtime::EventKind;
use gspn::runtime::journal::{Entry, JournalError, JournalReader, Recording};

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
    let journal = read_journal(&args.journal, &net, Some(&args.net))?;
    match args.web {
        Some(addr) => {
            let (recording, torn) = journal
                .into_recording()
                .map_err(|e| BadInput(format!("{}: {e}", args.journal.display())))?;
            warn_torn(&args.journal, torn.as_ref());
            viewer(addr, &args.journal, recording)
        }
        None => print_firings(&args.journal, journal),
    }
}

/// The journal at `path`, read a line at a time (issue 32: a 100 MB journal read whole
/// took 1.7 GB), its header checked against `net` (read from `--net net_file`, named when
/// the journal is of another net).
pub(crate) fn read_journal(
    path: &Path,
    net: &Net,
    net_file: Option<&Path>,
) -> anyhow::Result<JournalReader<BufReader<File>>> {
    let open = || -> anyhow::Result<BufReader<File>> {
        let file = File::open(path)
            .map_err(|e| BadInput(format!("cannot read {}: {e}", path.display())))?;
        Ok(BufReader::with_capacity(1 << 16, file))
    };
    let reader = match JournalReader::new(open()?, net) {
        // A journal written before headers recorded the initial marking.
        Err(JournalError::OtherNet { .. })
            if let Some(scaled) = crate::conform::scaled_net(open()?, net) =>
        {
            JournalReader::new(open()?, &scaled)
        }
        r => r,
    };
    reader.map_err(|e| {
        match (e, net_file) {
            (e @ JournalError::OtherNet { .. }, Some(file)) => BadInput(format!(
                "{}: {e}, read from --net {}",
                path.display(),
                file.display()
            )),
            (e, _) => BadInput(format!("{}: {e}", path.display())),
        }
        .into()
    })
}

/// Warns of a last line cut short (the run was killed while writing it).
pub(crate) fn warn_torn(path: &Path, torn: Option<&JournalError>) {
    if let Some(torn) = torn {
        eprintln!(
            "warning: {}: {torn}: skipped (the run was killed while writing it)",
            path.display()
        );
    }
}

/// Prints the initial marking and the marking after each firing (time, transition,
/// marking) as the journal is read.
fn print_firings(
    path: &Path,
    mut journal: JournalReader<BufReader<File>>,
) -> anyhow::Result<ExitCode> {
    let net = journal.net().clone();
    let mut out = std::io::BufWriter::new(std::io::stdout().lock());
    let row = |out: &mut dyn Write, time: f64, name: &str, tokens: &[u32]| {
        writeln!(
            out,
            "{time:>14.6}  {name:<24}  {}",
            net.format_marking(tokens)
        )
    };
    row(&mut out, 0.0, "(initial)", net.initial_marking().as_slice())?;
    for entry in journal.by_ref() {
        let entry = entry.map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
        if let Entry::Event(e) = entry
            && let EventKind::Fired {
                transition,
                marking,
                ..
            } = &e.kind
        {
            row(&mut out, e.time, &net.transition(*transition).name, marking)?;
        }
    }
    out.flush()?;
    warn_torn(path, journal.torn());
    Ok(ExitCode::SUCCESS)
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
