//! The room simulated robots drive in: locations on a topological map, walls, obstacles, the
//! robots' bodies and how they queue. A plan's `[map]` section resolves to a [`Map`]
//! (`gspn::plan` reads it); the world (feature `sim`) drives robots in it.

use schemars::JsonSchema;
use serde::Deserialize;

use crate::net::PlaceId;

/// An axis-aligned rectangle: lower-left corner and size (metres).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize, JsonSchema, serde::Serialize)]
#[serde(deny_unknown_fields)]
pub struct Rect {
    /// Left edge.
    pub x: f64,
    /// Bottom edge.
    pub y: f64,
    /// Width.
    pub w: f64,
    /// Height.
    pub h: f64,
}

/// A checked map: names are indices, every size is finite and positive.
#[derive(Clone, Debug, PartialEq)]
pub struct Map {
    /// Locations, in name order.
    pub locations: Vec<Location>,
    /// Edges of the topological map, as location indices.
    pub edges: Vec<(usize, usize)>,
    /// The patrol loop, as location indices (may be empty).
    pub patrol: Vec<usize>,
    /// Wall segments `[x1, y1, x2, y2]`.
    pub walls: Vec<[f64; 4]>,
    /// Rectangular obstacles.
    pub obstacles: Vec<Rect>,
    /// The robots' bodies.
    pub robot: RobotSpec,
    /// Lanes and spacing of the queues.
    pub queue: QueueSpec,
    /// Physics steps per simulated second.
    pub step_hz: f64,
    /// Seconds without progress before a `goto` fails.
    pub stuck_after: f64,
}

#[cfg(test)]
impl Map {
    /// A map of `locations` with no edges, walls or obstacles, default robots, one queue lane.
    pub(crate) fn bare(locations: Vec<Location>) -> Map {
        Map {
            locations,
            edges: vec![],
            patrol: vec![],
            walls: vec![],
            obstacles: vec![],
            robot: RobotSpec::default(),
            queue: QueueSpec {
                lanes: 1,
                spacing: 0.5,
            },
            step_hz: 20.0,
            stuck_after: 30.0,
        }
    }
}

/// One checked location.
#[derive(Clone, Debug, PartialEq)]
pub struct Location {
    /// Its name.
    pub name: String,
    /// x of the front of its queue.
    pub x: f64,
    /// y of the front of its queue.
    pub y: f64,
    /// Unit vector: the direction its queue grows in.
    pub queue_dir: [f64; 2],
    /// Places whose agents are here.
    pub places: Vec<PlaceId>,
}

/// A robot's body.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RobotSpec {
    /// Disc radius (m).
    pub radius: f64,
    /// Top speed (m/s).
    pub max_speed: f64,
    /// Top acceleration (m/s²).
    pub max_accel: f64,
}

impl Default for RobotSpec {
    /// A small indoor robot: radius 0.15 m, 1 m/s, 2 m/s² (the plan's defaults).
    fn default() -> Self {
        RobotSpec {
            radius: 0.15,
            max_speed: 1.0,
            max_accel: 2.0,
        }
    }
}

/// Queue layout at every location.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QueueSpec {
    /// Lanes side by side.
    pub lanes: u32,
    /// Metres between slots.
    pub spacing: f64,
}

impl Map {
    /// The index of the location named `name`.
    pub fn location(&self, name: &str) -> Option<usize> {
        self.locations.iter().position(|l| l.name == name)
    }

    /// The location whose `places` list `p`.
    pub fn location_of_place(&self, p: PlaceId) -> Option<usize> {
        self.locations.iter().position(|l| l.places.contains(&p))
    }

    /// Neighbours of location `i` in the topological map.
    pub fn neighbours(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        self.edges.iter().filter_map(move |&(a, b)| {
            if a == i {
                Some(b)
            } else if b == i {
                Some(a)
            } else {
                None
            }
        })
    }
}
