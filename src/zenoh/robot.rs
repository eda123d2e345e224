//! Robots over Zenoh: `plan-runner robot --zenoh` (one) and `plan-runner fleet` (many in one
//! process, on one session). Each robot serves the ExecPlace action at `/<id>/<server>` for
//! the plan's `ros2` places as three queryables (send_goal, get_result, cancel_goal), with
//! the DDS robot's net-timed decisions ([`crate::ros2::robot::decide`], the same seeded
//! stream per robot), and declares its node's liveliness token once its queryables are
//! there: the supervisor counts a robot ready when it sees the token.
//!
//! The robots leave when the supervisor says its run is over on `/gspn/run`, or when its
//! token has been gone for `lost_after` (both ignored with `stay`).

use std::collections::HashMap;
use std::future::Future;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use rand::SeedableRng;
use tokio::sync::{oneshot, watch};
use zenoh::Session;
use zenoh::query::Query;

use super::action::{
    CANCEL_NONE, CANCEL_UNKNOWN_GOAL, CancelGoalRequest, CancelGoalResponse, GetResultRequest,
    GetResultResponse, GoalId, STATUS_CANCELED, STATUS_SUCCEEDED, SendGoalRequest,
    SendGoalResponse,
};
use super::keys::{self, ActionService, Topic};
use super::presence::{Liveness, Presence};
use super::wire::{self, Attachment};
use super::{ZenohConfig, ZenohError};
use crate::net::Net;
use crate::ros2::msgs::{ExecPlaceResult, RunState, Time};
use crate::ros2::robot::{Leave, RobotStats, decide, id_hash};
use crate::ros2::settings::{NAV2_SERVER, Ros2Settings};
use crate::sample::Rng;

/// How the robots of a process run.
#[derive(Clone, Debug)]
pub struct FleetOptions {
    /// The robots' ids.
    pub ids: Vec<String>,
    /// Seed of the draws (mixed with each robot's id, as the DDS robot does).
    pub seed: u64,
    /// Seconds per unit of model time for the local delays.
    pub time_scale: f64,
    /// Keep serving after the run is over or the supervisor is lost.
    pub stay: bool,
}

/// What the robots of a process did.
#[derive(Clone, Debug, Default)]
pub struct FleetStats {
    /// Each robot's goals and cancellations (its `firings` stays 0: see [`Self::firings`]).
    pub robots: Vec<(String, RobotStats)>,
    /// Firings the process received on `/gspn/firings`.
    pub firings: u64,
    /// Why the robots left by themselves; `None` when stopped.
    pub left: Option<Leave>,
}

/// A goal being run: how to cancel it, and its result once it ended.
struct Goal {
    cancel: Option<oneshot::Sender<()>>,
    result: watch::Receiver<Option<GetResultResponse>>,
}

struct Robot {
    net: Arc<Net>,
    rng: Mutex<Rng>,
    time_scale: f64,
    stats: Mutex<RobotStats>,
    goals: Mutex<HashMap<GoalId, Goal>>,
}

