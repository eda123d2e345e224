//! The robot's side: `plan-runner robot --id R --plan PLAN` serves the ExecPlace action at
//! `/<R>/<server>` for the plan's `ros2` places, publishes its heartbeat, and listens to the
//! firings (optionally logging when each arrived, for latency measurements).
//!
//! The local action is the net's own timing: for a place whose outputs are exponential the
//! robot waits a delay drawn with the sum of their rates (× the time scale, in seconds) and
//! answers the transition that won the race (each with probability rate / sum); for a place
//! with an immediate output it answers at once with an empty transition (the supervisor's
//! policy decides). Draws come from a seeded RNG (seed and robot id), so a robot repeats
//! its choices.

use std::collections::BTreeMap;
use std::future::Future;
use std::io::Write;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use futures::StreamExt;
use rand::SeedableRng;
use ros2_client::action::{
    AsyncActionServer, ExecutingGoalHandle, GoalEndStatus, GoalId, NewGoalHandle,
};
use tokio::sync::oneshot;

use super::config::DdsConfig;
use super::firings::FiringListener;
use super::heartbeat::{Liveness, RobotWatch, SUPERVISOR};
use super::msgs::{
    ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult, RunState, Time, exec_place_type,
};
use super::settings::Ros2Settings;
use super::{Ros2Error, heartbeat};
use crate::net::Net;
use crate::sample::Rng;

mod decide;
pub use decide::{Decision, decide, id_hash};

type Server = AsyncActionServer<ExecPlaceGoal, ExecPlaceResult, ExecPlaceFeedback>;

/// How a robot process runs.
#[derive(Clone, Debug)]
pub struct RobotOptions {
    /// The robot's id (its namespace: `/<id>/<server>`).
    pub id: String,
    /// Seed of the robot's draws (mixed with its id).
    pub seed: u64,
    /// Seconds per unit of model time for the local delays (0 = answer at once).
    pub time_scale: f64,
    /// Appends `seq stamp_ns received_ns` for each firing received to this file.
    pub latency_log: Option<PathBuf>,
    /// Keep serving when the supervisor's run is over or its heartbeat stops (else
    /// [`serve`] returns then).
    pub stay: bool,
}

/// What a robot did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct RobotStats {
    /// Goals received.
    pub goals: u64,
    /// Goals cancelled: by the supervisor, or because the robot left while they ran.
    pub cancelled: u64,
    /// Firings received on `/gspn/firings`.
    pub firings: u64,
    /// Why the robot left by itself; `None` when it was stopped (Ctrl-C, SIGTERM).
    pub left: Option<Leave>,
}

/// Why a robot left by itself.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Leave {
    /// The supervisor said its run is over: why it stopped and after how many firings
    /// (`max_firings after 100 firings`).
    RunOver(String),
    /// The supervisor's heartbeats stopped for this long (it died, or the network is cut)
    /// without saying the run is over.
    SupervisorLost(Duration),
}

impl std::fmt::Display for Leave {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Leave::RunOver(why) => write!(f, "the supervisor's run is over ({why})"),
            Leave::SupervisorLost(after) => {
                write!(f, "the supervisor's heartbeat stopped (none for {after:?})")
            }
        }
    }
}

struct Shared {
    id: String,
    net: Arc<Net>,
    rng: Mutex<Rng>,
    time_scale: f64,
    stats: Mutex<RobotStats>,
    running: Mutex<Running>,
    /// The tasks of the goals received (finished ones pruned as new ones come).
    goal_tasks: Mutex<Vec<tokio::task::JoinHandle<()>>>,
    /// Notified at each goal: a supervisor exists, heard or not.
    goal_seen: tokio::sync::Notify,
}

/// Running goals and how to cancel them; once `closed` (the robot is leaving) a new goal is
/// cancelled as soon as it is accepted.
#[derive(Default)]
struct Running {
    goals: BTreeMap<GoalId, oneshot::Sender<()>>,
    closed: bool,
}

/// A robot that got goals from a supervisor whose heartbeat it never heard leaves after this
/// many times `lost_after` (it cannot tell a supervisor killed early from a slow discovery).
const UNHEARD_GRACE: u32 = 5;

/// How long a leaving robot waits for its cancelled goals to send their results.
const LEAVE_WAIT: Duration = Duration::from_secs(1);

