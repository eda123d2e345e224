//! Process groups: every program an action starts leads its own group, so a stop reaches
//! the program's children too. Live groups are registered, so a process that exits early
//! ([`terminate_all`]) leaves no orphan behind.

use std::collections::HashSet;
use std::sync::Mutex;
use std::time::Duration;

/// Process groups started by actions and not yet known to be gone.
static LIVE: Mutex<Option<HashSet<i32>>> = Mutex::new(None);

/// A running program's process group (its id is the leader's pid). Dropping it without
/// [`ProcessGroup::release`] sends SIGTERM to the group and SIGKILL after the grace period.
#[derive(Debug)]
pub(crate) struct ProcessGroup {
    pgid: i32,
    grace: Duration,
    armed: bool,
}

impl ProcessGroup {
    /// Registers the group led by `pid`.
    pub(crate) fn new(pid: u32, grace: Duration) -> ProcessGroup {
        let pgid = pid as i32;
        if let Ok(mut live) = LIVE.lock() {
            live.get_or_insert_with(HashSet::new).insert(pgid);
        }
        ProcessGroup {
            pgid,
            grace,
            armed: true,
        }
    }

    /// Sends `sig` to every process of the group; false when none is left.
    pub(crate) fn signal(&self, sig: i32) -> bool {
        signal_group(self.pgid, sig)
    }

    /// SIGTERM now, SIGKILL if anything of the group is still alive after the grace period
    /// (tokio time). Waits for that.
    pub(crate) async fn terminate(mut self) {
        self.terminate_in_place().await;
    }

    async fn terminate_in_place(&mut self) {
        if self.signal(libc::SIGTERM) {
            let step = Duration::from_millis(10);
            let mut waited = Duration::ZERO;
            while waited < self.grace && self.signal(0) {
                tokio::time::sleep(step).await;
                waited += step;
            }
            self.signal(libc::SIGKILL);
        }
        self.release();
    }

    /// The leader was reaped: kills what is left of the group (a program's children must not
    /// outlive its action) and forgets the group.
    pub(crate) fn finish(mut self) {
        self.signal(libc::SIGKILL);
        self.release();
    }

    fn release(&mut self) {
        if self.armed {
            self.armed = false;
            if let Ok(mut live) = LIVE.lock()
                && let Some(set) = live.as_mut()
            {
                set.remove(&self.pgid);
            }
        }
    }
}

impl Drop for ProcessGroup {
    fn drop(&mut self) {
        if !self.armed {
            return;
        }
        // Dropped mid-run (a timeout, an aborted task): stop it the graceful way if a runtime
        // can finish the job, else at once.
        let pgid = self.pgid;
        let grace = self.grace;
        self.release();
        if !signal_group(pgid, libc::SIGTERM) {
            return;
        }
        match tokio::runtime::Handle::try_current() {
            Ok(rt) => {
                remember(pgid);
                rt.spawn(async move {
                    let mut g = ProcessGroup {
                        pgid,
                        grace,
                        armed: true,
                    };
                    g.terminate_in_place().await;
                });
            }
            Err(_) => {
                signal_group(pgid, libc::SIGKILL);
            }
        }
    }
}

fn remember(pgid: i32) {
    if let Ok(mut live) = LIVE.lock() {
        live.get_or_insert_with(HashSet::new).insert(pgid);
    }
}

fn signal_group(pgid: i32, sig: i32) -> bool {
    // SAFETY: killpg only sends a signal; a stale id fails with ESRCH.
    unsafe { libc::killpg(pgid, sig) == 0 }
}

/// Kills (SIGKILL) every process group an action started that may still be alive. For a
/// program about to exit: `plan-runner` calls it last, so no action program outlives it.
pub fn terminate_all() {
    let groups: Vec<i32> = match LIVE.lock() {
        Ok(mut live) => live
            .take()
            .map(|s| s.into_iter().collect())
            .unwrap_or_default(),
        Err(_) => Vec::new(),
    };
    for g in groups {
        signal_group(g, libc::SIGKILL);
    }
}
