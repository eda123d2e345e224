//! Behaviour tests of the `cli` layer: one test binary, one module per behaviour.

#[path = "../support/mod.rs"]
mod support;

mod analyze;
mod analyze_answers_queries;
mod bad_limits;
mod check;
mod conform;
mod endless_runs;
mod faithful_execution;
mod full_disk_stops_the_run;
mod journal_survives_signals;
mod program_actions;
mod readme;
mod refusals_name_their_place;
mod replay_finds_its_net;
mod replay_robots;
mod replay_streams_the_journal;
mod robots_must_match_agents;
mod run;
mod run_on_robots;
mod signals_end_the_run_and_its_viewer;
mod simulate;
mod synthesize;
mod thesis_standalone;
