//! Behaviour tests of the `ros2` layer: one test binary, one module per behaviour.
#![cfg(feature = "ros2")]

#[path = "../support/mod.rs"]
mod support;

#[path = "support.rs"]
mod ros2_support;

#[path = "rtps.rs"]
mod ros2_rtps;

#[path = "hub.rs"]
mod ros2_hub;

mod any_ros2_node_is_a_robot;
mod concurrent_goals;
mod ctrl_c_while_waiting_for_robots;
mod fleet;
mod interfaces;
mod interop;
mod lifecycle;
mod multiprocess;
mod nav2_for_goto;
mod nav2_places;
mod netns;
mod python_robot;
mod rosout;
mod runs_recorded_to_mcap;
mod same_plan_on_nav2_robots;
mod security;
mod two_plans_in_two_namespaces;
