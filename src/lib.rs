//! # gspn — multi-robot plans as generalized stochastic Petri nets
//!
//! Model a multi-robot plan as a GSPN, check it, analyse it, simulate it, execute it on
//! agents or robots, and watch it run.
//!
//! # Layout
//!
//! - [`net`]: the model — places, transitions, arcs, markings, enabling and firing. Pure.
//! - [`io`]: readers and writers — PIPE XML, PNML, GreatSPN PNPRO, DOT, plan files.
//! - [`sim`]: the token game — exact GSPN semantics on virtual time, seeded; `sim::world`
//!   (feature `sim`): simulated robots in a rapier2d room, driven by built-in actions.
//! - [`analysis`]: the tangible reachability graph, properties (bounds, deadlocks, liveness,
//!   invariants), the CTMC (steady state, limiting, transient) and measures.
//! - [`policy`]: marking → distribution over immediate transitions, with an indexed lookup.
//! - [`check`]: summary and structural warnings (dead transitions, isolated places, policy
//!   rules that can never apply) for `plan-runner check`.
//! - `actions` (unix): actions as programs in any language — a command per action or a
//!   long-lived JSON Lines worker — registered on the runtime like any other action.
//! - [`runtime`]: the actor runtime — supervisor, agents, places, actions, events, journal;
//!   `Runtime::builder(net)…spawn()` embeds a running plan in a tokio service.
//! - `web` (feature `web`): the viewer — an axum server with embedded assets that draws a
//!   net, plays its token game and shows its analysis (`plan-runner serve`).
//! - `ros2` (feature `ros2`): the ROS 2 backend — robots as ExecPlace action servers,
//!   firings and the marking on topics, over DDS (`plan-runner robot`, `docs/ros2.md`).
//!
//! The everyday types are in [`prelude`].

#![warn(missing_docs, missing_debug_implementations, unreachable_pub)]
#![deny(unused_must_use)]

#[cfg(unix)]
pub mod actions;
pub mod analysis;
pub mod check;
pub mod io;
pub mod net;
pub mod policy;
#[cfg(feature = "ros2")]
pub mod ros2;
pub mod runtime;
pub mod sim;
#[cfg(feature = "web")]
pub mod web;

/// The everyday types, for `use gspn::prelude::*`.
pub mod prelude {
    pub use crate::io::{Format, LoadError, LoadErrorKind, Loaded, ReadOptions, read_net};
    pub use crate::net::{
        ArcKind, Marking, Net, NetBuilder, PlaceId, Servers, Timing, TransitionId,
    };
    pub use crate::runtime::{
        Action, ActionContext, AgentId, Outcome, Runtime, RuntimeHandle, StopReason, action_fn,
    };
}
