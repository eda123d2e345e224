//! The supervisor: one actor per running plan. It owns the marking, the policy and the agent
//! registry (through the [`Engine`]), serialises every firing, and never awaits a user action:
//! actions run in tasks hosted by the place actors and report back with an [`ActionDone`].
//!
//! The supervisor keeps only the decisions of when to fire and when to stop. Time is its
//! [`Clock`]'s ([`Mode`]):
//!
//! - **virtual** (`time_scale = 0`): a discrete-event loop ([`Supervisor::drive`]). The
//!   supervisor chooses only when no action is busy — every running action has reported or
//!   sleeps on the model clock — so everything that becomes ready at one model instant is
//!   there when it chooses (the priority rule holds among all of it), and what arrived is
//!   applied in agent order. Then it fires what is ready, or moves the clock to the next due
//!   instant: the net-timed race, a sleeper's wake-up, a timeout. Exactly reproducible from
//!   the seed, whatever the actions' programs take in wall-clock time.
//! - **tokio** and **real**: with no action running in tokio mode the supervisor plays the
//!   net-timed race in batches; otherwise it waits on the clock's tokio timer and fires what
//!   is ready as reports arrive.
//!
//! Built-in actions that take no model time and places without an action are applied inline
//! ([`PlaceSetup::instant`]): no task, no waiting. Events go to its [`EventSink`].

use std::sync::Arc;
use std::sync::atomic::Ordering;
use std::time::Duration;

use kameo::actor::{Actor, ActorRef, Spawn, WeakActorRef};
use kameo::error::Infallible;
use kameo::mailbox;
use kameo::mailbox::{MailboxReceiver, Signal};
use rustc_hash::FxHashMap;
use tokio::sync::{broadcast, mpsc, watch};

use super::StopReason;
use super::action::{ActionDone, CancelSource, CancelToken, Outcome, OutputLine};
use super::agent::{Agent, AgentMode, AgentState, Update};
use super::clock::{Clock, Mode, SleepRequest};
use super::engine::{Engine, Firing};
use super::event::{Event, EventKind, Watcher};
use super::handle::{Progress, Summary};
use super::id::AgentId;
use super::journal::Journal;
use super::place::Place;
use super::sink::EventSink;
use super::snapshot::Snapshots;
use super::{FailurePolicy, StopConditions};
use crate::net::{PlaceId, TransitionId};

mod actions;
mod actor;
mod messages;
mod time;
mod virtual_time;

use messages::{Continue, StopDeadline, Timer};
pub(crate) use messages::{GetAgents, GetMarking, StopRequest};
use virtual_time::VirtualTime;

/// Initial agents from which actor spawning is split over two threads.
const PARALLEL_SPAWN: usize = 20_000;

/// Firings played per message in the virtual-time fast path (then the mailbox gets a turn).
const BATCH: usize = 4096;

/// Per action place, what the supervisor needs besides the engine's queues.
pub(crate) struct PlaceSetup {
    pub(crate) place: PlaceId,
    pub(crate) action: Arc<dyn super::Action>,
    pub(crate) timeout: Option<f64>,
    pub(crate) on_failure: FailurePolicy,
    pub(crate) robot: Option<Arc<str>>,
    /// A built-in that takes no model time (or no action at all): its outcome and the line
    /// it writes, applied by the supervisor when the agent enters.
    pub(crate) instant: Option<(Outcome, Option<Arc<str>>)>,
    /// A place without an action (agents keep their identity there): no action events.
    pub(crate) passive: bool,
    /// The place has an immediate output transition (an action there may decide something
    /// at the instant it ends).
    pub(crate) decides: bool,
}

/// The supervisor actor.
pub(crate) struct Supervisor {
    eng: Engine,
    buf: Firing,
    setups: Vec<PlaceSetup>,
    /// Per setup, its place actor (none for inline setups).
    places: Vec<Option<ActorRef<Place>>>,
    clock: Clock,
    vt: VirtualTime,
    sleeps_tx: mpsc::UnboundedSender<SleepRequest>,
    sleeps_rx: Option<mpsc::UnboundedReceiver<SleepRequest>>,
    stop: StopConditions,
    stopping: Option<StopReason>,
    /// Virtual time: a firing limit or stop condition reached while actions were still
    /// computing at this instant; the run stops once they have ended or sleep.
    stop_at_rest: Option<StopReason>,
    finished: bool,
    continue_pending: bool,
    /// A stop was asked for because the journal could not be written.
    journal_stop_asked: bool,
    sink: EventSink,
    errors: Vec<String>,
    warnings: Vec<String>,
    done: watch::Sender<Option<Arc<Summary>>>,
    progress: Arc<Progress>,
    cancel: CancelSource,
    cancel_token: CancelToken,
    grace: Duration,
    me: Option<ActorRef<Supervisor>>,
    agent_mode: AgentMode,
    agent_actors: FxHashMap<AgentId, ActorRef<Agent>>,
    snapshots: Snapshots,
    reports_tx: mpsc::UnboundedSender<ActionDone>,
    reports_rx: Option<mpsc::UnboundedReceiver<ActionDone>>,
    output_tx: mpsc::UnboundedSender<OutputLine>,
    output_rx: Option<mpsc::UnboundedReceiver<OutputLine>>,
    robots: Vec<Arc<str>>,
    seed: u64,
    watcher: Option<Box<dyn Watcher>>,
}

