//! The [`Room`]: a rapier2d world of disc robots, walls and obstacles, stepped at a fixed
//! `dt`, with ORCA (dodgy_2d) between the robots. Synchronous and free of actors, so the
//! benchmark can step it directly.
//!
//! Each step: every robot wants to drive at its top speed towards its next waypoint, or to
//! slow down onto its final target (it can stop within its top acceleration); ORCA turns
//! that into a velocity that avoids the neighbours and the obstacles; the change of velocity
//! is capped by the top acceleration; rapier moves the dynamic bodies (walls and obstacles
//! push back). Then the robots' positions are read back and checked for contacts.

use std::borrow::Cow;
use std::collections::VecDeque;

use rapier2d::prelude::{ColliderBuilder, PhysicsWorld, RigidBodyBuilder, RigidBodyHandle};
use rustc_hash::FxHashSet;

use crate::world::map::{Map, Rect};

/// A 2-D vector of the room (rapier's glam `Vec2`).
pub type Vec2 = rapier2d::math::Vector;

/// How far a robot looks for neighbours to avoid (m).
const NEIGHBOUR_DIST: f32 = 2.0;
/// At most this many nearest neighbours enter ORCA.
const MAX_NEIGHBOURS: usize = 10;
/// ORCA keeps this much more than the bodies' radius between robots (m): the top
/// acceleration can keep a robot from taking ORCA's velocity at once, and a margin absorbs it.
const SAFETY: f32 = 0.05;
/// Obstacles farther than this from a robot are left out of its ORCA (m).
const OBSTACLE_DIST: f32 = 2.0;
/// A waypoint counts as passed within this distance (m).
const WAYPOINT_TOL: f32 = 0.6;

/// One robot's body and what it drives to.
#[derive(Clone, Debug)]
pub struct Body {
    handle: RigidBodyHandle,
    /// Position (m).
    pub pos: Vec2,
    /// Velocity (m/s).
    pub vel: Vec2,
    /// Points to pass first, in order.
    pub waypoints: VecDeque<Vec2>,
    /// Where it stops.
    pub target: Vec2,
}

/// The physics of the robots.
pub struct Room {
    phys: PhysicsWorld,
    /// The robots, by index.
    pub bodies: Vec<Body>,
    radius: f32,
    max_speed: f32,
    max_accel: f32,
    dt: f32,
    obstacles: Vec<dodgy_2d::Obstacle>,
    /// Bounding boxes of `obstacles`: (min, max).
    boxes: Vec<(Vec2, Vec2)>,
    options: dodgy_2d::AvoidanceOptions,
    grid: Grid,
    contacts: FxHashSet<(u32, u32)>,
    fresh: FxHashSet<(u32, u32)>,
    near: Vec<(f32, usize)>,
    /// Contact episodes so far: pairs that came closer than the sum of their radii.
    pub collisions: u64,
    /// The smallest clearance (centre distance minus both radii) seen between two robots
    /// within [`NEIGHBOUR_DIST`] of each other.
    pub min_separation: Option<f32>,
    /// Steps taken.
    pub steps: u64,
}

impl std::fmt::Debug for Room {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Room")
            .field("robots", &self.bodies.len())
            .field("steps", &self.steps)
            .finish()
    }
}

