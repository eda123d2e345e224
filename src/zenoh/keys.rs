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

use std::sync::atomic::{AtomicU32, Ordering};

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
    let (sub, ty) = service.parts();
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

impl ActionService {
    /// The three, in the order rclcpp's action server creates them.
    pub const ALL: [ActionService; 3] = [
        ActionService::SendGoal,
        ActionService::CancelGoal,
        ActionService::GetResult,
    ];

    /// The service's name under `_action/` and its ROS 2 type.
    fn parts(self) -> (&'static str, &'static str) {
        match self {
            ActionService::SendGoal => ("send_goal", "gspn_msgs/action/ExecPlace_SendGoal"),
            ActionService::GetResult => ("get_result", "gspn_msgs/action/ExecPlace_GetResult"),
            ActionService::CancelGoal => ("cancel_goal", "action_msgs/srv/CancelGoal"),
        }
    }
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

    /// Its QoS, as the DDS backend's.
    pub fn qos(self) -> Qos {
        match self {
            Topic::Firings | Topic::Drift => Qos::KEEP_ALL,
            Topic::Marking | Topic::Run => Qos::LATCHED,
        }
    }

    /// The key expression in `domain`.
    pub fn key(self, domain: u16) -> Result<String, TypeError> {
        let hash = hash_of(self.ty())?.0;
        Ok(topic(domain, self.name(), &dds_type(self.ty()), &hash))
    }
}

/// What a liveliness token announces: rmw_zenoh's entity kinds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EntityKind {
    /// `NN`: a node.
    Node,
    /// `MP`: a publisher.
    Publisher,
    /// `MS`: a subscription.
    Subscription,
    /// `SS`: a service server.
    Service,
    /// `SC`: a service client.
    Client,
}

impl EntityKind {
    /// The token's chunk.
    pub fn code(self) -> &'static str {
        match self {
            EntityKind::Node => "NN",
            EntityKind::Publisher => "MP",
            EntityKind::Subscription => "MS",
            EntityKind::Service => "SS",
            EntityKind::Client => "SC",
        }
    }
}

/// An endpoint's QoS as rmw_zenoh writes it into its token: each policy that differs from
/// rmw_zenoh's default (reliable, volatile, keep last 42, no deadline, lifespan or lease,
/// automatic liveliness) by its `rmw_qos_*_policy` number, the others left empty:
/// `<reliability>:<durability>:<history>,<depth>:<deadline s>,<ns>:<lifespan s>,<ns>:<liveliness>,<lease s>,<ns>`.
/// Every endpoint here is reliable, with no deadline, lifespan or lease.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Qos {
    /// Transient local (late joiners get the last samples) rather than volatile.
    pub transient_local: bool,
    /// Keep all rather than keep last `depth`.
    pub keep_all: bool,
    /// The depth of keep last (0 = rmw_zenoh's default, 42).
    pub depth: u32,
}

impl Qos {
    /// `/gspn/firings`, `/gspn/drift`: reliable, volatile, keep all.
    pub const KEEP_ALL: Qos = Qos {
        transient_local: false,
        keep_all: true,
        depth: 0,
    };
    /// `/gspn/marking`, `/gspn/run`, an action's status: transient local, depth 1.
    pub const LATCHED: Qos = Qos {
        transient_local: true,
        keep_all: false,
        depth: 1,
    };
    /// Services and an action's feedback: ROS 2's defaults (volatile, keep last 10).
    pub const DEFAULT: Qos = Qos {
        transient_local: false,
        keep_all: false,
        depth: 10,
    };

    /// The token's QoS chunk.
    pub fn chunk(self) -> String {
        let durability = if self.transient_local { "1" } else { "" };
        let history = if self.keep_all { "2" } else { "" };
        let depth = match self.depth {
            0 | 42 => String::new(),
            d => d.to_string(),
        };
        format!(":{durability}:{history},{depth}:,:,:,,")
    }
}

