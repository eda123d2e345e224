//! Model time for one run: the time scale, virtual time, and the one timer of the next
//! net-timed firing.
//!
//! Model time is `offset + tokio elapsed / scale`. With `time_scale = 0` (virtual time) the
//! supervisor jumps the clock from firing to firing; otherwise it waits on tokio timers
//! (paused clock in tests), which this clock arms and cancels.

use std::time::Duration;

use tokio::task::JoinHandle;
use tokio::time::Instant;

/// The run's clock and its pending timer.
#[derive(Debug)]
pub(crate) struct Clock {
    scale: f64,
    virtual_time: bool,
    start: Instant,
    offset: f64,
    now: f64,
    /// The pending timer and the race version it was sampled for.
    timer: Option<(JoinHandle<()>, u64)>,
    /// Bumped at each arming: a timer that fires after being replaced is ignored.
    generation: u64,
}

impl Clock {
    /// A clock at model time 0; `time_scale` ≤ 0 is virtual time.
    pub(crate) fn new(time_scale: f64) -> Clock {
        let virtual_time = time_scale <= 0.0;
        Clock {
            scale: if virtual_time { 1.0 } else { time_scale },
            virtual_time,
            start: Instant::now(),
            offset: 0.0,
            now: 0.0,
            timer: None,
            generation: 0,
        }
    }

    /// Starts counting from now (model time stays where it is).
    pub(crate) fn restart(&mut self) {
        self.start = Instant::now();
    }

    /// Model time of the last event.
    pub(crate) fn now(&self) -> f64 {
        self.now
    }

    /// True with `time_scale = 0`: time jumps from firing to firing.
    pub(crate) fn is_virtual(&self) -> bool {
        self.virtual_time
    }

    /// Model time by the tokio clock.
    fn read(&self) -> f64 {
        self.offset + self.start.elapsed().as_secs_f64() / self.scale
    }

    /// Brings `now` up to the tokio clock (never backwards).
    pub(crate) fn advance(&mut self) {
        let c = self.read();
        if c > self.now {
            self.now = c;
        }
    }

    /// Sets model time to `t` and counts on from there.
    pub(crate) fn jump_to(&mut self, t: f64) {
        self.set(t);
        self.anchor();
    }

    /// Sets model time to `t` without reading the tokio clock: for a burst of virtual-time
    /// firings, which [`anchor`](Self::anchor) ends (one clock read per burst, not per
    /// firing — it was 15% of the supervisor's own firing time).
    pub(crate) fn set(&mut self, t: f64) {
        self.now = t;
    }

    /// Counts on from the current model time: the tokio clock's reading now is `now`.
    pub(crate) fn anchor(&mut self) {
        self.offset = self.now - self.start.elapsed().as_secs_f64() / self.scale;
    }

    /// A model-time span in tokio time.
    pub(crate) fn to_tokio(&self, seconds: f64) -> Duration {
        crate::limits::duration(seconds * self.scale)
    }

    /// True when a timer is pending for race version `version` (its sample stays valid: the
    /// race is memoryless).
    pub(crate) fn armed_for(&self, version: u64) -> bool {
        self.timer.as_ref().is_some_and(|(_, v)| *v == version)
    }

    /// Replaces the pending timer by one that calls `wake(generation)` at model time `at`,
    /// sampled for race version `version`.
    pub(crate) fn arm(&mut self, at: f64, version: u64, wake: impl FnOnce(u64) + Send + 'static) {
        self.cancel();
        self.generation += 1;
        let wait = ((at - self.read()) * self.scale).max(0.0);
        let generation = self.generation;
        let h = tokio::spawn(async move {
            tokio::time::sleep(crate::limits::duration(wait)).await;
            wake(generation);
        });
        self.timer = Some((h, version));
    }

    /// Cancels the pending timer.
    pub(crate) fn cancel(&mut self) {
        if let Some((h, _)) = self.timer.take() {
            h.abort();
        }
    }

    /// A timer of `generation` fired: true when it is the pending one (then it is spent).
    pub(crate) fn fired(&mut self, generation: u64) -> bool {
        if generation != self.generation {
            return false;
        }
        self.timer = None;
        true
    }
}
