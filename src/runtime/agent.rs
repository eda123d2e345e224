//! Agents: one per token in an action place, with a stable id and a state.
//!
//! The supervisor keeps every agent's record (its place, state, outcome); with
//! [`AgentMode::Actor`] each agent is also a kameo actor that lives exactly as long as its
//! token and runs its own actions: the supervisor tells it [`Run`], it awaits the place's
//! action in its own task and reports the outcome. [`AgentMode::Light`] keeps only the
//! record — the actions still run concurrently, one tokio task each, spawned by the place
//! actor (see `docs/benchmarks.md` for what each mode costs).

use std::sync::Arc;

use kameo::Actor;
use kameo::message::{Context, Message};
use serde::{Deserialize, Serialize};
use tokio::sync::mpsc::UnboundedSender;

use super::action::{Action, ActionContext, ActionDone, Limit, run_action};
use super::id::AgentId;
use crate::net::PlaceId;

/// An agent's state, as the thesis named them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AgentState {
    /// In a place, no action running yet.
    Free,
    /// Its action is running.
    Occupied,
    /// Its action ended with `Fire` or `Decide`; the transition may fire now.
    Done,
    /// Its action ended, but the transition it is ready for is not enabled yet.
    Waiting,
    /// In a place with no output transition: nothing will happen to it.
    Inactive,
}

/// How agents are represented.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum AgentMode {
    /// A record in the supervisor; actions are tasks hosted by the place actors (about
    /// 1 KB per agent instead of 7 KB: for plans with very many agents and little memory).
    Light,
    /// The default, as DESIGN.md has it: a record plus a kameo actor per agent, spawned and
    /// killed with its token, running the agent's actions in its own task.
    #[default]
    Actor,
}

/// The actor of one agent ([`AgentMode::Actor`]): it runs the agent's actions and owns its
/// current place and state (it sets Occupied and Done itself; the supervisor tells it the
/// rest).
#[derive(Actor)]
pub(crate) struct Agent {
    /// The agent's id.
    pub id: AgentId,
    /// The place it is in.
    pub place: PlaceId,
    /// Its state.
    pub state: AgentState,
    /// Where outcomes go (the supervisor drains it in batches).
    pub(crate) reports: UnboundedSender<ActionDone>,
}

impl std::fmt::Debug for Agent {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Agent")
            .field("id", &self.id)
            .field("place", &self.place)
            .field("state", &self.state)
            .finish()
    }
}

/// Run the place's action for this agent, then report the outcome.
pub(crate) struct Run {
    pub(crate) ctx: ActionContext,
    pub(crate) ticket: u64,
    pub(crate) action: Arc<dyn Action>,
    /// The place's timeout for this run.
    pub(crate) limit: Limit,
}

impl Message<Run> for Agent {
    type Reply = ();

    async fn handle(&mut self, msg: Run, _: &mut Context<Self, Self::Reply>) {
        self.place = msg.ctx.place;
        self.state = AgentState::Occupied;
        let outcome = run_action(&msg.action, msg.ctx, msg.limit).await;
        self.state = AgentState::Done;
        let _ = self.reports.send(ActionDone {
            agent: self.id,
            ticket: msg.ticket,
            outcome,
        });
    }
}

/// The agent moved or changed state.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Update {
    /// Its place now.
    pub place: PlaceId,
    /// Its state now.
    pub state: AgentState,
}

impl Message<Update> for Agent {
    type Reply = ();

    async fn handle(&mut self, u: Update, _: &mut Context<Self, Self::Reply>) {
        self.place = u.place;
        self.state = u.state;
    }
}
