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

/// A signal that ends a command: its name and exit code (128 + its number).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Caught {
    /// The signal's name (`SIGTERM`).
    pub(crate) signal: &'static str,
    /// The exit code it gives, 128 + its number: SIGINT 130, SIGTERM 143, SIGHUP 129.
    pub(crate) code: u8,
}

/// The signals that end a command the way Ctrl-C does — SIGINT, SIGTERM and SIGHUP — and
/// the escalation: the **first** is handed to the command, which stops cleanly (a run's
/// actions cancelled, its journal closed with a `stopped` line, its viewer stopped); a
/// **second** ends the process at once with its own exit code, after killing every program
/// an action started (nothing is flushed: the journal keeps what was written, as after a
/// SIGKILL). So a shutdown that hangs (an action ignoring its cancellation, a slow
/// backend) never needs a SIGKILL from outside.
///
/// A thread of its own listens, with its own small runtime: it works whatever the
/// command's runtime is doing (a paused clock, a busy worker). Registered once, before the
/// command starts its work, so a signal during start-up is not lost. Clones share the one
/// listener.
#[derive(Clone, Debug)]
pub(crate) struct StopSignals {
    first: tokio::sync::watch::Receiver<Option<Caught>>,
}

impl StopSignals {
    /// Listens for the signals from now on (a thread of its own; call once per command).
    pub(crate) fn new() -> anyhow::Result<StopSignals> {
        let rt = tokio::runtime::Builder::new_current_thread()
            .enable_io()
            .build()?;
        let (tx, first) = tokio::sync::watch::channel(None);
        #[cfg(unix)]
        let mut listen = {
            use tokio::signal::unix::{SignalKind, signal};
            let _guard = rt.enter();
            Listen {
                int: signal(SignalKind::interrupt())?,
                term: signal(SignalKind::terminate())?,
                hup: signal(SignalKind::hangup())?,
            }
        };
        #[cfg(not(unix))]
        let mut listen = Listen {};
        std::thread::Builder::new()
            .name("signals".into())
            .spawn(move || {
                rt.block_on(async {
                    let caught = listen.next().await;
                    let _ = tx.send(Some(caught));
                    let again = listen.next().await;
                    eprintln!(
                        "{}: a second signal, ending at once (exit {})",
                        again.signal, again.code
                    );
                    // No program an action started outlives plan-runner.
                    #[cfg(unix)]
                    gspn::actions::terminate_all();
                    std::process::exit(i32::from(again.code));
                });
            })?;
        Ok(StopSignals { first })
    }

    /// The first signal, once it has come (at once if it already has).
    pub(crate) async fn recv(&mut self) -> Caught {
        loop {
            if let Some(caught) = *self.first.borrow_and_update() {
                return caught;
            }
            if self.first.changed().await.is_err() {
                // The listener is gone without a signal (it cannot be): wait forever, as a
                // command without signals would.
                return std::future::pending().await;
            }
        }
    }

    /// The first signal, if it has come.
    #[cfg(feature = "web")]
    pub(crate) fn caught(&self) -> Option<Caught> {
        *self.first.borrow()
    }
}

/// The listener's signal streams.
struct Listen {
    #[cfg(unix)]
    int: tokio::signal::unix::Signal,
    #[cfg(unix)]
    term: tokio::signal::unix::Signal,
    #[cfg(unix)]
    hup: tokio::signal::unix::Signal,
}

impl Listen {
    async fn next(&mut self) -> Caught {
        #[cfg(unix)]
        {
            let (signal, code) = tokio::select! {
                _ = self.int.recv() => ("SIGINT", 130),
                _ = self.term.recv() => ("SIGTERM", 143),
                _ = self.hup.recv() => ("SIGHUP", 129),
            };
            Caught { signal, code }
        }
        #[cfg(not(unix))]
        {
            let _ = tokio::signal::ctrl_c().await;
            Caught {
                signal: "Ctrl-C",
                code: 130,
            }
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

/// The tokio runtime of the long-running commands (a run, a robot, a fleet, a router, the
/// viewer): two worker threads, for the machine's two cores and no more.
pub(crate) fn two_threads() -> std::io::Result<tokio::runtime::Runtime> {
    tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .build()
}

/// The names of the flags among `flags` (given?, name) that were given, in order.
pub(crate) fn given_flags<'a>(flags: &[(bool, &'a str)]) -> Vec<&'a str> {
    flags
        .iter()
        .filter_map(|&(on, name)| on.then_some(name))
        .collect()
}

/// `p1≤1, p2≤3, …`: each place's bound, for the state-space lines of `analyze`.
pub(crate) fn place_bounds(net: &gspn::net::Net, bounds: &[u32]) -> String {
    let each: Vec<String> = net
        .places()
        .iter()
        .zip(bounds)
        .map(|(pl, b)| format!("{}≤{b}", pl.name))
        .collect();
    each.join(", ")
}
