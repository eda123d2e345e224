//! The world's messages: plain structs, each handled by the [`World`] actor in its turn.

use std::sync::Arc;

use kameo::message::{Context, Message};
use tokio::sync::oneshot;

use super::super::SimMetrics;
use super::{GotoError, World};
use crate::net::TransitionId;

/// Drive `robot` to `location` (see [`action`]).
#[derive(Debug)]
pub(crate) struct Goto {
    pub(crate) robot: Arc<str>,
    /// The agent the robot now carries (`None`: unchanged, e.g. a Nav2 goal).
    pub(crate) agent: Option<u64>,
    pub(crate) location: usize,
    pub(crate) reply: oneshot::Sender<Result<(), GotoError>>,
}

/// Reply when `robot` is at the front of its location's queue.
#[derive(Debug)]
pub(crate) struct Turn {
    pub(crate) robot: Arc<str>,
    pub(crate) reply: oneshot::Sender<()>,
}

/// Draw a holding time and an outcome from `robot`'s stream.
#[derive(Debug)]
pub(crate) struct Hold {
    pub(crate) robot: Arc<str>,
    pub(crate) agent: u64,
    pub(crate) seconds: Option<f64>,
    /// The place's exponential outputs with their rates.
    pub(crate) outputs: Vec<(TransitionId, f64)>,
    pub(crate) reply: oneshot::Sender<(f64, Option<TransitionId>)>,
}

/// A mirror world's robot has arrived where its [`Goto`] went.
#[derive(Debug)]
pub(crate) struct Arrived {
    pub(crate) robot: Arc<str>,
}

/// A mirror world's robot is at `(x, y)`.
#[derive(Debug)]
pub(crate) struct SetPose {
    pub(crate) robot: Arc<str>,
    pub(crate) x: f64,
    pub(crate) y: f64,
}

/// Ask for the metrics so far.
#[derive(Debug)]
pub(crate) struct GetMetrics;

impl Message<Goto> for World {
    type Reply = ();

    async fn handle(&mut self, m: Goto, _: &mut Context<Self, Self::Reply>) {
        self.goto(m);
    }
}

impl Message<Turn> for World {
    type Reply = ();

    async fn handle(&mut self, m: Turn, _: &mut Context<Self, Self::Reply>) {
        let front = self
            .names
            .get(&m.robot)
            .and_then(|&r| self.robots[r].location.map(|l| (r, l)));
        match front {
            Some((r, l)) if self.queues.front(l) != Some(r) => self.robots[r].turn = Some(m.reply),
            _ => {
                let _ = m.reply.send(());
            }
        }
    }
}

impl Message<Hold> for World {
    type Reply = ();

    async fn handle(&mut self, m: Hold, _: &mut Context<Self, Self::Reply>) {
        self.hold(m);
    }
}

impl Message<GetMetrics> for World {
    type Reply = SimMetrics;

    async fn handle(&mut self, _: GetMetrics, _: &mut Context<Self, Self::Reply>) -> SimMetrics {
        self.metrics()
    }
}

impl Message<Arrived> for World {
    type Reply = ();

    async fn handle(&mut self, m: Arrived, _: &mut Context<Self, Self::Reply>) {
        self.arrived(&m.robot);
    }
}

impl Message<SetPose> for World {
    type Reply = ();

    async fn handle(&mut self, m: SetPose, _: &mut Context<Self, Self::Reply>) {
        self.set_pose(m);
    }
}
