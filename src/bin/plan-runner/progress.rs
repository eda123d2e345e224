//! What `run` says about a run while it goes: a warning before a run in virtual time that
//! has no stop condition and cannot end on its own (the coverability and reachability
//! analysis of `gspn::check::endless`), the stop flags checked, and the progress shown —
//! a spinner on a terminal, else one line on stderr every [`EVERY`] (`--quiet`: none).

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use gspn::analysis::state_space::Monitor;
use gspn::check::endless;
use gspn::plan::Plan;
use gspn::runtime::Progress;
use indicatif::{ProgressBar, ProgressStyle};

use crate::common::BadInput;

/// Wall-clock time between two progress lines when stderr is not a terminal.
pub(crate) const EVERY: Duration = Duration::from_secs(3);

/// Refuses `--until` and `--max-firings` values no run can use.
pub(crate) fn check_stop_flags(
    until: Option<f64>,
    max_firings: Option<u64>,
) -> Result<(), BadInput> {
    if let Some(t) = until
        && !(t.is_finite() && t > 0.0)
    {
        return Err(BadInput(format!(
            "--until {t}: must be a finite model time > 0"
        )));
    }
    if max_firings == Some(0) {
        return Err(BadInput(
            "--max-firings 0: must be at least 1 (a run that may not fire at all would do nothing)"
                .into(),
        ));
    }
    Ok(())
}

/// The warning for a run of `plan` in virtual time with no stop condition that cannot end
/// on its own; `None` when it can (or the analysis cannot tell within its budget).
pub(crate) fn endless_warning(plan: &Plan) -> Option<String> {
    if !plan.stop.is_empty() || plan.time_scale.unwrap_or(0.0) > 0.0 {
        return None;
    }
    let why =
        endless::ending(&plan.net, gspn::check::ending_budget(&plan.net)).describe(&plan.net)?;
    Some(format!(
        "this run has no stop condition and {why}: it goes on until Ctrl-C (add --max-firings N or --until T, or [stop] in the plan)"
    ))
}

/// One progress line every [`EVERY`] of wall-clock time, for a stderr that is not a
/// terminal.
pub(crate) struct Lines {
    start: Instant,
    next: Instant,
}

impl Lines {
    pub(crate) fn new() -> Lines {
        let start = Instant::now();
        Lines {
            start,
            next: start + EVERY,
        }
    }

    /// Prints the line when it is due.
    pub(crate) fn tick(&mut self, progress: &Progress) {
        let now = Instant::now();
        if now >= self.next {
            self.next = now + EVERY;
            eprintln!(
                "progress: {} firings, model time {:.3}, {:.0} s",
                progress.firings(),
                progress.time(),
                (now - self.start).as_secs_f64()
            );
        }
    }
}

/// A spinner on stderr showing the markings an analysis has stored, drawn by polling its
/// [`Monitor`] (the library reports progress only there); cleared when dropped.
pub(crate) struct Spinner {
    done: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Spinner {
    /// Starts the spinner when `show` (a terminal, no `--json`); else draws nothing.
    pub(crate) fn start(show: bool, monitor: &Arc<Monitor>) -> Spinner {
        let done = Arc::new(AtomicBool::new(false));
        let thread = show.then(|| {
            let (done, monitor) = (Arc::clone(&done), Arc::clone(monitor));
            std::thread::spawn(move || {
                let bar = ProgressBar::new_spinner();
                if let Ok(style) =
                    ProgressStyle::with_template("{spinner} {pos} markings ({per_sec}) {elapsed}")
                {
                    bar.set_style(style);
                }
                while !done.load(Ordering::Relaxed) {
                    bar.set_position(monitor.markings() as u64);
                    std::thread::sleep(Duration::from_millis(100));
                }
                bar.finish_and_clear();
            })
        });
        Spinner { done, thread }
    }
}

impl Drop for Spinner {
    fn drop(&mut self) {
        self.done.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}
