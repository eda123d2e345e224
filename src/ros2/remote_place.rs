//! The supervisor's side of a `ros2` place: an [`Action`] that sends an ExecPlace goal to
//! the agent's robot at `/<robot>/<server>` and turns the result into an [`Outcome`].
//!
//! - result `transition` → [`Outcome::Fire`] (an unknown name fails), empty →
//!   [`Outcome::Decide`]; an aborted or rejected goal → [`Outcome::Failed`];
//! - the run being stopped → the goal is cancelled on the robot, [`Outcome::Cancelled`];
//! - the place's timeout (applied by the runtime, which drops the action) → the goal is
//!   cancelled on the robot too (a drop guard sends the cancel request);
//! - the robot's heartbeats stop ([`Liveness::Lost`]) or its server leaves DDS discovery
//!   ([`Liveness::Gone`], [`super::presence`]) → `Failed("robot … lost")`, and the
//!   plan's failure policy decides.
//!
//! Any number of goals at a time per robot and server: one task per link owns the action
//! client ([`RobotLink`]), sends the requests and hands each response to its caller by
//! request id (ros2-client's own calls drop responses meant for a concurrent call).

use std::collections::{BTreeMap, HashMap};
use std::future::Future;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use futures::StreamExt;
use ros2_client::action::{
    CancelGoalRequest, CancelGoalResponse, GetResultRequest, GoalId, GoalInfo, GoalStatusEnum,
    SendGoalRequest, SendGoalResponse,
};
use ros2_client::builtin_interfaces;
use ros2_client::dds::ActionClient;
use ros2_client::dds::Client;
use ros2_client::{Message, RmwRequestId};
use tokio::sync::{mpsc, oneshot, watch};

use super::heartbeat::Liveness;
use super::msgs::{ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult, KeyValue, PoseStamped};
use super::nav2::{Nav2Client, navigate};
use super::settings::{NAV2_SERVER, PlaceArgs};
use crate::net::PlaceId;
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome};

/// The ExecPlace action client of one robot's server.
pub type ExecPlaceClient = ActionClient<ExecPlaceGoal, ExecPlaceResult, ExecPlaceFeedback>;

/// How long a cancel request may take before the action gives up waiting for its answer.
const CANCEL_WAIT: Duration = Duration::from_secs(1);

/// A call through a link's action client; the answer comes back on the sender.
enum Call {
    Goal(ExecPlaceGoal, Reply<(GoalId, SendGoalResponse)>),
    Result(GoalId, Reply<(GoalStatusEnum, ExecPlaceResult)>),
    Cancel(GoalId, Reply<CancelGoalResponse>),
}

type Reply<T> = oneshot::Sender<Result<T, LinkError>>;

/// Why a call through a [`RobotLink`] got no answer.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum LinkError {
    /// The request could not be written (ros2-client's error).
    #[error("{0}")]
    Send(String),
    /// The link's task has ended (the run is stopping).
    #[error("the link's task has ended")]
    Ended,
}

/// Calls waiting for their response, by request id (callers that gave up are dropped on the
/// next insert).
struct Pending<T>(BTreeMap<RmwRequestId, Reply<T>>);

impl<T> Pending<T> {
    fn insert(&mut self, id: RmwRequestId, reply: Reply<T>) {
        self.0.retain(|_, r| !r.is_closed());
        self.0.insert(id, reply);
    }

    fn answer(&mut self, id: RmwRequestId, v: T) {
        if let Some(r) = self.0.remove(&id) {
            let _ = r.send(Ok(v));
        }
    }
}

/// Sends `req` through `client`, then waits (in the link's task) for its response.
async fn send<Req: Message + 'static, Resp: Message + 'static, T>(
    client: &Client<Req, Resp>,
    req: Req,
    reply: Reply<T>,
    pending: &mut Pending<T>,
) {
    match client.async_send_request(req).await {
        Ok(id) => pending.insert(id, reply),
        Err(e) => {
            let _ = reply.send(Err(LinkError::Send(format!("{e:?}"))));
        }
    }
}

