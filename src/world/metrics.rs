//! [`SimMetrics`]: what a simulated run measured (`plan-runner run --json`, key `sim`).
//!
//! - `collisions`: contact episodes — a pair of robots whose centres came closer than the sum
//!   of their radii counts once per episode, however many steps the contact lasts.
//! - `min_separation_m`: the smallest clearance seen between two robots, i.e. the distance
//!   between their centres minus both radii (negative = they overlapped), over every physics
//!   step, among pairs within 2 m of each other; `null` when no two robots ever came that close.
//! - `order_violations`: robots that left a location while a robot that had joined that
//!   location's queue before them was still there (robots must leave a location in the order
//!   they arrived — the thesis's robot 3 passing robot 4).
//! - `stuck_events`: `goto`s that failed because the robot made no progress for the map's
//!   `stuck_after` seconds.
//! - `cycles_per_robot`: per robot (in robot order), completed patrol loops: arrivals at the
//!   map's `patrol` locations in their cyclic order, back to where the loop started.

use serde::Serialize;

/// Metrics of a simulated run.
#[derive(Clone, Debug, PartialEq, Serialize, kameo::Reply)]
pub struct SimMetrics {
    /// Robots in the world.
    pub robots: usize,
    /// Simulated seconds.
    pub sim_time_s: f64,
    /// Simulated seconds per wall-clock second.
    pub real_time_factor: f64,
    /// Contact episodes between robots.
    pub collisions: u64,
    /// Smallest clearance between two robots (m).
    pub min_separation_m: Option<f64>,
    /// Robots that left a location before one that arrived earlier.
    pub order_violations: u64,
    /// `goto`s that failed for lack of progress.
    pub stuck_events: u64,
    /// Completed patrol loops, per robot.
    pub cycles_per_robot: Vec<u32>,
}

impl std::fmt::Display for SimMetrics {
    /// Three lines: robots and time, safety counts, patrol cycles.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "sim: {} robots, {:.1} s simulated ({:.1}× real time)",
            self.robots, self.sim_time_s, self.real_time_factor
        )?;
        writeln!(
            f,
            "  collisions {}  min separation {}  order violations {}  stuck {}",
            self.collisions,
            self.min_separation_m
                .map_or("-".to_string(), |s| format!("{s:.3} m")),
            self.order_violations,
            self.stuck_events
        )?;
        write!(f, "  patrol cycles per robot {:?}", self.cycles_per_robot)
    }
}
