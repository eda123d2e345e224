//! [`Fleet`]: a run with a [`Map`] made ready to run on simulated robots. A plan converts
//! into a [`FleetPlan`] (`gspn::plan` does it), so `Fleet::new(plan, n)` takes a plan.
//!
//! 1. The net's initial tokens in robot places (action places running built-in robot
//!    actions) are scaled to the number of robots asked for, largest remainder first
//!    ([`scaled_marking`]); the net must neither create nor destroy robots (a structural
//!    P-invariant over the non-resource places).
//! 2. Robots `r1 … rN` are bound to the initial agents in agent order (places in net order,
//!    then tokens) and lined up in the queue of the location of their start place.
//! 3. The [`World`] is spawned and every built-in action name of the plan is registered.

use std::sync::Arc;

use super::action::Navigator;
use super::map::Map;
use super::program::ProgramError;
use super::{RobotStart, SimAction, World, WorldHandle};
use crate::analysis::invariants::conserves_tokens;
use crate::net::{Net, PlaceId};
use crate::runtime::{Role, RuntimeBuilder};

/// Why a plan cannot run on simulated robots.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum FleetError {
    /// The plan has no `[map]`.
    #[error("the plan has no [map]: simulated robots need one (see docs/plans.md)")]
    NoMap,
    /// No initial token sits in a place with a built-in robot action.
    #[error(
        "no place with a built-in robot action (goto, measure, wait, decide) holds a token initially: there is no robot to start"
    )]
    NoRobots,
    /// `--robots 0`.
    #[error("the number of robots must be at least 1")]
    ZeroRobots,
    /// A transition would create or destroy robots.
    #[error(
        "transition `{transition}` changes the number of robots by {change}: robots cannot appear or vanish (make the places that count things `role = \"resource\"`)"
    )]
    RobotTokens {
        /// The transition.
        transition: String,
        /// Tokens it adds (negative: removes) outside resource places.
        change: i64,
    },
    /// A robot's start place is at no location of the map.
    #[error("place `{0}` holds robots initially but is listed at no location of the map")]
    Unplaced(String),
    /// A place holds tokens initially but its action is not a built-in robot action.
    #[error(
        "place `{place}` holds tokens initially but its action `{action}` is not a built-in robot action"
    )]
    NotARobotAction {
        /// The place.
        place: String,
        /// Its action.
        action: String,
    },
    /// An action name that starts like a built-in but is wrong.
    #[error("action `{action}`: {reason}")]
    BadAction {
        /// The action name.
        action: String,
        /// What is wrong.
        reason: ProgramError,
    },
    /// The net could not be rebuilt with the scaled marking.
    #[error("net: {0}")]
    Net(String),
}

/// A runtime builder with the robots bound and the built-in actions registered, and the
/// world they drive in. Spawn the builder; stop the world when the run is over.
#[derive(Debug)]
pub struct Fleet {
    /// The run, ready to spawn (seed and robots set).
    pub builder: RuntimeBuilder,
    /// The running world.
    pub world: WorldHandle,
    /// The seed of the run and of the world.
    pub seed: u64,
    /// The map the world was made from.
    pub map: Arc<Map>,
    /// The built-in actions registered on `builder`, by name.
    actions: Vec<(String, SimAction)>,
}

/// What a fleet is made from: a configured run (net, roles, policy, stop conditions, seed,
/// time scale, robot names) and the room, when there is one.
#[derive(Debug)]
pub struct FleetPlan {
    /// The run, configured but not spawned.
    pub run: RuntimeBuilder,
    /// The room; `None` is refused with [`FleetError::NoMap`].
    pub map: Option<Map>,
}

/// Places whose agents are robots: action places whose action is a built-in program.
fn robot_places(run: &RuntimeBuilder, map: &Map) -> Result<Vec<bool>, FleetError> {
    let net = run.net();
    let mut out = vec![false; net.place_count()];
    for p in net.place_ids() {
        if let Some(Role::Action { name, .. }) = run.role_of(p) {
            let prog = map.program(name).map_err(|reason| FleetError::BadAction {
                action: name.clone(),
                reason,
            })?;
            out[p.index()] = prog.is_some();
            if prog.is_none() && net.place(p).initial > 0 {
                return Err(FleetError::NotARobotAction {
                    place: net.place(p).name.clone(),
                    action: name.clone(),
                });
            }
        }
    }
    Ok(out)
}

/// The initial marking with the tokens of the `robot` places scaled to `n` in total:
/// each gets ⌊n·k/K⌋, then the places with the largest remainders one more (net order
/// breaks ties). Other places keep their tokens.
pub fn scaled_marking(net: &Net, robot: &[bool], n: usize) -> Vec<u32> {
    let m0: Vec<u32> = net.places().iter().map(|p| p.initial).collect();
    let total: u64 = m0
        .iter()
        .zip(robot)
        .filter(|&(_, &r)| r)
        .map(|(&k, _)| u64::from(k))
        .sum();
    if total == 0 {
        return m0;
    }
    let n = n as u64;
    let mut out = m0.clone();
    let mut rest = Vec::new();
    let mut given = 0;
    for (i, (&k, &r)) in m0.iter().zip(robot).enumerate() {
        if r {
            let share = n * u64::from(k);
            out[i] = (share / total) as u32;
            given += share / total;
            rest.push((share % total, i));
        }
    }
    rest.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    for &(_, i) in rest.iter().take((n - given) as usize) {
        out[i] += 1;
    }
    out
}

