//! Behaviour tests of the `web` layer: one test binary, one module per behaviour.
#![cfg(feature = "web")]

#[path = "../support/mod.rs"]
mod support;

mod analysis;
mod api;
mod bounded_under_abuse;
mod browser;
mod conform;
mod edit;
mod follow;
mod layout;
mod live;
mod look;
mod navigate;
mod pdf;
mod questions;
mod readable;
mod replay_robots;
mod replay_windows;
mod replay_world;
mod security;
mod share;
mod throughput;
