//! [`WorldHandle`]: what the rest of the crate holds of a running [`World`] — its view, its
//! metrics, the drives it is asked for, and in a mirror world the poses and arrivals it is
//! told.

use std::sync::Arc;

use kameo::actor::ActorRef;
use tokio::sync::{oneshot, watch};

use super::messages::{Arrived, GetMetrics, Goto, SetPose};
use super::{GotoError, World};
use crate::world::action::DriveError;
use crate::world::{SimMetrics, WorldView};

/// A running world: its view channel, its metrics, stop.
#[derive(Clone, Debug)]
pub struct WorldHandle {
    pub(super) actor: ActorRef<World>,
    pub(super) view: watch::Receiver<WorldView>,
    pub(super) scale: f64,
    pub(super) robots: Vec<Arc<str>>,
}

impl WorldHandle {
    /// The latest [`WorldView`], updated at most 20 times per simulated second.
    pub fn view(&self) -> watch::Receiver<WorldView> {
        self.view.clone()
    }

    /// The robots' names, in robot order.
    pub fn robots(&self) -> &[Arc<str>] {
        &self.robots
    }

    /// Tokio seconds per simulated second (1 in virtual time).
    pub fn scale(&self) -> f64 {
        self.scale
    }

    /// The metrics so far (`None` once the world is stopped).
    pub async fn metrics(&self) -> Option<SimMetrics> {
        self.actor.ask(GetMetrics).await.ok()
    }

    /// Stops the world (its robots stop where they are).
    pub fn stop(&self) {
        self.actor.kill();
    }

    /// Drives `robot` to the back of `location`'s queue, as a `goto` step does (its agent
    /// unchanged): what a simulated robot's Nav2 server (`crate::ros2::nav2`) does with a
    /// goal. `Err`: why it did not arrive, or that the world is gone.
    pub async fn drive(&self, robot: Arc<str>, location: usize) -> Result<(), GotoError> {
        let (reply, rx) = oneshot::channel();
        let goto = Goto {
            robot,
            agent: None,
            location,
            reply,
        };
        if self.actor.tell(goto).try_send().is_err() {
            return Err(GotoError::Gone);
        }
        rx.await.unwrap_or(Err(GotoError::Gone))
    }

    pub(crate) fn actor(&self) -> &ActorRef<World> {
        &self.actor
    }

    /// In a mirror world ([`World::spawn_mirror`]): `robot` has set out for `location`
    /// and `drive` takes it there (a Nav2 goal to a real robot). The world keeps the queues as
    /// a `goto` would — the robot leaves its location's queue when it sets out and joins the
    /// back of `location`'s — and counts the arrival when `drive` succeeds. `Err`: why
    /// `drive` did not arrive, or that the world is gone.
    pub async fn mirror_goto(
        &self,
        robot: Arc<str>,
        location: usize,
        drive: impl std::future::Future<Output = Result<(), DriveError>>,
    ) -> Result<(), DriveError> {
        let (reply, rx) = oneshot::channel();
        let goto = Goto {
            robot: Arc::clone(&robot),
            agent: None,
            location,
            reply,
        };
        if self.actor.tell(goto).try_send().is_err() {
            return Err(GotoError::Gone.into());
        }
        drive.await?;
        if self.actor.tell(Arrived { robot }).try_send().is_err() {
            return Err(GotoError::Gone.into());
        }
        Ok(rx.await.unwrap_or(Err(GotoError::Gone))?)
    }

    /// In a mirror world: `robot` is at `(x, y)` (frame `map`), e.g. from Nav2's feedback.
    pub fn set_pose(&self, robot: Arc<str>, x: f64, y: f64) {
        let _ = self.actor.tell(SetPose { robot, x, y }).try_send();
    }
}
