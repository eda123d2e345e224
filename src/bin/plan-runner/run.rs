//! `plan-runner run PLAN|NET`: execute a plan (or a bare net, every place net-timed) on agents.
//!
//! Action places run built-in actions or programs (`command`, `worker`); a name that is
//! neither is refused at load. A live one-line progress display on a terminal, else a
//! progress line on stderr every few seconds (`--quiet`: none); a warning before a run in
//! virtual time that has no stop condition and cannot end on its own; a summary at the end
//! (`--json`: `stopped, firings, time, agents_spawned, agents_ended, final_marking,
//! mean_tokens, throughput, errors`, plus `rewards` for a plan with `[rewards.NAME]`: each
//! one's `total`, `rate`, the 95% `half_width` of the rate from batch means and `batches`, and
//! `warnings` when there are some: a decision outside the plan's `[[policy]]` table, taken by
//! the net's weights, is a `warning` event and a line on stderr). Ctrl-C (SIGINT), SIGTERM and
//! SIGHUP stop the run cleanly (actions cancelled, a final `stopped` event, journal flushed,
//! the viewer stopped) with exit code 130, 143 and 129; a second signal ends the process at
//! once (see `common::StopSignals`).
//!
//! The backends (simulated robots for a plan with a `[map]`, ROS 2 for `ros2` places, the
//! viewer with `--web`) come from `backends.rs`; each adds its section to the summary (the
//! simulated world: key `sim`, see `gspn::world::SimMetrics`).

use std::io::IsTerminal;
use std::path::PathBuf;
use std::process::ExitCode;
use std::sync::Arc;
use std::time::Duration;

use anyhow::Context as _;

use gspn::runtime::{Backends, RuntimeBuilder, Section, StopReason, Summary};

use crate::backends::{self, BackendArgs};
use crate::common::{BadInput, Interrupted, NetArgs, StopSignals};
use crate::export;

/// Arguments of `run`.
#[derive(clap::Args, Debug)]
pub(crate) struct Args {
    /// A plan (`.toml`) or a net file (every place net-timed).
    file: PathBuf,
    /// Seed of every random choice (default: the plan's, else from the clock).
    #[arg(long)]
    seed: Option<u64>,
    /// Seconds of real time per second of model time: 0 = virtual time, as fast as
    /// possible; 1 = real time; 10 = ten times slower than real time, 0.1 = ten times faster
    /// (default: the plan's, else 0).
    #[arg(long, value_name = "X")]
    time_scale: Option<f64>,
    /// Stop at this model time.
    #[arg(long, value_name = "T")]
    until: Option<f64>,
    /// Stop after this many firings.
    #[arg(long, value_name = "N")]
    max_firings: Option<u64>,
    /// Write every event to this file (JSON Lines). FILE.mcap: the journal goes to
    /// FILE.mcap.jsonl and is exported to FILE.mcap as ROS 2 messages when the run ends
    /// (feature `ros2`).
    #[arg(long, value_name = "FILE")]
    journal: Option<PathBuf>,
    /// Print the summary as JSON.
    #[arg(long)]
    json: bool,
    /// Check every exponential transition's rate and every place's mean tokens while running
    /// (gspn::conform::Monitor): each drift is a `drift` event (journal, viewer, ROS 2) and a
    /// line on stderr.
    #[arg(long)]
    monitor: bool,
    /// No progress lines on stderr (printed every few seconds when stderr is not a
    /// terminal).
    #[arg(long)]
    quiet: bool,
    #[command(flatten)]
    backends: BackendArgs,
    #[command(flatten)]
    net: NetArgs,
}

