//! Behaviour tests of the `cli` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod analyze;
mod check;
mod program_actions;
mod readme;
mod run;
mod run_on_robots;
mod simulate;
mod synthesize;
