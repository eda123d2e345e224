//! The Zenoh transport (feature `zenoh`): the same plans, robots and topics as the ROS 2
//! backend ([`crate::ros2`]) over Zenoh instead of DDS, laid out as ROS 2's `rmw_zenoh_cpp`
//! lays them out, so fleets grow past one DDS domain: discovery goes through routers, not
//! N×N between every pair of participants (`docs/zenoh.md`).
//!
//! - [`keys`]: key expressions and liveliness tokens in rmw_zenoh's format.
//! - [`type_hash`]: ROS 2 type hashes, from the interfaces' own definitions.
//! - [`wire`]: CDR payloads and attachments.
//! - [`action`]: the request and response messages of the ExecPlace action's services.
//! - [`presence`]: who is there, from liveliness tokens (a token gone for `lost_after` →
//!   lost).
//! - [`supervisor`]: the supervisor's side of `plan-runner run --zenoh`.
//! - [`remote_place`]: the `ros2` action over Zenoh (ExecPlace as three queryables).
//! - [`robot`]: robots (`plan-runner robot --zenoh`, `plan-runner fleet`), any number per
//!   session.
//!
//! Every session here is a Zenoh *client* of a router (`plan-runner router`, or `zenohd`):
//! no multicast scouting, nothing listens but the router.

pub mod action;
pub mod keys;
pub mod presence;
pub mod remote_place;
pub mod robot;
pub mod supervisor;
pub mod type_hash;
pub mod wire;

use std::time::Duration;

pub use ::zenoh::Session;
pub use supervisor::ZenohBackend;

/// What went wrong in the Zenoh transport.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum ZenohError {
    /// Zenoh refused a configuration or a declaration.
    #[error("zenoh: {0}")]
    Zenoh(#[source] ::zenoh::Error),
    /// Robots did not show up in time: those missing, by id.
    #[error(
        "no liveliness token from {} robot(s) ({}) within {within:?} via {endpoint} (domain {domain}): are `plan-runner robot --zenoh` or `fleet` processes running?",
        missing.len(),
        shown(missing)
    )]
    RobotsMissing {
        /// The robots not seen.
        missing: Vec<String>,
        /// How long the supervisor waited.
        within: Duration,
        /// The router it connected to.
        endpoint: String,
        /// The domain.
        domain: u16,
    },
    /// Nobody subscribed to `/gspn/firings` in time (`--ros2-wait-subscribers`).
    #[error("no subscriber of /gspn/firings within {0:?}")]
    NoSubscriber(Duration),
    /// A robot of the plan has no presence watch (a bug).
    #[error("robot `{0}` is not watched")]
    Unwatched(String),
    /// A Nav2 place (`server = "navigate_to_pose"`), by name: Nav2 goals go over DDS only.
    #[error(
        "place `{0}` is a Nav2 place (server = \"navigate_to_pose\"): Nav2 goals go over DDS only; use transport = \"dds\""
    )]
    Nav2Place(String),
    /// A type hash could not be computed (a bug in the interfaces' definitions).
    #[error(transparent)]
    Type(#[from] type_hash::TypeError),
}

impl ZenohError {
    /// A Zenoh error, kept as the source.
    pub fn zenoh(e: ::zenoh::Error) -> ZenohError {
        ZenohError::Zenoh(e)
    }
}

/// The first ten of `ids`, then `…` if there are more.
fn shown(ids: &[String]) -> String {
    let mut s = ids.iter().take(10).cloned().collect::<Vec<_>>().join(", ");
    if ids.len() > 10 {
        s.push_str(", …");
    }
    s
}

/// How the processes of a fleet meet over Zenoh.
#[derive(Clone, Debug)]
pub struct ZenohConfig {
    /// The router every session connects to (`tcp/127.0.0.1:7447`).
    pub endpoint: String,
    /// The ROS domain id: the first chunk of every key expression.
    pub domain: u16,
    /// A robot (or the supervisor) whose liveliness token is gone this long is lost.
    pub lost_after: Duration,
    /// How long the supervisor waits for its robots.
    pub startup: Duration,
}

/// The session settings shared by clients and routers: no multicast scouting (sessions find
/// each other through the router they are given), the endpoints to connect to.
fn base_config(mode: &str, connect: &[String]) -> Result<::zenoh::Config, ZenohError> {
    let mut c = ::zenoh::Config::default();
    c.insert_json5("mode", &json5(&mode))
        .map_err(ZenohError::zenoh)?;
    c.insert_json5("scouting/multicast/enabled", "false")
        .map_err(ZenohError::zenoh)?;
    c.insert_json5("connect/endpoints", &json5(&connect))
        .map_err(ZenohError::zenoh)?;
    Ok(c)
}

/// A value as configuration text (JSON is JSON5).
fn json5<T: serde::Serialize + ?Sized>(v: &T) -> String {
    serde_json::to_string(v).unwrap_or_default()
}

/// Opens a client session to the router at `endpoint` (retrying the connection until it is
/// there, so robots may start before their router).
pub async fn client(endpoint: &str) -> Result<Session, ZenohError> {
    let mut c = base_config("client", &[endpoint.to_string()])?;
    // Keep trying to reach the router (a client that loses it reconnects by itself).
    c.insert_json5("connect/timeout_ms", "-1")
        .map_err(ZenohError::zenoh)?;
    ::zenoh::open(c).await.map_err(ZenohError::zenoh)
}

/// Opens a router listening on `listen` and connected to the routers `connect` (another
/// site's): the session routes the others' traffic for as long as it is kept. `lease`:
/// how long a peer may hear nothing from it before dropping the link (Zenoh's default
/// 10 s); a router whose link to another site is cut withdraws that site's liveliness
/// tokens after the other router's lease.
pub async fn router(
    listen: &[String],
    connect: &[String],
    lease: Option<Duration>,
) -> Result<Session, ZenohError> {
    let mut c = base_config("router", connect)?;
    if let Some(l) = lease {
        let ms = u64::try_from(l.as_millis()).unwrap_or(u64::MAX).max(1);
        c.insert_json5("transport/link/tx/lease", &ms.to_string())
            .map_err(ZenohError::zenoh)?;
    }
    c.insert_json5("listen/endpoints", &json5(listen))
        .map_err(ZenohError::zenoh)?;
    ::zenoh::open(c).await.map_err(ZenohError::zenoh)
}
