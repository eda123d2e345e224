//! Behaviour tests of the `model` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod check_warnings_are_sound;
mod policy;