impl std::fmt::Debug for Supervisor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Supervisor")
            .field("net", &self.eng.net().name())
            .field("firings", &self.eng.firings())
            .field("now", &self.clock.now())
            .finish()
    }
}

/// Everything the builder hands the supervisor.
pub(crate) struct SupervisorArgs {
    pub(crate) eng: Engine,
    pub(crate) setups: Vec<PlaceSetup>,
    pub(crate) mode: Mode,
    pub(crate) stop: StopConditions,
    pub(crate) bus: broadcast::Sender<Event>,
    pub(crate) journal: Option<Journal>,
    pub(crate) done: watch::Sender<Option<Arc<Summary>>>,
    pub(crate) progress: Arc<Progress>,
    pub(crate) grace: Duration,
    pub(crate) agent_mode: AgentMode,
    /// Robots for the initial agents, in agent order (empty: none).
    pub(crate) robots: Vec<Arc<str>>,
    /// The seed of the run (actions see it).
    pub(crate) seed: u64,
    /// Follows every firing (the live monitor).
    pub(crate) watcher: Option<Box<dyn Watcher>>,
}

impl Supervisor {
    /// Spawns the supervisor (unbounded mailbox: actions never block reporting).
    pub(crate) fn start(args: SupervisorArgs) -> ActorRef<Supervisor> {
        let (cancel, cancel_token) = CancelSource::new();
        let (reports_tx, reports_rx) = mpsc::unbounded_channel();
        let (output_tx, output_rx) = mpsc::unbounded_channel();
        let (sleeps_tx, sleeps_rx) = mpsc::unbounded_channel();
        let sup = Supervisor {
            eng: args.eng,
            buf: Firing::default(),
            setups: args.setups,
            places: Vec::new(),
            clock: Clock::new(args.mode),
            vt: VirtualTime::default(),
            sleeps_tx,
            sleeps_rx: Some(sleeps_rx),
            stop: args.stop,
            stopping: None,
            stop_at_rest: None,
            finished: false,
            continue_pending: false,
            journal_stop_asked: false,
            sink: EventSink::new(args.bus, args.journal),
            errors: Vec::new(),
            warnings: Vec::new(),
            done: args.done,
            progress: args.progress,
            cancel,
            cancel_token,
            grace: args.grace,
            me: None,
            agent_mode: args.agent_mode,
            agent_actors: FxHashMap::default(),
            snapshots: Snapshots::default(),
            reports_tx,
            reports_rx: Some(reports_rx),
            output_tx,
            output_rx: Some(output_rx),
            robots: args.robots,
            seed: args.seed,
            watcher: args.watcher,
        };
        Supervisor::spawn_with_mailbox(sup, mailbox::unbounded())
    }

    fn me(&self) -> &ActorRef<Supervisor> {
        self.me.as_ref().expect("set in on_start")
    }

    fn now(&self) -> f64 {
        self.clock.now()
    }

    fn observed(&self) -> bool {
        self.sink.observed()
    }

    fn emit(&mut self, kind: EventKind) {
        self.sink.emit(self.clock.now(), kind);
        // A journal that cannot be written (a full disk) stops the run: every later event
        // would be missing from it. Asked for by message, so the stop begins between two
        // turns, not inside the one that emitted.
        if !self.journal_stop_asked
            && self.stopping.is_none()
            && self.sink.journal_broken().is_some()
        {
            self.journal_stop_asked = self
                .me()
                .tell(StopRequest(StopReason::Journal))
                .try_send()
                .is_ok();
        }
    }

    fn ap(&self, p: PlaceId) -> usize {
        self.eng.action_index(p).expect("an action place")
    }

    fn set_state(&mut self, id: AgentId, state: AgentState) {
        let Some(place) = self.eng.set_state(id, state) else {
            return;
        };
        // An agent actor sets Occupied and Done itself (it runs the action).
        if !matches!(state, AgentState::Occupied | AgentState::Done)
            && let Some(a) = self.agent_actors.get(&id)
        {
            let _ = a.tell(Update { place, state }).try_send();
        }
    }

