//! Key expressions and liveliness tokens, in rmw_zenoh's format (its `docs/design.md`):
//!
//! ```text
//! topic      <domain>/<name without the leading />/<DDS type>/<type hash>
//!            0/gspn/firings/gspn_msgs::msg::dds_::Firing_/RIHS01_…
//! service    the same with the service's name and type (an action is three services under
//!            <name>/_action/: send_goal, get_result, cancel_goal)
//! token      @ros2_lv/<domain>/<session id>/<node id>/<entity id>/<kind>/<enclave>/<namespace>/<node>
//!            kind NN = a node; empty enclave or namespace = %, a / inside a chunk = %
//! ```
//!
//! A `*/gspn/firings/**` subscriber (any domain, any type hash) gets every firing.

use std::sync::LazyLock;

use super::wire::{Field, TIME, TypeDescription, TypeHash, action_hashes, cancel_goal_hash};
use crate::ros2::msgs;

/// The ROS 2 admin space of liveliness tokens.
pub const ADMIN_SPACE: &str = "@ros2_lv";

/// The node name of a robot (its namespace is `/<robot id>`).
pub const ROBOT_NODE: &str = "gspn_robot";

/// The supervisor's node: `/gspn/supervisor`.
pub const SUPERVISOR_NS: &str = "/gspn";
/// The supervisor's node name.
pub const SUPERVISOR_NODE: &str = "supervisor";

/// A ROS 2 name as a key expression chunk: `/gspn/firings` → `gspn/firings`.
fn strip(name: &str) -> &str {
    name.trim_matches('/')
}

/// `/` inside a token chunk becomes `%`; an empty chunk is `%`.
pub fn mangle(s: &str) -> String {
    if s.is_empty() {
        "%".into()
    } else {
        s.replace('/', "%")
    }
}

/// The inverse of [`mangle`].
pub fn unmangle(s: &str) -> String {
    if s == "%" {
        String::new()
    } else {
        s.replace('%', "/")
    }
}

/// A topic's key expression.
pub fn topic(domain: u16, name: &str, dds_type: &str, hash: &str) -> String {
    format!("{domain}/{}/{dds_type}/{hash}", strip(name))
}

/// The three services of action `/<robot>/<server>` (ExecPlace), each with its type's hash.
pub fn exec_place(domain: u16, robot: &str, server: &str, service: ActionService) -> String {
    let (sub, ty) = match service {
        ActionService::SendGoal => ("send_goal", "gspn_msgs::action::dds_::ExecPlace_SendGoal_"),
        ActionService::GetResult => (
            "get_result",
            "gspn_msgs::action::dds_::ExecPlace_GetResult_",
        ),
        ActionService::CancelGoal => ("cancel_goal", "action_msgs::srv::dds_::CancelGoal_"),
    };
    let hash = &SERVICE_HASHES[service as usize].0;
    format!("{domain}/{robot}/{server}/_action/{sub}/{ty}/{hash}")
}

/// The services an action is made of.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionService {
    /// `_action/send_goal`.
    SendGoal,
    /// `_action/get_result`.
    GetResult,
    /// `_action/cancel_goal`.
    CancelGoal,
}

/// A node's liveliness token: session `zid`, node id `node` within it.
pub fn node_token(domain: u16, zid: &str, node: u32, namespace: &str, name: &str) -> String {
    format!(
        "{ADMIN_SPACE}/{domain}/{zid}/{node}/{node}/NN/%/{}/{name}",
        mangle(namespace)
    )
}

/// The tokens of every node of `domain`, to subscribe to.
pub fn node_tokens(domain: u16) -> String {
    format!("{ADMIN_SPACE}/{domain}/*/*/*/NN/**")
}

/// A node as its token names it: (namespace, name), when `key` is a node token.
pub fn parse_node_token(key: &str) -> Option<(String, String)> {
    let parts: Vec<&str> = key.split('/').collect();
    match parts.as_slice() {
        [
            ADMIN_SPACE,
            _domain,
            _zid,
            _nid,
            _eid,
            "NN",
            _enclave,
            ns,
            name,
        ] => Some((unmangle(ns), name.to_string())),
        _ => None,
    }
}

/// A robot's namespace: `/<id>`.
pub fn robot_namespace(id: &str) -> String {
    format!("/{id}")
}

/// Whether `id` can name a robot: a ROS 2 name chunk (letters, digits, `_`, not starting
/// with a digit), which is also a safe key expression chunk.
pub fn valid_robot_id(id: &str) -> bool {
    let mut c = id.chars();
    matches!(c.next(), Some(f) if f.is_ascii_alphabetic() || f == '_')
        && c.all(|ch| ch.is_ascii_alphanumeric() || ch == '_')
}

/// The topics the supervisor publishes, with their ROS 2 types.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Topic {
    /// `/gspn/firings`, `gspn_msgs/msg/Firing`.
    Firings,
    /// `/gspn/marking`, `gspn_msgs/msg/Marking`.
    Marking,
    /// `/gspn/run`, `gspn_msgs/msg/RunState`.
    Run,
    /// `/gspn/drift`, `std_msgs/msg/String`.
    Drift,
}

