//! The supervisor's side of a `ros2` place over Zenoh: an [`Action`] that sends an ExecPlace
//! goal to `/<robot>/<server>` through the action's three queryables and turns the result
//! into an [`Outcome`], as the DDS [`crate::ros2::remote_place`] does:
//!
//! - a result `transition` → [`Outcome::Fire`], empty → [`Outcome::Decide`], a goal rejected,
//!   aborted or cancelled by the robot → [`Outcome::Failed`];
//! - the run stopped, or the action dropped (the place's timeout) → the goal is cancelled on
//!   the robot;
//! - the robot's token gone for `lost_after` ([`Liveness::Lost`]) → `Failed("robot … lost")`.
//!   A call that ends without a reply because the robot's queryables went away with its
//!   token (a cut link, a dead process) does not fail the goal by itself: the call is made
//!   again when the token is back (a cut shorter than `lost_after` costs nothing, as over
//!   DDS), and the goal fails as lost if it is not.
//!
//! A call is a Zenoh query whose attachment carries the client's GID and a sequence
//! number, as rmw_zenoh's service clients send it; `get_result` is a query the robot answers
//! when the goal ends.

use std::collections::HashMap;
use std::sync::Arc;
use std::sync::atomic::{AtomicU32, Ordering};
use std::time::Duration;

use serde::Serialize;
use serde::de::DeserializeOwned;
use tokio::sync::watch;
use zenoh::Session;

use super::action::{
    CancelGoalRequest, GetResultRequest, GetResultResponse, GoalId, GoalInfo, STATUS_SUCCEEDED,
    SendGoalRequest, SendGoalResponse,
};
use super::keys::{self, ActionService};
use super::presence::Liveness;
use super::type_hash::TypeError;
use super::wire::{self, Source, WireError};
use crate::net::PlaceId;
use crate::ros2::msgs::{ExecPlaceGoal, Time};
use crate::ros2::remote_place::{CancelGoal, GoalGuard, goal, server_and_robot, succeeded};
use crate::ros2::settings::PlaceArgs;
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome};

/// How long a goal or cancel request may wait for its answer.
const CALL_WAIT: Duration = Duration::from_secs(10);
/// How long after a call failed its robot's token may take to vanish for the failure to be
/// put down to the robot's absence (the router ends the query and withdraws the token at
/// about the same time, in either order).
const GONE_GRACE: Duration = Duration::from_secs(1);
/// How long a result may take: a goal runs as long as the robot's action does (the place's
/// own timeout, applied by the runtime, bounds it when the plan has one).
const RESULT_WAIT: Duration = Duration::from_secs(7 * 24 * 3600);

/// A service client's identity ([`Source`]: its GID and the sequence number of its next
/// request) and the goal ids it makes.
#[derive(Debug)]
pub struct ClientId {
    source: Source,
    goals: AtomicU32,
}

impl ClientId {
    /// The client named `name` (`/<robot>/<server>`) of this process.
    pub fn new(name: &str) -> ClientId {
        ClientId {
            source: Source::new(name),
            goals: AtomicU32::new(1),
        }
    }

    /// A fresh goal id: the GID's first 12 bytes and a counter.
    fn goal_id(&self) -> GoalId {
        let mut id = self.source.gid();
        let n = self.goals.fetch_add(1, Ordering::Relaxed);
        id[12..].copy_from_slice(&n.to_le_bytes());
        id
    }
}

