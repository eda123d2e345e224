//! The `[map]` section of a plan: the room the simulated robots drive in.
//!
//! ```toml
//! [map]
//! step_hz = 20.0                      # physics steps per simulated second
//! robot = { radius = 0.15, max_speed = 1.0, max_accel = 2.0 }
//! queue = { lanes = 4, spacing = 0.5 }  # how robots line up at a location
//! stuck_after = 30.0                  # seconds without progress before a goto fails
//! patrol = ["L1", "L2", "L3", "L4"]   # the loop counted in `cycles_per_robot`
//! edges = [["L1", "L2"], ["L2", "L3"], ["L3", "L4"], ["L4", "L1"]]
//! walls = [[0.0, 0.0, 14.0, 0.0]]     # segments x1, y1, x2, y2
//! obstacles = [{ x = 5.0, y = 5.0, w = 4.0, h = 4.0 }]  # rectangles: lower-left corner, size
//!
//! [map.locations.L1]
//! x = 2.0
//! y = 2.0
//! queue = [0.0, 1.0]                  # the direction its queue grows in (optional)
//! places = ["p1:Check_Temperature_L1", "p3:Decide_L1"]
//! ```
//!
//! [`MapFile`] is the TOML as written; [`MapFile::resolve`] checks names against the net and
//! the map itself (unknown locations in `edges`/`patrol`, unknown places, a place in two
//! locations, non-finite or negative sizes) and gives a [`Map`], with line and column errors.

use std::collections::BTreeMap;
use std::ops::Range;

use schemars::JsonSchema;
use serde::Deserialize;
use toml::Spanned;

use crate::io::{LoadError, LoadErrorKind};
use crate::net::Net;
use crate::world::map::{Location, Map, QueueSpec, Rect, RobotSpec};

/// The `[map]` section as written.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct MapFile {
    /// Physics steps per simulated second (default 20).
    #[schemars(with = "Option<f64>", range(min = 1.0))]
    pub step_hz: Option<Spanned<f64>>,
    /// The robots: disc radius (m), top speed (m/s), top acceleration (m/s²).
    pub robot: Option<RobotFile>,
    /// How robots line up at a location: side-by-side lanes and the distance between slots.
    pub queue: Option<QueueFile>,
    /// Seconds a robot on its way may go without getting closer to its goal before its
    /// `goto` fails with `stuck at (x, y)` (default 30).
    #[schemars(with = "Option<f64>", range(min = 0.0))]
    pub stuck_after: Option<Spanned<f64>>,
    /// Named places of the room.
    #[serde(default)]
    #[schemars(with = "BTreeMap<String, LocationFile>")]
    pub locations: BTreeMap<Spanned<String>, Spanned<LocationFile>>,
    /// The topological map: pairs of locations a robot drives between in a straight line.
    #[serde(default)]
    #[schemars(with = "Vec<[String; 2]>")]
    pub edges: Vec<[Spanned<String>; 2]>,
    /// The patrol loop, in order; a robot completes a cycle when it has arrived at each of
    /// them in this order and is back where it started.
    #[serde(default)]
    #[schemars(with = "Vec<String>")]
    pub patrol: Vec<Spanned<String>>,
    /// Wall segments `[x1, y1, x2, y2]` (metres).
    #[serde(default)]
    #[schemars(with = "Vec<[f64; 4]>")]
    pub walls: Vec<Spanned<[f64; 4]>>,
    /// Rectangular obstacles: lower-left corner `x, y`, width `w`, height `h` (metres).
    #[serde(default)]
    #[schemars(with = "Vec<Rect>")]
    pub obstacles: Vec<Spanned<Rect>>,
}

/// The robots' bodies.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct RobotFile {
    /// Disc radius in metres (default 0.15).
    pub radius: Option<f64>,
    /// Top speed in m/s (default 1).
    pub max_speed: Option<f64>,
    /// Top acceleration in m/s² (default 2).
    pub max_accel: Option<f64>,
}

/// How robots line up at a location.
#[derive(Clone, Copy, Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct QueueFile {
    /// Lanes side by side (default 4).
    pub lanes: Option<u32>,
    /// Metres between neighbouring slots, along and across the lanes (default 0.5).
    pub spacing: Option<f64>,
}

/// One location as written.
#[derive(Debug, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct LocationFile {
    /// x of the front of its queue (metres).
    pub x: f64,
    /// y of the front of its queue (metres).
    pub y: f64,
    /// The direction the queue grows in, from the front backwards (default: towards the
    /// location before it in `patrol`, else towards its first neighbour in `edges`).
    pub queue: Option<[f64; 2]>,
    /// The places whose agents are at this location (a robot entering one of them from
    /// another location's place has arrived here).
    #[serde(default)]
    #[schemars(with = "Vec<String>")]
    pub places: Vec<Spanned<String>>,
}