/// A node as its tokens name it: the session, the node's id in it, its namespace and name.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct NodeKey {
    /// The ROS domain id.
    pub domain: u16,
    /// The Zenoh session id.
    pub zid: String,
    /// The node's id within the session.
    pub id: u32,
    /// `/r7`, `/gspn`.
    pub namespace: String,
    /// `gspn_robot`, `supervisor`.
    pub name: String,
}

impl NodeKey {
    /// The node's own token: `@ros2_lv/<domain>/<zid>/<id>/<id>/NN/%/<namespace>/<name>`.
    pub fn token(&self) -> String {
        self.prefix(self.id, EntityKind::Node)
    }

    /// `@ros2_lv/<domain>/<zid>/<node id>/<entity id>/<kind>/%/<namespace>/<name>`.
    fn prefix(&self, entity: u32, kind: EntityKind) -> String {
        format!(
            "{ADMIN_SPACE}/{}/{}/{}/{entity}/{}/%/{}/{}",
            self.domain,
            self.zid,
            self.id,
            kind.code(),
            mangle(&self.namespace),
            self.name
        )
    }

    /// The token of endpoint `entity` of the node (its id in the session): a `kind` on the
    /// topic or service `name` (`/gspn/firings`) of ROS 2 type `ty` (`gspn_msgs/msg/Firing`,
    /// a service's type for a service) with `qos`.
    pub fn endpoint(
        &self,
        entity: u32,
        kind: EntityKind,
        name: &str,
        ty: &str,
        qos: Qos,
    ) -> Result<String, TypeError> {
        Ok(format!(
            "{}/{}/{}/{}/{}",
            self.prefix(entity, kind),
            mangle(name),
            dds_type(ty),
            hash_of(ty)?.0,
            qos.chunk()
        ))
    }
}

/// The ids of a session's nodes and endpoints, one counter for both, as rmw_zenoh numbers
/// the entities of a context.
#[derive(Debug, Default)]
pub struct EntityIds(AtomicU32);

impl EntityIds {
    /// The next id.
    pub fn next(&self) -> u32 {
        self.0.fetch_add(1, Ordering::Relaxed)
    }
}

/// The topics an action server publishes besides its services.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ActionTopic {
    /// `_action/feedback`, `<pkg>/action/<Name>_FeedbackMessage`.
    Feedback,
    /// `_action/status`, `action_msgs/msg/GoalStatusArray`.
    Status,
}

impl ActionTopic {
    fn parts(self) -> (&'static str, &'static str, Qos) {
        match self {
            ActionTopic::Feedback => (
                "feedback",
                "gspn_msgs/action/ExecPlace_FeedbackMessage",
                Qos::DEFAULT,
            ),
            ActionTopic::Status => ("status", "action_msgs/msg/GoalStatusArray", Qos::LATCHED),
        }
    }
}

/// The key expression of topic `topic` of the ExecPlace action `/<robot>/<server>`.
pub fn exec_place_topic(
    domain: u16,
    robot: &str,
    server: &str,
    topic: ActionTopic,
) -> Result<String, TypeError> {
    let (sub, ty, _) = topic.parts();
    Ok(self::topic(
        domain,
        &format!("/{robot}/{server}/_action/{sub}"),
        &dds_type(ty),
        &hash_of(ty)?.0,
    ))
}

/// The tokens of the ExecPlace action server `/<robot>/<server>` of `node`, as rclcpp's
/// action server declares them over rmw_zenoh: its three services (`SS`), its feedback and
/// status publishers (`MP`).
pub fn action_server_tokens(
    node: &NodeKey,
    ids: &EntityIds,
    robot: &str,
    server: &str,
) -> Result<Vec<String>, TypeError> {
    let base = format!("/{robot}/{server}/_action");
    let mut out = Vec::new();
    for s in ActionService::ALL {
        let (sub, ty) = s.parts();
        out.push(node.endpoint(
            ids.next(),
            EntityKind::Service,
            &format!("{base}/{sub}"),
            ty,
            Qos::DEFAULT,
        )?);
    }
    for t in [ActionTopic::Feedback, ActionTopic::Status] {
        let (sub, ty, qos) = t.parts();
        out.push(node.endpoint(
            ids.next(),
            EntityKind::Publisher,
            &format!("{base}/{sub}"),
            ty,
            qos,
        )?);
    }
    Ok(out)
}