/// The task owning one link's action client: sends the calls it is given and hands every
/// response to the call with its request id.
async fn serve_calls(client: ExecPlaceClient, mut calls: mpsc::UnboundedReceiver<Call>) {
    let (mut goals, mut results, mut cancels) = (
        Pending(BTreeMap::new()),
        Pending(BTreeMap::new()),
        Pending(BTreeMap::new()),
    );
    let goal_responses = client.goal_client().response_stream();
    let result_responses = client.result_client().response_stream();
    let cancel_responses = client.cancel_client().response_stream();
    futures::pin_mut!(goal_responses, result_responses, cancel_responses);
    loop {
        tokio::select! {
            c = calls.recv() => match c {
                None => break,
                Some(Call::Goal(goal, reply)) => {
                    let goal_id = GoalId::new_random();
                    let req = SendGoalRequest { goal_id, goal };
                    let (tx, rx) = oneshot::channel();
                    send(client.goal_client(), req, tx, &mut goals).await;
                    // The goal id travels with the response.
                    tokio::spawn(async move {
                        if let Ok(r) = rx.await {
                            let _ = reply.send(r.map(|resp| (goal_id, resp)));
                        }
                    });
                }
                Some(Call::Result(goal_id, reply)) => {
                    let req = GetResultRequest { goal_id };
                    send(client.result_client(), req, reply, &mut results).await;
                }
                Some(Call::Cancel(goal_id, reply)) => {
                    let goal_info = GoalInfo { goal_id, stamp: builtin_interfaces::Time::ZERO };
                    let req = CancelGoalRequest { goal_info };
                    send(client.cancel_client(), req, reply, &mut cancels).await;
                }
            },
            Some(r) = goal_responses.next() => match r {
                Ok((id, resp)) => goals.answer(id, resp),
                Err(e) => tracing::warn!("goal response: {e:?}"),
            },
            Some(r) = result_responses.next() => match r {
                Ok((id, resp)) => results.answer(id, (resp.status, resp.result)),
                Err(e) => tracing::warn!("result response: {e:?}"),
            },
            Some(r) = cancel_responses.next() => match r {
                Ok((id, resp)) => cancels.answer(id, resp),
                Err(e) => tracing::warn!("cancel response: {e:?}"),
            },
        }
    }
}

/// One robot's ExecPlace server as the supervisor reaches it: a task owns the action client
/// and serves any number of concurrent calls.
pub struct RobotLink {
    /// The robot.
    pub robot: String,
    calls: mpsc::UnboundedSender<Call>,
    task: tokio::task::JoinHandle<()>,
    liveness: watch::Receiver<Liveness>,
}

impl Drop for RobotLink {
    fn drop(&mut self) {
        self.task.abort();
    }
}

impl std::fmt::Debug for RobotLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotLink")
            .field("robot", &self.robot)
            .finish()
    }
}

impl RobotLink {
    /// A link through `client` (its task is spawned on the current tokio runtime), failing
    /// goals when `liveness` turns [`Liveness::Lost`] or [`Liveness::Gone`].
    pub fn new(
        robot: String,
        client: ExecPlaceClient,
        liveness: watch::Receiver<Liveness>,
    ) -> RobotLink {
        let (calls, rx) = mpsc::unbounded_channel();
        RobotLink {
            robot,
            calls,
            task: tokio::spawn(serve_calls(client, rx)),
            liveness,
        }
    }

    /// Waits until the robot's goal, result and cancel services of `client` are matched
    /// (needs the node's spinner running); before [`RobotLink::new`].
    pub async fn wait_for_server(client: &ExecPlaceClient, node: &ros2_client::Node) {
        client.goal_client().wait_for_service(node).await;
        client.result_client().wait_for_service(node).await;
        client.cancel_client().wait_for_service(node).await;
    }

    async fn call<T>(&self, make: impl FnOnce(Reply<T>) -> Call) -> Result<T, LinkError> {
        let (tx, rx) = oneshot::channel();
        self.calls.send(make(tx)).map_err(|_| LinkError::Ended)?;
        rx.await.map_err(|_| LinkError::Ended)?
    }

