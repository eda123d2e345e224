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

use std::fs::File;
use std::io::{BufReader, Write};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context as _;
use gspn::net::Net;
use gspn::plan::open;
use gspn::runtime::EventKind;
use gspn::runtime::journal::{Entry, JournalError, JournalHeader, JournalReader};

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
    let (net_file, named) = match &args.net {
        Some(f) => (f.clone(), format!("--net {}", f.display())),
        None => {
            let f = recorded_net(&args.journal)?;
            let named = format!("the recorded {}", f.display());
            (f, named)
        }
    };
    let net = open(&net_file, &args.net_args.read_options())?
        .into_plan()
        .net;
    let journal = read_journal(&args.journal, &net, Some(&named))?;
    match args.web {
        Some(addr) => viewer(addr, &args.journal, journal),
        None => print_firings(&args.journal, journal),
    }
}

/// The net file the journal's header records (`"file"`): as written (relative to the
/// directory the run was started in), else relative to the journal's own directory. Only
/// the header line is read.
fn recorded_net(journal: &Path) -> anyhow::Result<PathBuf> {
    let mut first = String::new();
    File::open(journal)
        .and_then(|f| std::io::BufRead::read_line(&mut BufReader::new(f), &mut first))
        .map_err(|e| BadInput(format!("cannot read {}: {e}", journal.display())))?;
    let header: JournalHeader<'_> = serde_json::from_str(&first).map_err(|e| {
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

/// The journal at `path`, read a line at a time (issue 32: a 100 MB journal read whole
/// took 1.7 GB), its header checked against `net` (read from `net_file`, named when the
/// journal is of another net: `--net FILE` or the recorded file).
pub(crate) fn read_journal(
    path: &Path,
    net: &Net,
    net_file: Option<&str>,
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
            (e @ JournalError::OtherNet { .. }, Some(file)) => {
                BadInput(format!("{}: {e}, read from {file}", path.display()))
            }
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
fn viewer(_: SocketAddr, _: &Path, _: JournalReader<BufReader<File>>) -> anyhow::Result<ExitCode> {
    Err(BadInput("--web needs plan-runner built with the `web` feature".into()).into())
}

/// Serves the journal at `path` (its header read by `journal`): the viewer reads it once
/// for the index of its windows, then a window at a time as the page asks.
#[cfg(feature = "web")]
fn viewer(
    addr: SocketAddr,
    path: &Path,
    journal: JournalReader<BufReader<File>>,
) -> anyhow::Result<ExitCode> {
    use gspn::web::{WebState, serve};
    let (state, torn) = WebState::for_journal(path, journal)
        .map_err(|e| BadInput(format!("{}: {e}", path.display())))?;
    warn_torn(path, torn.as_ref());
    let mut signals = crate::common::StopSignals::new()?;
    let rt = crate::common::two_threads()?;
    let served = rt.block_on(async {
        let listener = tokio::net::TcpListener::bind(addr)
            .await
            .with_context(|| format!("cannot listen on {addr}"))?;
        println!(
            "replay of {} ({} firings) at http://{}/",
            path.display(),
            state.replay_firings(),
            listener.local_addr()?
        );
        crate::serve::serve_until_signal(serve(listener, state), &mut signals).await
    });
    rt.shutdown_background();
    served
}