const FIRING: TypeDescription = TypeDescription {
    name: "gspn_msgs/msg/Firing",
    fields: &[
        ("seq", Field::Uint64),
        ("transition", Field::String),
        ("marking", Field::Uint32Seq),
        ("robots", Field::StringSeq),
        ("stamp", Field::Nested("builtin_interfaces/msg/Time")),
    ],
};
const MARKING: TypeDescription = TypeDescription {
    name: "gspn_msgs/msg/Marking",
    fields: &[
        ("seq", Field::Uint64),
        ("places", Field::StringSeq),
        ("tokens", Field::Uint32Seq),
    ],
};
const RUN_STATE: TypeDescription = TypeDescription {
    name: "gspn_msgs/msg/RunState",
    fields: &[
        ("state", Field::String),
        ("stopped", Field::String),
        ("firings", Field::Uint64),
    ],
};
const STRING: TypeDescription = TypeDescription {
    name: "std_msgs/msg/String",
    fields: &[("data", Field::String)],
};

const EXEC_PLACE_GOAL: TypeDescription = TypeDescription {
    name: "gspn_msgs/action/ExecPlace_Goal",
    fields: &[("place", Field::String), ("agent", Field::String)],
};
const EXEC_PLACE_RESULT: TypeDescription = TypeDescription {
    name: "gspn_msgs/action/ExecPlace_Result",
    fields: &[("transition", Field::String), ("outcome", Field::String)],
};

/// The hashes of the ExecPlace action's services, in [`ActionService`] order.
static SERVICE_HASHES: LazyLock<[TypeHash; 3]> = LazyLock::new(|| {
    let (send_goal, get_result) = action_hashes(
        "gspn_msgs/action/ExecPlace",
        &EXEC_PLACE_GOAL,
        &EXEC_PLACE_RESULT,
    );
    [send_goal, get_result, cancel_goal_hash()]
});

static HASHES: LazyLock<[TypeHash; 4]> = LazyLock::new(|| {
    [
        TypeHash::of(&FIRING, &[TIME]),
        TypeHash::of(&MARKING, &[]),
        TypeHash::of(&RUN_STATE, &[]),
        TypeHash::of(&STRING, &[]),
    ]
});

impl Topic {
    /// The ROS 2 topic name.
    pub fn name(self) -> &'static str {
        match self {
            Topic::Firings => msgs::FIRINGS_TOPIC,
            Topic::Marking => msgs::MARKING_TOPIC,
            Topic::Run => msgs::RUN_TOPIC,
            Topic::Drift => msgs::DRIFT_TOPIC,
        }
    }

    /// The DDS type name (`gspn_msgs::msg::dds_::Firing_`).
    pub fn dds_type(self) -> &'static str {
        match self {
            Topic::Firings => "gspn_msgs::msg::dds_::Firing_",
            Topic::Marking => "gspn_msgs::msg::dds_::Marking_",
            Topic::Run => "gspn_msgs::msg::dds_::RunState_",
            Topic::Drift => "std_msgs::msg::dds_::String_",
        }
    }

    /// The type's RIHS01 hash.
    pub fn type_hash(self) -> &'static str {
        &HASHES[self as usize].0
    }

    /// The key expression in `domain`.
    pub fn key(self, domain: u16) -> String {
        topic(domain, self.name(), self.dds_type(), self.type_hash())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_rmw_zenoh() {
        let k = Topic::Firings.key(0);
        assert!(k.starts_with("0/gspn/firings/gspn_msgs::msg::dds_::Firing_/RIHS01_"));
        assert_eq!(
            k.len(),
            "0/gspn/firings/gspn_msgs::msg::dds_::Firing_/RIHS01_".len() + 64
        );
        assert_eq!(
            Topic::Drift.key(3),
            "3/gspn/drift/std_msgs::msg::dds_::String_/RIHS01_df668c740482bbd48fb39d76a70dfd4bd59db1288021743503259e948f6b1a18"
        );
        let k = exec_place(0, "r1", "exec_place", ActionService::SendGoal);
        assert!(
            k.starts_with(
                "0/r1/exec_place/_action/send_goal/gspn_msgs::action::dds_::ExecPlace_SendGoal_/RIHS01_"
            ),
            "{k}"
        );
        assert_eq!(
            exec_place(0, "r1", "exec_place", ActionService::CancelGoal),
            "0/r1/exec_place/_action/cancel_goal/action_msgs::srv::dds_::CancelGoal_/RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a"
        );
    }

    #[test]
    fn a_node_token_reads_back() {
        let t = node_token(0, "a1b2", 4, "/r7", ROBOT_NODE);
        assert_eq!(t, "@ros2_lv/0/a1b2/4/4/NN/%/%r7/gspn_robot");
        assert_eq!(
            parse_node_token(&t),
            Some(("/r7".to_string(), ROBOT_NODE.to_string()))
        );
        assert_eq!(parse_node_token("0/gspn/firings/x/y"), None);
        assert_eq!(mangle(""), "%");
        assert_eq!(unmangle("%"), "");
    }

    #[test]
    fn robot_ids_are_name_chunks() {
        assert!(valid_robot_id("r_12"));
        assert!(!valid_robot_id("1r"));
        assert!(!valid_robot_id("r*"));
        assert!(!valid_robot_id("a/b"));
        assert!(!valid_robot_id(""));
    }
}