    fn fire_one(&mut self, t: TransitionId) {
        let mut buf = std::mem::take(&mut self.buf);
        if let Err(o) = self.eng.fire(t, self.now(), &mut buf) {
            self.buf = buf;
            let msg = self.eng.net().describe_overflow(&o);
            self.errors.push(msg.clone());
            self.emit(EventKind::Error { message: msg });
            self.begin_stop(StopReason::Failure);
            return;
        }
        self.progress
            .firings
            .store(self.eng.firings(), Ordering::Relaxed);
        self.progress
            .time
            .store(self.now().to_bits(), Ordering::Relaxed);
        let observed = self.observed();
        if observed {
            self.emit(EventKind::Fired {
                transition: t,
                consumed: buf.consumed.clone(),
                produced: buf.produced.clone(),
                marking: self.eng.marking().clone(),
                robots: buf.robots.clone(),
            });
        }
        if let Some(w) = &mut self.watcher {
            let now = self.clock.now();
            for d in w.fired(now, t, self.eng.marking().as_slice()) {
                self.sink.emit(now, EventKind::Drift(d));
            }
        }
        for &id in &buf.spawned {
            let place = self.eng.agent(id).expect("a live agent").place;
            self.spawn_agent_actor(id, place);
            if observed {
                self.emit(EventKind::AgentSpawned {
                    agent: id,
                    place,
                    robot: None,
                });
            }
        }
        for &id in &buf.ended {
            if let Some(a) = self.agent_actors.remove(&id) {
                a.kill();
            }
            if observed {
                self.emit(EventKind::AgentEnded { agent: id });
            }
        }
        // A firing that ends the run starts no action: the agents it moved stay where it
        // put them, and the run does not wait (in virtual time, until they finish or time
        // out) for programs whose outcome nothing would use.
        let ends = self.stop_reached();
        if ends.is_none() {
            for &id in &buf.produced {
                self.start_action(id, 0);
            }
        }
        self.buf = buf;
        if let Some(reason) = ends {
            self.begin_stop(reason);
        }
    }

    /// The firing limit or the stop condition, when the current marking reaches it.
    fn stop_reached(&self) -> Option<StopReason> {
        if let Some(max) = self.stop.max_firings
            && self.eng.firings() >= max
        {
            Some(StopReason::MaxFirings)
        } else if let Some(p) = &self.stop.when
            && p.eval(self.eng.marking())
        {
            Some(StopReason::Condition)
        } else {
            None
        }
    }

    /// Fires everything that is ready now (immediate transitions, reported events); in
    /// virtual time, [`Supervisor::drive`].
    fn settle(&mut self) {
        if self.clock.is_discrete() {
            self.drive();
            return;
        }
        self.fire_ready();
    }

    /// Fires what is ready now; in virtual time only while no action runs (then
    /// [`Supervisor::drive`] decides what may go on).
    #[inline]
    fn fire_ready(&mut self) {
        while self.stopping.is_none() && !(self.clock.is_discrete() && self.eng.running() > 0) {
            match self.eng.next_ready() {
                Some(t) => {
                    if let Some(m) = self.eng.take_first_miss() {
                        self.warn_outside_policy(&m, t);
                    }
                    self.fire_one(t)
                }
                None => break,
            }
        }
    }

    /// The first decision outside the policy's table: a warning event (and a summary
    /// warning, which the end of the run completes with the count).
    fn warn_outside_policy(&mut self, m: &[u32], t: TransitionId) {
        let net = self.eng.net();
        let message = format!(
            "no [[policy]] rule applies in marking {}: the net's weights decide (all 0 there: \
             uniformly among the enabled immediate transitions), `{}` fired; later decisions \
             outside the policy are counted, not reported",
            net.format_marking(m),
            net.transition(t).name
        );
        self.warnings.push(message.clone());
        self.emit(EventKind::Warning { message });
    }

    fn begin_stop(&mut self, reason: StopReason) {
        if self.stopping.is_some() {
            return;
        }
        // In virtual time a firing limit or a stop condition ends the run at the end of its
        // instant: the actions computing now end first (or sleep), so what they said — and
        // so the journal — does not depend on how fast they were.
        if self.clock.is_discrete()
            && matches!(reason, StopReason::MaxFirings | StopReason::Condition)
            && self.vt.busy()
        {
            self.stop_at_rest.get_or_insert(reason);
            return;
        }
        if !self.vt.busy() && self.vt.has_mail() {
            // What ended before the stop is part of the run.
            self.deliver();
            if self.stopping.is_some() {
                return;
            }
        }
        self.stopping = Some(reason);
        self.clock.cancel();
        self.cancel.cancel();
        self.vt.release();
        if self.eng.running() == 0 {
            self.finish();
        } else {
            let me = self.me().clone();
            let grace = self.grace;
            tokio::spawn(async move {
                tokio::time::sleep(grace).await;
                let _ = me.tell(StopDeadline).try_send();
            });
        }
    }

    fn finish(&mut self) {
        if self.finished {
            return;
        }
        self.finished = true;
        let reason = self.stopping.clone().unwrap_or(StopReason::Dead);
        self.emit(EventKind::Stopped {
            reason: reason.clone(),
        });
        if let Some(err) = self.sink.flush() {
            self.errors.push(format!("journal: {err}"));
        }
        let mut warnings = self.warnings.clone();
        let misses = self.eng.policy_misses();
        if misses > 0 {
            warnings.push(format!(
                "{misses} decision(s) in all were taken outside the policy, by the net's weights"
            ));
        }
        let summary = Summary::new(&self.eng, reason, self.now(), self.errors.clone(), warnings);
        let _ = self.done.send(Some(Arc::new(summary)));
        for (_, a) in self.agent_actors.drain() {
            a.kill();
        }
        for p in self.places.iter().flatten() {
            p.kill();
        }
    }
}
