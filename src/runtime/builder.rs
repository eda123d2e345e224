//! [`RuntimeBuilder`]: a net (or a plan), its actions and options → a running plan.

use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use tokio::sync::{broadcast, watch};

use super::action::Action;
use super::agent::AgentMode;
use super::builtin::Builtin;
use super::clock::Mode;
use super::engine::Engine;
use super::event::{Events, Watcher};
use super::handle::{Progress, RuntimeHandle};
use super::journal::{Journal, RunFacts};
use super::supervisor::{PlaceSetup, Supervisor, SupervisorArgs};
use super::{FailurePolicy, Role, RuntimeError, StopConditions, conservation};
use crate::analysis::decision::RewardSpec;
use crate::net::predicate::Predicate;
use crate::net::{Net, NetError, PlaceId};
use crate::policy::Policy;

/// Configures a run; [`RuntimeBuilder::spawn`] starts it inside the current tokio runtime.
pub struct RuntimeBuilder {
    net: Arc<Net>,
    roles: Vec<Option<Role>>,
    binds: Vec<(String, String)>,
    policy: Policy,
    rewards: Vec<RewardSpec>,
    actions: HashMap<String, Arc<dyn Action>>,
    seed: Option<u64>,
    time_scale: f64,
    stop: StopConditions,
    journal: Option<PathBuf>,
    source: Option<PathBuf>,
    agent_mode: AgentMode,
    event_capacity: usize,
    grace: Duration,
    subscribe: bool,
    robots: Vec<Arc<str>>,
    watcher: Option<Box<dyn Watcher>>,
    follow_tokio: bool,
}

impl std::fmt::Debug for RuntimeBuilder {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RuntimeBuilder")
            .field("net", &self.net.name())
            .field("actions", &self.actions.keys().collect::<Vec<_>>())
            .field("seed", &self.seed)
            .field("time_scale", &self.time_scale)
            .finish()
    }
}

impl RuntimeBuilder {
    pub(crate) fn new(net: Net) -> Self {
        let n = net.place_count();
        RuntimeBuilder {
            net: Arc::new(net),
            roles: vec![None; n],
            binds: Vec::new(),
            policy: Policy::empty(),
            rewards: Vec::new(),
            actions: HashMap::new(),
            seed: None,
            time_scale: 0.0,
            stop: StopConditions::default(),
            journal: None,
            source: None,
            agent_mode: AgentMode::default(),
            event_capacity: 1 << 14,
            grace: Duration::from_secs(5),
            subscribe: true,
            robots: Vec::new(),
            watcher: None,
            follow_tokio: false,
        }
    }

    /// The net this run will execute.
    pub fn net(&self) -> &Net {
        &self.net
    }

    /// The policy this run will follow.
    pub fn policy_value(&self) -> &Policy {
        &self.policy
    }

    /// The role of place `p`, when it has one.
    pub fn role_of(&self, p: PlaceId) -> Option<&Role> {
        self.roles.get(p.index()).and_then(Option::as_ref)
    }

    /// The robots bound to the initial agents, in agent order.
    pub fn robot_names(&self) -> &[Arc<str>] {
        &self.robots
    }

    /// The seed set so far (`None`: the clock picks one at spawn).
    pub fn seed_value(&self) -> Option<u64> {
        self.seed
    }

    /// The time scale set so far.
    pub fn time_scale_value(&self) -> f64 {
        self.time_scale
    }

    /// Replaces the net's initial marking (same places, same order); roles and the policy
    /// are kept.
    pub fn initial_marking(mut self, m: &[u32]) -> Result<Self, NetError> {
        self.net = Arc::new(self.net.with_initial_marking(m)?);
        Ok(self)
    }

    /// Replaces every stop condition (a plan file's `[stop]`).
    pub fn stop_conditions(mut self, stop: StopConditions) -> Self {
        self.stop = stop;
        self
    }

    /// The policy over immediate transitions (checked against the net by [`Policy::new`]).
    pub fn policy(mut self, policy: Policy) -> Self {
        self.policy = policy;
        self
    }

