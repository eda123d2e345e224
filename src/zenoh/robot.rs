//! Robots over Zenoh: `plan-runner robot --zenoh` (one) and `plan-runner fleet` (many in one
//! process, on one session). Each robot serves the ExecPlace action at `/<id>/<server>` for
//! the plan's `ros2` places as an rclcpp action server does over rmw_zenoh: three
//! queryables (send_goal, get_result, cancel_goal), a feedback topic (each running goal's
//! elapsed time, every second) and a status topic (the goals' states when one changes).
//! Its decisions are the DDS robot's net-timed ones ([`crate::ros2::robot::decide`], the
//! same seeded stream per robot). It declares a liveliness token per endpoint, as rmw_zenoh
//! does, and its node's token last: the supervisor counts a robot ready when it sees that
//! one.
//!
//! The robots leave when the supervisor says its run is over on `/gspn/run`, or when its
//! token has been gone for `lost_after` (both ignored with `stay`).

use std::collections::HashMap;
use std::future::Future;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::{Arc, Mutex};
use std::time::Duration;

use rand::SeedableRng;
use serde::Serialize;
use tokio::sync::{oneshot, watch};
use zenoh::Session;
use zenoh::liveliness::LivelinessToken;
use zenoh::query::Query;

use super::action::{
    CANCEL_NONE, CANCEL_UNKNOWN_GOAL, CancelGoalRequest, CancelGoalResponse, FeedbackMessage,
    GetResultRequest, GetResultResponse, GoalId, GoalInfo, GoalStatus, GoalStatusArray,
    STATUS_ABORTED, STATUS_CANCELED, STATUS_EXECUTING, STATUS_SUCCEEDED, SendGoalRequest,
    SendGoalResponse,
};
use super::keys::{self, ActionService, ActionTopic, EntityIds, NodeKey, Topic};
use super::presence::{Liveness, Presence};
use super::wire::{self, Attachment, Source, WireError};
use super::{ZenohConfig, ZenohError};
use crate::net::Net;
use crate::ros2::msgs::{ExecPlaceFeedback, ExecPlaceResult, RunState, Time};
use crate::ros2::robot::{Leave, RobotStats, decide, id_hash};
use crate::ros2::settings::Ros2Settings;
use crate::sample::Rng;

/// How often a running goal's feedback is published (as the DDS robot does).
const FEEDBACK_EVERY: Duration = Duration::from_secs(1);

/// How long an ended goal's result is kept for a late `get_result`.
const RESULT_KEPT: Duration = Duration::from_secs(60);

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

/// A goal being run: how to cancel it, when it was accepted, and its result once it ended.
struct Goal {
    cancel: Option<oneshot::Sender<()>>,
    accepted: Time,
    result: watch::Receiver<Option<GetResultResponse>>,
}

/// What a robot's action servers share: its draws and its counts.
struct Robot {
    net: Arc<Net>,
    rng: Mutex<Rng>,
    time_scale: f64,
    stats: Mutex<RobotStats>,
}

/// A topic written with `Session::put`, with its rmw_zenoh attachment (no declared
/// publisher: a fleet process has thousands of these topics).
struct Writer {
    key: String,
    source: Source,
}

impl Writer {
    fn new(key: String) -> Writer {
        let source = Source::new(&key);
        Writer { key, source }
    }

    async fn put<M: Serialize>(&self, session: &Session, m: &M) {
        let r = session
            .put(&self.key, wire::encode(m))
            .attachment(self.source.next().to_bytes())
            .await;
        if let Err(e) = r {
            tracing::warn!("publishing on {}: {e}", self.key);
        }
    }
}

