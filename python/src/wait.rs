//! Long calls on a thread of their own, the GIL released, Ctrl-C honoured.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc::{RecvTimeoutError, channel};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

use crate::errors::{Outcome, raise};

/// How often the caller looks for a pending signal (Ctrl-C) while the work runs.
const POLL: Duration = Duration::from_millis(50);

/// Runs `work` on a new thread while the calling thread waits without the GIL, waking every
/// [`POLL`] to run Python's signal handlers. When one raises (KeyboardInterrupt), `cancel`
/// is set — the work stops at its next check (the library's monitors poll it) — and the
/// exception propagates at once: control is back in Python within [`POLL`] plus the handler.
pub(crate) fn interruptible<T: Send + 'static>(
    py: Python<'_>,
    cancel: Arc<AtomicBool>,
    work: impl FnOnce() -> Outcome<T> + Send + 'static,
) -> PyResult<T> {
    interruptible_with_grace(py, cancel, Duration::ZERO, work)
}

/// [`interruptible`], giving cancelled work up to `grace` to finish before the exception
/// propagates: a run stops cleanly (actions cancelled, the journal's last event written).
pub(crate) fn interruptible_with_grace<T: Send + 'static>(
    py: Python<'_>,
    cancel: Arc<AtomicBool>,
    grace: Duration,
    work: impl FnOnce() -> Outcome<T> + Send + 'static,
) -> PyResult<T> {
    let (tx, rx) = channel();
    std::thread::Builder::new()
        .name("gspn-work".into())
        .spawn(move || {
            let _ = tx.send(work());
        })
        .map_err(|e| PyRuntimeError::new_err(format!("cannot start a thread: {e}")))?;
    let mut rx = rx;
    loop {
        // The receiver moves into the GIL-free closure and back (it is Send, not Sync).
        let (answer, back) = py.detach(move || (rx.recv_timeout(POLL), rx));
        rx = back;
        match answer {
            Ok(r) => return raise(py, r),
            Err(RecvTimeoutError::Timeout) => {
                if let Err(e) = py.check_signals() {
                    cancel.store(true, Ordering::Relaxed);
                    let _ = py.detach(move || rx.recv_timeout(grace));
                    return Err(e);
                }
            }
            Err(RecvTimeoutError::Disconnected) => {
                return Err(PyRuntimeError::new_err(
                    "gspn: the engine's thread ended without an answer (a bug: please report it)",
                ));
            }
        }
    }
}