    /// Reward structures to count (a plan's `[rewards.NAME]`): the summary gives what each
    /// earned ([`Summary::rewards`](super::Summary::rewards)).
    pub fn rewards(mut self, rewards: Vec<RewardSpec>) -> Self {
        self.rewards = rewards;
        self
    }

    /// Registers an action under a name; places whose role names it run it.
    pub fn action(mut self, name: impl Into<String>, action: impl Action) -> Self {
        self.actions.insert(name.into(), Arc::new(action));
        self
    }

    /// Makes `place` an action place running the action registered as `action` (no
    /// timeout, failure stops the run). Unknown place names fail at [`RuntimeBuilder::spawn`].
    pub fn bind(mut self, place: impl Into<String>, action: impl Into<String>) -> Self {
        self.binds.push((place.into(), action.into()));
        self
    }

    /// Binds the initial agents to robots, in agent order (places that are not resources, in
    /// net order, then their tokens): agent 0 gets the first name, and so on. An agent keeps
    /// its robot as it moves through the net
    /// ([`ActionContext::robot`](super::ActionContext::robot), the `robots` of
    /// [`Fired`](super::EventKind::Fired)). [`RuntimeBuilder::spawn`] refuses a count that
    /// differs from the initial agents, and a net that can create or destroy robot tokens
    /// outside resource places.
    pub fn robots<S: AsRef<str>>(mut self, names: impl IntoIterator<Item = S>) -> Self {
        self.robots = names.into_iter().map(|s| Arc::from(s.as_ref())).collect();
        self
    }

    /// Sets the role of a place (what a plan file's `[places."…"]` says).
    pub fn role(mut self, place: PlaceId, role: Role) -> Self {
        if let Some(r) = self.roles.get_mut(place.index()) {
            *r = Some(role);
        }
        self
    }

