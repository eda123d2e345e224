//! The ROS 2 backend (feature `ros2`): robots as ROS 2 action servers, firings on a topic,
//! over real DDS with the pure-Rust `ros2-client` (no ROS installation needed).
//!
//! - [`msgs`]: the `gspn_msgs` interfaces (`ros2/gspn_msgs/`) as Rust types with the DDS type
//!   names ROS 2 gives them.
//! - [`backend`]: the supervisor's side: [`Ros2Backend`] links to every robot's ExecPlace
//!   server, registers the `ros2` action ([`remote_place`]) and publishes the run's firings
//!   and marking ([`firings`]).
//! - [`robot`]: the robot's side (`plan-runner robot`): serves ExecPlace for the plan's
//!   `ros2` places with net-timed local actions.
//! - [`presence`]: whether a robot is there, from DDS discovery of its ExecPlace server
//!   (any ROS 2 node can be a robot) and its heartbeat when it sends one; a robot lost
//!   fails its actions.
//! - [`heartbeat`]: the optional heartbeats of `plan-runner robot` and the supervisor, and
//!   [`heartbeat::RobotWatch`] that follows them.
//! - [`bag`]: a run's journal exported as MCAP (ROS 2 messages, CDR), for `ros2 bag play`
//!   and Foxglove.
//! - [`rosout`]: the ROS 2 layer's warnings and errors on `/rosout` when asked.
//! - [`nav2`]: Nav2's `NavigateToPose` for `ros2` places with `server = "navigate_to_pose"`
//!   (real Nav2 robots) and for `goto` on simulated robots (`run --robots N --ros2`), which
//!   the world serves, with the robots' poses on `/<robot>/pose`.
//! - [`names`]: `--ros-args` and the names of topics and actions under the run's namespace.
//! - [`config`]: domain, networks (loopback by default), timings.
//! - [`settings`]: what a plan tells the backend ([`Ros2Settings`]); compiled without the
//!   feature too, so plans read the same everywhere.
//!
//! See `docs/ros2.md` for the topics, the plan keys and the DDS settings.

pub mod settings;

#[cfg(feature = "ros2")]
pub mod backend;
#[cfg(feature = "ros2")]
pub mod bag;
#[cfg(feature = "ros2")]
pub mod config;
#[cfg(feature = "ros2")]
pub mod firings;
#[cfg(feature = "ros2")]
pub mod heartbeat;
#[cfg(feature = "ros2")]
pub mod msgs;
#[cfg(feature = "ros2")]
pub mod names;
#[cfg(feature = "ros2")]
pub mod nav2;
#[cfg(feature = "ros2")]
pub mod presence;
#[cfg(feature = "ros2")]
pub mod remote_place;
#[cfg(feature = "ros2")]
pub mod robot;
#[cfg(feature = "ros2")]
pub mod rosout;

#[cfg(feature = "ros2")]
pub use backend::Ros2Backend;
#[cfg(feature = "ros2")]
pub use config::DdsConfig;
pub use settings::{DEFAULT_SERVER, NAV2_SERVER, ROS2_ACTION, Ros2Settings};

/// What went wrong in the ROS 2 backend.
#[cfg(feature = "ros2")]
#[derive(Debug, thiserror::Error)]
pub enum Ros2Error {
    /// Creating or using a DDS entity failed.
    #[error("DDS: {0}")]
    Dds(String),
    /// The settings could not be used.
    #[error(transparent)]
    Config(#[from] config::ConfigError),
    /// Robots (or subscribers) did not show up in time.
    #[error("{0}")]
    Startup(String),
    /// Anything else.
    #[error("{0}")]
    Other(String),
}

#[cfg(feature = "ros2")]
impl Ros2Error {
    /// A DDS error from ros2-client or RustDDS (their errors only implement `Debug`).
    pub fn dds(e: impl std::fmt::Debug) -> Ros2Error {
        Ros2Error::Dds(format!("{e:?}"))
    }
}
