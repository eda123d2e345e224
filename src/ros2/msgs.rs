//! The `gspn_msgs` interfaces (`ros2/gspn_msgs/`) as Rust types, serialised by ros2-client
//! in the same CDR layout as the ROS 2 generated code, under the DDS type names ROS 2 gives
//! them (`gspn_msgs::msg::dds_::Firing_`, …). Interfaces v2 ([`INTERFACES_VERSION`]):
//! `tests/ros2/interfaces.rs` parses the `.msg`/`.action` files and checks them against these
//! types and the Python robot's, so the copies cannot drift apart.

use ros2_client::{ActionTypeName, Message, MessageTypeName};
use serde::{Deserialize, Serialize};

pub mod common;
pub mod nav2;
pub mod schema;

pub use common::{Header, KeyValue, MAP_FRAME, Point, Pose, PoseStamped, Quaternion, Time};

/// The ROS 2 package of the interfaces.
pub const PACKAGE: &str = "gspn_msgs";
/// Topic of [`Firing`]s.
pub const FIRINGS_TOPIC: &str = "/gspn/firings";
/// Topic of the [`Marking`].
pub const MARKING_TOPIC: &str = "/gspn/marking";
/// Topic of the robots' [`Heartbeat`]s.
pub const HEARTBEAT_TOPIC: &str = "/gspn/heartbeat";
/// Topic of the supervisor's own [`Heartbeat`]s (`robot` = `supervisor`): robots leave when
/// they stop.
pub const SUPERVISOR_HEARTBEAT_TOPIC: &str = "/gspn/supervisor_heartbeat";
/// Topic of the supervisor's [`RunState`].
pub const RUN_TOPIC: &str = "/gspn/run";
/// Topic of the live monitor's [`Drift`]s (`run --monitor`).
pub const DRIFT_TOPIC: &str = "/gspn/drift";

/// The version of the interfaces, as `ros2/gspn_msgs/package.xml` says it.
pub const INTERFACES_VERSION: &str = "2.0.0";

/// `gspn_msgs/msg/Firing`: one firing, on [`FIRINGS_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Firing {
    /// When the supervisor published it (no frame).
    pub header: Header,
    /// Model time of the firing.
    pub model_time: f64,
    /// Firings so far, this one included (1, 2, 3, … without gaps).
    pub seq: u64,
    /// The transition's name.
    pub transition: String,
    /// Tokens per place after the firing, in the net's place order.
    pub marking: Vec<u32>,
    /// Robots whose agents the firing consumed.
    pub robots: Vec<String>,
}
impl Message for Firing {}

/// `gspn_msgs/msg/Marking`: the current marking, on [`MARKING_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Marking {
    /// When the supervisor published it (no frame).
    pub header: Header,
    /// Model time of the marking (that of the last firing).
    pub model_time: f64,
    /// Firings so far (the `seq` of the last [`Firing`]; 0 = the initial marking).
    pub seq: u64,
    /// Place names, in the net's order.
    pub places: Vec<String>,
    /// Tokens per place, same order.
    pub tokens: Vec<u32>,
}
impl Message for Marking {}

/// `gspn_msgs/msg/Heartbeat`: a robot process is alive, on [`HEARTBEAT_TOPIC`] (optional:
/// robots without one are watched through DDS discovery).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Heartbeat {
    /// The robot's id.
    pub robot: String,
    /// Heartbeats sent before this one.
    pub seq: u64,
}
impl Message for Heartbeat {}

/// `gspn_msgs/msg/RunState`: the supervisor's run is [`RunState::RUNNING`] or
/// [`RunState::OVER`], on [`RUN_TOPIC`] (robots leave when it is over).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunState {
    /// [`RunState::RUNNING`] or [`RunState::OVER`].
    pub state: u8,
    /// Why the run stopped (`max_firings`, `failure`, …); empty while running.
    pub stopped: String,
    /// Firings so far.
    pub firings: u64,
}
impl Message for RunState {}

impl RunState {
    /// [`RunState::state`] of a run that has started.
    pub const RUNNING: u8 = 1;
    /// [`RunState::state`] of a run that has ended.
    pub const OVER: u8 = 2;
}

/// `gspn_msgs/msg/Drift`: the live monitor found the run drifting from the model, on
/// [`DRIFT_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Drift {
    /// When the supervisor published it (no frame).
    pub header: Header,
    /// Model time at which the drift was found.
    pub model_time: f64,
    /// The transition whose rate drifted (empty for a place).
    pub transition: String,
    /// The place whose mean tokens drifted (empty for a transition).
    pub place: String,
    /// The observation over the monitor's window.
    pub observed: f64,
    /// The model's value.
    pub predicted: f64,
    /// The 95% interval of the observation: low end.
    pub interval_low: f64,
    /// High end.
    pub interval_high: f64,
    /// Sample size: firings (a rate) or batches (mean tokens).
    pub n: u64,
    /// The test's p-value.
    pub p_value: f64,
    /// One line for people.
    pub text: String,
}
impl Message for Drift {}

