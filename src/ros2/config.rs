//! DDS settings: the domain, the networks a participant uses, and how robots are watched.
//!
//! Defaults suit a sandbox: loopback only (`127.0.0.1`), domain 0. The plan's `[ros2]` table
//! sets them for a plan; the environment (`GSPN_ROS2_DOMAIN`, then `ROS_DOMAIN_ID`;
//! `GSPN_ROS2_NETWORKS`) overrides the plan, and command-line flags override both (see
//! `docs/ros2.md`).
//!
//! Every DDS socket binds to the one configured address (RustDDS patched for it:
//! `vendor/rustdds`), not to `0.0.0.0`; `0.0.0.0` is accepted as "every interface".

use std::net::IpAddr;
use std::time::Duration;

use ros2_client::dds::ServiceMapping;
use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::{Context, NodeName, NodeOptions};

use super::settings::Ros2Settings;

/// The start of the DDS entity name of every gspn robot's participant (`gspn robot r3`):
/// robots ignore the participants whose name starts with it.
pub const ROBOT_PARTICIPANT: &str = "gspn robot ";

/// How a process joins DDS and how the supervisor watches robots.
#[derive(Clone, Debug, PartialEq)]
pub struct DdsConfig {
    /// The DDS domain id (0–232).
    pub domain_id: u16,
    /// The local address every DDS socket binds to and the only one advertised and used for
    /// multicast (one address; `0.0.0.0` = every interface, the wildcard).
    pub networks: Vec<IpAddr>,
    /// How many participant indices of this host (0..n) a participant announces itself to
    /// by unicast SPDP on 127.0.0.1 (loopback has no multicast): at least the number of
    /// processes on the domain, so any start order works (≤ 120).
    pub localhost_peers: u16,
    /// How often a robot publishes its heartbeat.
    pub heartbeat: Duration,
    /// A robot whose heartbeats stop for this long is lost.
    pub lost_after: Duration,
    /// How long the supervisor waits for every robot (and subscriber) before it starts.
    pub startup: Duration,
    /// How ExecPlace's services carry their request ids: `Enhanced` (RPC over DDS, in
    /// inline QoS; Fast DDS's ROS 2) or `Cyclone` (a header in the payload, as
    /// `rmw_cyclonedds_cpp` does; any DDS that cannot write inline QoS can speak it).
    pub service_mapping: ServiceMapping,
    /// Whether the process's node publishes the ROS 2 layer's warnings and errors on
    /// `/rosout` ([`super::rosout`]).
    pub rosout: bool,
    /// The run's namespace (`""` = the root; `--ros-args -r __ns:=/fleet_a`): every node,
    /// topic and action of the run is under it ([`super::names`]).
    pub namespace: String,
    /// The node's name instead of the process's own (`--ros-args -r __node:=NAME`).
    pub node_name: Option<String>,
}

impl Default for DdsConfig {
    fn default() -> Self {
        DdsConfig {
            domain_id: 0,
            networks: vec![IpAddr::from([127, 0, 0, 1])],
            localhost_peers: 12,
            heartbeat: Duration::from_millis(100),
            lost_after: Duration::from_millis(1000),
            startup: Duration::from_secs(30),
            service_mapping: ServiceMapping::Enhanced,
            rosout: false,
            namespace: String::new(),
            node_name: None,
        }
    }
}

/// A DDS setting that could not be used.
#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    /// An environment variable holds something unusable.
    #[error("environment variable {name}=`{value}`: {why}")]
    Env {
        /// The variable.
        name: &'static str,
        /// Its value.
        value: String,
        /// What is expected.
        why: &'static str,
    },
    /// The networks cannot be bound.
    #[error("DDS networks {0}: give one IPv4 address (or 0.0.0.0 for every interface)")]
    Networks(String),
    /// The DDS participant or the ROS 2 node could not be created.
    #[error("DDS: {0}")]
    Dds(String),
}

