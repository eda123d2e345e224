//! Nav2's `nav2_msgs/action/NavigateToPose`, the action a ROS 2 robot running Nav2 moves
//! with, as Nav2 defines it (ros-navigation/navigation2, `nav2_msgs/action/
//! NavigateToPose.action` on branches `main` and `lyrical` at commit a3a97043, August 2026):
//! fields in the file's order, so the CDR is the generated code's. Jazzy and Kilted have
//! the same goal and result; their feedback stops before `position_tracking_error`.

use ros2_client::{ActionTypeName, Message};
use serde::{Deserialize, Serialize};

use super::common::PoseStamped;

/// The package.
pub const PACKAGE: &str = "nav2_msgs";
/// The action's name under a robot's namespace: `/<robot>/navigate_to_pose`.
pub const ACTION: &str = "navigate_to_pose";

/// `builtin_interfaces/Duration`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Duration {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Duration {
    /// `d`, saturated to what the message can hold.
    pub fn from_std(d: std::time::Duration) -> Duration {
        Duration {
            sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX),
            nanosec: d.subsec_nanos(),
        }
    }
}

/// `NavigateToPose` goal: drive to `pose`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NavigateToPoseGoal {
    /// Where to, in the frame of its header (`map`).
    pub pose: PoseStamped,
    /// The behaviour tree to use (empty: the navigator's default).
    pub behavior_tree: String,
}
impl Message for NavigateToPoseGoal {}

/// `NavigateToPose` result: an error code ([`NavigateToPoseResult::NONE`] when it arrived)
/// and a message.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct NavigateToPoseResult {
    /// One of the constants below.
    pub error_code: u16,
    /// What went wrong, for people.
    pub error_msg: String,
}
impl Message for NavigateToPoseResult {}

impl NavigateToPoseResult {
    /// No error.
    pub const NONE: u16 = 0;
    /// The goal was rejected.
    pub const GOAL_REJECTED: u16 = 1;
    /// Sending the goal failed.
    pub const SEND_GOAL_FAILURE: u16 = 2;
    /// Any other failure.
    pub const UNKNOWN: u16 = 9000;
    /// The behaviour tree could not be loaded.
    pub const FAILED_TO_LOAD_BEHAVIOR_TREE: u16 = 9001;
    /// A transform was missing.
    pub const TF_ERROR: u16 = 9002;
    /// Navigation timed out.
    pub const TIMEOUT: u16 = 9003;
}

/// `NavigateToPose` feedback: where the robot is and how far it has left.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct NavigateToPoseFeedback {
    /// The robot's pose now.
    pub current_pose: PoseStamped,
    /// Time since the goal started.
    pub navigation_time: Duration,
    /// The navigator's estimate of the time left.
    pub estimated_time_remaining: Duration,
    /// Recovery behaviours run so far.
    pub number_of_recoveries: i16,
    /// Metres left along the path.
    pub distance_remaining: f32,
    /// Metres off the path.
    pub position_tracking_error: f32,
    /// Radians off the path's heading.
    pub heading_tracking_error: f32,
}
impl Message for NavigateToPoseFeedback {}

/// The action type `nav2_msgs/action/NavigateToPose`.
pub fn navigate_to_pose_type() -> ActionTypeName {
    ActionTypeName::new(PACKAGE, "NavigateToPose")
}
