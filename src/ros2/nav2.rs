//! Nav2: `nav2_msgs/action/NavigateToPose` ([`super::msgs::nav2`]) to
//! `/<robot>/navigate_to_pose`, the action a ROS 2 robot running Nav2 moves with.
//!
//! - Real robots: a `ros2` place with `server = "navigate_to_pose"` and a `target` sends its
//!   agents' robots there ([`navigate`], called by [`super::remote_place`]); the
//!   supervisor waits for each robot's Nav2 server at start and follows its presence.
//! - Simulated robots (`run --robots N --ros2`, feature `sim`, [`sim`]): every `goto L` of
//!   the built-in actions goes as a goal to `L`'s pose, and the world serves the action for
//!   each robot and publishes its pose as `geometry_msgs/PoseStamped` on `/<robot>/pose`.
//! - The same plan on real robots (`run --robots N --nav2`): the same goals go to robots
//!   that run Nav2; a mirror world (`crate::world::World::spawn_mirror`) keeps the queues
//!   and draws of the built-in actions and shows each robot at its feedback's pose.
//!   `plan-runner sim-nav2` serves simulated robots as such a fleet from a process of its own.
//!
//! ```text
//! ros2 place (navigate_to_pose) ─┐
//! SimAction `goto L` ────────────┴▶ navigate() ──DDS──▶ /<robot>/navigate_to_pose
//!                                                      (Nav2, or SimNav2 ▶ WorldHandle::drive)
//! ```
//!
//! - succeeded → the step is done (a Nav2 place lets the policy decide); aborted, rejected
//!   → `Failed("Nav2 Aborted: error 9000 …")`, and the place's `on_failure` decides;
//! - the step given up (run stopped, place timeout) → the goal is cancelled.

use std::sync::Arc;
use std::time::Duration;

use futures::StreamExt;
use ros2_client::action::{ActionClientQosPolicies, ActionServerQosPolicies, GoalStatusEnum};
use ros2_client::qos::{Durability, History};
use ros2_client::{ActionClient, Node, QosProfile};

use super::Ros2Error;
use super::config::DdsConfig;
use super::msgs::PoseStamped;
use super::msgs::nav2::{
    ACTION, NavigateToPoseFeedback, NavigateToPoseGoal, NavigateToPoseResult, navigate_to_pose_type,
};

#[cfg(feature = "sim")]
mod sim;
#[cfg(feature = "sim")]
pub use sim::{AT_LOCATION, Nav2Goals, Nav2Navigator, SimNav2};

/// How long a cancel request may take.
const CANCEL_WAIT: Duration = Duration::from_secs(1);

/// Why a `NavigateToPose` goal did not end with the robot there.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
#[non_exhaustive]
pub enum Nav2Error {
    /// The goal request could not be sent or was not answered (DDS).
    #[error("/{robot}/{ACTION}: sending the goal: {reason}")]
    Send {
        /// The robot.
        robot: String,
        /// ros2-client's error.
        reason: String,
    },
    /// The server refused the goal.
    #[error("/{robot}/{ACTION}: goal rejected")]
    Rejected {
        /// The robot.
        robot: String,
    },
    /// The result request failed (DDS).
    #[error("/{robot}/{ACTION}: result: {reason}")]
    Result {
        /// The robot.
        robot: String,
        /// ros2-client's error.
        reason: String,
    },
    /// The feedback stream ended before the result came.
    #[error("/{robot}/{ACTION}: feedback ended")]
    FeedbackEnded {
        /// The robot.
        robot: String,
    },
    /// The goal ended other than succeeded: Nav2's status, error code and message.
    #[error("Nav2 {status}: error {code} {message}")]
    Ended {
        /// The goal's final status (`Aborted`, `Canceled`, …).
        status: String,
        /// Nav2's `error_code`.
        code: u16,
        /// Nav2's `error_msg`.
        message: String,
    },
    /// The step was given up and the goal cancelled.
    #[error("cancelled")]
    Cancelled,
}

/// A `NavigateToPose` action client.
pub type Nav2Client =
    ActionClient<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>;

pub(crate) fn service_qos() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepAll)
}

pub(crate) fn feedback_qos() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::Volatile)
        .history(History::KeepLast { depth: 1 })
}

pub(crate) fn status_qos() -> QosProfile {
    QosProfile::publisher_default()
        .durability(Durability::TransientLocal)
        .history(History::KeepLast { depth: 1 })
}

/// The QoS of an action server that gspn's clients match — a robot's `ExecPlace`
/// (`super::robot`) or a simulated `NavigateToPose`: services reliable and keep-all,
/// feedback keep-last 1, status transient-local.
pub fn server_qos() -> ActionServerQosPolicies {
    ActionServerQosPolicies {
        goal_service: service_qos(),
        result_service: service_qos(),
        cancel_service: service_qos(),
        feedback_publisher: feedback_qos(),
        status_publisher: status_qos(),
    }
}

