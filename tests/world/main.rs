//! Behaviour tests of the `world` layer: one test binary, one module per behaviour.
#![cfg(feature = "sim")]

#[path = "../support/mod.rs"]
mod support;

mod map;
mod mirror;
mod patrol;