/// Why a call to a robot's action service failed.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum CallError {
    /// Zenoh refused the query.
    #[error("zenoh: {0}")]
    Zenoh(#[source] zenoh::Error),
    /// The query ended without a reply (no server, or it went away).
    #[error("no reply (is the robot's server up?)")]
    NoReply,
    /// The server replied with an error (its payload, as text).
    #[error("the server answered an error: {0}")]
    Server(String),
    /// The reply is not the response expected.
    #[error(transparent)]
    Decode(#[from] WireError),
}

/// Calls service `key` with `req`; the first reply, decoded.
pub async fn call<Req: Serialize, Resp: DeserializeOwned>(
    session: &Session,
    client: &ClientId,
    key: &str,
    req: &Req,
    wait: Duration,
) -> Result<Resp, CallError> {
    let replies = session
        .get(key)
        .payload(wire::encode(req))
        .attachment(client.source.next().to_bytes())
        .timeout(wait)
        .await
        .map_err(CallError::Zenoh)?;
    let reply = replies.recv_async().await.map_err(|_| CallError::NoReply)?;
    match reply.result() {
        Ok(sample) => Ok(wire::decode(&sample.payload().to_bytes())?),
        Err(e) => Err(CallError::Server(
            String::from_utf8_lossy(&e.payload().to_bytes()).into_owned(),
        )),
    }
}

/// Why a goal came to nothing.
#[derive(Debug, thiserror::Error)]
enum GoalError {
    /// The goal did not reach the robot.
    #[error("sending the goal to robot `{0}`: {1}")]
    Send(String, #[source] CallError),
    /// The robot said no.
    #[error("robot `{0}` rejected the goal")]
    Rejected(String),
    /// The result did not come back.
    #[error("result from robot `{0}`: {1}")]
    Result(String, #[source] CallError),
}

/// One robot's ExecPlace server as the supervisor reaches it.
#[derive(Debug)]
pub struct RobotLink {
    /// The robot.
    pub robot: String,
    session: Session,
    client: ClientId,
    keys: [String; 3],
    liveness: watch::Receiver<Liveness>,
    present: watch::Receiver<bool>,
}

impl RobotLink {
    /// A link to `/<robot>/<server>` in `domain`, failing goals when `liveness` turns lost;
    /// `present`: whether the robot's token is there now.
    pub fn new(
        session: Session,
        domain: u16,
        robot: String,
        server: &str,
        liveness: watch::Receiver<Liveness>,
        present: watch::Receiver<bool>,
    ) -> Result<RobotLink, TypeError> {
        let key = |s| keys::exec_place(domain, &robot, server, s);
        let client = ClientId::new(&format!("/{robot}/{server}"));
        Ok(RobotLink {
            keys: [
                key(ActionService::SendGoal)?,
                key(ActionService::GetResult)?,
                key(ActionService::CancelGoal)?,
            ],
            robot,
            session,
            client,
            liveness,
            present,
        })
    }

    /// After a call failed: whether the robot's token vanished (within [`GONE_GRACE`]) and
    /// came back, so the call is worth making again. Never returns while the robot stays
    /// away: the caller also waits for [`Liveness::Lost`].
    async fn back_after_absence(&self) -> bool {
        let mut present = self.present.clone();
        let gone = tokio::time::timeout(GONE_GRACE, present.wait_for(|p| !*p))
            .await
            .is_ok_and(|r| r.is_ok());
        if !gone {
            return false;
        }
        present.wait_for(|p| *p).await.is_ok()
    }

    /// `send_goal`, made again whenever it failed because the robot was away.
    async fn send_goal_until_back(
        &self,
        goal: &ExecPlaceGoal,
    ) -> Result<(GoalId, bool), CallError> {
        loop {
            match self.send_goal(goal.clone()).await {
                Err(_) if self.back_after_absence().await => continue,
                r => return r,
            }
        }
    }

    /// `get_result`, asked again whenever it failed because the robot was away (a robot
    /// that kept running still has the goal; a restarted one answers "unknown goal").
    async fn result_until_back(&self, goal_id: GoalId) -> Result<GetResultResponse, CallError> {
        loop {
            match self.result(goal_id).await {
                Err(_) if self.back_after_absence().await => continue,
                r => return r,
            }
        }
    }

    async fn send_goal(&self, goal: ExecPlaceGoal) -> Result<(GoalId, bool), CallError> {
        let goal_id = self.client.goal_id();
        let req = SendGoalRequest { goal_id, goal };
        let r: SendGoalResponse =
            call(&self.session, &self.client, &self.keys[0], &req, CALL_WAIT).await?;
        Ok((goal_id, r.accepted))
    }

    async fn result(&self, goal_id: GoalId) -> Result<GetResultResponse, CallError> {
        let req = GetResultRequest { goal_id };
        call(
            &self.session,
            &self.client,
            &self.keys[1],
            &req,
            RESULT_WAIT,
        )
        .await
    }

    async fn cancel(&self, goal_id: GoalId) {
        let req = CancelGoalRequest {
            goal_info: GoalInfo {
                goal_id,
                stamp: Time::default(),
            },
        };
        let r: Result<super::action::CancelGoalResponse, CallError> =
            call(&self.session, &self.client, &self.keys[2], &req, CALL_WAIT).await;
        if let Err(e) = r {
            tracing::warn!("cancelling a goal of robot `{}`: {e}", self.robot);
        }
    }
}

/// The [`Action`] of every `ros2` place of a plan, over Zenoh.
#[derive(Debug, Clone)]
pub struct ZenohPlaces {
    servers: Arc<HashMap<PlaceId, String>>,
    args: Arc<HashMap<PlaceId, PlaceArgs>>,
    links: Arc<HashMap<(String, String), Arc<RobotLink>>>,
}

impl ZenohPlaces {
    /// The action for places `servers` (place → server name) with their `args` over `links`
    /// (server, link).
    pub fn new(
        servers: HashMap<PlaceId, String>,
        args: HashMap<PlaceId, PlaceArgs>,
        links: Vec<(String, Arc<RobotLink>)>,
    ) -> Self {
        ZenohPlaces {
            servers: Arc::new(servers),
            args: Arc::new(args),
            links: Arc::new(
                links
                    .into_iter()
                    .map(|(server, l)| ((l.robot.clone(), server), l))
                    .collect(),
            ),
        }
    }
}

impl Action for ZenohPlaces {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let (server, robot) = match server_and_robot(&self.servers, &ctx) {
            Ok(it) => it,
            Err(m) => return Box::pin(async move { Outcome::Failed(m) }),
        };
        let Some(link) = self.links.get(&(robot.to_string(), server.clone())) else {
            let m = format!("robot `{robot}` has no link to server `{server}`");
            return Box::pin(async move { Outcome::Failed(m) });
        };
        let goal = goal(&ctx, self.args.get(&ctx.place));
        Box::pin(exec(Arc::clone(link), goal, ctx))
    }
}

impl CancelGoal for RobotLink {
    type Id = GoalId;

    async fn send_cancel(self: Arc<Self>, id: GoalId) {
        self.cancel(id).await
    }
}

enum Ended {
    Result(Result<GetResultResponse, GoalError>),
    Lost,
    Cancel,
}

async fn exec(link: Arc<RobotLink>, goal: ExecPlaceGoal, ctx: ActionContext) -> Outcome {
    let robot = link.robot.clone();
    let lost_msg = || format!("robot `{robot}` lost (its liveliness token is gone)");
    let mut live = link.liveness.clone();
    if *live.borrow() == Liveness::Lost {
        return Outcome::Failed(lost_msg());
    }
    let guard = GoalGuard::new(Arc::clone(&link));
    let work = async {
        let (id, accepted) = link
            .send_goal_until_back(&goal)
            .await
            .map_err(|e| GoalError::Send(robot.clone(), e))?;
        if !accepted {
            return Err(GoalError::Rejected(robot.clone()));
        }
        guard.set(Some(id));
        link.result_until_back(id)
            .await
            .map_err(|e| GoalError::Result(robot.clone(), e))
    };
    let ended = tokio::select! {
        r = work => Ended::Result(r),
        _ = live.wait_for(|s| *s == Liveness::Lost) => Ended::Lost,
        _ = ctx.cancel.cancelled() => Ended::Cancel,
    };
    match ended {
        Ended::Result(r) => {
            guard.set(None);
            match r {
                Ok(r) if r.status == STATUS_SUCCEEDED => succeeded(&robot, &r.result, &ctx),
                Ok(r) => Outcome::Failed(format!(
                    "robot `{robot}` ended the goal with status {}: {}",
                    r.status, r.result.message
                )),
                Err(e) => Outcome::Failed(e.to_string()),
            }
        }
        Ended::Lost => {
            guard.set(None);
            Outcome::Failed(lost_msg())
        }
        Ended::Cancel => {
            if let Some(id) = guard.take() {
                link.cancel(id).await;
            }
            Outcome::Cancelled
        }
    }
}
