//! Behaviour tests of the `analysis` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod ctmc;
mod decision_model;
mod decision_objectives;
mod invariants;
mod mcc_oracles;
mod memory_is_bounded;
mod properties;
mod queries_match_storm;
mod state_space;
mod steady_state_from_columns;
mod steady_state_random_nets;
mod storm_cross_check;
mod synthesis_intervals_hold;
mod synthesis_random_models;
mod synthesised_policy;
mod thesis_reference;
mod vanishing_elimination;
