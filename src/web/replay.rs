//! A recorded run in the viewer (`plan-runner replay --web`): the journal's frames and, when
//! the run had a simulated world, its map and the robots' poses over time (the journal's
//! `map` and `world` side records, see [`crate::world::WorldBackend`]'s doc).

use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::{Value, json};

use super::stays::RobotStays;
use super::{WebState, api};
use crate::net::Net;
use crate::runtime::journal::{Frame, Recording};

/// What `GET /api/replay` serves.
#[derive(Debug)]
pub(crate) struct Replay {
    /// The initial marking, then the marking after each firing.
    pub(crate) frames: Vec<Frame>,
    /// `{"map", "radius", "frames": [{"time", "robots"}]}` when the journal recorded a world.
    pub(crate) world: Option<Value>,
    /// The conformance table along the run (`[{time, rows}]`, see `conform::replay_rows`).
    pub(crate) conform: Option<Value>,
    /// Each robot's stays in places (`[{robot, stays}]`, see [`RobotStays`]), empty when
    /// no robot was bound.
    pub(crate) robots: Value,
}

impl Replay {
    /// The frames of a journal of `net` without a world.
    pub(crate) fn of_frames(net: &Net, frames: Vec<Frame>) -> Replay {
        Replay {
            conform: super::conform::replay_rows(net, &frames),
            frames,
            world: None,
            robots: Value::Array(Vec::new()),
        }
    }

    /// The frames and the world of `recording`.
    pub(crate) fn of_recording(recording: &Recording) -> Replay {
        let map = recording.records("map").next();
        let world = map.map(|m| {
            let frames: Vec<Value> = recording
                .records("world")
                .map(|r| json!({ "time": r.time, "robots": r.data }))
                .collect();
            json!({
                "map": m.data.get("map").cloned().unwrap_or(Value::Null),
                "radius": m.data.get("radius").cloned().unwrap_or(Value::Null),
                "robots": recording.robots,
                "frames": frames,
            })
        });
        let frames = recording.frames();
        Replay {
            conform: super::conform::replay_rows(&recording.net, &frames),
            frames,
            world,
            robots: RobotStays::of(&recording.events).json(&recording.net),
        }
    }
}

/// `GET /api/replay`: `{"frames": [{time, transition, tokens}], "robots": [{robot, stays:
/// [{t0, t1, place, agent}]}], "world"?: {map, radius,
/// robots, frames: [{time, robots: [{id, agent, x, y}]}]}, "conform"?: [{time, rows}]}` (404
/// without a recording; `conform`: the monitor's table of transitions' rates along the run).
pub(crate) async fn frames(State(state): State<WebState>) -> Response {
    match state.inner.replay.get() {
        Some(r) => {
            let mut v = json!({ "frames": r.frames, "robots": r.robots });
            if let Some(w) = &r.world {
                v["world"] = w.clone();
            }
            if let Some(c) = &r.conform {
                v["conform"] = c.clone();
            }
            axum::Json(v).into_response()
        }
        None => api::error(StatusCode::NOT_FOUND, "no recorded run"),
    }
}
