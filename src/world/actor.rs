//! The [`World`] actor: steps the room, moves robots through the queues, publishes views.

use std::sync::Arc;
use std::time::Duration;

use kameo::actor::{Actor, ActorRef, Spawn, WeakActorRef};
use kameo::error::Infallible;
use kameo::mailbox::{self, MailboxReceiver, Signal};
use rand::SeedableRng;
use rustc_hash::FxHashMap;
use tokio::sync::{oneshot, watch};
use tokio::time::Instant;

use super::map::Map;
use super::queue::Queues;
use super::room::{Room, Vec2};
use super::{MapView, RobotView, SimMetrics, WorldView};
use messages::{Goto, Hold, SetPose};

use crate::sample::{self, Rng};

mod handle;
pub(super) mod messages;

pub use handle::WorldHandle;

/// Views per simulated second, at most.
const VIEWS_PER_SECOND: f64 = 20.0;
/// A robot has arrived when it is this close to its slot (m).
const ARRIVED: f32 = 0.1;
/// Getting this much closer to the goal counts as progress (m).
const PROGRESS: f32 = 0.05;

/// Why a `goto` did not arrive.
#[derive(Clone, Debug, PartialEq)]
#[non_exhaustive]
pub enum GotoError {
    /// No progress for the map's `stuck_after` seconds, at this position.
    Stuck(f32, f32),
    /// The topological map has no path between the two locations.
    NoPath(String, String),
    /// No robot of that name in the world.
    UnknownRobot(String),
    /// The world was stopped.
    Gone,
}

impl std::error::Error for GotoError {}

impl std::fmt::Display for GotoError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            GotoError::Stuck(x, y) => write!(f, "stuck at ({x:.2}, {y:.2})"),
            GotoError::NoPath(a, b) => write!(f, "no path from `{a}` to `{b}` on the map"),
            GotoError::UnknownRobot(r) => write!(f, "no robot `{r}` in the world"),
            GotoError::Gone => write!(f, "the world is gone"),
        }
    }
}

#[derive(Debug)]
struct Robot {
    name: Arc<str>,
    agent: Option<u64>,
    location: Option<usize>,
    arrived: bool,
    goto: Option<oneshot::Sender<Result<(), GotoError>>>,
    best: f32,
    progress_step: u64,
    turn: Option<oneshot::Sender<()>>,
    rng: Rng,
    patrol_at: Option<usize>,
    streak: usize,
    cycles: u32,
}

/// The world actor: owns the room, the queues and the metrics.
pub struct World {
    map: Arc<Map>,
    room: Room,
    queues: Queues,
    robots: Vec<Robot>,
    names: FxHashMap<Arc<str>, usize>,
    scale: f64,
    tick_len: Duration,
    next_tick: Instant,
    clock_start: Instant,
    wall_start: std::time::Instant,
    stuck_steps: u64,
    stuck_events: u64,
    order_violations: u64,
    view_tx: watch::Sender<WorldView>,
    map_view: Arc<MapView>,
    view_every: u64,
    active: bool,
    /// The robots drive themselves (real robots, `run --nav2`): no physics steps; a robot's
    /// pose and its arrival come from outside ([`WorldHandle::mirror_goto`]).
    mirror: bool,
}

impl std::fmt::Debug for World {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("World")
            .field("robots", &self.robots.len())
            .field("steps", &self.room.steps)
            .finish()
    }
}

/// A robot at the start: its name, the location whose queue it starts in, and the agent it
/// carries (when known; the world learns it from the robot's first action otherwise).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct RobotStart {
    /// The robot's name.
    pub name: Arc<str>,
    /// Index of its start location in the map.
    pub location: usize,
    /// The agent it carries.
    pub agent: Option<u64>,
}

impl World {
    /// Spawns a world on `map` with one robot per [`RobotStart`], lined up in the
    /// locations' queues in this order. `time_scale` as the runtime's (0 = virtual time);
    /// `seed` seeds every robot's draws (one stream per robot).
    pub fn spawn(map: Arc<Map>, robots: &[RobotStart], time_scale: f64, seed: u64) -> WorldHandle {
        World::spawn_as(map, robots, time_scale, seed, false)
    }

