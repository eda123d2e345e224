//! The ExecPlace action's services and topics as ROS 2 generates them for any action
//! (`action_msgs`, `unique_identifier_msgs`): the messages in field order, so their CDR is
//! what an rclcpp/rclpy action client or server sends.

use serde::{Deserialize, Serialize};

use crate::ros2::msgs::{ExecPlaceFeedback, ExecPlaceGoal, ExecPlaceResult, Time};

/// `unique_identifier_msgs/msg/UUID`: a goal's id.
pub type GoalId = [u8; 16];

/// `action_msgs/msg/GoalStatus` STATUS_EXECUTING.
pub const STATUS_EXECUTING: i8 = 2;
/// `action_msgs/msg/GoalStatus` STATUS_SUCCEEDED.
pub const STATUS_SUCCEEDED: i8 = 4;
/// `action_msgs/msg/GoalStatus` STATUS_CANCELED.
pub const STATUS_CANCELED: i8 = 5;
/// `action_msgs/msg/GoalStatus` STATUS_ABORTED.
pub const STATUS_ABORTED: i8 = 6;
/// `action_msgs/srv/CancelGoal` ERROR_NONE.
pub const CANCEL_NONE: i8 = 0;
/// `action_msgs/srv/CancelGoal` ERROR_UNKNOWN_GOAL_ID.
pub const CANCEL_UNKNOWN_GOAL: i8 = 2;

/// `ExecPlace_SendGoal_Request`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct SendGoalRequest {
    /// The goal's id, chosen by the client.
    pub goal_id: GoalId,
    /// The goal.
    pub goal: ExecPlaceGoal,
}

/// `ExecPlace_SendGoal_Response`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct SendGoalResponse {
    /// Whether the server took the goal.
    pub accepted: bool,
    /// When it did.
    pub stamp: Time,
}

/// `ExecPlace_GetResult_Request`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetResultRequest {
    /// The goal.
    pub goal_id: GoalId,
}

/// `ExecPlace_GetResult_Response`: answered once the goal has ended.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GetResultResponse {
    /// `STATUS_SUCCEEDED`, `STATUS_CANCELED`, `STATUS_ABORTED`.
    pub status: i8,
    /// The result.
    pub result: ExecPlaceResult,
}

/// `action_msgs/msg/GoalInfo`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalInfo {
    /// The goal.
    pub goal_id: GoalId,
    /// When it was accepted (zero in a cancel request: this goal only).
    pub stamp: Time,
}

/// `action_msgs/srv/CancelGoal_Request`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CancelGoalRequest {
    /// Which goal.
    pub goal_info: GoalInfo,
}

/// `action_msgs/srv/CancelGoal_Response`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct CancelGoalResponse {
    /// `CANCEL_NONE` or why not.
    pub return_code: i8,
    /// The goals now cancelling.
    pub goals_canceling: Vec<GoalInfo>,
}

/// `ExecPlace_FeedbackMessage`: a goal's feedback on the action's feedback topic.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct FeedbackMessage {
    /// The goal.
    pub goal_id: GoalId,
    /// Its feedback.
    pub feedback: ExecPlaceFeedback,
}

/// `action_msgs/msg/GoalStatus`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalStatus {
    /// The goal and when it was accepted.
    pub goal_info: GoalInfo,
    /// `STATUS_EXECUTING`, `STATUS_SUCCEEDED`, …
    pub status: i8,
}

/// `action_msgs/msg/GoalStatusArray`: the goals of a server, on the action's status topic.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct GoalStatusArray {
    /// One per goal.
    pub status_list: Vec<GoalStatus>,
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::zenoh::wire::{decode, encode};

    #[test]
    fn a_send_goal_request_is_the_uuid_then_the_goal() {
        let r = SendGoalRequest {
            goal_id: [1; 16],
            goal: ExecPlaceGoal {
                place: "p".into(),
                agent: 3,
                ..ExecPlaceGoal::default()
            },
        };
        let b = encode(&r);
        assert_eq!(&b[4..20], &[1; 16]);
        // "p\0" with its length 2, then the agent as a u64 aligned at 8 of the body (24).
        assert_eq!(&b[20..26], &[2, 0, 0, 0, b'p', 0]);
        assert_eq!(&b[28..36], &3u64.to_le_bytes());
        assert_eq!(decode::<SendGoalRequest>(&b).unwrap(), r);
    }
}