/// The tokens of `node`'s client of the ExecPlace action `/<robot>/<server>`: its three
/// service clients (`SC`; it reads neither feedback nor status, so it declares no
/// subscription).
pub fn action_client_tokens(
    node: &NodeKey,
    ids: &EntityIds,
    robot: &str,
    server: &str,
) -> Result<Vec<String>, TypeError> {
    ActionService::ALL
        .iter()
        .map(|s| {
            let (sub, ty) = s.parts();
            node.endpoint(
                ids.next(),
                EntityKind::Client,
                &format!("/{robot}/{server}/_action/{sub}"),
                ty,
                Qos::DEFAULT,
            )
        })
        .collect()
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
        let node = NodeKey {
            domain: 0,
            zid: "a1b2".into(),
            id: 4,
            namespace: "/r7".into(),
            name: ROBOT_NODE.into(),
        };
        let t = node.token();
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
    fn endpoint_tokens_carry_name_type_hash_and_qos() {
        let node = NodeKey {
            domain: 0,
            zid: "z9".into(),
            id: 1,
            namespace: SUPERVISOR_NS.into(),
            name: SUPERVISOR_NODE.into(),
        };
        let firing = hash_of("gspn_msgs/msg/Firing").unwrap().0;
        assert_eq!(
            node.endpoint(
                2,
                EntityKind::Publisher,
                "/gspn/firings",
                "gspn_msgs/msg/Firing",
                Topic::Firings.qos()
            )
            .unwrap(),
            format!(
                "@ros2_lv/0/z9/1/2/MP/%/%gspn/supervisor/%gspn%firings/gspn_msgs::msg::dds_::Firing_/{firing}/::2,:,:,:,,"
            )
        );
        // rmw_zenoh's own default (reliable, volatile, keep last 42): every chunk empty.
        let default = Qos {
            transient_local: false,
            keep_all: false,
            depth: 42,
        };
        assert_eq!(default.chunk(), "::,:,:,:,,");
        assert_eq!(Qos::LATCHED.chunk(), ":1:,1:,:,:,,");
        assert_eq!(Qos::DEFAULT.chunk(), "::,10:,:,:,,");
        let ids = EntityIds::default();
        let robot = NodeKey {
            id: ids.next(),
            namespace: "/r1".into(),
            name: ROBOT_NODE.into(),
            ..node.clone()
        };
        let server = action_server_tokens(&robot, &ids, "r1", "exec_place").unwrap();
        let kinds: Vec<(&str, &str, &str)> = server
            .iter()
            .map(|t| {
                let c: Vec<&str> = t.split('/').collect();
                (c[4], c[5], c[9])
            })
            .collect();
        assert_eq!(
            kinds,
            [
                ("1", "SS", "%r1%exec_place%_action%send_goal"),
                ("2", "SS", "%r1%exec_place%_action%cancel_goal"),
                ("3", "SS", "%r1%exec_place%_action%get_result"),
                ("4", "MP", "%r1%exec_place%_action%feedback"),
                ("5", "MP", "%r1%exec_place%_action%status"),
            ]
        );
        assert!(server[4].ends_with(
            "/action_msgs::msg::dds_::GoalStatusArray_/RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e/:1:,1:,:,:,,"
        ));
        let client = action_client_tokens(&node, &ids, "r1", "exec_place").unwrap();
        assert_eq!(client.len(), 3);
        assert!(client[1].contains("/1/7/SC/%/%gspn/supervisor/%r1%exec_place%_action%cancel_goal/action_msgs::srv::dds_::CancelGoal_/RIHS01_573d8b0a"));
        assert_eq!(
            exec_place_topic(0, "r1", "exec_place", ActionTopic::Status).unwrap(),
            "0/r1/exec_place/_action/status/action_msgs::msg::dds_::GoalStatusArray_/RIHS01_6c1684b00f177d37438febe6e709fc4e2b0d4248dca4854946f9ed8b30cda83e"
        );
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
