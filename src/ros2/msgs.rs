//! The `gspn_msgs` interfaces (`ros2/gspn_msgs/`) as Rust types, serialised by ros2-client
//! in the same CDR layout as the ROS 2 generated code, under the DDS type names ROS 2 gives
//! them (`gspn_msgs::msg::dds_::Firing_`, …).

use ros2_client::{ActionTypeName, Message, MessageTypeName};
use serde::{Deserialize, Serialize};

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
/// Topic of the live monitor's drifts (`run --monitor`), as JSON in a [`StringMsg`].
pub const DRIFT_TOPIC: &str = "/gspn/drift";

/// `builtin_interfaces/Time`: seconds and nanoseconds since the Unix epoch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds within the second.
    pub nanosec: u32,
}

impl Time {
    /// The wall clock now.
    pub fn now() -> Time {
        let d = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        Time {
            sec: i32::try_from(d.as_secs()).unwrap_or(i32::MAX),
            nanosec: d.subsec_nanos(),
        }
    }

    /// Nanoseconds since the Unix epoch.
    pub fn as_nanos(&self) -> i128 {
        i128::from(self.sec) * 1_000_000_000 + i128::from(self.nanosec)
    }
}

/// `gspn_msgs/msg/Firing`: one firing, on [`FIRINGS_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Firing {
    /// Firings so far, this one included (1, 2, 3, … without gaps).
    pub seq: u64,
    /// The transition's name.
    pub transition: String,
    /// Tokens per place after the firing, in the net's place order.
    pub marking: Vec<u32>,
    /// Robots whose agents the firing consumed.
    pub robots: Vec<String>,
    /// When the supervisor published it.
    pub stamp: Time,
}
impl Message for Firing {}

/// `gspn_msgs/msg/Marking`: the current marking, on [`MARKING_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Marking {
    /// Firings so far (the `seq` of the last [`Firing`]; 0 = the initial marking).
    pub seq: u64,
    /// Place names, in the net's order.
    pub places: Vec<String>,
    /// Tokens per place, same order.
    pub tokens: Vec<u32>,
}
impl Message for Marking {}

/// `gspn_msgs/msg/Heartbeat`: a robot process is alive, on [`HEARTBEAT_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Heartbeat {
    /// The robot's id.
    pub robot: String,
    /// Heartbeats sent before this one.
    pub seq: u64,
}
impl Message for Heartbeat {}

/// `gspn_msgs/msg/RunState`: the supervisor's run is `running` or `over`, on [`RUN_TOPIC`]
/// (robots leave when it is over).
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct RunState {
    /// `running` or `over`.
    pub state: String,
    /// Why the run stopped (`max_firings`, `failure`, …); empty while running.
    pub stopped: String,
    /// Firings so far.
    pub firings: u64,
}
impl Message for RunState {}

/// `std_msgs/msg/String`: one JSON document, on [`DRIFT_TOPIC`].
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StringMsg {
    /// The text.
    pub data: String,
}
impl Message for StringMsg {}

/// DDS type of [`StringMsg`]: `std_msgs::msg::dds_::String_`.
pub fn string_type() -> MessageTypeName {
    MessageTypeName::new("std_msgs", "String")
}

/// [`RunState::state`] of a run that has started.
pub const RUN_RUNNING: &str = "running";
/// [`RunState::state`] of a run that has ended.
pub const RUN_OVER: &str = "over";

/// `gspn_msgs/action/ExecPlace` goal: run the action of `place` for `agent`.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExecPlaceGoal {
    /// The action place, by name.
    pub place: String,
    /// The agent, its id in decimal.
    pub agent: String,
}
impl Message for ExecPlaceGoal {}

/// `gspn_msgs/action/ExecPlace` result.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct ExecPlaceResult {
    /// The transition to fire; empty = let the policy decide.
    pub transition: String,
    /// How it went, for people.
    pub outcome: String,
}
impl Message for ExecPlaceResult {}

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

    #[test]
    fn time_counts_nanoseconds() {
        let t = Time { sec: 2, nanosec: 5 };
        assert_eq!(t.as_nanos(), 2_000_000_005);
        assert!(Time::now().sec > 1_700_000_000);
    }
}
