//! Behaviour tests of the `token_game` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod conformance;
mod firing;
mod reference_nets;
mod token_counts_never_wrap;
mod token_game_runs;
