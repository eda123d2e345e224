//! The standard ROS 2 messages the `gspn_msgs` interfaces use (`std_msgs/Header`,
//! `geometry_msgs/PoseStamped`, `diagnostic_msgs/KeyValue`), with their fields in ROS 2's
//! order so they serialise to the same CDR as the generated code.

use ros2_client::{Message, MessageTypeName};
use serde::{Deserialize, Serialize};

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

/// `std_msgs/Header`: when (and in which frame) a message was made.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct Header {
    /// Wall-clock time.
    pub stamp: Time,
    /// The coordinate frame (empty for messages that have none).
    pub frame_id: String,
}

impl Header {
    /// Stamped now, in `frame_id`.
    pub fn now(frame_id: &str) -> Header {
        Header {
            stamp: Time::now(),
            frame_id: frame_id.to_string(),
        }
    }
}

/// The frame poses are given in: the map's (as Nav2 expects goals).
pub const MAP_FRAME: &str = "map";

/// `geometry_msgs/Point`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Point {
    /// Metres along x.
    pub x: f64,
    /// Metres along y.
    pub y: f64,
    /// Metres along z.
    pub z: f64,
}

/// `geometry_msgs/Quaternion` (the identity is `w = 1`).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

impl Default for Quaternion {
    fn default() -> Self {
        Quaternion::from_yaw(0.0)
    }
}

impl Quaternion {
    /// A rotation of `yaw` radians about z (a ground robot's heading).
    pub fn from_yaw(yaw: f64) -> Quaternion {
        let (s, c) = (yaw / 2.0).sin_cos();
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: s,
            w: c,
        }
    }

    /// The heading about z, in radians.
    pub fn yaw(&self) -> f64 {
        (2.0 * (self.w * self.z + self.x * self.y))
            .atan2(1.0 - 2.0 * (self.y * self.y + self.z * self.z))
    }
}

/// `geometry_msgs/Pose`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pose {
    /// Where.
    pub position: Point,
    /// Which way.
    pub orientation: Quaternion,
}

/// `geometry_msgs/PoseStamped`.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PoseStamped {
    /// When, and the frame of `pose`.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}
impl Message for PoseStamped {}

impl PoseStamped {
    /// A ground pose `(x, y, yaw)` in the map frame, stamped now.
    pub fn on_map(x: f64, y: f64, yaw: f64) -> PoseStamped {
        PoseStamped {
            header: Header::now(MAP_FRAME),
            pose: Pose {
                position: Point { x, y, z: 0.0 },
                orientation: Quaternion::from_yaw(yaw),
            },
        }
    }
}

/// DDS type of [`PoseStamped`]: `geometry_msgs::msg::dds_::PoseStamped_`.
pub fn pose_stamped_type() -> MessageTypeName {
    MessageTypeName::new("geometry_msgs", "PoseStamped")
}

/// `diagnostic_msgs/KeyValue`: one named argument.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct KeyValue {
    /// The name.
    pub key: String,
    /// The value, as text.
    pub value: String,
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn time_counts_nanoseconds() {
        let t = Time { sec: 2, nanosec: 5 };
        assert_eq!(t.as_nanos(), 2_000_000_005);
        assert!(Time::now().sec > 1_700_000_000);
    }

    #[test]
    fn a_yaw_survives_the_quaternion() {
        let q = Quaternion::from_yaw(1.25);
        assert!((q.yaw() - 1.25).abs() < 1e-12);
        assert_eq!(Quaternion::default().w, 1.0);
        let p = PoseStamped::on_map(1.0, 2.0, 0.0);
        assert_eq!(p.header.frame_id, "map");
        assert_eq!(
            p.pose.position,
            Point {
                x: 1.0,
                y: 2.0,
                z: 0.0
            }
        );
    }
}
