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

use tokio::sync::oneshot;

use super::WorldHandle;
use super::actor::messages::{Goto, Hold, Turn};
use super::map::Map;
use super::program::{ProgramError, Step};
use crate::net::Timing;
use crate::runtime::{Action, ActionContext, ActionFuture, Outcome};

/// A built-in robot program bound to a world.
#[derive(Clone, Debug)]
pub struct SimAction {
    steps: Arc<[Step]>,
    world: WorldHandle,
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
        }))
    }
}

/// Awaits `rx` unless the run is being stopped first.
async fn or_cancel<T>(ctx: &ActionContext, rx: oneshot::Receiver<T>) -> Option<T> {
    tokio::select! {
        r = rx => r.ok(),
        _ = ctx.cancel.cancelled() => None,
    }
}

impl Action for SimAction {
    fn run(&self, ctx: ActionContext) -> ActionFuture {
        let steps = Arc::clone(&self.steps);
        let world = self.world.clone();
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
                    Step::Goto(location) => {
                        let (reply, rx) = oneshot::channel();
                        let msg = Goto {
                            robot: Arc::clone(&robot),
                            agent: ctx.agent.0,
                            location,
                            reply,
                        };
                        if actor.tell(msg).try_send().is_err() {
                            return Outcome::Failed("the world is gone".into());
                        }
                        match or_cancel(&ctx, rx).await {
                            None => return Outcome::Cancelled,
                            Some(Err(e)) => return Outcome::Failed(e.to_string()),
                            Some(Ok(())) => Outcome::Decide,
                        }
                    }
                    Step::Measure(seconds) | Step::Wait(seconds) => {
                        let outputs = ctx
                            .outputs()
                            .into_iter()
                            .filter_map(|t| match ctx.net.transition(t).timing {
                                Timing::Exponential { rate, .. } => Some((t, rate)),
                                Timing::Immediate { .. } => None,
                            })
                            .collect();
                        let (reply, rx) = oneshot::channel();
                        let msg = Hold {
                            robot: Arc::clone(&robot),
                            agent: ctx.agent.0,
                            seconds,
                            outputs,
                            reply,
                        };
                        if actor.tell(msg).try_send().is_err() {
                            return Outcome::Failed("the world is gone".into());
                        }
                        let Some((secs, pick)) = or_cancel(&ctx, rx).await else {
                            return Outcome::Cancelled;
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
                        let (reply, rx) = oneshot::channel();
                        let msg = Turn {
                            robot: Arc::clone(&robot),
                            reply,
                        };
                        if actor.tell(msg).try_send().is_err() {
                            return Outcome::Failed("the world is gone".into());
                        }
                        match or_cancel(&ctx, rx).await {
                            None => return Outcome::Cancelled,
                            Some(()) => Outcome::Decide,
                        }
                    }
                };
            }
            outcome
        })
    }
}
