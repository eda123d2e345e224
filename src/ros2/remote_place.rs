//! The supervisor's side of a `ros2` place: an [`Action`] that sends an ExecPlace goal to
//! the agent's robot at `/<robot>/<server>` and turns the result into an [`Outcome`].
//!
//! - result `transition` → [`Outcome::Fire`] (an unknown name fails), empty →
//!   [`Outcome::Decide`]; an aborted or rejected goal → [`Outcome::Failed`];
//! - the run being stopped → the goal is cancelled on the robot, [`Outcome::Cancelled`];
//! - the place's timeout (applied by the runtime, which drops the action) → the goal is
//!   cancelled on the robot too (a drop guard sends the cancel request);
//! - the robot's heartbeats stop ([`Liveness::Lost`]) → `Failed("robot … lost")`, and the
//!   plan's failure policy decides.
//!
//! One goal at a time per robot and server: ros2-client's service client drops responses
//! meant for a concurrent call, so calls through one client are serialised.

use std::collections::HashMap;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use ros2_client::action::{GoalId, GoalStatusEnum};
use ros2_client::builtin_interfaces;
use ros2_client::dds::ActionClient;
use tokio::sync::watch;

use super::heartbeat::Liveness;
use super::msgs::{ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult};
use crate::net::PlaceId;
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome};

/// The ExecPlace action client of one robot's server.
pub type ExecPlaceClient = ActionClient<ExecPlaceGoal, ExecPlaceResult, ExecPlaceFeedback>;

/// How long a cancel request may take before the action gives up waiting for its answer.
const CANCEL_WAIT: Duration = Duration::from_secs(1);

/// One robot's ExecPlace server as the supervisor reaches it.
pub struct RobotLink {
    /// The robot.
    pub robot: String,
    client: tokio::sync::Mutex<ExecPlaceClient>,
    liveness: watch::Receiver<Liveness>,
}

impl std::fmt::Debug for RobotLink {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("RobotLink")
            .field("robot", &self.robot)
            .finish()
    }
}

impl RobotLink {
    /// A link through `client`, failing goals when `liveness` turns [`Liveness::Lost`].
    pub fn new(
        robot: String,
        client: ExecPlaceClient,
        liveness: watch::Receiver<Liveness>,
    ) -> RobotLink {
        RobotLink {
            robot,
            client: tokio::sync::Mutex::new(client),
            liveness,
        }
    }

    /// Waits until the robot's goal, result and cancel services are matched (needs the
    /// node's spinner running).
    pub async fn wait_for_server(&self, node: &ros2_client::Node) {
        let c = self.client.lock().await;
        c.goal_client().wait_for_service(node).await;
        c.result_client().wait_for_service(node).await;
        c.cancel_client().wait_for_service(node).await;
    }
}

/// The [`Action`] of every `ros2` place of a plan.
#[derive(Debug, Clone)]
pub struct RemotePlaces {
    /// Server name of each `ros2` place.
    servers: Arc<HashMap<PlaceId, String>>,
    /// Links by (robot, server).
    links: Arc<HashMap<(String, String), Arc<RobotLink>>>,
}

impl RemotePlaces {
    /// The action for places `servers` (place → server name) over `links`.
    pub fn new(servers: HashMap<PlaceId, String>, links: Vec<(String, Arc<RobotLink>)>) -> Self {
        RemotePlaces {
            servers: Arc::new(servers),
            links: Arc::new(
                links
                    .into_iter()
                    .map(|(server, l)| ((l.robot.clone(), server), l))
                    .collect(),
            ),
        }
    }
}

impl Action for RemotePlaces {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let Some(server) = self.servers.get(&ctx.place) else {
            let m = format!("place `{}` is not a ros2 place", ctx.place_name());
            return Box::pin(async move { Outcome::Failed(m) });
        };
        let Some(robot) = ctx.robot.clone() else {
            let m = format!(
                "agent {} in ros2 place `{}` has no robot (give the plan `robots = [...]`)",
                ctx.agent.0,
                ctx.place_name()
            );
            return Box::pin(async move { Outcome::Failed(m) });
        };
        let Some(link) = self.links.get(&(robot.to_string(), server.clone())) else {
            let m = format!("robot `{robot}` has no link to server `{server}`");
            return Box::pin(async move { Outcome::Failed(m) });
        };
        Box::pin(exec(Arc::clone(link), ctx))
    }
}

/// Cancels the goal on the robot if the action is dropped before the goal ended (the
/// runtime's timeout drops it).
struct GoalGuard {
    link: Arc<RobotLink>,
    goal: Mutex<Option<GoalId>>,
}

impl GoalGuard {
    fn set(&self, g: Option<GoalId>) {
        if let Ok(mut s) = self.goal.lock() {
            *s = g;
        }
    }
    fn take(&self) -> Option<GoalId> {
        self.goal.lock().ok().and_then(|mut s| s.take())
    }
}

impl Drop for GoalGuard {
    fn drop(&mut self) {
        if let Some(id) = self.take() {
            let link = Arc::clone(&self.link);
            if let Ok(rt) = tokio::runtime::Handle::try_current() {
                rt.spawn(async move {
                    let c = link.client.lock().await;
                    let _ = tokio::time::timeout(
                        CANCEL_WAIT,
                        c.async_cancel_goal(id, builtin_interfaces::Time::ZERO),
                    )
                    .await;
                });
            }
        }
    }
}

enum Ended {
    Result(Result<(GoalStatusEnum, ExecPlaceResult), String>),
    Lost,
    Cancel,
}

async fn exec(link: Arc<RobotLink>, ctx: ActionContext) -> Outcome {
    let robot = link.robot.clone();
    let lost_msg = || format!("robot `{robot}` lost (its heartbeats stopped)");
    let mut live = link.liveness.clone();
    if *live.borrow() == Liveness::Lost {
        return Outcome::Failed(lost_msg());
    }
    let guard = GoalGuard {
        link: Arc::clone(&link),
        goal: Mutex::new(None),
    };
    let client = tokio::select! {
        c = link.client.lock() => c,
        _ = live.wait_for(|s| *s == Liveness::Lost) => return Outcome::Failed(lost_msg()),
        _ = ctx.cancel.cancelled() => return Outcome::Cancelled,
    };
    let goal = ExecPlaceGoal {
        place: ctx.place_name().to_string(),
        agent: ctx.agent.0.to_string(),
    };
    let work = async {
        let (id, resp) = client
            .async_send_goal(goal)
            .await
            .map_err(|e| format!("sending the goal to robot `{robot}`: {e:?}"))?;
        if !resp.accepted {
            return Err(format!("robot `{robot}` rejected the goal"));
        }
        guard.set(Some(id));
        client
            .async_request_result(id)
            .await
            .map_err(|e| format!("result from robot `{robot}`: {e:?}"))
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
                Ok((GoalStatusEnum::Succeeded, res)) if res.transition.is_empty() => {
                    Outcome::Decide
                }
                Ok((GoalStatusEnum::Succeeded, res)) => ctx.fire(&res.transition),
                Ok((status, res)) => Outcome::Failed(format!(
                    "robot `{robot}` ended the goal {status:?}: {}",
                    res.outcome
                )),
                Err(e) => Outcome::Failed(e),
            }
        }
        Ended::Lost => {
            guard.set(None);
            Outcome::Failed(lost_msg())
        }
        Ended::Cancel => {
            if let Some(id) = guard.take() {
                let _ = tokio::time::timeout(
                    CANCEL_WAIT,
                    client.async_cancel_goal(id, builtin_interfaces::Time::ZERO),
                )
                .await;
            }
            Outcome::Cancelled
        }
    }
}