impl Room {
    /// A room with the map's walls and obstacles and one robot at each of `starts`.
    pub fn new(map: &Map, starts: &[Vec2]) -> Room {
        let dt = (1.0 / map.step_hz) as f32;
        let mut phys = PhysicsWorld {
            gravity: Vec2::ZERO,
            ..Default::default()
        };
        phys.integration_parameters.dt = dt;
        for w in &map.walls {
            let (a, b) = (v(w[0], w[1]), v(w[2], w[3]));
            phys.insert(
                RigidBodyBuilder::fixed(),
                ColliderBuilder::segment(a, b).friction(0.0),
            );
        }
        for r in &map.obstacles {
            let c = v(r.x + r.w / 2.0, r.y + r.h / 2.0);
            phys.insert(
                RigidBodyBuilder::fixed().translation(c),
                ColliderBuilder::cuboid((r.w / 2.0) as f32, (r.h / 2.0) as f32).friction(0.0),
            );
        }
        let radius = map.robot.radius as f32;
        let bodies = starts
            .iter()
            .map(|&p| {
                let (handle, _) = phys.insert(
                    RigidBodyBuilder::dynamic().translation(p).lock_rotations(),
                    ColliderBuilder::ball(radius).friction(0.0).restitution(0.0),
                );
                Body {
                    handle,
                    pos: p,
                    vel: Vec2::ZERO,
                    waypoints: VecDeque::new(),
                    target: p,
                }
            })
            .collect();
        let obstacles: Vec<dodgy_2d::Obstacle> = map
            .obstacles
            .iter()
            .map(polygon)
            .chain(map.walls.iter().map(slab))
            .collect();
        let boxes = obstacles.iter().map(bounds).collect();
        Room {
            phys,
            bodies,
            radius,
            max_speed: map.robot.max_speed as f32,
            max_accel: map.robot.max_accel as f32,
            dt,
            obstacles,
            boxes,
            options: dodgy_2d::AvoidanceOptions {
                // dodgy keeps this far from obstacles (it does not add the agent's radius).
                obstacle_margin: radius + SAFETY,
                time_horizon: 1.5,
                obstacle_time_horizon: 1.0,
            },
            grid: Grid::new(NEIGHBOUR_DIST),
            contacts: FxHashSet::default(),
            fresh: FxHashSet::default(),
            near: Vec::new(),
            collisions: 0,
            min_separation: None,
            steps: 0,
        }
    }

    /// The step length (s).
    pub fn dt(&self) -> f32 {
        self.dt
    }

    /// The robots' radius (m).
    pub fn radius(&self) -> f32 {
        self.radius
    }

    /// True when robot `i` stands on its target and has nothing else to pass.
    pub fn settled(&self, i: usize) -> bool {
        let b = &self.bodies[i];
        b.waypoints.is_empty() && b.pos.distance(b.target) < 0.05 && b.vel.length() < 0.05
    }

    /// The distance robot `i` still has to drive (through its waypoints).
    pub fn remaining(&self, i: usize) -> f32 {
        let b = &self.bodies[i];
        let mut d = 0.0;
        let mut at = b.pos;
        for &w in b.waypoints.iter().chain(std::iter::once(&b.target)) {
            d += at.distance(w);
            at = w;
        }
        d
    }

    fn preferred(&self, b: &Body) -> Vec2 {
        if let Some(&w) = b.waypoints.front() {
            let d = w - b.pos;
            return d.normalize_or_zero() * self.max_speed;
        }
        let d = b.target - b.pos;
        let dist = d.length();
        if dist < 0.01 {
            return Vec2::ZERO;
        }
        // Fast enough to arrive, slow enough to stop in time, and never overshoot in a step.
        let speed = self
            .max_speed
            .min((2.0 * self.max_accel * dist).sqrt() * 0.9)
            .min(dist / self.dt);
        d / dist * speed
    }

