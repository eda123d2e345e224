//! A recorded run in the viewer (`plan-runner replay --web`): the journal's frames and, when
//! the run had a simulated world, its map and the robots' poses over time (the journal's
//! `map` and `world` side records, see [`crate::world::WorldBackend`]'s doc).

use axum::extract::State;
use axum::http::StatusCode;
use axum::response::{IntoResponse, Response};
use serde_json::{Value, json};

use super::{WebState, api};
use crate::runtime::journal::{Frame, Recording};

/// What `GET /api/replay` serves.
#[derive(Debug)]
pub(crate) struct Replay {
    /// The initial marking, then the marking after each firing.
    pub(crate) frames: Vec<Frame>,
    /// `{"map", "radius", "frames": [{"time", "robots"}]}` when the journal recorded a world.
    pub(crate) world: Option<Value>,
}

impl Replay {
    /// The frames of a journal without a world.
    pub(crate) fn of_frames(frames: Vec<Frame>) -> Replay {
        Replay {
            frames,
            world: None,
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
        Replay {
            frames: recording.frames(),
            world,
        }
    }
}

/// `GET /api/replay`: `{"frames": [{time, transition, tokens}], "world"?: {map, radius,
/// robots, frames: [{time, robots: [{id, agent, x, y}]}]}}` (404 without a recording).
pub(crate) async fn frames(State(state): State<WebState>) -> Response {
    match state.inner.replay.get() {
        Some(r) => {
            let mut v = json!({ "frames": r.frames });
            if let Some(w) = &r.world {
                v["world"] = w.clone();
            }
            axum::Json(v).into_response()
        }
        None => api::error(StatusCode::NOT_FOUND, "no recorded run"),
    }
}
