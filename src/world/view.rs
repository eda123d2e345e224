//! [`WorldView`]: what a viewer draws — the map and every robot, at one simulated time.
//!
//! Its JSON form is exactly
//! `{"time": s, "map": {"locations": [{"name","x","y"}], "edges": [["L1","L2"]],
//! "walls": [[x1,y1,x2,y2]], "obstacles": [{"x","y","w","h"}]}, "robots": [{"id": "r1",
//! "agent": 3, "x", "y", "radius"}]}`.

use std::sync::Arc;

use serde::Serialize;

use crate::world::map::{Map, Rect};

/// The room and its robots at one time.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct WorldView {
    /// Simulated time (s).
    pub time: f64,
    /// The map (shared between views: it does not change).
    pub map: Arc<MapView>,
    /// Every robot.
    pub robots: Vec<RobotView>,
}

/// The static part of a [`WorldView`].
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct MapView {
    /// Named locations.
    pub locations: Vec<LocationView>,
    /// Edges of the topological map, by location name.
    pub edges: Vec<[String; 2]>,
    /// Wall segments `[x1, y1, x2, y2]`.
    pub walls: Vec<[f64; 4]>,
    /// Rectangles: lower-left corner, width, height.
    pub obstacles: Vec<Rect>,
}

/// A location of the map.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LocationView {
    /// Its name.
    pub name: String,
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
}

/// One robot.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RobotView {
    /// The robot's name.
    pub id: Arc<str>,
    /// The agent it carries now (`null` before its first action).
    pub agent: Option<u64>,
    /// x (m).
    pub x: f64,
    /// y (m).
    pub y: f64,
    /// Disc radius (m).
    pub radius: f64,
}

impl MapView {
    /// The drawable part of `map`.
    pub fn new(map: &Map) -> MapView {
        let name = |i: usize| map.locations[i].name.clone();
        MapView {
            locations: map
                .locations
                .iter()
                .map(|l| LocationView {
                    name: l.name.clone(),
                    x: l.x,
                    y: l.y,
                })
                .collect(),
            edges: map.edges.iter().map(|&(a, b)| [name(a), name(b)]).collect(),
            walls: map.walls.clone(),
            obstacles: map.obstacles.clone(),
        }
    }
}

impl WorldView {
    /// The views of `view` as JSON values (the viewer's world feed,
    /// `gspn::web::LiveRun::with_world`): a task forwards each new view until the world or
    /// every reader is gone. Call inside a tokio runtime.
    pub fn json_feed(
        mut view: tokio::sync::watch::Receiver<WorldView>,
    ) -> tokio::sync::watch::Receiver<serde_json::Value> {
        let json = |v: &WorldView| serde_json::to_value(v).unwrap_or(serde_json::Value::Null);
        let (tx, rx) = tokio::sync::watch::channel(json(&view.borrow_and_update()));
        tokio::spawn(async move {
            while view.changed().await.is_ok() {
                let v = json(&view.borrow_and_update());
                if tx.send(v).is_err() {
                    break;
                }
            }
        });
        rx
    }
}