    /// One physics step of `dt`.
    pub fn step(&mut self) {
        for b in &mut self.bodies {
            while let Some(&w) = b.waypoints.front() {
                if b.pos.distance(w) < WAYPOINT_TOL {
                    b.waypoints.pop_front();
                } else {
                    break;
                }
            }
        }
        self.grid.fill(self.bodies.iter().map(|b| b.pos));
        let agents: Vec<dodgy_2d::Agent> = self
            .bodies
            .iter()
            .map(|b| dodgy_2d::Agent {
                position: dv(b.pos),
                velocity: dv(b.vel),
                radius: self.radius + SAFETY,
                avoidance_responsibility: 1.0,
            })
            .collect();
        let mut obstacles: Vec<Cow<'_, dodgy_2d::Obstacle>> = Vec::new();
        let mut neighbours: Vec<Cow<'_, dodgy_2d::Agent>> = Vec::with_capacity(MAX_NEIGHBOURS);
        let mut new_vel = Vec::with_capacity(self.bodies.len());
        for i in 0..self.bodies.len() {
            let b = &self.bodies[i];
            let pref = self.preferred(b);
            self.near.clear();
            let near = &mut self.near;
            let bodies = &self.bodies;
            self.grid.around(b.pos, |j| {
                if j != i {
                    let d = bodies[j].pos.distance_squared(b.pos);
                    if d < NEIGHBOUR_DIST * NEIGHBOUR_DIST {
                        near.push((d, j));
                    }
                }
            });
            if self.near.len() > MAX_NEIGHBOURS {
                self.near
                    .select_nth_unstable_by(MAX_NEIGHBOURS, |a, b| a.0.total_cmp(&b.0));
                self.near.truncate(MAX_NEIGHBOURS);
            }
            // Only obstacles the robot could reach within their time horizon matter.
            obstacles.clear();
            for (o, &(lo, hi)) in self.obstacles.iter().zip(&self.boxes) {
                if b.pos.clamp(lo, hi).distance(b.pos) < OBSTACLE_DIST {
                    obstacles.push(Cow::Borrowed(o));
                }
            }
            neighbours.clear();
            neighbours.extend(self.near.iter().map(|&(_, j)| Cow::Borrowed(&agents[j])));
            let avoid = agents[i].compute_avoiding_velocity(
                &neighbours,
                &obstacles,
                dv(pref),
                self.max_speed,
                self.dt,
                &self.options,
            );
            let want = Vec2::new(avoid.x, avoid.y);
            let dv_max = self.max_accel * self.dt;
            let change = (want - b.vel).clamp_length_max(dv_max);
            new_vel.push(b.vel + change);
        }
        drop(neighbours);
        drop(obstacles);
        for (b, &vel) in self.bodies.iter().zip(&new_vel) {
            if let Some(rb) = self.phys.bodies.get_mut(b.handle) {
                rb.set_linvel(vel, true);
            }
        }
        self.phys.step();
        for b in &mut self.bodies {
            if let Some(rb) = self.phys.bodies.get(b.handle) {
                b.pos = rb.translation();
                b.vel = rb.linvel();
            }
        }
        self.steps += 1;
        self.check_contacts();
    }

    /// Counts new contact episodes and the smallest clearance.
    fn check_contacts(&mut self) {
        self.grid.fill(self.bodies.iter().map(|b| b.pos));
        self.fresh.clear();
        let touch = 2.0 * self.radius;
        let mut min = self.min_separation.unwrap_or(f32::INFINITY);
        let mut seen = false;
        for i in 0..self.bodies.len() {
            let p = self.bodies[i].pos;
            let bodies = &self.bodies;
            let fresh = &mut self.fresh;
            self.grid.around(p, |j| {
                if j > i {
                    let d = bodies[j].pos.distance(p);
                    if d < NEIGHBOUR_DIST {
                        seen = true;
                        min = min.min(d - touch);
                    }
                    if d < touch {
                        fresh.insert((i as u32, j as u32));
                    }
                }
            });
        }
        if seen {
            self.min_separation = Some(min);
        }
        self.collisions += self.fresh.difference(&self.contacts).count() as u64;
        std::mem::swap(&mut self.contacts, &mut self.fresh);
    }
}

fn v(x: f64, y: f64) -> Vec2 {
    Vec2::new(x as f32, y as f32)
}

/// dodgy_2d uses glam 0.29: convert through x and y.
fn dv(p: Vec2) -> dodgy_2d::Vec2 {
    dodgy_2d::Vec2::new(p.x, p.y)
}

/// A rectangle as an ORCA obstacle (counter-clockwise: solid inside).
fn polygon(r: &Rect) -> dodgy_2d::Obstacle {
    let (x0, y0, x1, y1) = (
        r.x as f32,
        r.y as f32,
        (r.x + r.w) as f32,
        (r.y + r.h) as f32,
    );
    dodgy_2d::Obstacle::Closed {
        vertices: vec![
            dodgy_2d::Vec2::new(x0, y0),
            dodgy_2d::Vec2::new(x1, y0),
            dodgy_2d::Vec2::new(x1, y1),
            dodgy_2d::Vec2::new(x0, y1),
        ],
    }
}