/// One robot's ExecPlace action server `/<robot>/<server>`: its goals and the writers of
/// its feedback and status topics.
struct Server {
    robot: Arc<Robot>,
    session: Session,
    goals: Mutex<HashMap<GoalId, Goal>>,
    feedback: Writer,
    status: Writer,
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
    let servers = settings.exec_place_servers();
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
    let ids = EntityIds::default();
    let mut robots = Vec::new();
    let mut action_servers = Vec::new();
    let mut tasks = Vec::new();
    let mut tokens = Vec::new();
    for id in &opts.ids {
        let node = NodeKey {
            domain: d,
            zid: session.zid().to_string(),
            id: ids.next(),
            namespace: keys::robot_namespace(id),
            name: keys::ROBOT_NODE.to_string(),
        };
        let robot = Arc::new(Robot {
            net: Arc::clone(&net),
            rng: Mutex::new(Rng::seed_from_u64(opts.seed ^ id_hash(id))),
            time_scale: opts.time_scale,
            stats: Mutex::new(RobotStats::default()),
        });
        let mut endpoints = Vec::new();
        for &server in &servers {
            let (s, keys) =
                serve_action(session, &node, &ids, id, server, &robot, &mut tasks).await?;
            endpoints.extend(keys);
            action_servers.push(s);
        }
        endpoints.push(node.endpoint(
            ids.next(),
            keys::EntityKind::Subscription,
            Topic::Run.name(),
            Topic::Run.ty(),
            Topic::Run.qos(),
        )?);
        endpoints.push(node.endpoint(
            ids.next(),
            keys::EntityKind::Subscription,
            Topic::Firings.name(),
            Topic::Firings.ty(),
            Topic::Firings.qos(),
        )?);
        // Last: the node's token says the robot is ready.
        endpoints.push(node.token());
        for key in endpoints {
            tokens.push(declare_token(session, key).await?);
        }
        robots.push((id.clone(), robot));
    }
    let left = tokio::select! {
        _ = stop => None,
        l = leave(&run, &supervisor, cfg.lost_after), if !opts.stay => Some(l),
    };
    drop(tokens);
    // Goals still running end cancelled (their results are still answered).
    for s in &action_servers {
        if let Ok(mut goals) = s.goals.lock() {
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

/// Serves robot `id`'s ExecPlace action `server`: its three services as queryables (their
/// tasks go to `tasks`), its feedback and status writers. The server, and the keys of its
/// endpoints' liveliness tokens.
async fn serve_action(
    session: &Session,
    node: &NodeKey,
    ids: &EntityIds,
    id: &str,
    server: &str,
    robot: &Arc<Robot>,
    tasks: &mut Vec<tokio::task::JoinHandle<()>>,
) -> Result<(Arc<Server>, Vec<String>), ZenohError> {
    let d = node.domain;
    let s = Arc::new(Server {
        robot: Arc::clone(robot),
        session: session.clone(),
        goals: Mutex::new(HashMap::new()),
        feedback: Writer::new(keys::exec_place_topic(
            d,
            id,
            server,
            ActionTopic::Feedback,
        )?),
        status: Writer::new(keys::exec_place_topic(d, id, server, ActionTopic::Status)?),
    });
    for service in ActionService::ALL {
        let q = session
            .declare_queryable(keys::exec_place(d, id, server, service)?)
            .await
            .map_err(ZenohError::zenoh)?;
        let s = Arc::clone(&s);
        tasks.push(tokio::spawn(async move {
            while let Ok(query) = q.recv_async().await {
                answer(&s, service, query).await;
            }
        }));
    }
    let endpoints = keys::action_server_tokens(node, ids, id, server)?;
    Ok((s, endpoints))
}

/// Declares the liveliness token `key`.
pub(super) async fn declare_token(
    session: &Session,
    key: String,
) -> Result<LivelinessToken, ZenohError> {
    session
        .liveliness()
        .declare_token(key)
        .await
        .map_err(ZenohError::zenoh)
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
async fn reply<M: Serialize>(query: &Query, resp: &M) {
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

fn request<M: serde::de::DeserializeOwned>(query: &Query) -> Result<M, WireError> {
    let b = query
        .payload()
        .map(|p| p.to_bytes().into_owned())
        .unwrap_or_default();
    wire::decode(&b)
}

async fn answer(server: &Arc<Server>, service: ActionService, query: Query) {
    match service {
        ActionService::SendGoal => match request::<SendGoalRequest>(&query) {
            Ok(req) => {
                let accepted = start_goal(server, req).await;
                let resp = SendGoalResponse {
                    accepted: accepted.is_some(),
                    stamp: accepted.unwrap_or_default(),
                };
                reply(&query, &resp).await;
            }
            Err(e) => tracing::warn!("a send_goal request: {e}"),
        },
        ActionService::GetResult => match request::<GetResultRequest>(&query) {
            Ok(req) => {
                let result = server
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
                            status: STATUS_ABORTED,
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
                    server.goals.lock().ok().and_then(|mut g| {
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

/// Publishes the server's status: its running goals and the one that just ended (ROS 2's
/// servers also list ended goals until their result expires; a fleet of busy robots would
/// publish long lists for nothing).
async fn publish_status(server: &Server, ended: Option<GoalStatus>) {
    let mut status_list: Vec<GoalStatus> = server
        .goals
        .lock()
        .map(|goals| {
            goals
                .iter()
                .filter(|(_, g)| g.result.borrow().is_none())
                .map(|(id, g)| GoalStatus {
                    goal_info: GoalInfo {
                        goal_id: *id,
                        stamp: g.accepted,
                    },
                    status: STATUS_EXECUTING,
                })
                .collect()
        })
        .unwrap_or_default();
    status_list.extend(ended);
    status_list.sort_by_key(|s| s.goal_info.goal_id);
    server
        .status
        .put(&server.session, &GoalStatusArray { status_list })
        .await;
}

/// Accepts and starts a goal: when it was accepted, or `None` when its place is unknown
/// (rejected).
async fn start_goal(server: &Arc<Server>, req: SendGoalRequest) -> Option<Time> {
    let robot = &server.robot;
    let Some(place) = robot.net.place_by_name(&req.goal.place) else {
        tracing::warn!("goal for unknown place `{}`: rejected", req.goal.place);
        return None;
    };
    let decision = match robot.rng.lock() {
        Ok(mut rng) => decide(&robot.net, place, robot.time_scale, &mut rng),
        Err(_) => return None,
    };
    if let Ok(mut s) = robot.stats.lock() {
        s.goals += 1;
    }
    let (cancel, cancelled) = oneshot::channel();
    let (done, result) = watch::channel(None);
    let accepted = Time::now();
    if let Ok(mut g) = server.goals.lock() {
        g.insert(
            req.goal_id,
            Goal {
                cancel: Some(cancel),
                accepted,
                result,
            },
        );
    }
    publish_status(server, None).await;
    tokio::spawn(run_goal(
        Arc::clone(server),
        req.goal_id,
        accepted,
        decision,
        cancelled,
        done,
    ));
    Some(accepted)
}

/// Runs goal `id` to its end (its delay, or a cancel request), publishing its feedback
/// every [`FEEDBACK_EVERY`] meanwhile, then its result and the status.
async fn run_goal(
    server: Arc<Server>,
    id: GoalId,
    accepted: Time,
    decision: crate::ros2::robot::Decision,
    mut cancelled: oneshot::Receiver<()>,
    done: watch::Sender<Option<GetResultResponse>>,
) {
    let start = tokio::time::Instant::now();
    let wait = tokio::time::sleep(crate::limits::duration(decision.delay));
    tokio::pin!(wait);
    let mut feedback = tokio::time::interval_at(start + FEEDBACK_EVERY, FEEDBACK_EVERY);
    // Open until cancelled, or until nobody can cancel any more.
    let mut cancellable = true;
    let resp = loop {
        tokio::select! {
            _ = &mut wait => break GetResultResponse {
                status: STATUS_SUCCEEDED,
                result: ExecPlaceResult::fire_or_decide(decision.transition, "net-timed"),
            },
            c = &mut cancelled, if cancellable => {
                if c.is_err() {
                    cancellable = false;
                    continue;
                }
                if let Ok(mut s) = server.robot.stats.lock() {
                    s.cancelled += 1;
                }
                break GetResultResponse {
                    status: STATUS_CANCELED,
                    result: ExecPlaceResult::cancelled(),
                };
            }
            _ = feedback.tick() => {
                let elapsed = start.elapsed().as_secs_f64();
                let msg = FeedbackMessage { goal_id: id, feedback: ExecPlaceFeedback { elapsed } };
                server.feedback.put(&server.session, &msg).await;
            }
        }
    };
    let status = resp.status;
    let _ = done.send(Some(resp));
    let ended = GoalStatus {
        goal_info: GoalInfo {
            goal_id: id,
            stamp: accepted,
        },
        status,
    };
    publish_status(&server, Some(ended)).await;
    // Kept a while for a late get_result, then forgotten.
    tokio::time::sleep(RESULT_KEPT).await;
    if let Ok(mut g) = server.goals.lock() {
        g.remove(&id);
    }
}