pub(crate) fn main(args: Args) -> anyhow::Result<ExitCode> {
    let mcap = args.journal.as_deref().filter(|j| export::is_mcap(j));
    #[cfg(not(feature = "ros2"))]
    if let Some(m) = mcap {
        return Err(BadInput(format!(
            "--journal {}: MCAP needs the feature `ros2` (cargo build --features ros2)",
            m.display()
        ))
        .into());
    }
    let mut plan = crate::common::open_checked(&args.file, &args.net)?.into_plan();
    if let Some(x) = args.time_scale {
        if !(x.is_finite() && (0.0..=gspn::limits::MAX_SECONDS).contains(&x)) {
            let shown = if x.abs() >= 1e15 {
                format!("{x:e}")
            } else {
                x.to_string()
            };
            return Err(BadInput(format!(
                "--time-scale {shown}: {}",
                gspn::plan::resolve::TIME_SCALE_EXPECTED
            ))
            .into());
        }
        plan.time_scale = Some(x);
        plan.check_time_scale(&format!("--time-scale {x}"), x)?;
    }
    if let Some(s) = args.seed {
        plan.seed = Some(s);
    }
    crate::progress::check_stop_flags(args.until, args.max_firings)?;
    if let Some(t) = args.until {
        plan.stop.time_limit = Some(t);
    }
    if let Some(n) = args.max_firings {
        plan.stop.max_firings = Some(n);
    }
    for w in plan
        .warnings
        .iter()
        .chain(&crate::progress::endless_warning(&plan))
    {
        eprintln!("warning: {w}");
    }
    backends::check(&plan, &args.backends)?;
    // Registered before the backends start: a signal while ROS 2 waits for its robots
    // ends the wait at once with the signal's exit code.
    let signals = StopSignals::new()?;
    let rt = backends::tokio_runtime(&plan).context("starting tokio")?;
    let ran = rt.block_on(async {
        let mut waiting = signals.clone();
        let setup = backends::setup(plan, &args.backends, &signals);
        let (run, mut backends) = tokio::select! {
            r = setup => r?,
            caught = waiting.recv() => {
                return Err(Interrupted {
                    what: "waiting for the robots",
                    signal: caught.signal,
                    code: caught.code,
                }
                .into());
            }
        };
        execute(run, &args, &mut backends, signals).await
    });
    // Tasks still running (an action's program being stopped, a viewer's analysis on a
    // blocking thread) must not hold the exit up: `main` kills what actions left behind.
    rt.shutdown_background();
    let (summary, sections, code) = ran?;
    if let Some(m) = mcap {
        let (firings, _, _, poses, robots) = export::write(&export::journal_beside(m), m)?;
        eprintln!(
            "{}: {firings} firings, {poses} poses of {robots} robot(s) (journal: {})",
            m.display(),
            export::journal_beside(m).display()
        );
    }
    if args.json {
        if sections.is_empty() {
            println!("{}", serde_json::to_string_pretty(&summary)?);
        } else {
            let mut v = serde_json::to_value(&summary)?;
            for (name, s) in sections {
                v[name] = s.json;
            }
            println!("{}", serde_json::to_string_pretty(&v)?);
        }
    } else {
        print_summary(&summary)?;
        for (_, s) in &sections {
            if !s.text.is_empty() {
                println!("{}", s.text);
            }
        }
    }
    Ok(ExitCode::from(code))
}