/// Serves the plan's `ros2` places as robot `opts.id` until `stop` completes, the
/// supervisor says its run is over or its heartbeat stops (both ignored with `opts.stay`).
/// Goals still running then are cancelled (and counted).
pub async fn serve(
    net: &Net,
    settings: &Ros2Settings,
    cfg: &DdsConfig,
    opts: RobotOptions,
    stop: impl Future<Output = ()>,
) -> Result<RobotStats, Ros2Error> {
    let node_name = format!("robot_{}", sanitize(&opts.id));
    let mut node = cfg.node(&node_name, Some(&opts.id))?;
    // From here on the ROS 2 layer's warnings reach /rosout too, when asked.
    let rosout = cfg
        .rosout
        .then(|| super::rosout::forward(&mut node))
        .transpose()?;
    let spinner = node.spinner().map_err(Ros2Error::dds)?;
    let spin = tokio::spawn(spinner.spin());
    // `heartbeat = 0`: none; the supervisor then sees the robot through discovery alone.
    let beat = (!cfg.heartbeat.is_zero())
        .then(|| heartbeat::publish(&mut node, &opts.id, cfg.heartbeat))
        .transpose()?;
    let supervisor = RobotWatch::supervisor(&mut node, cfg.lost_after)?;
    let shared = Arc::new(Shared {
        id: opts.id.clone(),
        net: Arc::new(net.clone()),
        rng: Mutex::new(Rng::seed_from_u64(opts.seed ^ id_hash(&opts.id))),
        time_scale: opts.time_scale,
        stats: Mutex::new(RobotStats::default()),
        running: Mutex::new(Running::default()),
        goal_tasks: Mutex::new(Vec::new()),
        goal_seen: tokio::sync::Notify::new(),
    });
    // Nav2 places' goals go to the robot's Nav2 (`navigate_to_pose`), not to this process.
    let servers = settings.exec_place_servers();
    let mut tasks = Vec::new();
    for s in servers {
        let name = super::names::action(&node, &opts.id, s)?;
        let server = node
            .create_action_server::<ExecPlaceGoal, ExecPlaceResult, ExecPlaceFeedback>(
                cfg.service_mapping,
                &name,
                &exec_place_type(),
                super::nav2::server_qos(),
            )
            .map_err(Ros2Error::dds)?;
        let server = Arc::new(AsyncActionServer::new(server));
        tasks.push(tokio::spawn(serve_goals(server, Arc::clone(&shared))));
    }
    let listener = FiringListener::new(&mut node)?;
    let listen = listen(&listener, opts.latency_log.clone(), Arc::clone(&shared));
    let over = run_over(&listener, &opts);
    let lost = supervisor_lost(&supervisor, &shared.goal_seen, &opts, cfg.lost_after);
    let mut left = None;
    tokio::select! {
        _ = stop => {}
        r = listen => r?,
        l = over => left = Some(l),
        l = lost => left = Some(l),
    }
    // No new goals; the running ones are cancelled and given a moment to say so.
    for t in tasks {
        t.abort();
    }
    cancel_running(&shared);
    let mut goals = shared
        .goal_tasks
        .lock()
        .map(|mut g| std::mem::take(&mut *g))
        .unwrap_or_default();
    let ended = async {
        for g in &mut goals {
            let _ = g.await;
        }
    };
    let _ = tokio::time::timeout(LEAVE_WAIT, ended).await;
    for g in goals {
        g.abort();
    }
    if let Some(r) = rosout {
        r.finish(LEAVE_WAIT).await;
    }
    if let Some(b) = beat {
        b.abort();
    }
    spin.abort();
    let mut stats = shared
        .stats
        .lock()
        .map_err(|_| Ros2Error::Other("poisoned".into()))?
        .clone();
    stats.left = left;
    Ok(stats)
}

/// Cancels every running goal and every goal still to be accepted (the robot is leaving).
fn cancel_running(shared: &Shared) {
    if let Ok(mut r) = shared.running.lock() {
        r.closed = true;
        for (_, tx) in std::mem::take(&mut r.goals) {
            let _ = tx.send(());
        }
    }
}

