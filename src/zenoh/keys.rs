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

use super::type_hash::{TypeError, hash_of};
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

/// The DDS name ROS 2 gives type `pkg/kind/Name`: `pkg::kind::dds_::Name_`.
pub fn dds_type(full_name: &str) -> String {
    match full_name.rsplit_once('/') {
        Some((scope, name)) => format!("{}::dds_::{name}_", scope.replace('/', "::")),
        None => format!("{full_name}_"),
    }
}

/// The key expression of the service `/<robot>/<server>/_action/<sub>` of the ExecPlace
/// action, each with its type's hash. rmw_zenoh names a service's type after its response
/// type without `Response_` (`gspn_msgs::action::dds_::ExecPlace_SendGoal_`).
pub fn exec_place(
    domain: u16,
    robot: &str,
    server: &str,
    service: ActionService,
) -> Result<String, TypeError> {
    let (sub, ty) = match service {
        ActionService::SendGoal => ("send_goal", "gspn_msgs/action/ExecPlace_SendGoal"),
        ActionService::GetResult => ("get_result", "gspn_msgs/action/ExecPlace_GetResult"),
        ActionService::CancelGoal => ("cancel_goal", "action_msgs/srv/CancelGoal"),
    };
    let hash = hash_of(ty)?.0;
    Ok(format!(
        "{domain}/{robot}/{server}/_action/{sub}/{}/{hash}",
        dds_type(ty)
    ))
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
    /// `/gspn/drift`, `gspn_msgs/msg/Drift`.
    Drift,
}

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

    /// The ROS 2 type.
    pub fn ty(self) -> &'static str {
        match self {
            Topic::Firings => "gspn_msgs/msg/Firing",
            Topic::Marking => "gspn_msgs/msg/Marking",
            Topic::Run => "gspn_msgs/msg/RunState",
            Topic::Drift => "gspn_msgs/msg/Drift",
        }
    }

    /// The key expression in `domain`.
    pub fn key(self, domain: u16) -> Result<String, TypeError> {
        let hash = hash_of(self.ty())?.0;
        Ok(topic(domain, self.name(), &dds_type(self.ty()), &hash))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_follow_rmw_zenoh() {
        let k = Topic::Firings.key(0).unwrap();
        let prefix = "0/gspn/firings/gspn_msgs::msg::dds_::Firing_/RIHS01_";
        assert!(k.starts_with(prefix), "{k}");
        assert_eq!(k.len(), prefix.len() + 64);
        assert!(
            Topic::Drift
                .key(3)
                .unwrap()
                .starts_with("3/gspn/drift/gspn_msgs::msg::dds_::Drift_/RIHS01_")
        );
        let k = exec_place(0, "r1", "exec_place", ActionService::SendGoal).unwrap();
        assert!(
            k.starts_with(
                "0/r1/exec_place/_action/send_goal/gspn_msgs::action::dds_::ExecPlace_SendGoal_/RIHS01_"
            ),
            "{k}"
        );
        assert_eq!(
            exec_place(0, "r1", "exec_place", ActionService::CancelGoal).unwrap(),
            "0/r1/exec_place/_action/cancel_goal/action_msgs::srv::dds_::CancelGoal_/RIHS01_573d8b0a534451d7bc2ac8c5ffde8ac14b8593b7001175d0cd6516dcbeb8689a"
        );
        assert_eq!(
            dds_type("std_msgs/msg/String"),
            "std_msgs::msg::dds_::String_"
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