/// Runs `run` with its backends: journal, progress, stop signals, then every backend's
/// section. The exit code is the summary's, or 128 + the signal's number when SIGINT,
/// SIGTERM or SIGHUP stopped the run. A signal during the run also ends the viewer (it
/// stays up after a run that ended on its own, until a signal); a second signal ends the
/// process at once ([`StopSignals`]).
async fn execute(
    run: RuntimeBuilder,
    args: &Args,
    backends: &mut Backends,
    mut signals: StopSignals,
) -> anyhow::Result<(Summary, Vec<(&'static str, Section)>, u8)> {
    let mut b = backends.attach(run)?;
    if let Some(j) = &args.journal {
        b = if export::is_mcap(j) {
            b.journal(export::journal_beside(j))
        } else {
            b.journal(j)
        };
    }
    if args.monitor {
        let m = gspn::conform::SharedMonitor::new(crate::conform::monitor_for(
            b.net(),
            b.policy_value(),
            1_000_000,
        ));
        #[cfg(feature = "web")]
        let _ = args.backends.monitor.set(m.clone());
        b = b.watch(m);
    }
    let mut handle = b.spawn().map_err(|e| BadInput(e.to_string()))?;
    let monitor = args.monitor.then(|| {
        // Subscribed before the backends start, so it sees the run from its first event.
        let events = handle.events();
        tokio::spawn(crate::conform::print_drifts(
            Arc::clone(handle.net()),
            events,
        ))
    });
    let handle = match backends.start(handle).await {
        Ok(h) => h,
        Err(e) => {
            backends.stop();
            return Err(e.into());
        }
    };
    for w in handle.warnings() {
        eprintln!("warning: {w}");
    }
    let live = !args.json && std::io::stderr().is_terminal();
    let progress = handle.progress();
    let bar = live.then(|| {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(Duration::from_millis(100));
        bar
    });
    let wait = handle.wait();
    tokio::pin!(wait);
    let mut ticker = tokio::time::interval(Duration::from_millis(200));
    let mut lines = (!live && !args.quiet).then(crate::progress::Lines::new);
    let mut interrupted: Option<u8> = None;
    let summary = loop {
        tokio::select! {
            s = &mut wait => break s,
            caught = signals.recv(), if interrupted.is_none() => {
                interrupted = Some(caught.code);
                let note = format!(
                    "{}: stopping the run (a second signal ends plan-runner at once)",
                    caught.signal
                );
                match &bar {
                    Some(bar) => bar.println(note),
                    None => eprintln!("{note}"),
                }
                handle.interrupt();
            }
            _ = ticker.tick() => {
                if let Some(bar) = &bar {
                    bar.set_message(format!(
                        "firings {}  time {:.3}",
                        progress.firings(),
                        progress.time()
                    ));
                }
                if let Some(lines) = &mut lines {
                    lines.tick(&progress);
                }
            }
        }
    };
    if let Some(bar) = bar {
        bar.finish_and_clear();
    }
    // A journal that could not be written stopped the run: say so where an operator
    // looks, not only in the summary on stdout (`journal: No space left on device`).
    if summary.stopped == StopReason::Journal {
        for e in summary.errors.iter().filter(|e| e.starts_with("journal: ")) {
            eprintln!("{e}");
        }
    }
    if let Some(m) = monitor {
        let drifts = m.await.unwrap_or(0);
        eprintln!("monitor: {drifts} drift(s)");
    }
    // A decision outside the policy's table (also a `warning` event in the journal).
    for w in &summary.warnings {
        eprintln!("warning: {w}");
    }
    eprintln!("seed {}", handle.seed());
    let sections = backends.finish(&summary).await;
    backends.stop();
    let code = match interrupted {
        Some(code) if summary.stopped == StopReason::Interrupted => code,
        _ => summary.exit_code(),
    };
    Ok((summary, sections, code))
}

fn print_summary(s: &Summary) -> anyhow::Result<()> {
    println!(
        "stopped: {} after {} firings at time {:.4}",
        s.stopped, s.firings, s.time
    );
    println!(
        "agents: {} spawned, {} ended",
        s.agents_spawned, s.agents_ended
    );
    println!("place                          final    mean tokens");
    // In net order, as `analyze` lists them.
    for ((p, k), (_, m)) in s.final_marking.iter().zip(s.mean_tokens.iter()) {
        println!("  {p:<28} {k:>6}   {m:>12.6}");
    }
    println!("transition                     throughput");
    for (t, x) in s.throughput.iter() {
        println!("  {t:<28} {x:>12.6}");
    }
    for (name, r) in &s.rewards {
        let interval = match r.half_width {
            Some(h) => format!(" ± {h:.6} (95%, {} batches)", r.batches),
            None => String::new(),
        };
        println!(
            "reward {name}: {:.6} per unit of time{interval}, {:.6} in all",
            r.rate, r.total
        );
    }
    for e in &s.errors {
        println!("error: {e}");
    }
    Ok(())
}