/// Completes when the supervisor's heartbeat stops for `after` — once heard, or once a goal
/// came while none had been heard yet (a supervisor killed before its heartbeat reached this
/// robot) — never with `opts.stay`, which says so and keeps serving.
async fn supervisor_lost(
    watch: &RobotWatch,
    goal_seen: &tokio::sync::Notify,
    opts: &RobotOptions,
    after: Duration,
) -> Leave {
    let Some(mut live) = watch.liveness(SUPERVISOR) else {
        return std::future::pending().await;
    };
    let lost = || {
        tracing::info!(
            "robot {}: {}; idle, serving until stopped (--stay)",
            opts.id,
            Leave::SupervisorLost(after)
        );
    };
    // Set while goals came from a supervisor whose heartbeat was never heard.
    let mut unheard: Option<tokio::time::Instant> = None;
    loop {
        let timer = async {
            match unheard {
                Some(t) => tokio::time::sleep_until(t).await,
                None => std::future::pending().await,
            }
        };
        tokio::select! {
            c = live.changed() => {
                if c.is_err() {
                    return std::future::pending().await;
                }
                let now = *live.borrow_and_update();
                match now {
                    Liveness::Lost if !opts.stay => return Leave::SupervisorLost(after),
                    Liveness::Lost => lost(),
                    Liveness::Alive => {
                        unheard = None;
                        tracing::info!("robot {}: a supervisor is here", opts.id);
                    }
                    Liveness::Unknown | Liveness::Gone => {}
                }
            }
            _ = goal_seen.notified() => {
                // Discovery of the heartbeat topic may lag the goals' on a loaded host:
                // a supervisor never heard gets UNHEARD_GRACE × lost_after.
                if *live.borrow() == Liveness::Unknown && unheard.is_none() {
                    unheard = Some(tokio::time::Instant::now() + after * UNHEARD_GRACE);
                }
            }
            _ = timer => {
                unheard = None;
                if *live.borrow() == Liveness::Unknown {
                    if !opts.stay {
                        return Leave::SupervisorLost(after * UNHEARD_GRACE);
                    }
                    lost();
                }
            }
        }
    }
}

/// Completes when the supervisor says its run is over (never with `opts.stay`, which says
/// once that the robot stays, idle).
async fn run_over(listener: &FiringListener, opts: &RobotOptions) -> Leave {
    let states = listener.run_states();
    futures::pin_mut!(states);
    while let Some(s) = states.next().await {
        if s.state != RunState::OVER {
            continue;
        }
        let over = Leave::RunOver(format!("{} after {} firings", s.stopped, s.firings));
        if !opts.stay {
            return over;
        }
        tracing::info!(
            "robot {}: {over}; idle, serving until stopped (--stay)",
            opts.id
        );
    }
    std::future::pending().await
}

/// A robot id as part of a node name (letters, digits, underscores).
fn sanitize(id: &str) -> String {
    id.chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect()
}

async fn listen(
    listener: &FiringListener,
    log: Option<PathBuf>,
    shared: Arc<Shared>,
) -> Result<(), Ros2Error> {
    let mut out = match &log {
        Some(p) => Some(
            std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(p)
                .map_err(|e| Ros2Error::Other(format!("{}: {e}", p.display())))?,
        ),
        None => None,
    };
    let firings = listener.firings();
    futures::pin_mut!(firings);
    while let Some(f) = firings.next().await {
        let now = Time::now();
        if let Ok(mut s) = shared.stats.lock() {
            s.firings += 1;
        }
        if let Some(out) = &mut out {
            // One line per firing, written at once: a killed robot loses nothing logged.
            let _ = writeln!(
                out,
                "{} {} {}",
                f.seq,
                f.header.stamp.as_nanos(),
                now.as_nanos()
            );
        }
    }
    Ok(())
}

/// Receives goals and cancel requests of one server; each goal runs in its own task.
async fn serve_goals(server: Arc<Server>, shared: Arc<Shared>) {
    loop {
        tokio::select! {
            g = server.receive_new_goal() => match g {
                Ok(handle) => {
                    let task =
                        tokio::spawn(run_goal(Arc::clone(&server), handle, Arc::clone(&shared)));
                    if let Ok(mut tasks) = shared.goal_tasks.lock() {
                        tasks.retain(|t| !t.is_finished());
                        tasks.push(task);
                    }
                }
                Err(e) => tracing::warn!("receiving a goal: {e:?}"),
            },
            c = server.receive_cancel_request() => match c {
                Ok(cancel) => {
                    let ours: Vec<GoalId> = {
                        let mut running = match shared.running.lock() {
                            Ok(r) => r,
                            Err(_) => continue,
                        };
                        let ids: Vec<GoalId> =
                            cancel.goals().filter(|g| running.goals.contains_key(g)).collect();
                        for g in &ids {
                            if let Some(tx) = running.goals.remove(g) {
                                let _ = tx.send(());
                            }
                        }
                        ids
                    };
                    let _ = server.respond_to_cancel_requests(&cancel, ours.into_iter()).await;
                }
                Err(e) => tracing::warn!("receiving a cancel request: {e:?}"),
            },
        }
    }
}

