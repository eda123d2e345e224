//! The interfaces' definitions as text: the `gspn_msgs` files themselves (compiled in from
//! `ros2/gspn_msgs/`) and the standard ROS 2 messages they use, and the `ros2msg` schema of
//! a message (its definition followed by those of its dependencies), as rosbag2 writes it
//! into MCAP files and Foxglove and `ros2 bag play` read it.

/// `gspn_msgs` message definitions, by full name.
pub const GSPN: &[(&str, &str)] = &[
    (
        "gspn_msgs/msg/Firing",
        include_str!("../../../ros2/gspn_msgs/msg/Firing.msg"),
    ),
    (
        "gspn_msgs/msg/Marking",
        include_str!("../../../ros2/gspn_msgs/msg/Marking.msg"),
    ),
    (
        "gspn_msgs/msg/RunState",
        include_str!("../../../ros2/gspn_msgs/msg/RunState.msg"),
    ),
    (
        "gspn_msgs/msg/Drift",
        include_str!("../../../ros2/gspn_msgs/msg/Drift.msg"),
    ),
    (
        "gspn_msgs/msg/Heartbeat",
        include_str!("../../../ros2/gspn_msgs/msg/Heartbeat.msg"),
    ),
];

/// The ExecPlace action definition (goal, result and feedback separated by `---`).
pub const EXEC_PLACE: &str = include_str!("../../../ros2/gspn_msgs/action/ExecPlace.action");

/// The standard messages the interfaces use, as ROS 2 (Humble and later) defines them,
/// comments left out: those of the messages, and those every action is made of (its goal
/// ids, statuses, and the event message of each of its services).
pub const STANDARD: &[(&str, &str)] = &[
    ("builtin_interfaces/msg/Time", "int32 sec\nuint32 nanosec\n"),
    (
        "std_msgs/msg/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    ),
    (
        "geometry_msgs/msg/PoseStamped",
        "std_msgs/Header header\nPose pose\n",
    ),
    (
        "geometry_msgs/msg/Pose",
        "Point position\nQuaternion orientation\n",
    ),
    (
        "geometry_msgs/msg/Point",
        "float64 x\nfloat64 y\nfloat64 z\n",
    ),
    (
        "geometry_msgs/msg/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    ),
    ("diagnostic_msgs/msg/KeyValue", "string key\nstring value\n"),
    ("unique_identifier_msgs/msg/UUID", "uint8[16] uuid\n"),
    (
        "action_msgs/msg/GoalInfo",
        "unique_identifier_msgs/UUID goal_id\nbuiltin_interfaces/Time stamp\n",
    ),
    (
        "action_msgs/msg/GoalStatus",
        "int8 STATUS_UNKNOWN = 0\nint8 STATUS_ACCEPTED = 1\nint8 STATUS_EXECUTING = 2\n\
         int8 STATUS_CANCELING = 3\nint8 STATUS_SUCCEEDED = 4\nint8 STATUS_CANCELED = 5\n\
         int8 STATUS_ABORTED = 6\nGoalInfo goal_info\nint8 status\n",
    ),
    (
        "action_msgs/msg/GoalStatusArray",
        "GoalStatus[] status_list\n",
    ),
    (
        "service_msgs/msg/ServiceEventInfo",
        "uint8 REQUEST_SENT = 0\nuint8 REQUEST_RECEIVED = 1\nuint8 RESPONSE_SENT = 2\n\
         uint8 RESPONSE_RECEIVED = 3\nuint8 event_type\nbuiltin_interfaces/Time stamp\n\
         char[16] client_gid\nint64 sequence_number\n",
    ),
];

/// The standard services the interfaces use (request and response separated by `---`): every
/// action's `cancel_goal`.
pub const STANDARD_SERVICES: &[(&str, &str)] = &[(
    "action_msgs/srv/CancelGoal",
    "action_msgs/GoalInfo goal_info\n---\nint8 ERROR_NONE = 0\nint8 ERROR_REJECTED = 1\n\
     int8 ERROR_UNKNOWN_GOAL_ID = 2\nint8 ERROR_GOAL_TERMINATED = 3\nint8 return_code\n\
     action_msgs/GoalInfo[] goals_canceling\n",
)];

/// The definition of message `name` (`pkg/msg/Type`, or `pkg/Type`).
pub fn definition(name: &str) -> Option<&'static str> {
    let full = full_name(name, "");
    GSPN.iter()
        .chain(STANDARD)
        .find(|(n, _)| *n == full)
        .map(|(_, d)| *d)
}

/// `pkg/Type` → `pkg/msg/Type`; a bare `Type` is in package `pkg`.
fn full_name(ty: &str, pkg: &str) -> String {
    match ty.split('/').collect::<Vec<_>>()[..] {
        [p, t] => format!("{p}/msg/{t}"),
        [t] => format!("{pkg}/msg/{t}"),
        _ => ty.to_string(),
    }
}

/// The message types the fields of `def` (a definition in package `pkg`) use, in order, as
/// full names; primitives left out.
fn dependencies(def: &str, pkg: &str) -> Vec<String> {
    const PRIMITIVES: &[&str] = &[
        "bool", "byte", "char", "int8", "uint8", "int16", "uint16", "int32", "uint32", "int64",
        "uint64", "float32", "float64", "string", "wstring",
    ];
    def.lines()
        .map(|l| l.split('#').next().unwrap_or("").trim())
        .filter(|l| !l.is_empty() && !l.contains('='))
        .filter_map(|l| l.split_whitespace().next())
        .map(|ty| ty.split('[').next().unwrap_or(ty))
        .map(|ty| ty.split("<=").next().unwrap_or(ty))
        .filter(|ty| !PRIMITIVES.contains(ty))
        .map(|ty| full_name(ty, pkg))
        .collect()
}

/// The `ros2msg` schema of message `name` (`pkg/msg/Type`): its definition, then each message
/// it uses (transitively, once each), after a line of 80 `=` and `MSG: pkg/Type`.
pub fn ros2msg(name: &str) -> Option<String> {
    let mut out = definition(name)?.to_string();
    let pkg = |n: &str| n.split('/').next().unwrap_or("").to_string();
    let mut todo = dependencies(&out, &pkg(name));
    let mut seen: Vec<String> = Vec::new();
    while !todo.is_empty() {
        let dep = todo.remove(0);
        if seen.contains(&dep) {
            continue;
        }
        let def = definition(&dep)?;
        let short = dep.replace("/msg/", "/");
        out.push_str(&format!("\n{}\nMSG: {short}\n{def}", "=".repeat(80)));
        todo.extend(dependencies(def, &pkg(&dep)));
        seen.push(dep);
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_schema_carries_every_message_it_uses_once() {
        let s = ros2msg("gspn_msgs/msg/Firing").unwrap();
        assert!(s.starts_with(definition("gspn_msgs/msg/Firing").unwrap()));
        let deps: Vec<&str> = s.lines().filter_map(|l| l.strip_prefix("MSG: ")).collect();
        assert_eq!(deps, ["std_msgs/Header", "builtin_interfaces/Time"]);
        let p = ros2msg("geometry_msgs/msg/PoseStamped").unwrap();
        let deps: Vec<&str> = p.lines().filter_map(|l| l.strip_prefix("MSG: ")).collect();
        assert_eq!(
            deps,
            [
                "std_msgs/Header",
                "geometry_msgs/Pose",
                "builtin_interfaces/Time",
                "geometry_msgs/Point",
                "geometry_msgs/Quaternion"
            ]
        );
        assert_eq!(ros2msg("gspn_msgs/msg/Nope"), None);
    }
}
