//! The robot world: the room ([`map`]) and the robot programs ([`program`]) a plan
//! describes, and (feature `sim`) simulated robots in a rapier2d room stepped by a `World`
//! actor, driven by the built-in robot actions (`goto`, `measure`, `wait`, `decide`).
//!
//! - [`map`]: the checked room — locations, topological map, walls, obstacles, bodies, queues.
//! - [`program`]: built-in robot programs (`goto L2; measure`) read against a map.
//!
//! With feature `sim`:
//! - [`room`]: the physics — disc robots as dynamic rapier bodies, walls and obstacles as
//!   static colliders, ORCA (dodgy_2d) between robots; synchronous, benchmarkable.
//! - [`queue`]: first-come-first-served queues with lanes at every location.
//! - [`action`]: the built-in [`Action`](crate::runtime::Action)s and how a plan names them.
//! - [`fleet`]: a plan with a `[map]` → robots placed, world spawned, actions registered.
//! - [`backend`]: the world as a [`Backend`](crate::runtime::Backend) of its run.
//! - [`metrics`]: collisions, clearance, order violations, stuck robots, patrol cycles.
//! - [`view`]: [`WorldView`], what a viewer draws, published on a `watch` channel.
//!
//! Time: the world steps `1 / step_hz` of simulated time per tick and sleeps on tokio time
//! between ticks (`dt × time_scale`; with time scale 0, tokio's paused clock jumps straight to
//! the next tick, so a run is as fast as the computer allows). It steps only while some robot
//! moves: a world of parked robots costs nothing.
//!
//! ```
//! use gspn::io::ReadOptions;
//! use gspn::plan::read_plan;
//! use gspn::world::Fleet;
//!
//! let rt = tokio::runtime::Builder::new_current_thread()
//!     .enable_all()
//!     .start_paused(true) // virtual time: as fast as the steps compute
//!     .build()
//!     .unwrap();
//! rt.block_on(async {
//!     let path = std::path::Path::new("plans/temperature-patrol/plan.toml");
//!     let mut plan = read_plan(path, &ReadOptions::default()).unwrap();
//!     plan.stop.time_limit = Some(150.0);
//!     let fleet = Fleet::new(plan, Some(2)).unwrap();
//!     let handle = fleet.builder.spawn().unwrap();
//!     handle.wait().await;
//!     let m = fleet.world.metrics().await.unwrap();
//!     fleet.world.stop();
//!     assert_eq!((m.robots, m.collisions, m.stuck_events), (2, 0, 0));
//!     assert!(m.cycles_per_robot.iter().all(|&c| c >= 1), "{m:?}");
//! });
//! ```

pub mod map;
pub mod program;

#[cfg(feature = "sim")]
pub(crate) mod action;
#[cfg(feature = "sim")]
mod actor;
#[cfg(feature = "sim")]
pub(crate) mod backend;
#[cfg(feature = "sim")]
pub mod fleet;
#[cfg(feature = "sim")]
pub(crate) mod metrics;
#[cfg(feature = "sim")]
pub(crate) mod queue;
#[cfg(feature = "sim")]
pub mod room;
#[cfg(feature = "sim")]
pub(crate) mod view;

#[cfg(feature = "sim")]
pub use action::{DriveError, Navigator, SimAction};
#[cfg(feature = "sim")]
pub use actor::{GotoError, RobotStart, World, WorldHandle};
#[cfg(feature = "sim")]
pub use backend::WorldBackend;
#[cfg(feature = "sim")]
pub use fleet::{Fleet, FleetError};
#[cfg(feature = "sim")]
pub use metrics::SimMetrics;
#[cfg(feature = "sim")]
pub use view::{MapView, RobotView, WorldView};