/// Serves the robots `opts.ids` through `session` until `stop` completes or they leave.
pub async fn serve(
    session: &Session,
    net: &Net,
    settings: &Ros2Settings,
    cfg: &ZenohConfig,
    opts: FleetOptions,
    stop: impl Future<Output = ()>,
) -> Result<FleetStats, ZenohError> {
    let d = cfg.domain;
    let net = Arc::new(net.clone());
    // Nav2 places' goals go to a robot's Nav2, not to ExecPlace (and not over Zenoh).
    let mut servers: Vec<&str> = settings
        .servers
        .iter()
        .map(|(_, s)| s.as_str())
        .filter(|&s| s != NAV2_SERVER)
        .collect();
    servers.sort_unstable();
    servers.dedup();
    let run = session
        .declare_subscriber(Topic::Run.key(d)?)
        .await
        .map_err(ZenohError::zenoh)?;
    let firings = session
        .declare_subscriber(Topic::Firings.key(d)?)
        .await
        .map_err(ZenohError::zenoh)?;
    let received = Arc::new(AtomicU64::new(0));
    let counter = {
        let received = Arc::clone(&received);
        tokio::spawn(async move {
            while firings.recv_async().await.is_ok() {
                received.fetch_add(1, Ordering::Relaxed);
            }
        })
    };
    let supervisor = Presence::supervisor(session, d, cfg.lost_after).await?;
    let zid = session.zid().to_string();
    let mut robots = Vec::new();
    let mut tasks = Vec::new();
    let mut tokens = Vec::new();
    for (i, id) in opts.ids.iter().enumerate() {
        let robot = Arc::new(Robot {
            net: Arc::clone(&net),
            rng: Mutex::new(Rng::seed_from_u64(opts.seed ^ id_hash(id))),
            time_scale: opts.time_scale,
            stats: Mutex::new(RobotStats::default()),
            goals: Mutex::new(HashMap::new()),
        });
        for &server in &servers {
            for service in [
                ActionService::SendGoal,
                ActionService::GetResult,
                ActionService::CancelGoal,
            ] {
                let q = session
                    .declare_queryable(keys::exec_place(d, id, server, service)?)
                    .await
                    .map_err(ZenohError::zenoh)?;
                let robot = Arc::clone(&robot);
                tasks.push(tokio::spawn(async move {
                    while let Ok(query) = q.recv_async().await {
                        answer(&robot, service, query).await;
                    }
                }));
            }
        }
        // Last: the token says the robot is ready.
        let node = u32::try_from(i + 1).unwrap_or(u32::MAX);
        let token = session
            .liveliness()
            .declare_token(keys::node_token(
                d,
                &zid,
                node,
                &keys::robot_namespace(id),
                keys::ROBOT_NODE,
            ))
            .await
            .map_err(ZenohError::zenoh)?;
        tokens.push(token);
        robots.push((id.clone(), robot));
    }
    let left = tokio::select! {
        _ = stop => None,
        l = leave(&run, &supervisor, cfg.lost_after), if !opts.stay => Some(l),
    };
    drop(tokens);
    // Goals still running end cancelled (their results are still answered).
    for (_, r) in &robots {
        if let Ok(mut goals) = r.goals.lock() {
            for g in goals.values_mut() {
                if let Some(c) = g.cancel.take() {
                    let _ = c.send(());
                }
            }
        }
    }
    tokio::time::sleep(Duration::from_millis(200)).await;
    for t in tasks {
        t.abort();
    }
    counter.abort();
    Ok(FleetStats {
        robots: robots
            .into_iter()
            .map(|(id, r)| {
                let s = r.stats.lock().map(|s| s.clone()).unwrap_or_default();
                (id, s)
            })
            .collect(),
        firings: received.load(Ordering::Relaxed),
        left,
    })
}

/// Completes when the robots should leave: the run is over, or the supervisor (once seen)
/// has been lost.
async fn leave(
    run: &zenoh::pubsub::Subscriber<zenoh::handlers::FifoChannelHandler<zenoh::sample::Sample>>,
    supervisor: &Presence,
    lost_after: Duration,
) -> Leave {
    let mut live = supervisor
        .liveness(keys::SUPERVISOR_NODE)
        .unwrap_or_else(|| watch::channel(Liveness::Unknown).1);
    let over = async {
        while let Ok(s) = run.recv_async().await {
            if let Ok(r) = wire::decode::<RunState>(&s.payload().to_bytes())
                && r.state == RunState::OVER
            {
                return Leave::RunOver(format!("{} after {} firings", r.stopped, r.firings));
            }
        }
        std::future::pending().await
    };
    tokio::select! {
        l = over => l,
        _ = live.wait_for(|l| *l == Liveness::Lost) => Leave::SupervisorLost(lost_after),
    }
}

/// Replies `resp` to `query`, echoing its attachment's sequence number and GID.
async fn reply<M: serde::Serialize>(query: &Query, resp: &M) {
    let mut r = query.reply(query.key_expr().clone(), wire::encode(resp));
    if let Some(a) = query
        .attachment()
        .and_then(|a| Attachment::parse(&a.to_bytes()))
    {
        r = r.attachment(Attachment::now(a.seq, a.gid).to_bytes());
    }
    if let Err(e) = r.await {
        tracing::warn!("replying to {}: {e}", query.key_expr());
    }
}