    /// A world whose robots drive themselves (real robots running Nav2, `run --nav2`): it
    /// steps no physics and keeps what the built-in actions need — the locations' queues,
    /// each robot's draws, the turns — with the poses and arrivals it is told
    /// ([`WorldHandle::mirror_goto`], [`WorldHandle::set_pose`]). Robots start in the
    /// queues of their start locations, as in [`World::spawn`].
    pub fn spawn_mirror(
        map: Arc<Map>,
        robots: &[RobotStart],
        time_scale: f64,
        seed: u64,
    ) -> WorldHandle {
        World::spawn_as(map, robots, time_scale, seed, true)
    }

    fn spawn_as(
        map: Arc<Map>,
        robots: &[RobotStart],
        time_scale: f64,
        seed: u64,
        mirror: bool,
    ) -> WorldHandle {
        let mut queues = Queues::new(&map);
        for (r, s) in robots.iter().enumerate() {
            queues.join(s.location, r);
        }
        let mut starts = vec![Vec2::ZERO; robots.len()];
        for l in 0..map.locations.len() {
            for (r, p) in queues.slots(l) {
                starts[r] = p;
            }
        }
        let room = Room::new(&map, &starts);
        let scale = if time_scale > 0.0 { time_scale } else { 1.0 };
        let dt = f64::from(room.dt());
        let robots: Vec<Robot> = robots
            .iter()
            .enumerate()
            .map(|(r, s)| {
                let mut rng = Rng::seed_from_u64(seed);
                rng.set_stream(r as u64 + 1);
                Robot {
                    name: Arc::clone(&s.name),
                    agent: s.agent,
                    location: Some(s.location),
                    arrived: true,
                    goto: None,
                    best: f32::INFINITY,
                    progress_step: 0,
                    turn: None,
                    rng,
                    patrol_at: map.patrol.iter().position(|&p| p == s.location),
                    streak: 0,
                    cycles: 0,
                }
            })
            .collect();
        let names = robots
            .iter()
            .enumerate()
            .map(|(i, r)| (Arc::clone(&r.name), i))
            .collect();
        let map_view = Arc::new(MapView::new(&map));
        let mut w = World {
            stuck_steps: (map.stuck_after / dt).ceil() as u64,
            view_every: ((map.step_hz / VIEWS_PER_SECOND).round() as u64).max(1),
            map,
            room,
            queues,
            robots,
            names,
            scale,
            tick_len: crate::limits::duration(dt * scale),
            next_tick: Instant::now(),
            clock_start: Instant::now(),
            wall_start: std::time::Instant::now(),
            stuck_events: 0,
            order_violations: 0,
            view_tx: watch::channel(WorldView {
                time: 0.0,
                map: Arc::clone(&map_view),
                robots: Vec::new(),
            })
            .0,
            map_view,
            active: false,
            mirror,
        };
        let first = w.view();
        let (tx, rx) = watch::channel(first);
        w.view_tx = tx;
        let names = w.robots.iter().map(|r| Arc::clone(&r.name)).collect();
        let actor = World::spawn_with_mailbox(w, mailbox::unbounded());
        WorldHandle {
            actor,
            view: rx,
            scale,
            robots: names,
        }
    }

    fn sim_time(&self) -> f64 {
        self.clock_start.elapsed().as_secs_f64() / self.scale
    }

    fn view(&self) -> WorldView {
        let radius = f64::from(self.room.radius());
        WorldView {
            time: self.sim_time(),
            map: Arc::clone(&self.map_view),
            robots: self
                .robots
                .iter()
                .zip(&self.room.bodies)
                .map(|(r, b)| RobotView {
                    id: Arc::clone(&r.name),
                    agent: r.agent,
                    x: f64::from(b.pos.x),
                    y: f64::from(b.pos.y),
                    radius,
                })
                .collect(),
        }
    }

