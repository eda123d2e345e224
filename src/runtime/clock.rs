//! Model time for one run: the time scale, virtual time, and the one timer of the next
//! net-timed firing; and [`ModelClock`], the actions' view of it.
//!
//! Three ways for model time to pass ([`Mode`]):
//!
//! - **virtual** (`time_scale = 0`, the default): the supervisor owns the clock. It moves
//!   only by the net's delays and by the durations actions state ([`ModelClock::sleep`]),
//!   and only when every running action is asleep on it — the wall-clock time a program takes
//!   never enters it. Same seed, same run.
//! - **tokio** (`time_scale = 0` in a simulated world, which steps physics on tokio's paused
//!   clock): model time is tokio's time; the world and its built-in actions run on one thread
//!   on that paused clock.
//! - **real** (`time_scale > 0`): model time is `offset + tokio elapsed / scale`; actions
//!   take the time they take.

use std::time::Duration;

use tokio::sync::{mpsc, oneshot};
use tokio::task::JoinHandle;
use tokio::time::Instant;

use super::id::AgentId;

/// How model time passes in a run; see the [module docs](self).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Mode {
    /// The supervisor's discrete-event clock.
    Virtual,
    /// Tokio's (paused) clock, one model second a tokio second.
    Tokio,
    /// Scaled real time: tokio seconds per model second.
    Real(f64),
}

impl Mode {
    /// The mode of `time_scale`; `follow_tokio` picks [`Mode::Tokio`] over
    /// [`Mode::Virtual`] for `time_scale = 0`.
    pub(crate) fn of(time_scale: f64, follow_tokio: bool) -> Mode {
        match (time_scale > 0.0, follow_tokio) {
            (true, _) => Mode::Real(time_scale),
            (false, true) => Mode::Tokio,
            (false, false) => Mode::Virtual,
        }
    }
}

/// An action's request to sleep on the virtual clock.
#[derive(Debug)]
pub(crate) struct SleepRequest {
    pub(crate) agent: AgentId,
    pub(crate) ticket: u64,
    pub(crate) seconds: f64,
    pub(crate) wake: oneshot::Sender<()>,
}

/// Model time as an action sees it: [`ModelClock::sleep`] takes model seconds in every mode.
///
/// In virtual time a sleep is the only way an action takes model time: the supervisor
/// advances the clock when every running action is asleep (or done) and wakes the sleepers
/// due at the new instant, in agent order. An action should sleep once at a time (two
/// sleeps awaited together count as one).
#[derive(Clone, Debug)]
pub struct ModelClock(ClockKind);

#[derive(Clone, Debug)]
enum ClockKind {
    /// Tokio seconds per model second.
    Tokio(f64),
    Virtual {
        tx: mpsc::UnboundedSender<SleepRequest>,
        agent: AgentId,
        ticket: u64,
    },
}

impl ModelClock {
    /// A clock of tokio time at `scale` tokio seconds per model second (for actions run
    /// outside a runtime, as in tests: `ModelClock::tokio(1.0)`).
    pub fn tokio(scale: f64) -> ModelClock {
        ModelClock(ClockKind::Tokio(scale))
    }

    pub(crate) fn virtual_for(
        tx: mpsc::UnboundedSender<SleepRequest>,
        agent: AgentId,
        ticket: u64,
    ) -> ModelClock {
        ModelClock(ClockKind::Virtual { tx, agent, ticket })
    }

    /// True on the supervisor's virtual clock (`time_scale = 0`, no simulated world).
    pub fn is_virtual(&self) -> bool {
        matches!(self.0, ClockKind::Virtual { .. })
    }

    /// Waits `seconds` of model time (0 or less: returns at once). In virtual time the
    /// supervisor wakes the action when the run's clock reaches the instant; if the run ends
    /// first, the sleep ends too (the action then sees its cancel token set).
    pub async fn sleep(&self, seconds: f64) {
        if seconds.is_nan() || seconds <= 0.0 {
            return;
        }
        match &self.0 {
            ClockKind::Tokio(scale) => {
                tokio::time::sleep(crate::limits::duration(seconds * scale)).await;
            }
            ClockKind::Virtual { tx, agent, ticket } => {
                let (wake, rx) = oneshot::channel();
                let req = SleepRequest {
                    agent: *agent,
                    ticket: *ticket,
                    seconds,
                    wake,
                };
                if tx.send(req).is_ok() {
                    let _ = rx.await;
                }
            }
        }
    }
}

/// The run's clock and its pending timer.
#[derive(Debug)]
pub(crate) struct Clock {
    mode: Mode,
    scale: f64,
    start: Instant,
    offset: f64,
    now: f64,
    /// The pending timer and the race version it was sampled for.
    timer: Option<(JoinHandle<()>, u64)>,
    /// Bumped at each arming: a timer that fires after being replaced is ignored.
    generation: u64,
}

impl Clock {
    /// A clock at model time 0.
    pub(crate) fn new(mode: Mode) -> Clock {
        Clock {
            mode,
            scale: match mode {
                Mode::Real(s) => s,
                Mode::Virtual | Mode::Tokio => 1.0,
            },
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

    /// True with `time_scale = 0`: time jumps from firing to firing when no action runs.
    pub(crate) fn is_virtual(&self) -> bool {
        !matches!(self.mode, Mode::Real(_))
    }

    /// True on the supervisor's discrete-event clock ([`Mode::Virtual`]).
    pub(crate) fn is_discrete(&self) -> bool {
        self.mode == Mode::Virtual
    }

    /// The mode.
    pub(crate) fn mode(&self) -> Mode {
        self.mode
    }

    /// Model time by the tokio clock.
    fn read(&self) -> f64 {
        self.offset + self.start.elapsed().as_secs_f64() / self.scale
    }

    /// Brings `now` up to the tokio clock (never backwards); the discrete clock does not
    /// read it.
    pub(crate) fn advance(&mut self) {
        if self.is_discrete() {
            return;
        }
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
