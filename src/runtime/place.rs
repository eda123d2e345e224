//! Place actors: one per action place, hosting its [`Action`] and running each agent's
//! action concurrently (one tokio task per agent), under the place's timeout.
//!
//! The place never waits for an action: it spawns the task and returns to its mailbox. The
//! task reports the outcome to the supervisor; a panic or a timeout becomes
//! [`Outcome::Failed`] for that agent only.

use std::sync::Arc;

use kameo::Actor;
use kameo::message::{Context, Message};

use super::action::{Action, ActionContext, ActionDone, Limit, run_action};
use tokio::sync::mpsc::UnboundedSender;

/// The actor of one action place.
#[derive(Actor)]
pub(crate) struct Place {
    pub(crate) action: Arc<dyn Action>,
    /// Where the tasks report outcomes (drained by the supervisor in batches).
    pub(crate) reports: UnboundedSender<ActionDone>,
}

impl std::fmt::Debug for Place {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Place").finish_non_exhaustive()
    }
}

/// Start the action for one agent.
#[derive(Debug)]
pub(crate) struct Start {
    pub(crate) ctx: ActionContext,
    /// The supervisor's tag for this start (stale reports are ignored).
    pub(crate) ticket: u64,
    /// The place's timeout for this run.
    pub(crate) limit: Limit,
}

impl Message<Start> for Place {
    type Reply = ();

    async fn handle(&mut self, msg: Start, _: &mut Context<Self, Self::Reply>) {
        let agent = msg.ctx.agent;
        let fut = run_action(&self.action, msg.ctx, msg.limit);
        let sup = self.reports.clone();
        tokio::spawn(async move {
            let outcome = fut.await;
            let _ = sup.send(ActionDone {
                agent,
                ticket: msg.ticket,
                outcome,
            });
        });
    }
}