    fn publish(&self) {
        if self.view_tx.receiver_count() > 0 {
            self.view_tx.send_replace(self.view());
        }
    }

    fn metrics(&self) -> SimMetrics {
        let sim = self.sim_time();
        let wall = self.wall_start.elapsed().as_secs_f64();
        SimMetrics {
            robots: self.robots.len(),
            sim_time_s: sim,
            real_time_factor: if wall > 0.0 { sim / wall } else { 0.0 },
            collisions: self.room.collisions,
            min_separation_m: self.room.min_separation.map(f64::from),
            order_violations: self.order_violations,
            stuck_events: self.stuck_events,
            cycles_per_robot: self.robots.iter().map(|r| r.cycles).collect(),
        }
    }

    fn wake(&mut self) {
        if !self.active && !self.mirror {
            self.active = true;
            self.next_tick = Instant::now() + self.tick_len;
        }
    }

    /// Points every robot of `loc` at its slot; robots on their way there re-arm progress.
    fn retarget(&mut self, loc: usize) {
        for (r, p) in self.queues.slots(loc) {
            self.room.bodies[r].target = p;
            if self.robots[r].goto.is_some() {
                self.robots[r].best = f32::INFINITY;
            }
        }
        self.wake();
    }

    fn release_turn(&mut self, loc: usize) {
        if let Some(f) = self.queues.front(loc)
            && let Some(tx) = self.robots[f].turn.take()
        {
            let _ = tx.send(());
        }
    }

    fn route(&self, from: usize, to: usize) -> Option<Vec<usize>> {
        let pos = |i: usize| {
            Vec2::new(
                self.map.locations[i].x as f32,
                self.map.locations[i].y as f32,
            )
        };
        let mm = |a: usize, b: usize| (pos(a).distance(pos(b)) * 1000.0) as u64;
        pathfinding::prelude::astar(
            &from,
            |&n| {
                self.map
                    .neighbours(n)
                    .map(move |m| (m, mm(n, m)))
                    .collect::<Vec<_>>()
            },
            |&n| mm(n, to),
            |&n| n == to,
        )
        .map(|(path, _)| path)
    }

    fn goto(&mut self, m: Goto) {
        let Some(&r) = self.names.get(&m.robot) else {
            let _ = m
                .reply
                .send(Err(GotoError::UnknownRobot(m.robot.to_string())));
            return;
        };
        if let Some(agent) = m.agent {
            self.robots[r].agent = Some(agent);
        }
        if self.robots[r].location == Some(m.location) {
            if self.robots[r].arrived {
                let _ = m.reply.send(Ok(()));
            } else {
                // A retry after a failure: keep driving, with a fresh stuck timer.
                let rb = &mut self.robots[r];
                rb.goto = Some(m.reply);
                rb.best = f32::INFINITY;
                self.wake();
            }
            return;
        }
        let from = self.robots[r].location;
        let path = match from {
            Some(f) => match self.route(f, m.location) {
                Some(p) => p,
                None => {
                    let name = |i: usize| self.map.locations[i].name.clone();
                    let _ = m
                        .reply
                        .send(Err(GotoError::NoPath(name(f), name(m.location))));
                    return;
                }
            },
            None => vec![m.location],
        };
        if let Some(f) = from {
            if let Some(ahead) = self.queues.leave(f, r)
                && ahead > 0
            {
                self.order_violations += 1;
            }
            self.retarget(f);
            self.release_turn(f);
        }
        self.queues.join(m.location, r);
        let waypoints = path[1..path.len().saturating_sub(1)]
            .iter()
            .map(|&i| self.queues.point(i))
            .collect();
        self.room.bodies[r].waypoints = waypoints;
        let rb = &mut self.robots[r];
        rb.location = Some(m.location);
        rb.arrived = false;
        rb.goto = Some(m.reply);
        rb.best = f32::INFINITY;
        self.retarget(m.location);
    }

