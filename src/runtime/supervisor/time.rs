//! How model time passes for the supervisor: the next net-timed firing in real (or tokio)
//! time ([`Supervisor::schedule`]), the batch loop when no action runs, and the virtual-time
//! loop ([`Supervisor::drive`]) with what it delivers.

use super::*;

impl Supervisor {
    pub(super) fn kick(&mut self) {
        if !self.continue_pending {
            self.continue_pending = true;
            let _ = self.me().tell(Continue).try_send();
        }
    }

    /// After every change: nothing more can happen (stop), the fast path (virtual time, no
    /// action running), or a timer for the next net-timed firing or the time limit.
    pub(super) fn schedule(&mut self) {
        if self.stopping.is_some() || self.clock.is_discrete() {
            return;
        }
        if self.clock.is_virtual() && self.eng.running() == 0 {
            self.clock.cancel();
            self.kick();
            return;
        }
        let total = self.eng.race_total();
        if total <= 0.0 && self.eng.running() == 0 {
            self.dead();
            return;
        }
        if self.clock.armed_for(self.eng.race_version()) {
            return; // the race did not change: the pending sample stays valid (memoryless)
        }
        self.clock.cancel();
        let (mut at, mut limit) = (f64::INFINITY, false);
        if let Some(dt) = self.eng.sample_delay() {
            at = self.now() + dt;
        }
        if let Some(u) = self.stop.time_limit
            && u < at
        {
            (at, limit) = (u, true);
        }
        if at.is_finite() {
            let me = self.me().clone();
            self.clock
                .arm(at, self.eng.race_version(), move |generation| {
                    let _ = me
                        .tell(Timer {
                            generation,
                            at,
                            limit,
                        })
                        .try_send();
                });
        }
    }

    pub(super) fn dead(&mut self) {
        let stuck = self.eng.stuck();
        if stuck.is_empty() {
            self.begin_stop(StopReason::Dead);
            return;
        }
        let names: Vec<String> = stuck
            .iter()
            .map(|&t| self.eng.net().transition(t).name.clone())
            .collect();
        for n in &names {
            let msg = format!("transition `{n}` was chosen by an action but never became enabled");
            self.errors.push(msg.clone());
            self.emit(EventKind::Error { message: msg });
        }
        self.begin_stop(StopReason::Stuck);
    }

    pub(super) fn fast_path(&mut self) {
        let more = self.fire_burst();
        // Model time moved without reading the tokio clock: anchor it once, before an action
        // started in the burst can report (its end time is counted from here).
        self.clock.anchor();
        if more {
            self.schedule();
        }
    }

    /// Up to `BATCH` virtual-time firings while no action runs; false when the run stopped or
    /// died in the burst.
    pub(super) fn fire_burst(&mut self) -> bool {
        for _ in 0..BATCH {
            if self.stopping.is_some() || self.eng.running() > 0 {
                break;
            }
            let Some((dt, t)) = self.eng.sample_race() else {
                self.dead();
                return false;
            };
            let at = self.now() + dt;
            if let Some(u) = self.stop.time_limit
                && at > u
            {
                self.clock.set(u);
                self.begin_stop(StopReason::TimeLimit);
                return false;
            }
            self.clock.set(at);
            self.fire_one(t);
            self.fire_ready();
        }
        true
    }

    /// The virtual-time loop: when no action is busy, delivers what arrived (in agent
    /// order); while no *deciding* action is busy (see [`VirtualTime`]), fires what is
    /// ready; when nothing is ready and no action is busy, moves the clock to the next due
    /// instant — the race's next firing, a sleeper's wake-up or a timeout — and wakes what is
    /// due there.
    /// Returns when an action is busy (its report or sleep calls this again), when nothing can
    /// happen any more, or after [`BATCH`] firings (a `Continue` message goes on, so the
    /// mailbox gets a turn).
    ///
    /// With no action that takes model time, its draws are the token game's: one uniform for
    /// an immediate choice, then for a race the delay and the winner.
    pub(super) fn drive(&mut self) {
        if !self.clock.is_discrete() {
            return;
        }
        let mut fired = 0;
        loop {
            if self.stopping.is_some() {
                return;
            }
            if let Some(reason) = &self.stop_at_rest {
                if self.vt.busy() {
                    return;
                }
                let reason = reason.clone();
                self.deliver();
                self.stop_at_rest = None;
                self.begin_stop(reason);
                return;
            }
            if !self.vt.busy() && self.vt.has_mail() {
                self.deliver();
                continue;
            }
            if self.eng.running() == 0 {
                // No action runs (so none sleeps, nothing waits for delivery): the token
                // game's own loop, in batches — the same draws as the loop below.
                self.fire_ready();
                if self.stopping.is_some() || self.stop_at_rest.is_some() {
                    continue;
                }
                if self.eng.running() == 0 {
                    if !self.fire_burst() {
                        return;
                    }
                    if self.eng.running() == 0 && self.stopping.is_none() {
                        self.kick();
                        return;
                    }
                }
                continue;
            }
            if self.vt.deciding() {
                return; // its end at this instant could make a decision ready
            }
            if fired >= BATCH {
                self.kick();
                return;
            }
            if let Some(t) = self.eng.next_ready() {
                if let Some(m) = self.eng.take_first_miss() {
                    self.warn_outside_policy(&m, t);
                }
                self.fire_one(t);
                fired += 1;
                continue;
            }
            if self.vt.busy() {
                return; // the clock waits for every action that computes
            }
            // Nothing fires at this instant: the clock moves to the next due one.
            let due = self.vt.next_due();
            let race = self.eng.sample_delay().map(|dt| self.now() + dt);
            let at = match (race, due) {
                (Some(r), Some(d)) => r.min(d),
                (Some(r), None) => r,
                (None, Some(d)) => d,
                (None, None) => {
                    if self.eng.running() == 0 {
                        self.dead();
                    }
                    return;
                }
            };
            if let Some(u) = self.stop.time_limit
                && at > u
            {
                self.clock.set(u);
                self.begin_stop(StopReason::TimeLimit);
                return;
            }
            self.clock.set(at.max(self.now()));
            // A wake-up at the race's instant goes first (a tie has probability 0).
            if race.is_some_and(|r| due.is_none_or(|d| r < d)) {
                if let Some(t) = self.eng.pick_race() {
                    self.fire_one(t);
                    fired += 1;
                }
                continue;
            }
            self.vt.wake_due(at);
        }
    }

    /// Applies the output lines and reports that waited for the actions to stop being busy,
    /// each in agent order (virtual time).
    ///
    /// Once the run is stopping, every action still running ends as cancelled, whatever it
    /// answered: the run was over at that instant, and what a program says while it is being
    /// stopped depends on how fast it was.
    pub(super) fn deliver(&mut self) {
        let (lines, reports) = self.vt.take_mail();
        let stopped = self.stopping.is_some();
        for o in lines {
            self.action_output(o);
        }
        for mut r in reports {
            if stopped {
                r.outcome = Outcome::Cancelled;
            }
            self.action_done(r);
        }
    }
}
