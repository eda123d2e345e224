//! DDS settings: the domain, the networks a participant uses, and how robots are watched.
//!
//! Defaults suit a sandbox: loopback only (`127.0.0.1`), domain 0. The plan's `[ros2]` table
//! sets them for a plan; the environment (`GSPN_ROS2_DOMAIN`, `GSPN_ROS2_NETWORKS`) overrides
//! the plan, and command-line flags override both (see `docs/ros2.md`).

use std::net::IpAddr;
use std::time::Duration;

use ros2_client::dds::rustdds::DomainParticipantBuilder;
use ros2_client::{Context, NodeName, NodeOptions};

use super::settings::Ros2Settings;

/// How a process joins DDS and how the supervisor watches robots.
#[derive(Clone, Debug, PartialEq)]
pub struct DdsConfig {
    /// The DDS domain id (0–232).
    pub domain_id: u16,
    /// The local addresses used for discovery, multicast and advertised locators.
    pub networks: Vec<IpAddr>,
    /// How often a robot publishes its heartbeat.
    pub heartbeat: Duration,
    /// A robot whose heartbeats stop for this long is lost.
    pub lost_after: Duration,
    /// How long the supervisor waits for every robot (and subscriber) before it starts.
    pub startup: Duration,
}

impl Default for DdsConfig {
    fn default() -> Self {
        DdsConfig {
            domain_id: 0,
            networks: vec![IpAddr::from([127, 0, 0, 1])],
            heartbeat: Duration::from_millis(100),
            lost_after: Duration::from_millis(1000),
            startup: Duration::from_secs(30),
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
    /// The DDS participant or the ROS 2 node could not be created.
    #[error("DDS: {0}")]
    Dds(String),
}

impl DdsConfig {
    /// The defaults, then the plan's `[ros2]` settings, then the environment.
    pub fn resolve(plan: &Ros2Settings) -> Result<DdsConfig, ConfigError> {
        let mut c = DdsConfig::default();
        if let Some(d) = plan.domain_id {
            c.domain_id = d;
        }
        if !plan.networks.is_empty() {
            c.networks.clone_from(&plan.networks);
        }
        if let Some(s) = plan.heartbeat {
            c.heartbeat = Duration::from_secs_f64(s);
        }
        if let Some(s) = plan.lost_after {
            c.lost_after = Duration::from_secs_f64(s);
        }
        if let Some(s) = plan.startup {
            c.startup = Duration::from_secs_f64(s);
        }
        if let Ok(v) = std::env::var("GSPN_ROS2_DOMAIN") {
            c.domain_id = parse_domain(&v).map_err(|why| ConfigError::Env {
                name: "GSPN_ROS2_DOMAIN",
                value: v.clone(),
                why,
            })?;
        }
        if let Ok(v) = std::env::var("GSPN_ROS2_NETWORKS") {
            c.networks = parse_networks(&v).map_err(|why| ConfigError::Env {
                name: "GSPN_ROS2_NETWORKS",
                value: v.clone(),
                why,
            })?;
        }
        Ok(c)
    }

    /// A ROS 2 context (one DDS participant) with these settings.
    pub fn context(&self) -> Result<Context, ConfigError> {
        let dp = DomainParticipantBuilder::new(self.domain_id)
            .with_only_networks(self.networks.iter().copied())
            .build()
            .map_err(|e| ConfigError::Dds(format!("{e:?}")))?;
        Context::from_domain_participant(dp).map_err(|e| ConfigError::Dds(format!("{e:?}")))
    }

    /// A node named `name` in namespace `/gspn`, in a new context.
    pub fn node(&self, name: &str) -> Result<ros2_client::Node, ConfigError> {
        let ctx = self.context()?;
        let name = NodeName::new("/gspn", name).map_err(|e| ConfigError::Dds(format!("{e:?}")))?;
        ctx.new_node(name, NodeOptions::new().enable_rosout(false))
            .map_err(|e| ConfigError::Dds(format!("{e:?}")))
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
    fn the_plan_overrides_the_defaults() {
        let plan = Ros2Settings {
            domain_id: Some(17),
            networks: vec![],
            heartbeat: Some(0.05),
            lost_after: Some(0.5),
            startup: None,
            ..Ros2Settings::default()
        };
        let c = DdsConfig {
            domain_id: plan.domain_id.unwrap(),
            heartbeat: Duration::from_millis(50),
            lost_after: Duration::from_millis(500),
            ..DdsConfig::default()
        };
        // The environment is not set in tests (GSPN_ROS2_* belong to the CLI's users).
        if std::env::var_os("GSPN_ROS2_DOMAIN").is_none()
            && std::env::var_os("GSPN_ROS2_NETWORKS").is_none()
        {
            assert_eq!(DdsConfig::resolve(&plan).unwrap(), c);
        }
    }
}
