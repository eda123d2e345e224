//! Behaviour tests of the `runtime` layer: one test binary, one module per behaviour.

#[macro_use]
#[path = "../support/mod.rs"]
mod support;

mod actions_see_the_marking;
mod actor_agents_at_scale;
mod agent_identity;
mod agents_match_tokens;
mod builtin_actions;
mod conformance;
mod conformance_without_false_alarms;
mod differential;
mod failures;
mod golden_trace;
mod matches_analysis;
mod old_journal_replays;
mod policy;
mod program_actions;
mod repeats_from_seed;
mod robot_tokens;
mod robots_follow_agents;
mod stop_leaves_complete_journal;
mod thesis_nets_match_reference;
mod token_counts_never_wrap;