/// The name `/<ns>/<robot>/<leaf>` under `node`'s run namespace.
pub(crate) fn robot_name(
    node: &Node,
    robot: &str,
    leaf: &str,
) -> Result<ros2_client::Name, Ros2Error> {
    super::names::action(node, robot, leaf)
}

/// A client of `robot`'s `/<robot>/navigate_to_pose` under `node`'s run namespace.
pub fn client(node: &mut Node, cfg: &DdsConfig, robot: &str) -> Result<Nav2Client, Ros2Error> {
    let qos = ActionClientQosPolicies {
        goal_service: service_qos(),
        result_service: service_qos(),
        cancel_service: service_qos(),
        feedback_subscription: feedback_qos(),
        status_subscription: status_qos(),
    };
    let name = robot_name(node, robot, ACTION)?;
    node.create_action_client::<NavigateToPoseGoal, NavigateToPoseResult, NavigateToPoseFeedback>(
        cfg.service_mapping,
        &name,
        &navigate_to_pose_type(),
        qos,
    )
    .map_err(Ros2Error::dds)
}

/// Waits until `client`'s goal, result and cancel services are matched with a server.
pub async fn wait_for_server(client: &Nav2Client, node: &Node) {
    client.goal_client().wait_for_service(node).await;
    client.result_client().wait_for_service(node).await;
    client.cancel_client().wait_for_service(node).await;
}

/// Cancels the goal it holds when dropped before the goal ended (the step was given up).
struct CancelOnDrop {
    client: Arc<Nav2Client>,
    goal: Option<ros2_client::action::GoalId>,
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if let Some(id) = self.goal.take() {
            let client = Arc::clone(&self.client);
            tokio::spawn(async move {
                let cancel =
                    client.async_cancel_goal(id, ros2_client::builtin_interfaces::Time::ZERO);
                let _ = tokio::time::timeout(CANCEL_WAIT, cancel).await;
            });
        }
    }
}

/// Sends `robot` (through its `client`) to `pose` and waits for the result: `Ok` when Nav2
/// says it arrived (`SUCCEEDED`), else why not (rejected, aborted with its error code and
/// message, cancelled). When `stop` resolves first, the goal is cancelled (the cancel
/// request answered, or [`CANCEL_WAIT`]) and the answer is `Err("cancelled")`; dropping the
/// future cancels the goal too, in a task of its own. Each feedback's `current_pose` goes
/// to `on_pose` (a mirror world shows the robot there). One goal at a time per client
/// (ros2-client's calls drop responses meant for a concurrent call).
pub async fn navigate(
    client: Arc<Nav2Client>,
    robot: &str,
    pose: PoseStamped,
    stop: impl std::future::Future<Output = ()>,
    mut on_pose: impl FnMut(&PoseStamped),
) -> Result<(), Nav2Error> {
    let goal = NavigateToPoseGoal {
        pose,
        behavior_tree: String::new(),
    };
    let (id, response) = client
        .async_send_goal(goal)
        .await
        .map_err(|e| Nav2Error::Send {
            robot: robot.to_string(),
            reason: format!("{e:?}"),
        })?;
    if !response.accepted {
        return Err(Nav2Error::Rejected {
            robot: robot.to_string(),
        });
    }
    let mut guard = CancelOnDrop {
        client: Arc::clone(&client),
        goal: Some(id),
    };
    // Feedback is read for the pose and so the reader does not fill up; the result says
    // whether the robot arrived.
    let feedback = client.feedback_stream(id).for_each(|f| {
        if let Ok(f) = f {
            on_pose(&f.current_pose);
        }
        async {}
    });
    let result = client.async_request_result(id);
    tokio::pin!(feedback);
    let (status, result) = tokio::select! {
        r = result => r.map_err(|e| Nav2Error::Result {
            robot: robot.to_string(),
            reason: format!("{e:?}"),
        })?,
        _ = &mut feedback => return Err(Nav2Error::FeedbackEnded { robot: robot.to_string() }),
        _ = stop => {
            let cancel = client.async_cancel_goal(id, ros2_client::builtin_interfaces::Time::ZERO);
            let _ = tokio::time::timeout(CANCEL_WAIT, cancel).await;
            guard.goal = None;
            return Err(Nav2Error::Cancelled);
        }
    };
    guard.goal = None;
    match status {
        GoalStatusEnum::Succeeded => Ok(()),
        other => Err(Nav2Error::Ended {
            status: format!("{other:?}"),
            code: result.error_code,
            message: result.error_msg,
        }),
    }
}
