//! [`WorldBackend`]: the simulated world as a [`Backend`] of its run — after the run it
//! reports the world's [`SimMetrics`](super::SimMetrics) (summary key `sim`) and stops the
//! world (its robots and its clock), before any later backend finishes.
//!
//! A run with a journal gets the world in it as side records
//! ([`JournalTap`](crate::runtime::journal::JournalTap)): `map` once (`{"map": MapView,
//! "radius": metres}`), then `world` at every view the world publishes (20 per simulated
//! second while a robot moves): `[{"id", "agent", "x", "y"}]`, positions to the millimetre.
//! `plan-runner replay --web` draws them.

use serde::Serialize;

use super::WorldHandle;
use super::view::WorldView;
use crate::runtime::journal::JournalTap;
use crate::runtime::{Backend, BackendFuture, Section, Start, Started, Summary};

/// The world a [`Fleet`](super::Fleet) spawned, attached to the fleet's run.
#[derive(Debug)]
pub struct WorldBackend {
    world: WorldHandle,
    recorder: Option<tokio::task::JoinHandle<()>>,
}

impl WorldBackend {
    /// The backend of `world` (the fleet's builder already has its actions and robots).
    pub fn new(world: WorldHandle) -> Self {
        WorldBackend {
            world,
            recorder: None,
        }
    }
}

/// One robot in a `world` record.
#[derive(Serialize)]
struct Pose<'a> {
    id: &'a str,
    #[serde(skip_serializing_if = "Option::is_none")]
    agent: Option<u64>,
    x: f64,
    y: f64,
}

/// Millimetres are enough for a map and halve the journal's world lines.
fn mm(v: f64) -> f64 {
    (v * 1000.0).round() / 1000.0
}

/// Writes `view`'s robots as a `world` record.
fn record_view(tap: &JournalTap, view: &WorldView) {
    let poses: Vec<Pose<'_>> = view
        .robots
        .iter()
        .map(|r| Pose {
            id: &r.id,
            agent: r.agent,
            x: mm(r.x),
            y: mm(r.y),
        })
        .collect();
    tap.record("world", view.time, &poses);
}

impl Backend for WorldBackend {
    fn name(&self) -> &'static str {
        "sim"
    }

    /// With a journal: records the map, then every view the world publishes until it stops.
    fn started<'a>(&'a mut self, start: Start<'a>) -> Started<'a> {
        if let Some(tap) = start.run.journal_tap() {
            let mut view = self.world.view();
            let first = view.borrow_and_update().clone();
            let radius = first.robots.first().map_or(0.0, |r| r.radius);
            tap.record(
                "map",
                first.time,
                &serde_json::json!({ "map": &*first.map, "radius": radius }),
            );
            record_view(&tap, &first);
            self.recorder = Some(tokio::spawn(async move {
                while view.changed().await.is_ok() {
                    let v = view.borrow_and_update().clone();
                    record_view(&tap, &v);
                }
            }));
        }
        Box::pin(async { Ok(()) })
    }

    fn finish<'a>(&'a mut self, _summary: &'a Summary) -> BackendFuture<'a, Option<Section>> {
        Box::pin(async move {
            let metrics = self.world.metrics().await;
            let json = serde_json::to_value(&metrics).unwrap_or(serde_json::Value::Null);
            let text = metrics.map(|m| m.to_string()).unwrap_or_default();
            // The run is over: the robots stop where they are and the world's clock with
            // them, even while a later backend (the viewer) keeps the process up.
            self.world.stop();
            Some(Section::new(json, text))
        })
    }

    fn stop(&mut self) {
        self.world.stop();
        if let Some(r) = self.recorder.take() {
            r.abort();
        }
    }
}
