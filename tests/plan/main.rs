//! Behaviour tests of the `plan` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod import_thesis;
mod plan_file;
mod program_actions;