fn request<M: serde::de::DeserializeOwned>(query: &Query) -> Result<M, String> {
    let b = query
        .payload()
        .map(|p| p.to_bytes().into_owned())
        .unwrap_or_default();
    wire::decode(&b)
}

async fn answer(robot: &Arc<Robot>, service: ActionService, query: Query) {
    match service {
        ActionService::SendGoal => match request::<SendGoalRequest>(&query) {
            Ok(req) => {
                let accepted = start_goal(robot, req);
                let resp = SendGoalResponse {
                    accepted,
                    stamp: Time::now(),
                };
                reply(&query, &resp).await;
            }
            Err(e) => tracing::warn!("a send_goal request: {e}"),
        },
        ActionService::GetResult => match request::<GetResultRequest>(&query) {
            Ok(req) => {
                let result = robot
                    .goals
                    .lock()
                    .ok()
                    .and_then(|g| g.get(&req.goal_id).map(|g| g.result.clone()));
                // The answer waits for the goal's end: in its own task.
                tokio::spawn(async move {
                    let resp = match result {
                        Some(mut rx) => {
                            let _ = rx.wait_for(Option::is_some).await;
                            let r = rx.borrow().clone();
                            r.unwrap_or_default()
                        }
                        None => GetResultResponse {
                            status: super::action::STATUS_ABORTED,
                            result: ExecPlaceResult {
                                outcome: ExecPlaceResult::FAILED,
                                transition: String::new(),
                                message: "unknown goal".into(),
                            },
                        },
                    };
                    reply(&query, &resp).await;
                });
            }
            Err(e) => tracing::warn!("a get_result request: {e}"),
        },
        ActionService::CancelGoal => match request::<CancelGoalRequest>(&query) {
            Ok(req) => {
                let id = req.goal_info.goal_id;
                let found =
                    robot.goals.lock().ok().and_then(|mut g| {
                        g.get_mut(&id).map(|g| g.cancel.take().map(|c| c.send(())))
                    });
                let resp = CancelGoalResponse {
                    return_code: if found.is_some() {
                        CANCEL_NONE
                    } else {
                        CANCEL_UNKNOWN_GOAL
                    },
                    goals_canceling: found.map(|_| req.goal_info).into_iter().collect(),
                };
                reply(&query, &resp).await;
            }
            Err(e) => tracing::warn!("a cancel_goal request: {e}"),
        },
    }
}

/// Accepts and starts a goal (false: its place is unknown, rejected).
fn start_goal(robot: &Arc<Robot>, req: SendGoalRequest) -> bool {
    let Some(place) = robot.net.place_by_name(&req.goal.place) else {
        tracing::warn!("goal for unknown place `{}`: rejected", req.goal.place);
        return false;
    };
    let decision = match robot.rng.lock() {
        Ok(mut rng) => decide(&robot.net, place, robot.time_scale, &mut rng),
        Err(_) => return false,
    };
    if let Ok(mut s) = robot.stats.lock() {
        s.goals += 1;
    }
    let (cancel, cancelled) = oneshot::channel();
    let (done, result) = watch::channel(None);
    if let Ok(mut g) = robot.goals.lock() {
        g.insert(
            req.goal_id,
            Goal {
                cancel: Some(cancel),
                result,
            },
        );
    }
    let robot = Arc::clone(robot);
    tokio::spawn(async move {
        let wait = tokio::time::sleep(crate::limits::duration(decision.delay));
        let resp = tokio::select! {
            _ = wait => GetResultResponse {
                status: STATUS_SUCCEEDED,
                result: ExecPlaceResult::fire_or_decide(decision.transition, "net-timed"),
            },
            Ok(()) = cancelled => {
                if let Ok(mut s) = robot.stats.lock() {
                    s.cancelled += 1;
                }
                GetResultResponse {
                    status: STATUS_CANCELED,
                    result: ExecPlaceResult::cancelled(),
                }
            }
        };
        let _ = done.send(Some(resp));
        // Kept a while for a late get_result, then forgotten.
        tokio::time::sleep(Duration::from_secs(60)).await;
        if let Ok(mut g) = robot.goals.lock() {
            g.remove(&req.goal_id);
        }
    });
    true
}