    /// A mirror world's robot reports its pose.
    fn set_pose(&mut self, m: SetPose) {
        let Some(&r) = self.names.get(&m.robot) else {
            return;
        };
        let p = Vec2::new(m.x as f32, m.y as f32);
        let b = &mut self.room.bodies[r];
        b.pos = p;
        b.target = p;
        b.waypoints.clear();
        self.publish();
    }

    /// A mirror world's robot has arrived where its `goto` went.
    fn arrived(&mut self, robot: &str) {
        if let Some(&r) = self.names.get(robot)
            && self.robots[r].goto.is_some()
        {
            self.arrive(r);
        }
    }

    fn arrive(&mut self, r: usize) {
        let patrol = &self.map.patrol;
        let rb = &mut self.robots[r];
        rb.arrived = true;
        if let Some(tx) = rb.goto.take() {
            let _ = tx.send(Ok(()));
        }
        let Some(loc) = rb.location else { return };
        let Some(k) = patrol.iter().position(|&p| p == loc) else {
            rb.patrol_at = None;
            rb.streak = 0;
            return;
        };
        match rb.patrol_at {
            Some(prev) if (prev + 1) % patrol.len() == k => {
                rb.streak += 1;
                if rb.streak == patrol.len() {
                    rb.cycles += 1;
                    rb.streak = 0;
                }
            }
            _ => rb.streak = 0,
        }
        rb.patrol_at = Some(k);
    }

    fn tick(&mut self) {
        self.room.step();
        let step = self.room.steps;
        let mut moving = false;
        for r in 0..self.robots.len() {
            if self.robots[r].goto.is_some() {
                let b = &self.room.bodies[r];
                if b.waypoints.is_empty() && b.pos.distance(b.target) < ARRIVED {
                    self.arrive(r);
                } else {
                    let rem = self.room.remaining(r);
                    let rb = &mut self.robots[r];
                    if rem < rb.best - PROGRESS || rb.best.is_infinite() {
                        rb.best = rem;
                        rb.progress_step = step;
                    } else if step - rb.progress_step >= self.stuck_steps {
                        let p = self.room.bodies[r].pos;
                        if let Some(tx) = rb.goto.take() {
                            let _ = tx.send(Err(GotoError::Stuck(p.x, p.y)));
                        }
                        self.stuck_events += 1;
                    }
                    moving = true;
                }
            }
            moving |= !self.room.settled(r);
        }
        if step.is_multiple_of(self.view_every) || !moving {
            self.publish();
        }
        self.active = moving;
    }

    fn hold(&mut self, m: Hold) {
        let Some(&r) = self.names.get(&m.robot) else {
            let _ = m.reply.send((0.0, None));
            return;
        };
        let rb = &mut self.robots[r];
        rb.agent = Some(m.agent);
        let total: f64 = m.outputs.iter().map(|o| o.1).sum();
        let seconds = m.seconds.unwrap_or_else(|| {
            if total > 0.0 {
                sample::exponential(&mut rb.rng, total)
            } else {
                0.0
            }
        });
        let pick = if total > 0.0 {
            sample::pick_weighted(&mut rb.rng, &m.outputs)
        } else {
            None
        };
        let _ = m.reply.send((seconds, pick));
    }
}

impl Actor for World {
    type Args = World;
    type Error = Infallible;

    async fn on_start(mut w: World, _: ActorRef<Self>) -> Result<Self, Self::Error> {
        w.clock_start = Instant::now();
        w.wall_start = std::time::Instant::now();
        w.publish();
        Ok(w)
    }

    /// Ticks while some robot moves; otherwise only waits for messages.
    async fn next(
        &mut self,
        _: WeakActorRef<Self>,
        mailbox_rx: &mut MailboxReceiver<Self>,
    ) -> Result<Option<Signal<Self>>, Self::Error> {
        while self.active {
            tokio::select! {
                biased;
                sig = mailbox_rx.recv() => return Ok(sig),
                _ = tokio::time::sleep_until(self.next_tick) => {
                    self.tick();
                    self.next_tick += self.tick_len;
                }
            }
        }
        Ok(mailbox_rx.recv().await)
    }
}