impl Fleet {
    /// Prepares `plan` (which must have a map) for `robots` robots (`None`: as many as the
    /// net's initial tokens in robot places) and spawns the world. Call inside a tokio
    /// runtime (with a paused clock for virtual time faster than real time).
    pub fn new(plan: impl Into<FleetPlan>, robots: Option<usize>) -> Result<Fleet, FleetError> {
        Fleet::build(plan.into(), robots, false)
    }

    /// The same for robots that drive themselves — real robots running Nav2 (`run --nav2`,
    /// see `crate::ros2::nav2`): the world is a mirror ([`World::spawn_mirror`]) that keeps
    /// the queues, draws and turns of the built-in actions and the poses it is told. Give
    /// the fleet its navigator with [`Fleet::navigate_with`]: without one, a `goto` never
    /// arrives.
    pub fn mirror(plan: impl Into<FleetPlan>, robots: Option<usize>) -> Result<Fleet, FleetError> {
        Fleet::build(plan.into(), robots, true)
    }

    fn build(plan: FleetPlan, robots: Option<usize>, mirror: bool) -> Result<Fleet, FleetError> {
        let FleetPlan { run, map } = plan;
        let map = Arc::new(map.ok_or(FleetError::NoMap)?);
        let robot = robot_places(&run, &map)?;
        let net = run.net();
        let resources: Vec<PlaceId> = net
            .place_ids()
            .filter(|&p| matches!(run.role_of(p), Some(Role::Resource)))
            .collect();
        if let Err(leaks) = conserves_tokens(net, &resources) {
            let leak = &leaks[0];
            return Err(FleetError::RobotTokens {
                transition: net.transition(leak.transition).name.clone(),
                change: leak.delta,
            });
        }
        let mut run = run;
        if let Some(n) = robots {
            if n == 0 {
                return Err(FleetError::ZeroRobots);
            }
            let m = scaled_marking(run.net(), &robot, n);
            run = run
                .initial_marking(&m)
                .map_err(|e| FleetError::Net(e.to_string()))?;
        }
        let net = run.net();
        let mut starts = Vec::new();
        for p in net.place_ids() {
            let k = net.place(p).initial;
            if !robot[p.index()] || k == 0 {
                continue;
            }
            let loc = map
                .location_of_place(p)
                .ok_or_else(|| FleetError::Unplaced(net.place(p).name.clone()))?;
            for _ in 0..k {
                // The plan's robot names when it lists them (and no count was asked for).
                let i = starts.len();
                let name: Arc<str> = match run.robot_names().get(i) {
                    Some(n) if robots.is_none() => Arc::clone(n),
                    _ => Arc::from(format!("r{}", i + 1)),
                };
                // Robots are bound to the initial agents in agent order: agent i carries robot i.
                let agent = Some(i as u64);
                starts.push(RobotStart {
                    name,
                    location: loc,
                    agent,
                });
            }
        }
        if starts.is_empty() {
            return Err(FleetError::NoRobots);
        }
        let seed = run.seed_value().unwrap_or_else(|| {
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.as_nanos() as u64)
        });
        let spawn = if mirror {
            World::spawn_mirror
        } else {
            World::spawn
        };
        let world = spawn(Arc::clone(&map), &starts, run.time_scale_value(), seed);
        let mut names: Vec<String> = net
            .place_ids()
            .filter_map(|p| match run.role_of(p) {
                Some(Role::Action { name, .. }) => Some(name.clone()),
                _ => None,
            })
            .collect();
        names.sort();
        names.dedup();
        let bound: Vec<Arc<str>> = starts.into_iter().map(|s| s.name).collect();
        let mut actions = Vec::new();
        // The world steps on tokio's clock: with time scale 0, model time is that clock.
        let mut builder = run.seed(seed).robots(bound).follow_tokio_clock(true);
        for name in names {
            let action =
                SimAction::parse(&map, &name, &world).map_err(|reason| FleetError::BadAction {
                    action: name.clone(),
                    reason,
                })?;
            if let Some(a) = action {
                builder = builder.action(name.clone(), a.clone());
                actions.push((name, a));
            }
        }
        Ok(Fleet {
            builder,
            world,
            seed,
            map,
            actions,
        })
    }

    /// Makes every `goto` of the plan's built-in actions go through `navigator` (Nav2 over
    /// ROS 2: `crate::ros2::nav2`) instead of asking the world directly.
    pub fn navigate_with(mut self, navigator: Arc<dyn Navigator>) -> Fleet {
        for (name, action) in &mut self.actions {
            *action = action.clone().navigated_by(Arc::clone(&navigator));
            self.builder = self.builder.action(name.clone(), action.clone());
        }
        self
    }
}