/// `gspn_msgs/action/ExecPlace` goal: run the action of `place` for `agent`, with the
/// place's arguments from the plan.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ExecPlaceGoal {
    /// The action place, by name.
    pub place: String,
    /// The agent's id.
    pub agent: u64,
    /// Whether [`ExecPlaceGoal::target`] means anything.
    pub has_target: bool,
    /// The place's target pose (frame `map`), e.g. where `goto` drives.
    pub target: PoseStamped,
    /// The place's other arguments.
    pub args: Vec<KeyValue>,
}
impl Message for ExecPlaceGoal {}

/// `gspn_msgs/action/ExecPlace` result.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExecPlaceResult {
    /// [`ExecPlaceResult::FIRE`], [`ExecPlaceResult::DECIDE`], [`ExecPlaceResult::FAILED`]
    /// or [`ExecPlaceResult::CANCELLED`].
    pub outcome: u8,
    /// With `FIRE`: the transition to fire (an output of the place).
    pub transition: String,
    /// How the action went, for people.
    pub message: String,
}
impl Message for ExecPlaceResult {}

impl ExecPlaceResult {
    /// Fire [`ExecPlaceResult::transition`].
    pub const FIRE: u8 = 0;
    /// Let the supervisor's policy choose.
    pub const DECIDE: u8 = 1;
    /// The action failed: the place's `on_failure` applies.
    pub const FAILED: u8 = 2;
    /// The goal was cancelled.
    pub const CANCELLED: u8 = 3;

    /// Fire `transition`, or let the policy decide when it is empty.
    pub fn fire_or_decide(transition: String, message: &str) -> ExecPlaceResult {
        let outcome = if transition.is_empty() {
            ExecPlaceResult::DECIDE
        } else {
            ExecPlaceResult::FIRE
        };
        ExecPlaceResult {
            outcome,
            transition,
            message: message.to_string(),
        }
    }

    /// The goal was cancelled.
    pub fn cancelled() -> ExecPlaceResult {
        ExecPlaceResult {
            outcome: ExecPlaceResult::CANCELLED,
            transition: String::new(),
            message: "cancelled".into(),
        }
    }
}

/// `gspn_msgs/action/ExecPlace` feedback.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct ExecPlaceFeedback {
    /// Seconds since the robot started the goal.
    pub elapsed: f64,
}
impl Message for ExecPlaceFeedback {}

/// DDS type of [`Firing`]: `gspn_msgs::msg::dds_::Firing_`.
pub fn firing_type() -> MessageTypeName {
    MessageTypeName::new(PACKAGE, "Firing")
}

/// DDS type of [`Marking`]: `gspn_msgs::msg::dds_::Marking_`.
pub fn marking_type() -> MessageTypeName {
    MessageTypeName::new(PACKAGE, "Marking")
}

/// DDS type of [`Heartbeat`]: `gspn_msgs::msg::dds_::Heartbeat_`.
pub fn heartbeat_type() -> MessageTypeName {
    MessageTypeName::new(PACKAGE, "Heartbeat")
}

/// DDS type of [`Drift`]: `gspn_msgs::msg::dds_::Drift_`.
pub fn drift_type() -> MessageTypeName {
    MessageTypeName::new(PACKAGE, "Drift")
}

/// DDS type of [`RunState`]: `gspn_msgs::msg::dds_::RunState_`.
pub fn run_state_type() -> MessageTypeName {
    MessageTypeName::new(PACKAGE, "RunState")
}

/// The action type `gspn_msgs/action/ExecPlace`.
pub fn exec_place_type() -> ActionTypeName {
    ActionTypeName::new(PACKAGE, "ExecPlace")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dds_type_names_are_the_ones_ros2_generates() {
        assert_eq!(
            firing_type().dds_msg_type(),
            "gspn_msgs::msg::dds_::Firing_"
        );
        assert_eq!(
            marking_type().dds_msg_type(),
            "gspn_msgs::msg::dds_::Marking_"
        );
        assert_eq!(
            heartbeat_type().dds_msg_type(),
            "gspn_msgs::msg::dds_::Heartbeat_"
        );
        assert_eq!(
            run_state_type().dds_msg_type(),
            "gspn_msgs::msg::dds_::RunState_"
        );
    }
}
