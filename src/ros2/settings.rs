//! What the ROS 2 backend is told by a plan: the DDS settings of its `[ros2]` table and the
//! places it serves. Compiled with or without the feature `ros2`, so every plan reads the same.

use crate::net::PlaceId;

/// The action name that makes a place a ROS 2 place: its agents' actions are ExecPlace goals
/// sent to their robots (feature `ros2`, `docs/ros2.md`).
pub const ROS2_ACTION: &str = "ros2";

/// The ExecPlace action server a `ros2` place uses when the plan names none.
pub const DEFAULT_SERVER: &str = "exec_place";

/// The server name that makes a `ros2` place a Nav2 goal: its agents' actions are
/// `nav2_msgs/action/NavigateToPose` goals to the place's `target` pose, sent to
/// `/<robot>/navigate_to_pose` (Nav2's own action on a robot running Nav2), not ExecPlace.
pub const NAV2_SERVER: &str = "navigate_to_pose";

/// The plan's `[ros2]` table and its `ros2` places, resolved.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Ros2Settings {
    /// The DDS domain id.
    pub domain_id: Option<u16>,
    /// The local addresses DDS may use (empty = the backend's default, loopback).
    pub networks: Vec<std::net::IpAddr>,
    /// Seconds between a robot's heartbeats.
    pub heartbeat: Option<f64>,
    /// Seconds without a heartbeat after which a robot is lost.
    pub lost_after: Option<f64>,
    /// Seconds the supervisor waits for its robots before it gives up.
    pub startup: Option<f64>,
    /// How ExecPlace's services carry request ids (default [`ServiceMapping::Enhanced`]).
    pub service_mapping: ServiceMapping,
    /// Whether the process's node forwards the ROS 2 layer's warnings and errors to
    /// `/rosout` (`None`: not said; the default is off; `--ros2-rosout` turns it on).
    pub rosout: Option<bool>,
    /// DDS (default) or Zenoh.
    pub transport: Transport,
    /// The plan's Zenoh router endpoint (`[ros2] zenoh`).
    pub zenoh: Option<String>,
    /// Places whose action is `ros2`, with their ExecPlace server name, in net order.
    pub servers: Vec<(PlaceId, String)>,
    /// The arguments each `ros2` place sends in its ExecPlace goals (places without any are
    /// absent), in net order.
    pub args: Vec<(PlaceId, PlaceArgs)>,
}

impl Ros2Settings {
    /// The ExecPlace servers the plan's `ros2` places name, each once, in name order (Nav2
    /// places' goals go to a robot's own Nav2, not to an ExecPlace server).
    pub fn exec_place_servers(&self) -> Vec<&str> {
        let mut servers: Vec<&str> = self
            .servers
            .iter()
            .map(|(_, s)| s.as_str())
            .filter(|&s| s != NAV2_SERVER)
            .collect();
        servers.sort_unstable();
        servers.dedup();
        servers
    }
}

/// A `ros2` place's arguments from the plan, sent with every ExecPlace goal.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PlaceArgs {
    /// The target pose `[x, y, yaw]` (metres, metres, radians; frame `map`): the place's
    /// `target`.
    pub target: Option<[f64; 3]>,
    /// The place's `args`, by key.
    pub args: Vec<(String, String)>,
}

/// How the ExecPlace services (send goal, get result, cancel) carry the id that pairs a
/// response with its request on the wire; the supervisor and its robots must agree.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ServiceMapping {
    /// RPC over DDS "Enhanced": the id in the samples' inline QoS (ROS 2 on Fast DDS;
    /// gspn's robots).
    #[default]
    Enhanced,
    /// A 16-byte header before the payload, as ROS 2's `rmw_cyclonedds_cpp` writes it: what a
    /// DDS without access to inline QoS can speak (the Python robot on Cyclone DDS).
    Cyclone,
}

impl ServiceMapping {
    /// The mapping named `s` in a plan (`"enhanced"`, `"cyclone"`).
    pub fn parse(s: &str) -> Option<ServiceMapping> {
        match s {
            "enhanced" => Some(ServiceMapping::Enhanced),
            "cyclone" => Some(ServiceMapping::Cyclone),
            _ => None,
        }
    }
}

/// How the supervisor and its robots meet (`[ros2] transport`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Transport {
    /// DDS, the ROS 2 default (feature `ros2`).
    #[default]
    Dds,
    /// Zenoh through a router, as rmw_zenoh does (feature `zenoh`).
    Zenoh,
}

impl Transport {
    /// The transport named `s` in a plan (`"dds"`, `"zenoh"`).
    pub fn parse(s: &str) -> Option<Transport> {
        match s {
            "dds" => Some(Transport::Dds),
            "zenoh" => Some(Transport::Zenoh),
            _ => None,
        }
    }
}