    /// Sends `goal`; the goal's id and the server's response.
    pub async fn send_goal(
        &self,
        goal: ExecPlaceGoal,
    ) -> Result<(GoalId, SendGoalResponse), LinkError> {
        self.call(|r| Call::Goal(goal, r)).await
    }

    /// Asks for the result of goal `id`: answered when the goal has ended.
    pub async fn request_result(
        &self,
        id: GoalId,
    ) -> Result<(GoalStatusEnum, ExecPlaceResult), LinkError> {
        self.call(|r| Call::Result(id, r)).await
    }

    /// Asks the robot to cancel goal `id`.
    pub async fn cancel_goal(&self, id: GoalId) -> Result<CancelGoalResponse, LinkError> {
        self.call(|r| Call::Cancel(id, r)).await
    }
}

/// The [`Action`] of every `ros2` place of a plan.
#[derive(Debug, Clone)]
pub struct RemotePlaces {
    /// Server name of each `ros2` place.
    servers: Arc<HashMap<PlaceId, String>>,
    /// Arguments of the places that have some.
    args: Arc<HashMap<PlaceId, PlaceArgs>>,
    /// Links by (robot, server).
    links: Arc<HashMap<(String, String), Arc<RobotLink>>>,
    /// Each robot's Nav2 (`navigate_to_pose`) client and presence, for Nav2 places.
    nav2: Arc<HashMap<String, Nav2Link>>,
}

/// A robot's `NavigateToPose` client and its presence.
#[derive(Clone)]
pub struct Nav2Link {
    /// The client of `/<robot>/navigate_to_pose`.
    pub client: Arc<Nav2Client>,
    /// The robot's presence.
    pub liveness: watch::Receiver<Liveness>,
}

impl std::fmt::Debug for Nav2Link {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Nav2Link")
            .field("liveness", &*self.liveness.borrow())
            .finish_non_exhaustive()
    }
}

impl RemotePlaces {
    /// The action for places `servers` (place → server name) with their `args` over `links`.
    pub fn new(
        servers: HashMap<PlaceId, String>,
        args: HashMap<PlaceId, PlaceArgs>,
        links: Vec<(String, Arc<RobotLink>)>,
        nav2: HashMap<String, Nav2Link>,
    ) -> Self {
        RemotePlaces {
            servers: Arc::new(servers),
            args: Arc::new(args),
            nav2: Arc::new(nav2),
            links: Arc::new(
                links
                    .into_iter()
                    .map(|(server, l)| ((l.robot.clone(), server), l))
                    .collect(),
            ),
        }
    }
}

/// The server of a `ros2` place and the robot of the agent in it, or why the action cannot
/// run there (the same for every transport).
pub(crate) fn server_and_robot<'a>(
    servers: &'a HashMap<PlaceId, String>,
    ctx: &ActionContext,
) -> Result<(&'a String, Arc<str>), String> {
    let Some(server) = servers.get(&ctx.place) else {
        return Err(format!("place `{}` is not a ros2 place", ctx.place_name()));
    };
    let Some(robot) = ctx.robot.clone() else {
        return Err(format!(
            "agent {} in ros2 place `{}` has no robot (give the plan `robots = [...]`)",
            ctx.agent.0,
            ctx.place_name()
        ));
    };
    Ok((server, robot))
}

impl Action for RemotePlaces {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let (server, robot) = match server_and_robot(&self.servers, &ctx) {
            Ok(it) => it,
            Err(m) => return Box::pin(async move { Outcome::Failed(m) }),
        };
        if server == NAV2_SERVER {
            let target = self.args.get(&ctx.place).and_then(|a| a.target);
            let (Some(link), Some([x, y, yaw])) = (self.nav2.get(&*robot), target) else {
                let m = format!("robot `{robot}` has no Nav2 client (or the place no target)");
                return Box::pin(async move { Outcome::Failed(m) });
            };
            let pose = PoseStamped::on_map(x, y, yaw);
            let (client, live) = (Arc::clone(&link.client), link.liveness.clone());
            return Box::pin(nav2_exec(client, robot.to_string(), pose, live, ctx));
        }
        let Some(link) = self.links.get(&(robot.to_string(), server.clone())) else {
            let m = format!("robot `{robot}` has no link to server `{server}`");
            return Box::pin(async move { Outcome::Failed(m) });
        };
        let goal = goal(&ctx, self.args.get(&ctx.place));
        Box::pin(exec(Arc::clone(link), goal, ctx))
    }
}

