//! # gspn — multi-robot plans as generalized stochastic Petri nets
//!
//! Model a multi-robot plan as a GSPN, check it, analyse it, simulate it, execute it on
//! agents or robots, and watch it run.
//!
//! # Layout
//!
//! Layers point one way: the model at the bottom, the runtime driving it, backends plugging
//! into the runtime, and [`plan`] on top wiring them together. Nothing below [`plan`]
//! imports it or [`io`].
//!
//! - [`net`]: the model — places, transitions, arcs, markings, enabling and firing. Pure.
//! - [`sample`]: chance at the bottom layer — the seeded generator, the portable exponential
//!   sampler, weighted picks and the sum tree; every random draw goes through it.
//! - [`stats`]: statistics at the bottom layer — estimates with 95% intervals, batch means,
//!   Student t quantiles and the distribution functions; `sim`, `runtime` and `conform` all
//!   read them from here.
//! - [`firing`]: the firing rules, once — enabling, the immediate choice, the exponential
//!   race with server semantics, the statistics; the explorer, the token game and the
//!   runtime drive it with their own choosers.
//! - [`policy`]: marking → distribution over immediate transitions, with an indexed lookup.
//! - [`analysis`]: the tangible reachability graph, properties (bounds, deadlocks, liveness,
//!   invariants), the CTMC (steady state, limiting, transient) and measures.
//! - [`io`]: net formats only — PIPE XML, PNML, GreatSPN PNPRO, DOT, PRISM.
//! - [`sim`]: the token game — exact GSPN semantics on virtual time, seeded — and
//!   Monte-Carlo estimates.
//! - [`conform`]: a recorded run (a journal, or a token-game run) set beside its net's
//!   predictions row by row with a verdict, the live drift monitor, and the net fitted back
//!   from runs (`plan-runner conform`).
//! - [`runtime`]: the actor runtime — supervisor, agents, places, actions, events, journal,
//!   roles and stop conditions; `Runtime::builder(net)…spawn()` embeds a running plan in a
//!   tokio service.
//! - `actions` (unix): actions as programs in any language — a command per action or a
//!   long-lived JSON Lines worker — registered on the runtime like any other action.
//! - [`world`]: the robot world — the room a plan describes (`world::map`), built-in robot
//!   programs (`goto L2; measure`), and (feature `sim`) simulated robots in a rapier2d room.
//! - [`ros2`]: the ROS 2 backend (feature `ros2`) — robots as ExecPlace action servers,
//!   firings and the marking on topics, over DDS (`plan-runner robot`, `docs/ros2.md`);
//!   `ros2::settings` (what a plan tells it) is compiled without the feature too.
//! - [`limits`]: the largest token count and duration a user may ask for.
//! - `web` (feature `web`): the viewer — an axum server with embedded assets that draws a
//!   net, plays its token game and shows its analysis (`plan-runner serve`).
//! - [`plan`]: the composition root — the plan file (TOML) read and resolved, import-thesis,
//!   and `Plan::runtime_builder()` wiring net, roles, policy and stop conditions into a run.
//! - [`check`]: summary and structural warnings (dead transitions, isolated places, policy
//!   rules that can never apply) for `plan-runner check`.
//!
//! The everyday types are in [`prelude`].
//!
//! # Features
//!
//! `web` (the viewer), `sim` (simulated robots) and `cli` (the `plan-runner` binary's
//! argument parsing, error reports, logging and terminal spinner) are on by default; `ros2`
//! adds the DDS backend. A service embedding the library builds it with
//! `default-features = false` and the backends it wants: no terminal or command-line crate
//! (clap, anyhow, tracing-subscriber, indicatif) comes with it. Long analyses report
//! progress only through their [`Monitor`](analysis::state_space::Monitor); a caller draws
//! its own display by polling it.

#![warn(missing_docs, missing_debug_implementations, unreachable_pub)]
#![deny(unused_must_use)]

#[cfg(unix)]
pub mod actions;
pub mod analysis;
pub mod check;
pub mod conform;
pub mod firing;
pub mod io;
pub mod limits;
pub mod net;
pub mod plan;
pub mod policy;
pub mod ros2;
pub mod runtime;
pub mod sample;
pub mod sim;
pub mod stats;
#[cfg(feature = "web")]
pub mod web;
pub mod world;

/// The everyday types, for `use gspn::prelude::*`.
pub mod prelude {
    pub use crate::io::{Format, LoadError, LoadErrorKind, Loaded, ReadOptions, read_net};
    pub use crate::net::{
        ArcKind, Marking, Net, NetBuilder, PlaceId, Servers, Timing, TransitionId,
    };
    pub use crate::plan::{Plan, read_plan};
    pub use crate::runtime::{
        Action, ActionContext, AgentId, Outcome, Runtime, RuntimeHandle, StopReason, action_fn,
    };
}