impl DdsConfig {
    /// The plan's `[ros2]` settings over the environment over the defaults: the domain is
    /// the plan's, else `GSPN_ROS2_DOMAIN`, else `ROS_DOMAIN_ID`, else 0; the networks the
    /// plan's, else `GSPN_ROS2_NETWORKS`, else `127.0.0.1` (flags override all: the CLI).
    pub fn resolve(plan: &Ros2Settings) -> Result<DdsConfig, ConfigError> {
        DdsConfig::resolve_with(plan, |name| std::env::var(name).ok())
    }

    /// [`DdsConfig::resolve`] with the environment given as a function (for tests).
    pub fn resolve_with(
        plan: &Ros2Settings,
        env: impl Fn(&str) -> Option<String>,
    ) -> Result<DdsConfig, ConfigError> {
        let mut c = DdsConfig::default();
        for name in ["ROS_DOMAIN_ID", "GSPN_ROS2_DOMAIN"] {
            if let Some(v) = env(name) {
                c.domain_id = parse_domain(&v).map_err(|why| ConfigError::Env {
                    name,
                    value: v.clone(),
                    why,
                })?;
            }
        }
        if let Some(v) = env("GSPN_ROS2_NETWORKS") {
            c.networks = parse_networks(&v).map_err(|why| ConfigError::Env {
                name: "GSPN_ROS2_NETWORKS",
                value: v.clone(),
                why,
            })?;
        }
        if let Some(d) = plan.domain_id {
            c.domain_id = d;
        }
        if !plan.networks.is_empty() {
            c.networks.clone_from(&plan.networks);
        }
        if let Some(s) = plan.heartbeat {
            c.heartbeat = crate::limits::duration(s);
        }
        if let Some(s) = plan.lost_after {
            c.lost_after = crate::limits::duration(s);
        }
        if let Some(s) = plan.startup {
            c.startup = crate::limits::duration(s);
        }
        c.service_mapping = match plan.service_mapping {
            super::settings::ServiceMapping::Enhanced => ServiceMapping::Enhanced,
            super::settings::ServiceMapping::Cyclone => ServiceMapping::Cyclone,
        };
        c.rosout = plan.rosout.unwrap_or(false);
        c.bind_address()?;
        Ok(c)
    }

    /// Room for a fleet of `processes` participants on one host: announce to that many
    /// participant indices plus a margin (viewers, recorders), between 12 and 120.
    pub fn for_fleet(mut self, processes: usize) -> DdsConfig {
        self.localhost_peers = (processes + 8).clamp(12, 120) as u16;
        self
    }

    /// The address every socket binds to: `None` for the wildcard (`0.0.0.0`), else the one
    /// IPv4 address of `networks` (RustDDS listens on IPv4 only).
    pub fn bind_address(&self) -> Result<Option<IpAddr>, ConfigError> {
        let bad = || {
            let list: Vec<String> = self.networks.iter().map(ToString::to_string).collect();
            ConfigError::Networks(format!("`{}`", list.join(",")))
        };
        match self.networks.as_slice() {
            [a] if a.is_unspecified() && a.is_ipv4() => Ok(None),
            [a @ IpAddr::V4(_)] => Ok(Some(*a)),
            _ => Err(bad()),
        }
    }

    /// A ROS 2 context (one DDS participant) with these settings: every socket bound to the
    /// configured address. A `robot`'s participant announces the entity name
    /// `gspn robot <id>` ([`ROBOT_PARTICIPANT`]) and ignores every other participant that
    /// announces one: robots talk only to the supervisor (and to tools and listeners), so
    /// a fleet's discovery traffic grows with the number of robots instead of its square.
    pub fn context(&self, robot: Option<&str>) -> Result<Context, ConfigError> {
        let mut b = DomainParticipantBuilder::new(self.domain_id)
            .localhost_peer_count(self.localhost_peers);
        if let Some(a) = self.bind_address()? {
            b = b.with_only_networks([a]).bind_address(a);
        }
        if let Some(id) = robot {
            b = b
                .entity_name(format!("{ROBOT_PARTICIPANT}{id}"))
                .ignore_participants_named(ROBOT_PARTICIPANT);
        }
        let dp = b.build().map_err(|e| ConfigError::Dds(format!("{e:?}")))?;
        Context::from_domain_participant(dp).map_err(|e| ConfigError::Dds(format!("{e:?}")))
    }

