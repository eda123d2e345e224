//! [`SimAction`]: the built-in robot actions, registered for every action name of a plan
//! with a `[map]` that reads as a program of steps (see [`Map::program`]):
//!
//! | step | what the robot does | outcome when it is the last step |
//! |---|---|---|
//! | `goto L` | leaves its location, drives along the topological map (A*) to the back of `L`'s queue, avoiding other robots (ORCA) | `Decide` |
//! | `measure [S]` | stands `S` seconds (default: exponential with the total rate of the place's exponential outputs) | one exponential output, drawn ∝ its rate |
//! | `wait [S]` | the same, without measuring | the same |
//! | `decide` | waits until it is at the front of its location's queue | `Decide` |
//!
//! A `goto` that makes no progress for the map's `stuck_after` seconds ends the action with
//! `Failed("stuck at (x, y)")`: the runtime reports it as an error event and the place's
//! failure policy decides (retry, fire, stop).

use std::sync::Arc;

use kameo::actor::ActorRef;
use kameo::message::Message;
use tokio::sync::oneshot;

use super::WorldHandle;
use super::actor::World;
use super::actor::messages::{Goto, Hold, Turn};
use super::map::Map;
use super::program::{ProgramError, Step};
use crate::net::{Timing, TransitionId};
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome};

/// How `goto` steps reach their location when not by asking the world directly: through
/// Nav2's `NavigateToPose` over ROS 2 (`crate::ros2::nav2`, `run --robots N --ros2`), which
/// the world serves for its robots, so a plan drives simulated robots the way it would
/// drive real ones.
pub trait Navigator: Send + Sync + std::fmt::Debug {
    /// Drives `robot` to `location` of the map; `Err`: why it did not arrive. Dropping the
    /// future gives the drive up (a Nav2 goal is cancelled).
    fn goto(
        &self,
        robot: Arc<str>,
        location: usize,
    ) -> std::pin::Pin<Box<dyn std::future::Future<Output = Result<(), DriveError>> + Send>>;
}

/// Why a [`Navigator`]'s drive did not arrive, with its cause (e.g.
/// `crate::ros2::nav2::Nav2Error`).
pub type DriveError = Box<dyn std::error::Error + Send + Sync>;

/// A built-in robot program bound to a world.
#[derive(Clone, Debug)]
pub struct SimAction {
    steps: Arc<[Step]>,
    world: WorldHandle,
    navigator: Option<Arc<dyn Navigator>>,
}

impl SimAction {
    /// The action named `name` on `map`, when it is a built-in program (`Ok(None)`: a user
    /// action).
    pub fn parse(
        map: &Map,
        name: &str,
        world: &WorldHandle,
    ) -> Result<Option<SimAction>, ProgramError> {
        Ok(map.program(name)?.map(|steps| SimAction {
            steps: steps.into(),
            world: world.clone(),
            navigator: None,
        }))
    }

    /// The same program with its `goto` steps going through `navigator`.
    pub fn navigated_by(self, navigator: Arc<dyn Navigator>) -> SimAction {
        SimAction {
            navigator: Some(navigator),
            ..self
        }
    }
}

/// The place's exponential outputs with their rates: what a `measure` or `wait` draws from.
fn exponential_outputs(ctx: &ActionContext) -> Vec<(TransitionId, f64)> {
    ctx.outputs()
        .into_iter()
        .filter_map(|t| match ctx.net.transition(t).timing {
            Timing::Exponential { rate, .. } => Some((t, rate)),
            Timing::Immediate { .. } => None,
        })
        .collect()
}

/// Sends the world `make(reply)` and awaits the reply; `Err` is the action's outcome when the
/// world is gone or the run is being stopped first.
async fn ask<M, T>(
    world: &ActorRef<World>,
    ctx: &ActionContext,
    make: impl FnOnce(oneshot::Sender<T>) -> M,
) -> Result<T, Outcome>
where
    World: Message<M>,
    M: Send + 'static,
{
    let (reply, rx) = oneshot::channel();
    if world.tell(make(reply)).try_send().is_err() {
        return Err(Outcome::Failed("the world is gone".into()));
    }
    tokio::select! {
        r = rx => r.map_err(|_| Outcome::Cancelled),
        _ = ctx.cancel.cancelled() => Err(Outcome::Cancelled),
    }
}

impl Action for SimAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let steps = Arc::clone(&self.steps);
        let world = self.world.clone();
        let navigator = self.navigator.clone();
        Box::pin(async move {
            let Some(robot) = ctx.robot.clone() else {
                return Outcome::Failed(format!(
                    "agent {} has no robot: built-in robot actions need `robots` (run with --robots N)",
                    ctx.agent.0
                ));
            };
            let actor = world.actor();
            let mut outcome = Outcome::Decide;
            for step in steps.iter() {
                outcome = match *step {
                    Step::Goto(location) if navigator.is_some() => {
                        let nav = navigator
                            .as_ref()
                            .map(|n| n.goto(Arc::clone(&robot), location));
                        let Some(drive) = nav else { continue };
                        tokio::select! {
                            r = drive => match r {
                                Ok(()) => Outcome::Decide,
                                Err(e) => return Outcome::Failed(e.to_string()),
                            },
                            _ = ctx.cancel.cancelled() => return Outcome::Cancelled,
                        }
                    }
                    Step::Goto(location) => {
                        let (robot, agent) = (Arc::clone(&robot), ctx.agent.0);
                        let goto = |reply| Goto {
                            robot,
                            agent: Some(agent),
                            location,
                            reply,
                        };
                        match ask(actor, &ctx, goto).await {
                            Err(outcome) => return outcome,
                            Ok(Err(e)) => return Outcome::Failed(e.to_string()),
                            Ok(Ok(())) => Outcome::Decide,
                        }
                    }
                    Step::Measure(seconds) | Step::Wait(seconds) => {
                        let (robot, agent) = (Arc::clone(&robot), ctx.agent.0);
                        let hold = |reply| Hold {
                            robot,
                            agent,
                            seconds,
                            outputs: exponential_outputs(&ctx),
                            reply,
                        };
                        let (secs, pick) = match ask(actor, &ctx, hold).await {
                            Ok(r) => r,
                            Err(outcome) => return outcome,
                        };
                        let sleep =
                            tokio::time::sleep(crate::limits::duration(secs * world.scale()));
                        tokio::select! {
                            _ = sleep => {}
                            _ = ctx.cancel.cancelled() => return Outcome::Cancelled,
                        }
                        pick.map_or(Outcome::Decide, Outcome::Fire)
                    }
                    Step::Decide => {
                        let robot = Arc::clone(&robot);
                        match ask(actor, &ctx, |reply| Turn { robot, reply }).await {
                            Err(outcome) => return outcome,
                            Ok(()) => Outcome::Decide,
                        }
                    }
                };
            }
            outcome
        })
    }
}
