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

/// `NavigateToPose` feedback: where the robot is and how far it has left. It reads the
/// feedback of every distribution: Jazzy's and Kilted's end after `distance_remaining` (the
/// two tracking errors then read as 0).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
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

impl<'de> Deserialize<'de> for NavigateToPoseFeedback {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{Error, SeqAccess, Visitor};
        struct Fields;
        impl<'de> Visitor<'de> for Fields {
            type Value = NavigateToPoseFeedback;

            fn expecting(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
                f.write_str("NavigateToPose feedback")
            }

            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
                fn next<'de, A: SeqAccess<'de>, T: Deserialize<'de>>(
                    seq: &mut A,
                    k: usize,
                ) -> Result<T, A::Error> {
                    seq.next_element()?
                        .ok_or_else(|| A::Error::invalid_length(k, &"7 fields"))
                }
                let current_pose = next(&mut seq, 0)?;
                let navigation_time = next(&mut seq, 1)?;
                let estimated_time_remaining = next(&mut seq, 2)?;
                let number_of_recoveries = next(&mut seq, 3)?;
                let distance_remaining = next(&mut seq, 4)?;
                // New in Lyrical: a Jazzy or Kilted message ends here (the CDR reader then
                // fails for want of bytes, which means "absent").
                let mut newer = || seq.next_element::<f32>().ok().flatten().unwrap_or(0.0);
                let position_tracking_error = newer();
                let heading_tracking_error = newer();
                Ok(NavigateToPoseFeedback {
                    current_pose,
                    navigation_time,
                    estimated_time_remaining,
                    number_of_recoveries,
                    distance_remaining,
                    position_tracking_error,
                    heading_tracking_error,
                })
            }
        }
        const FIELDS: &[&str] = &[
            "current_pose",
            "navigation_time",
            "estimated_time_remaining",
            "number_of_recoveries",
            "distance_remaining",
            "position_tracking_error",
            "heading_tracking_error",
        ];
        d.deserialize_struct("NavigateToPoseFeedback", FIELDS, Fields)
    }
}

/// The action type `nav2_msgs/action/NavigateToPose`.
pub fn navigate_to_pose_type() -> ActionTypeName {
    ActionTypeName::new(PACKAGE, "NavigateToPose")
}

#[cfg(test)]
mod tests {
    use super::*;
    use byteorder::LittleEndian;
    use rustdds::cdr_encoding::{from_bytes, to_vec};

    #[test]
    fn feedback_of_jazzy_and_kilted_reads_without_the_tracking_errors() {
        let full = NavigateToPoseFeedback {
            current_pose: PoseStamped::on_map(3.25, -1.5, 0.0),
            navigation_time: Duration { sec: 4, nanosec: 5 },
            estimated_time_remaining: Duration { sec: 6, nanosec: 7 },
            number_of_recoveries: 2,
            distance_remaining: 8.5,
            position_tracking_error: 0.25,
            heading_tracking_error: 0.125,
        };
        let bytes = to_vec::<_, LittleEndian>(&full).unwrap();
        let (back, _) = from_bytes::<NavigateToPoseFeedback, LittleEndian>(&bytes).unwrap();
        assert_eq!(back, full);
        // Jazzy/Kilted: the same bytes without the last two float32.
        let short = &bytes[..bytes.len() - 8];
        let (old, _) = from_bytes::<NavigateToPoseFeedback, LittleEndian>(short).unwrap();
        assert_eq!(
            old,
            NavigateToPoseFeedback {
                position_tracking_error: 0.0,
                heading_tracking_error: 0.0,
                ..full.clone()
            }
        );
        // Shorter than Jazzy's is refused.
        assert!(
            from_bytes::<NavigateToPoseFeedback, LittleEndian>(&bytes[..bytes.len() - 12]).is_err()
        );
    }
}