    /// A node named `name` (or [`DdsConfig::node_name`]) in namespace `<namespace>/gspn`,
    /// in a new context (robot `robot`'s, see [`DdsConfig::context`]).
    pub fn node(&self, name: &str, robot: Option<&str>) -> Result<ros2_client::Node, ConfigError> {
        let ctx = self.context(robot)?;
        let name = self.node_name.as_deref().unwrap_or(name);
        let ns = super::names::node_namespace(&self.namespace);
        let name = NodeName::new(&ns, name).map_err(|e| ConfigError::Dds(format!("{e:?}")))?;
        ctx.new_node(name, NodeOptions::new().enable_rosout(false))
            .map_err(|e| ConfigError::Dds(format!("{e:?}")))
    }
}

impl DdsConfig {
    /// Applies `--ros-args`: the namespace, the node's name, and `-p` parameters, which
    /// override the plan's `[ros2]` keys of the same names (`domain_id`, `heartbeat`,
    /// `lost_after`, `startup`, `service_mapping`, `rosout`).
    pub fn apply_ros_args(
        &mut self,
        a: &super::names::RosArgs,
    ) -> Result<(), super::names::RosArgsError> {
        if let Some(ns) = &a.namespace {
            self.namespace.clone_from(ns);
        }
        if let Some(n) = &a.node {
            self.node_name = Some(n.clone());
        }
        for (k, v) in &a.params {
            let bad = |why: &str| super::names::RosArgsError::Parameter {
                key: k.clone(),
                value: v.clone(),
                reason: why.to_string(),
            };
            let seconds = || {
                v.parse::<f64>()
                    .ok()
                    .filter(|&x| crate::limits::valid_seconds(x))
                    .map(crate::limits::duration)
                    .ok_or_else(|| bad(crate::limits::SECONDS_EXPECTED))
            };
            match k.as_str() {
                "domain_id" => self.domain_id = parse_domain(v).map_err(bad)?,
                // 0: no heartbeat (robots are seen through discovery).
                "heartbeat" if v.parse::<f64>() == Ok(0.0) => self.heartbeat = Duration::ZERO,
                "heartbeat" => self.heartbeat = seconds()?,
                "lost_after" => self.lost_after = seconds()?,
                "startup" => self.startup = seconds()?,
                "rosout" => {
                    self.rosout = v.parse().map_err(|_| bad("expected true or false"))?;
                }
                "service_mapping" => {
                    self.service_mapping = match v.as_str() {
                        "enhanced" => ServiceMapping::Enhanced,
                        "cyclone" => ServiceMapping::Cyclone,
                        _ => return Err(bad("expected enhanced or cyclone")),
                    };
                }
                _ => {
                    return Err(bad(
                        "unknown parameter (domain_id, heartbeat, lost_after, startup, service_mapping, rosout)",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// A domain id: an integer in 0..=232.
pub fn parse_domain(s: &str) -> Result<u16, &'static str> {
    match s.trim().parse::<u16>() {
        Ok(d) if d <= 232 => Ok(d),
        _ => Err("expected a domain id in 0..=232"),
    }
}

/// A comma-separated list of IP addresses, e.g. `127.0.0.1` or `127.0.0.1,10.0.0.5`.
pub fn parse_networks(s: &str) -> Result<Vec<IpAddr>, &'static str> {
    let v: Result<Vec<IpAddr>, _> = s
        .split(',')
        .map(str::trim)
        .filter(|x| !x.is_empty())
        .map(str::parse)
        .collect();
    match v {
        Ok(v) if !v.is_empty() => Ok(v),
        _ => Err("expected IP addresses separated by commas"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn domains_and_networks_parse() {
        assert_eq!(parse_domain("42"), Ok(42));
        assert!(parse_domain("233").is_err());
        assert!(parse_domain("x").is_err());
        assert_eq!(
            parse_networks("127.0.0.1, 10.0.0.5"),
            Ok(vec![
                IpAddr::from([127, 0, 0, 1]),
                IpAddr::from([10, 0, 0, 5])
            ])
        );
        assert!(parse_networks("").is_err());
        assert!(parse_networks("localhost").is_err());
    }

    #[test]
    fn the_plan_overrides_the_environment_which_overrides_the_defaults() {
        let plan = Ros2Settings {
            domain_id: Some(17),
            networks: vec![],
            heartbeat: Some(0.05),
            lost_after: Some(0.5),
            startup: None,
            ..Ros2Settings::default()
        };
        let none = |_: &str| None;
        let c = DdsConfig::resolve_with(&plan, none).unwrap();
        assert_eq!(
            c,
            DdsConfig {
                domain_id: 17,
                heartbeat: Duration::from_millis(50),
                lost_after: Duration::from_millis(500),
                ..DdsConfig::default()
            }
        );
        let env = |vars: &'static [(&'static str, &'static str)]| {
            move |name: &str| {
                vars.iter()
                    .find(|(k, _)| *k == name)
                    .map(|(_, v)| v.to_string())
            }
        };
        let bare = Ros2Settings::default();
        let ros = env(&[("ROS_DOMAIN_ID", "42")]);
        assert_eq!(DdsConfig::resolve_with(&bare, ros).unwrap().domain_id, 42);
        let both = env(&[("ROS_DOMAIN_ID", "42"), ("GSPN_ROS2_DOMAIN", "7")]);
        assert_eq!(DdsConfig::resolve_with(&bare, both).unwrap().domain_id, 7);
        assert_eq!(DdsConfig::resolve_with(&plan, both).unwrap().domain_id, 17);
        assert_eq!(DdsConfig::resolve_with(&bare, none).unwrap().domain_id, 0);
        let bad = env(&[("ROS_DOMAIN_ID", "300")]);
        let e = DdsConfig::resolve_with(&bare, bad).unwrap_err().to_string();
        assert_eq!(
            e,
            "environment variable ROS_DOMAIN_ID=`300`: expected a domain id in 0..=232"
        );
        let nets = env(&[("GSPN_ROS2_NETWORKS", "10.0.0.5")]);
        let c = DdsConfig::resolve_with(&bare, nets).unwrap();
        assert_eq!(c.bind_address().unwrap(), Some(IpAddr::from([10, 0, 0, 5])));
    }

    #[test]
    fn sockets_bind_to_one_ipv4_address_or_the_wildcard() {
        let with = |n: &[IpAddr]| DdsConfig {
            networks: n.to_vec(),
            ..DdsConfig::default()
        };
        let lo = IpAddr::from([127, 0, 0, 1]);
        assert_eq!(DdsConfig::default().bind_address().unwrap(), Some(lo));
        assert_eq!(
            with(&[IpAddr::from([0, 0, 0, 0])]).bind_address().unwrap(),
            None
        );
        let two = with(&[lo, IpAddr::from([10, 0, 0, 5])]).bind_address();
        assert_eq!(
            two.unwrap_err().to_string(),
            "DDS networks `127.0.0.1,10.0.0.5`: give one IPv4 address (or 0.0.0.0 for every interface)"
        );
        assert!(with(&["::1".parse().unwrap()]).bind_address().is_err());
        assert_eq!(DdsConfig::default().for_fleet(64).localhost_peers, 72);
        assert_eq!(DdsConfig::default().for_fleet(1).localhost_peers, 12);
        assert_eq!(DdsConfig::default().for_fleet(500).localhost_peers, 120);
    }
}