    /// The seed of every random choice (default: from the clock; the handle tells which).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = Some(seed);
        self
    }

    /// 0 = virtual time, as fast as possible (the default); 1 = real time; 0.5 = twice as fast.
    ///
    /// In virtual time the model clock moves only by the net's delays and by the model
    /// seconds actions sleep ([`ModelClock::sleep`](super::ModelClock::sleep)); the time a
    /// program takes never enters it, so the same seed gives the same run. See
    /// `docs/execution.md`.
    pub fn time_scale(mut self, scale: f64) -> Self {
        self.time_scale = scale;
        self
    }

    /// With `time_scale = 0`, model time is tokio's (paused) clock instead of the
    /// supervisor's own: for a simulated world that steps physics on tokio time (the world's
    /// [`Fleet`](crate::world) sets it). Actions then take the tokio time they take.
    pub fn follow_tokio_clock(mut self, yes: bool) -> Self {
        self.follow_tokio = yes;
        self
    }

    /// Stops at this model time.
    pub fn until(mut self, t: f64) -> Self {
        self.stop.time_limit = Some(t);
        self
    }

    /// Stops after this many firings.
    pub fn max_firings(mut self, n: u64) -> Self {
        self.stop.max_firings = Some(n);
        self
    }

    /// Stops as soon as the marking satisfies `p`.
    pub fn stop_when(mut self, p: Predicate) -> Self {
        self.stop.when = Some(p);
        self
    }

    /// Follows every firing with `watcher` and emits the drifts it reports (see
    /// [`Watcher`]).
    pub fn watch(mut self, watcher: impl Watcher) -> Self {
        self.watcher = Some(Box::new(watcher));
        self
    }

    /// Writes every event to this file as JSON Lines.
    pub fn journal(mut self, path: impl Into<PathBuf>) -> Self {
        self.journal = Some(path.into());
        self
    }

    /// The file the net (or plan) was read from: the journal's header names it, so a
    /// journal that does not match a net file says which file it came from.
    pub fn source(mut self, path: impl Into<PathBuf>) -> Self {
        self.source = Some(path.into());
        self
    }

    /// One kameo actor per agent (the default) or light agents (records).
    pub fn agent_mode(mut self, mode: AgentMode) -> Self {
        self.agent_mode = mode;
        self
    }

    /// How many events the bus keeps for slow subscribers (default 16384).
    pub fn event_capacity(mut self, n: usize) -> Self {
        self.event_capacity = n.max(1);
        self
    }

    /// How long a stop waits for cancelled actions (tokio time; default 5 s).
    pub fn grace(mut self, d: Duration) -> Self {
        self.grace = d;
        self
    }

    /// Whether the handle holds a subscription from the start (default true). Without one,
    /// and without a journal, the supervisor builds no events until someone subscribes.
    pub fn subscribe_at_start(mut self, yes: bool) -> Self {
        self.subscribe = yes;
        self
    }

    /// Checks the configuration and starts the run in the current tokio runtime: the time
    /// scale ([`check_time`](Self::check_time)), the actions bound by name
    /// ([`bind_places`](Self::bind_places)), each place's action ([`place_setups`](Self::place_setups)),
    /// the journal ([`open_journal`](Self::open_journal)), then the supervisor.
    pub fn spawn(mut self) -> Result<RuntimeHandle, RuntimeError> {
        self.check_time()?;
        let net = Arc::clone(&self.net);
        self.bind_places(&net)?;
        let warnings = Vec::new();
        let setups = self.place_setups(&net)?;
        let seed = self.seed.unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as u64)
        });
        let journal = self.open_journal(&net, seed)?;
        let journal_tap = journal.as_ref().and_then(Journal::tap);
        let places: Vec<PlaceId> = setups.iter().map(|s| s.place).collect();
        let eng = Engine::new(
            Arc::clone(&net),
            &places,
            self.policy,
            self.rewards,
            ChaCha8Rng::seed_from_u64(seed),
        );
        let (bus, rx) = broadcast::channel(self.event_capacity);
        let first = if self.subscribe {
            Some(Events(rx))
        } else {
            drop(rx);
            None
        };
        let weak = bus.downgrade();
        let (done_tx, done_rx) = watch::channel(None);
        let progress = Arc::new(Progress::default());
        let sup = Supervisor::start(SupervisorArgs {
            eng,
            setups,
            mode: Mode::of(self.time_scale, self.follow_tokio),
            stop: self.stop,
            bus,
            journal,
            done: done_tx,
            progress: Arc::clone(&progress),
            grace: self.grace,
            agent_mode: self.agent_mode,
            robots: self.robots,
            seed,
            watcher: self.watcher,
        });
        Ok(RuntimeHandle {
            sup,
            done: done_rx,
            first,
            bus: weak,
            progress,
            net,
            warnings,
            seed,
            journal_tap,
        })
    }

    /// A tokio runtime to run in, and a time scale that every delay of the net fits.
    fn check_time(&self) -> Result<(), RuntimeError> {
        if tokio::runtime::Handle::try_current().is_err() {
            return Err(RuntimeError::NoTokio);
        }
        let scale = self.time_scale;
        if !(scale.is_finite() && (0.0..=crate::limits::MAX_SECONDS).contains(&scale)) {
            return Err(RuntimeError::BadTimeScale(scale));
        }
        if let Some((t, rate)) = crate::limits::too_slow_for_real_time(&self.net, scale) {
            return Err(RuntimeError::DelayTooLong {
                transition: self.net.transition(t).name.clone(),
                rate,
                scale,
                seconds: scale / rate,
            });
        }
        Ok(())
    }

    /// The actions bound to places by name become the places' roles; with robots, the
    /// robots' tokens must be conserved.
    fn bind_places(&mut self, net: &Net) -> Result<(), RuntimeError> {
        for (place, action) in std::mem::take(&mut self.binds) {
            let p = net
                .place_by_name(&place)
                .ok_or_else(|| RuntimeError::UnknownPlace(place.clone()))?;
            self.roles[p.index()] = Some(Role::Action {
                name: action,
                timeout: None,
                on_failure: FailurePolicy::Stop,
                robot: None,
            });
        }
        if !self.robots.is_empty()
            || self
                .roles
                .iter()
                .any(|r| matches!(r, Some(Role::Action { robot: Some(_), .. })))
        {
            conservation::check_robot_tokens(net, &self.roles)?;
        }
        Ok(())
    }

    /// What each place does with its agents: its action (registered, or a built-in), or —
    /// once a run has agents — a transparent wait for the places without one; one agent per
    /// robot.
    fn place_setups(&self, net: &Net) -> Result<Vec<PlaceSetup>, RuntimeError> {
        let mut setups = Vec::new();
        for p in net.place_ids() {
            if let Some(Role::Action {
                name,
                timeout,
                on_failure,
                robot,
            }) = &self.roles[p.index()]
            {
                let (action, instant) = self.action_of(net, p, name)?;
                setups.push(PlaceSetup {
                    place: p,
                    action,
                    timeout: *timeout,
                    on_failure: *on_failure,
                    robot: robot.as_deref().map(Arc::from),
                    instant,
                    passive: false,
                    decides: false,
                });
            }
        }
        // Identity: once a run has agents, every place that is not a resource keeps them — a
        // place without an action is a transparent one (its agents are ready at once).
        if !setups.is_empty() || !self.robots.is_empty() {
            let wait = Arc::new(Builtin::Wait(None).action()) as Arc<dyn Action>;
            for p in net.place_ids() {
                if self.roles[p.index()].is_none() {
                    setups.push(PlaceSetup {
                        place: p,
                        action: Arc::clone(&wait),
                        timeout: None,
                        on_failure: FailurePolicy::Stop,
                        robot: None,
                        instant: Some((super::Outcome::Decide, None)),
                        passive: true,
                        decides: false,
                    });
                }
            }
            // Agents are made in place order (the robots' order).
            setups.sort_by_key(|s| s.place);
        }
        for s in &mut setups {
            s.decides = net
                .consumers(s.place)
                .iter()
                .any(|&t| net.transition(t).is_immediate());
        }
        if !self.robots.is_empty() {
            let agents: u64 = setups
                .iter()
                .map(|s| u64::from(net.place(s.place).initial))
                .sum();
            if agents != self.robots.len() as u64 {
                return Err(RuntimeError::RobotCount {
                    robots: self.robots.len(),
                    agents,
                });
            }
        }
        Ok(setups)
    }

    /// The action named `name` for place `p`: the one registered under that name, else the
    /// built-in the name spells, with the outcome it has at once when it takes no time.
    #[allow(clippy::type_complexity)]
    fn action_of(
        &self,
        net: &Net,
        p: PlaceId,
        name: &str,
    ) -> Result<(Arc<dyn Action>, Option<(super::Outcome, Option<Arc<str>>)>), RuntimeError> {
        if let Some(a) = self.actions.get(name) {
            return Ok((Arc::clone(a), None));
        }
        match Builtin::parse(name, net, p) {
            Some(Ok(b)) => {
                let instant = b.instant();
                Ok((Arc::new(b.action()) as Arc<dyn Action>, instant))
            }
            Some(Err(reason)) => Err(RuntimeError::BadBuiltin {
                place: net.place(p).name.clone(),
                reason,
            }),
            None => {
                let mut known: Vec<String> = self.actions.keys().cloned().collect();
                known.sort();
                Err(RuntimeError::UnknownAction {
                    place: net.place(p).name.clone(),
                    action: name.to_string(),
                    known,
                })
            }
        }
    }

    /// The run's journal, its header written, when one was asked for.
    fn open_journal(&self, net: &Net, seed: u64) -> Result<Option<Journal>, RuntimeError> {
        let Some(path) = &self.journal else {
            return Ok(None);
        };
        Journal::create(
            path,
            net,
            RunFacts {
                seed,
                time_scale: self.time_scale,
                file: self.source.as_deref(),
                robots: &self.robots,
            },
        )
        .map(Some)
        .map_err(|e| RuntimeError::Journal {
            path: path.clone(),
            source: e,
        })
    }
}