type At<'a> = &'a dyn Fn(Range<usize>, LoadErrorKind) -> LoadError;

fn positive(
    v: Option<f64>,
    default: f64,
    what: &'static str,
    span: Range<usize>,
    at: At<'_>,
) -> Result<f64, LoadError> {
    let v = v.unwrap_or(default);
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(at(
            span,
            LoadErrorKind::OutOfRange {
                what,
                name: "map".into(),
                value: v.to_string(),
                expected: "must be a finite number > 0",
            },
        ))
    }
}

impl MapFile {
    /// Checks the map against `net`; `at` turns a span of the plan's text into an error.
    /// In the order of the section: the [`topology`](Self::topology) (edges and patrol by
    /// location), the [`locations`](Self::locations) and their places,
    /// [`queue directions`](Self::queue_directions), [`walls and obstacles`](Self::solids),
    /// then the robots' and queues' [`settings`](Self::settings).
    pub fn resolve(&self, net: &Net, section: Range<usize>, at: At<'_>) -> Result<Map, LoadError> {
        let (edges, patrol) = self.topology(at)?;
        let mut locations = self.locations(net, at)?;
        self.queue_directions(&mut locations, &edges, &patrol, at)?;
        let (walls, obstacles) = self.solids(at)?;
        let (robot, queue, step_hz, stuck_after) = self.settings(section, at)?;
        Ok(Map {
            locations,
            edges,
            patrol,
            walls,
            obstacles,
            robot,
            queue,
            step_hz,
            stuck_after,
        })
    }

    /// The edges and the patrol loop, as indices of locations (in name order).
    #[allow(clippy::type_complexity)]
    fn topology(&self, at: At<'_>) -> Result<(Vec<(usize, usize)>, Vec<usize>), LoadError> {
        let names: Vec<&str> = self
            .locations
            .keys()
            .map(|k| k.get_ref().as_str())
            .collect();
        let find = |n: &Spanned<String>| -> Result<usize, LoadError> {
            names.iter().position(|&x| x == n.get_ref()).ok_or_else(|| {
                at(
                    n.span(),
                    LoadErrorKind::UnknownNode {
                        what: "location",
                        name: n.get_ref().clone(),
                    },
                )
            })
        };
        let mut edges = Vec::with_capacity(self.edges.len());
        for [a, b] in &self.edges {
            let (i, j) = (find(a)?, find(b)?);
            if i == j {
                return Err(at(
                    b.span(),
                    LoadErrorKind::Invalid(format!("edge from `{}` to itself", a.get_ref())),
                ));
            }
            edges.push((i, j));
        }
        let mut patrol = Vec::with_capacity(self.patrol.len());
        for n in &self.patrol {
            patrol.push(find(n)?);
        }
        Ok((edges, patrol))
    }

    /// The locations with their places (each place at one location at most); queue
    /// directions are left for [`queue_directions`](Self::queue_directions).
    fn locations(&self, net: &Net, at: At<'_>) -> Result<Vec<Location>, LoadError> {
        let mut locations = Vec::with_capacity(self.locations.len());
        let mut owner: Vec<Option<String>> = vec![None; net.place_count()];
        for (name, loc) in &self.locations {
            let l = loc.get_ref();
            if !(l.x.is_finite() && l.y.is_finite()) {
                return Err(at(
                    loc.span(),
                    LoadErrorKind::Invalid(format!(
                        "location `{}`: x and y must be finite",
                        name.get_ref()
                    )),
                ));
            }
            let mut places = Vec::with_capacity(l.places.len());
            for p in &l.places {
                let id = net.place_by_name(p.get_ref()).ok_or_else(|| {
                    at(
                        p.span(),
                        LoadErrorKind::UnknownNode {
                            what: "place",
                            name: p.get_ref().clone(),
                        },
                    )
                })?;
                if let Some(other) = &owner[id.index()] {
                    return Err(at(
                        p.span(),
                        LoadErrorKind::Invalid(format!(
                            "place `{}` is already at location `{other}`",
                            p.get_ref()
                        )),
                    ));
                }
                owner[id.index()] = Some(name.get_ref().clone());
                places.push(id);
            }
            locations.push(Location {
                name: name.get_ref().clone(),
                x: l.x,
                y: l.y,
                queue_dir: [0.0, -1.0],
                places,
            });
        }
        Ok(locations)
    }