async fn run_goal(server: Arc<Server>, handle: NewGoalHandle<ExecPlaceGoal>, shared: Arc<Shared>) {
    let Some(goal) = server.get_new_goal(handle.clone()) else {
        return;
    };
    if let Ok(mut s) = shared.stats.lock() {
        s.goals += 1;
    }
    shared.goal_seen.notify_one();
    let Some(place) = shared.net.place_by_name(&goal.place) else {
        tracing::warn!("goal for unknown place `{}`: rejected", goal.place);
        let _ = server.reject_goal(handle).await;
        return;
    };
    let decision = match shared.rng.lock() {
        Ok(mut rng) => decide(&shared.net, place, shared.time_scale, &mut rng),
        Err(_) => return,
    };
    let id = handle.goal_id();
    let (tx, rx) = oneshot::channel();
    if let Ok(mut r) = shared.running.lock() {
        if r.closed {
            let _ = tx.send(());
        } else {
            r.goals.insert(id, tx);
        }
    }
    let Ok(accepted) = server.accept_goal(handle).await else {
        return;
    };
    let Ok(executing) = server.start_executing_goal(accepted).await else {
        return;
    };
    tracing::debug!(
        "robot {}: goal `{}` (agent {}) started: {:?} after {:.3} s",
        shared.id,
        goal.place,
        goal.agent,
        decision.transition,
        decision.delay
    );
    let (status, result) = run_decision(&server, executing.clone(), decision, rx, &shared).await;
    tracing::debug!(
        "robot {}: goal `{}` (agent {}) ended: {status:?}",
        shared.id,
        goal.place,
        goal.agent
    );
    if let Ok(mut r) = shared.running.lock() {
        r.goals.remove(&id);
    }
    let send = server.send_result_response(executing, status, result);
    if tokio::time::timeout(Duration::from_secs(5), send)
        .await
        .is_err()
    {
        tracing::warn!("goal {id:?}: nobody asked for the result");
    }
}

async fn run_decision(
    server: &Server,
    executing: ExecutingGoalHandle<ExecPlaceGoal>,
    decision: Decision,
    mut cancelled: oneshot::Receiver<()>,
    shared: &Shared,
) -> (GoalEndStatus, ExecPlaceResult) {
    let start = tokio::time::Instant::now();
    let done = tokio::time::sleep(crate::limits::duration(decision.delay));
    tokio::pin!(done);
    let mut feedback =
        tokio::time::interval_at(start + Duration::from_secs(1), Duration::from_secs(1));
    loop {
        tokio::select! {
            _ = &mut done => {
                return (
                    GoalEndStatus::Succeeded,
                    ExecPlaceResult::fire_or_decide(decision.transition, "net-timed"),
                );
            }
            _ = &mut cancelled => {
                if let Ok(mut s) = shared.stats.lock() {
                    s.cancelled += 1;
                }
                return (GoalEndStatus::Canceled, ExecPlaceResult::cancelled());
            }
            _ = feedback.tick() => {
                let elapsed = start.elapsed().as_secs_f64();
                let _ = server
                    .publish_feedback(executing.clone(), ExecPlaceFeedback { elapsed })
                    .await;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    #[test]
    fn the_race_picks_outputs_in_proportion_to_their_rates() {
        let mut b = NetBuilder::new("n");
        let p = b.place("P", 1);
        let q = b.place("Q", 0);
        let fast = b.exponential("fast", 3.0, Servers::Single);
        let slow = b.exponential("slow", 1.0, Servers::Single);
        let now = b.immediate("now", 1.0, 1);
        for t in [fast, slow] {
            b.input(p, t, 1);
            b.output(t, p, 1);
        }
        b.input(q, now, 1);
        b.output(now, p, 1);
        let net = b.build().unwrap();
        let mut rng = Rng::seed_from_u64(1);
        let n = 20_000;
        let (mut fasts, mut delay) = (0, 0.0);
        for _ in 0..n {
            let d = decide(&net, p, 2.0, &mut rng);
            fasts += usize::from(d.transition == "fast");
            delay += d.delay;
        }
        let share = fasts as f64 / n as f64;
        assert!((share - 0.75).abs() < 0.02, "{share}");
        // Mean of Exp(4) × 2 s = 0.5 s.
        let mean = delay / n as f64;
        assert!((mean - 0.5).abs() < 0.02, "{mean}");
        let d = decide(&net, q, 2.0, &mut rng);
        assert_eq!(
            d,
            Decision {
                delay: 0.0,
                transition: String::new()
            }
        );
    }

    #[test]
    fn each_robot_draws_its_own_stream() {
        assert_ne!(id_hash("r1"), id_hash("r2"));
        assert_eq!(sanitize("r-1.a"), "r_1_a");
    }
}