/// A wall as an ORCA obstacle: the segment thickened to a 2 cm slab (counter-clockwise), so
/// it is solid on both sides.
fn slab(w: &[f64; 4]) -> dodgy_2d::Obstacle {
    let (a, b) = (v(w[0], w[1]), v(w[2], w[3]));
    let n = (b - a).perp().normalize_or_zero() * 0.01;
    let corners = [a - n, b - n, b + n, a + n];
    dodgy_2d::Obstacle::Closed {
        vertices: corners.iter().map(|&c| dv(c)).collect(),
    }
}

fn bounds(o: &dodgy_2d::Obstacle) -> (Vec2, Vec2) {
    let (dodgy_2d::Obstacle::Closed { vertices } | dodgy_2d::Obstacle::Open { vertices }) = o;
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    for p in vertices {
        lo = lo.min(Vec2::new(p.x, p.y));
        hi = hi.max(Vec2::new(p.x, p.y));
    }
    (lo, hi)
}

/// A uniform grid of robot indices, rebuilt every step (cell = the neighbour distance).
#[derive(Debug, Default)]
struct Grid {
    cell: f32,
    cells: rustc_hash::FxHashMap<(i32, i32), Vec<usize>>,
}

impl Grid {
    fn new(cell: f32) -> Grid {
        Grid {
            cell,
            cells: Default::default(),
        }
    }

    fn key(&self, p: Vec2) -> (i32, i32) {
        (
            (p.x / self.cell).floor() as i32,
            (p.y / self.cell).floor() as i32,
        )
    }

    fn fill(&mut self, points: impl Iterator<Item = Vec2>) {
        for v in self.cells.values_mut() {
            v.clear();
        }
        for (i, p) in points.enumerate() {
            let k = self.key(p);
            self.cells.entry(k).or_default().push(i);
        }
    }

    /// Calls `f` with every index in the 3×3 cells around `p`.
    fn around(&self, p: Vec2, mut f: impl FnMut(usize)) {
        let (cx, cy) = self.key(p);
        for dx in -1..=1 {
            for dy in -1..=1 {
                if let Some(v) = self.cells.get(&(cx + dx, cy + dy)) {
                    v.iter().for_each(|&j| f(j));
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn open_map(walls: Vec<[f64; 4]>) -> Map {
        Map {
            walls,
            ..Map::bare(vec![])
        }
    }

    #[test]
    fn two_robots_swap_places_head_on_without_touching() {
        let (a, b) = (Vec2::new(1.0, 0.0), Vec2::new(5.0, 0.0));
        let mut room = Room::new(&open_map(vec![]), &[a, b]);
        room.bodies[0].target = b;
        room.bodies[1].target = a;
        for _ in 0..200 {
            room.step();
        }
        assert!(
            room.bodies[0].pos.distance(b) < 0.05,
            "{:?}",
            room.bodies[0].pos
        );
        assert!(
            room.bodies[1].pos.distance(a) < 0.05,
            "{:?}",
            room.bodies[1].pos
        );
        assert!(room.settled(0) && room.settled(1));
        assert_eq!(room.collisions, 0);
        let s = room.min_separation.unwrap();
        assert!(s > 0.0 && s < 1.0, "{s}");
        assert_eq!(room.steps, 200);
    }

    #[test]
    fn a_wall_stops_a_robot() {
        let mut room = Room::new(&open_map(vec![[3.0, -2.0, 3.0, 2.0]]), &[Vec2::ZERO]);
        room.bodies[0].target = Vec2::new(6.0, 0.0);
        for _ in 0..200 {
            room.step();
        }
        let p = room.bodies[0].pos;
        // Stops short of the wall by its radius and the avoidance margin, without touching.
        assert!(p.x > 2.7 && p.x < 3.0 - 0.01 - 0.15 - 0.04, "{p:?}");
        assert!(p.y.abs() < 0.05, "{p:?}");
        assert!((room.remaining(0) - (6.0 - p.x)).abs() < 1e-4);
    }
}