    /// Queue directions: as written, else towards the location before it (on the patrol,
    /// else along an edge).
    fn queue_directions(
        &self,
        locations: &mut [Location],
        edges: &[(usize, usize)],
        patrol: &[usize],
        at: At<'_>,
    ) -> Result<(), LoadError> {
        for (k, (name, loc)) in self.locations.iter().enumerate() {
            let l = loc.get_ref();
            let dir = match l.queue {
                Some([dx, dy]) => {
                    let n = (dx * dx + dy * dy).sqrt();
                    if !(n.is_finite() && n > 0.0) {
                        return Err(at(
                            loc.span(),
                            LoadErrorKind::Invalid(format!(
                                "location `{}`: queue direction must be a non-zero vector",
                                name.get_ref()
                            )),
                        ));
                    }
                    [dx / n, dy / n]
                }
                None => {
                    let before = patrol
                        .iter()
                        .position(|&p| p == k)
                        .map(|i| patrol[(i + patrol.len() - 1) % patrol.len()])
                        .filter(|&p| p != k)
                        .or_else(|| {
                            edges
                                .iter()
                                .find_map(|&(a, b)| (b == k).then_some(a).or((a == k).then_some(b)))
                        });
                    match before {
                        Some(b) => {
                            let (dx, dy) = (locations[b].x - l.x, locations[b].y - l.y);
                            let n = (dx * dx + dy * dy).sqrt();
                            if n > 0.0 {
                                [dx / n, dy / n]
                            } else {
                                [0.0, -1.0]
                            }
                        }
                        None => [0.0, -1.0],
                    }
                }
            };
            locations[k].queue_dir = dir;
        }
        Ok(())
    }

    /// The walls (finite segments) and obstacles (finite rectangles of positive size).
    #[allow(clippy::type_complexity)]
    fn solids(&self, at: At<'_>) -> Result<(Vec<[f64; 4]>, Vec<Rect>), LoadError> {
        let mut walls = Vec::with_capacity(self.walls.len());
        for w in &self.walls {
            if w.get_ref().iter().any(|v| !v.is_finite()) {
                return Err(at(
                    w.span(),
                    LoadErrorKind::Invalid("wall: coordinates must be finite".into()),
                ));
            }
            walls.push(*w.get_ref());
        }
        let mut obstacles = Vec::with_capacity(self.obstacles.len());
        for o in &self.obstacles {
            let r = *o.get_ref();
            if !([r.x, r.y, r.w, r.h].iter().all(|v| v.is_finite()) && r.w > 0.0 && r.h > 0.0) {
                return Err(at(
                    o.span(),
                    LoadErrorKind::Invalid("obstacle: x, y must be finite and w, h > 0".into()),
                ));
            }
            obstacles.push(r);
        }
        Ok((walls, obstacles))
    }

    /// The robots' size and speed, the queues, the physics rate and the stuck timeout, each
    /// as written or its default.
    #[allow(clippy::type_complexity)]
    fn settings(
        &self,
        section: Range<usize>,
        at: At<'_>,
    ) -> Result<(RobotSpec, QueueSpec, f64, f64), LoadError> {
        let rf = self.robot.unwrap_or(RobotFile {
            radius: None,
            max_speed: None,
            max_accel: None,
        });
        let d = RobotSpec::default();
        let robot = RobotSpec {
            radius: positive(rf.radius, d.radius, "robot.radius", section.clone(), at)?,
            max_speed: positive(
                rf.max_speed,
                d.max_speed,
                "robot.max_speed",
                section.clone(),
                at,
            )?,
            max_accel: positive(
                rf.max_accel,
                d.max_accel,
                "robot.max_accel",
                section.clone(),
                at,
            )?,
        };
        let qf = self.queue.unwrap_or(QueueFile {
            lanes: None,
            spacing: None,
        });
        let lanes = qf.lanes.unwrap_or(4);
        if lanes == 0 {
            return Err(at(
                section,
                LoadErrorKind::Invalid("queue.lanes must be ≥ 1".into()),
            ));
        }
        let spacing = positive(qf.spacing, 0.5, "queue.spacing", section.clone(), at)?;
        if spacing < 2.0 * robot.radius {
            return Err(at(
                section,
                LoadErrorKind::Invalid(format!(
                    "queue.spacing {spacing} is less than a robot's diameter {}: queued robots would overlap",
                    2.0 * robot.radius
                )),
            ));
        }
        let step_hz = match &self.step_hz {
            Some(s) => positive(Some(*s.get_ref()), 20.0, "step_hz", s.span(), at)?,
            None => 20.0,
        };
        let stuck_after = match &self.stuck_after {
            Some(s) => {
                let v = *s.get_ref();
                if !crate::limits::valid_seconds(v) {
                    return Err(at(
                        s.span(),
                        LoadErrorKind::OutOfRange {
                            what: "stuck_after",
                            name: "map".into(),
                            value: v.to_string(),
                            expected: crate::limits::SECONDS_EXPECTED,
                        },
                    ));
                }
                v
            }
            None => 30.0,
        };
        Ok((robot, QueueSpec { lanes, spacing }, step_hz, stuck_after))
    }
}