/// The ExecPlace goal of `ctx`'s agent in its place, with the place's arguments.
pub fn goal(ctx: &ActionContext, args: Option<&PlaceArgs>) -> ExecPlaceGoal {
    let mut goal = ExecPlaceGoal {
        place: ctx.place_name().to_string(),
        agent: ctx.agent.0,
        ..ExecPlaceGoal::default()
    };
    if let Some(a) = args {
        if let Some([x, y, yaw]) = a.target {
            goal.has_target = true;
            goal.target = PoseStamped::on_map(x, y, yaw);
        }
        goal.args = a
            .args
            .iter()
            .map(|(key, value)| KeyValue {
                key: key.clone(),
                value: value.clone(),
            })
            .collect();
    }
    goal
}

/// A link to a robot's ExecPlace server that can cancel one of its goals (DDS here, Zenoh in
/// `crate::zenoh::remote_place`).
pub(crate) trait CancelGoal: Send + Sync + 'static {
    /// The transport's goal id.
    type Id: Send + 'static;
    /// Asks the robot to cancel goal `id` (waiting a bounded time for the answer).
    fn send_cancel(self: Arc<Self>, id: Self::Id) -> impl Future<Output = ()> + Send;
}

impl CancelGoal for RobotLink {
    type Id = GoalId;

    async fn send_cancel(self: Arc<Self>, id: GoalId) {
        let _ = tokio::time::timeout(CANCEL_WAIT, self.cancel_goal(id)).await;
    }
}

/// Cancels the goal on the robot if the action is dropped before the goal ended (the
/// runtime's timeout drops it).
pub(crate) struct GoalGuard<L: CancelGoal> {
    link: Arc<L>,
    goal: Mutex<Option<L::Id>>,
}

impl<L: CancelGoal> GoalGuard<L> {
    /// A guard of `link`'s goals, holding none yet.
    pub(crate) fn new(link: Arc<L>) -> Self {
        GoalGuard {
            link,
            goal: Mutex::new(None),
        }
    }

    /// The goal to cancel if dropped (`None`: nothing to cancel).
    pub(crate) fn set(&self, g: Option<L::Id>) {
        if let Ok(mut s) = self.goal.lock() {
            *s = g;
        }
    }

    /// The goal held, which the guard then no longer cancels.
    pub(crate) fn take(&self) -> Option<L::Id> {
        self.goal.lock().ok().and_then(|mut s| s.take())
    }
}

impl<L: CancelGoal> Drop for GoalGuard<L> {
    fn drop(&mut self) {
        if let Some(id) = self.take()
            && let Ok(rt) = tokio::runtime::Handle::try_current()
        {
            rt.spawn(Arc::clone(&self.link).send_cancel(id));
        }
    }
}

enum Ended {
    Result(Result<(GoalStatusEnum, ExecPlaceResult), String>),
    Lost(Liveness),
    Cancel,
}

