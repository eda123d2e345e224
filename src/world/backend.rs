//! [`WorldBackend`]: the simulated world as a [`Backend`] of its run — after the run it
//! reports the world's [`SimMetrics`](super::SimMetrics) (summary key `sim`) and stops the
//! world (its robots and its clock), before any later backend finishes.

use super::WorldHandle;
use crate::runtime::{Backend, BackendFuture, Section, Summary};

/// The world a [`Fleet`](super::Fleet) spawned, attached to the fleet's run.
#[derive(Debug)]
pub struct WorldBackend {
    world: WorldHandle,
}

impl WorldBackend {
    /// The backend of `world` (the fleet's builder already has its actions and robots).
    pub fn new(world: WorldHandle) -> Self {
        WorldBackend { world }
    }
}

impl Backend for WorldBackend {
    fn name(&self) -> &'static str {
        "sim"
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
    }
}
