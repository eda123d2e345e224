//! What every command shares: net options, loading, exit codes.

use std::path::Path;

use gspn::io::{LoadError, Loaded, ReadOptions, read_net};

/// Options of every command that reads a net.
#[derive(clap::Args, Debug, Clone, Default)]
pub(crate) struct NetArgs {
    /// The page to read (PNPRO files may hold several `<gspn>` pages).
    #[arg(long, value_name = "NAME")]
    pub(crate) page: Option<String>,
    /// Set a template parameter (PNPRO), overriding the file's last binding. Repeatable.
    #[arg(long = "param", value_name = "NAME=VALUE", value_parser = parse_param)]
    pub(crate) params: Vec<(String, String)>,
}

impl NetArgs {
    pub(crate) fn read_options(&self) -> ReadOptions {
        ReadOptions {
            page: self.page.clone(),
            params: self.params.clone(),
        }
    }
}

fn parse_param(s: &str) -> Result<(String, String), String> {
    match s.split_once('=') {
        Some((k, v)) if !k.trim().is_empty() => Ok((k.trim().to_string(), v.trim().to_string())),
        _ => Err(format!("`{s}` is not NAME=VALUE")),
    }
}

/// Bad input the user gave on the command line (exit code 2).
#[derive(Debug, thiserror::Error)]
#[error("{0}")]
pub(crate) struct BadInput(pub(crate) String);

/// Reads a net file with the command's options.
pub(crate) fn load_net(path: &Path, args: &NetArgs) -> anyhow::Result<Loaded> {
    Ok(read_net(path, &args.read_options())?)
}

/// Exit code for an error: 2 for bad input, 128 + the signal for an interruption, 1 for
/// anything else.
pub(crate) fn exit_code_for(e: &anyhow::Error) -> u8 {
    for cause in e.chain() {
        if let Some(i) = cause.downcast_ref::<Interrupted>() {
            return i.code;
        }
        if cause.is::<LoadError>() || cause.is::<BadInput>() {
            return 2;
        }
    }
    1
}

/// A run ended by a signal before it had a summary (e.g. while waiting for ROS 2 robots):
/// exit code 128 + the signal's number.
#[derive(Debug, thiserror::Error)]
#[error("{what}: interrupted by {signal}")]
pub(crate) struct Interrupted {
    /// What was under way.
    pub(crate) what: &'static str,
    /// The signal's name.
    pub(crate) signal: &'static str,
    /// The exit code.
    pub(crate) code: u8,
}

/// The signals that end a run the way Ctrl-C does: actions cancelled, journal flushed, a
/// final `stopped` event. Each gives its own exit code, 128 + its number: SIGINT 130,
/// SIGTERM 143, SIGHUP 129. Registered once, before the run starts, so a signal during
/// start-up is not lost.
pub(crate) struct StopSignals {
    #[cfg(unix)]
    term: tokio::signal::unix::Signal,
    #[cfg(unix)]
    hup: tokio::signal::unix::Signal,
    #[cfg(unix)]
    int: tokio::signal::unix::Signal,
}

impl StopSignals {
    /// Listens for the signals (inside a tokio runtime).
    pub(crate) fn new() -> anyhow::Result<StopSignals> {
        #[cfg(unix)]
        {
            use tokio::signal::unix::{SignalKind, signal};
            Ok(StopSignals {
                term: signal(SignalKind::terminate())?,
                hup: signal(SignalKind::hangup())?,
                int: signal(SignalKind::interrupt())?,
            })
        }
        #[cfg(not(unix))]
        Ok(StopSignals {})
    }

    /// The next signal: its name and exit code.
    pub(crate) async fn recv(&mut self) -> (&'static str, u8) {
        #[cfg(unix)]
        {
            tokio::select! {
                _ = self.int.recv() => ("SIGINT", 130),
                _ = self.term.recv() => ("SIGTERM", 143),
                _ = self.hup.recv() => ("SIGHUP", 129),
            }
        }
        #[cfg(not(unix))]
        {
            let _ = tokio::signal::ctrl_c().await;
            ("Ctrl-C", 130)
        }
    }
}

/// Opens a plan or a net ([`gspn::plan::open`]) and refuses a plan naming an action that is
/// not known (`plan-runner` registers no action of its own): bad input at its line and column.
pub(crate) fn open_checked(path: &Path, args: &NetArgs) -> anyhow::Result<gspn::plan::Opened> {
    let opened = gspn::plan::open(path, &args.read_options())?;
    if let gspn::plan::Opened::Plan(plan) = &opened {
        plan.check_actions(&[])?;
    }
    Ok(opened)
}