async fn exec(link: Arc<RobotLink>, goal: ExecPlaceGoal, ctx: ActionContext) -> Outcome {
    let robot = link.robot.clone();
    let lost_msg = |l: Liveness| match l {
        Liveness::Gone => format!("robot `{robot}` lost (its ExecPlace server left DDS discovery)"),
        _ => format!("robot `{robot}` lost (its heartbeats stopped)"),
    };
    let mut live = link.liveness.clone();
    let now = *live.borrow();
    if now.is_lost() {
        return Outcome::Failed(lost_msg(now));
    }
    let guard = GoalGuard::new(Arc::clone(&link));
    let work = async {
        let (id, resp) = link
            .send_goal(goal)
            .await
            .map_err(|e| format!("sending the goal to robot `{robot}`: {e}"))?;
        if !resp.accepted {
            return Err(format!("robot `{robot}` rejected the goal"));
        }
        guard.set(Some(id));
        link.request_result(id)
            .await
            .map_err(|e| format!("result from robot `{robot}`: {e}"))
    };
    let ended = tokio::select! {
        r = work => Ended::Result(r),
        l = live.wait_for(|s| s.is_lost()) => Ended::Lost(l.map(|l| *l).unwrap_or(Liveness::Gone)),
        _ = ctx.cancel.cancelled() => Ended::Cancel,
    };
    match ended {
        Ended::Result(r) => {
            guard.set(None);
            match r {
                Ok((status, res)) => outcome(&robot, status, &res, &ctx),
                Err(e) => Outcome::Failed(e),
            }
        }
        Ended::Lost(l) => {
            guard.set(None);
            Outcome::Failed(lost_msg(l))
        }
        Ended::Cancel => {
            if let Some(id) = guard.take() {
                let _ = tokio::time::timeout(CANCEL_WAIT, link.cancel_goal(id)).await;
            }
            Outcome::Cancelled
        }
    }
}

/// A Nav2 place's action: `robot` drives to `pose` through its Nav2; arrived → the policy
/// decides, anything else (aborted, rejected, the robot lost) fails the action; the run
/// stopped or the place's timeout cancels the goal (`nav2::navigate`'s drop guard).
async fn nav2_exec(
    client: Arc<Nav2Client>,
    robot: String,
    pose: PoseStamped,
    mut live: watch::Receiver<Liveness>,
    ctx: ActionContext,
) -> Outcome {
    let lost = |l: Liveness| match l {
        Liveness::Gone => {
            format!("robot `{robot}` lost (its {NAV2_SERVER} server left DDS discovery)")
        }
        _ => format!("robot `{robot}` lost (its heartbeats stopped)"),
    };
    let now = *live.borrow();
    if now.is_lost() {
        return Outcome::Failed(lost(now));
    }
    tokio::select! {
        r = navigate(client, &robot, pose, ctx.cancel.cancelled(), |_| {}) => match r {
            Ok(()) => Outcome::Decide,
            Err(_) if ctx.cancel.is_cancelled() => Outcome::Cancelled,
            Err(e) => Outcome::Failed(format!("robot `{robot}`: {e}")),
        },
        l = live.wait_for(|s| s.is_lost()) => {
            Outcome::Failed(lost(l.map(|l| *l).unwrap_or(Liveness::Gone)))
        }
    }
}

/// What a goal's end means for the place: a succeeded goal fires the robot's transition or
/// lets the policy decide; a goal the robot says FAILED, aborted or cancelled by itself
/// fails the action (the place's `on_failure` applies).
fn outcome(
    robot: &str,
    status: GoalStatusEnum,
    res: &ExecPlaceResult,
    ctx: &ActionContext,
) -> Outcome {
    match status {
        GoalStatusEnum::Succeeded => succeeded(robot, res, ctx),
        status => Outcome::Failed(format!(
            "robot `{robot}` ended the goal {status:?}: {}",
            res.message
        )),
    }
}

/// The outcome of a goal that `robot` ended as succeeded with `res` (over DDS or Zenoh).
pub fn succeeded(robot: &str, res: &ExecPlaceResult, ctx: &ActionContext) -> Outcome {
    match res.outcome {
        ExecPlaceResult::FIRE => ctx.fire(&res.transition),
        ExecPlaceResult::DECIDE => Outcome::Decide,
        ExecPlaceResult::FAILED => {
            Outcome::Failed(format!("robot `{robot}` failed: {}", res.message))
        }
        o => Outcome::Failed(format!(
            "robot `{robot}` answered outcome {o}, not FIRE (0), DECIDE (1) or FAILED (2): {}",
            res.message
        )),
    }
}
