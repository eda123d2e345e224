//! How an edit reaches the viewer's state: whether the net may be edited, the check of the
//! edited net against the plan served, and the token game and analysis replaced by ones of
//! the new net.

use std::sync::Arc;

use crate::analysis::decision::RewardSpec;
use crate::net::Net;
use crate::policy::Policy;
use crate::web::WebState;

use super::{EditError, History};

impl WebState {
    /// Whether the page may edit the net: not a live run, a replay, or a policy or rewards
    /// without their plan.
    pub(crate) fn editable(&self) -> Result<(), EditError> {
        let why = if self.live().is_some() {
            Some("a live run's net cannot be edited")
        } else if self.inner.replay.get().is_some() {
            Some("a recorded run's net cannot be edited")
        } else if self.inner.plan.get().is_none() {
            self.inner.not_editable.as_deref()
        } else {
            None
        };
        match why {
            Some(w) => Err(EditError::NotEditable(w.to_string())),
            None => Ok(()),
        }
    }

    /// The plan's policy and rewards resolved against `net` by the plan reader's checks
    /// ([`crate::plan::PlanText::check`]); `None` without a plan; its error, with the
    /// plan's line, when `net` does not fit the plan.
    fn fit_plan(&self, net: &Net) -> Result<Option<PlanFit>, EditError> {
        let Some(text) = self.inner.plan.get() else {
            return Ok(None);
        };
        match text.check(Net::clone(net)) {
            Ok(plan) => Ok(Some(PlanFit {
                policy: (!plan.policy.is_empty()).then(|| Arc::new(plan.policy)),
                rewards: plan.rewards,
            })),
            Err(e) => Err(EditError::BreaksPlan {
                line: e.span.and_then(|s| text.line(s.line)).map(str::to_string),
                error: e.to_string(),
            }),
        }
    }

    /// Changes the net's history with `f` (an edit, an undo, a redo; it is given the check
    /// against the plan, [`WebState::fit_plan`]) and, when it gives a new current net, plays
    /// and analyses that one (under the plan's policy resolved against it): the token game
    /// starts again from its initial marking, a running analysis or question is cancelled,
    /// and the other pages are told.
    pub(crate) fn change(
        &self,
        f: impl FnOnce(
            &mut History,
            &dyn Fn(&Net) -> Result<Option<PlanFit>, EditError>,
        ) -> Result<(Arc<Net>, Option<PlanFit>), EditError>,
    ) -> Result<(), EditError> {
        self.editable()?;
        let mut history = self.editor();
        let (net, fit) = f(&mut history, &|n| self.fit_plan(n))?;
        // Without a plan there is no policy or reward (else the net is not editable).
        let (policy, plan) = match fit {
            Some(PlanFit { policy, rewards }) => (policy.clone(), Some((policy, rewards))),
            None => (None, None),
        };
        self.session().replace_net(net.clone(), policy);
        {
            let mut job = self
                .inner
                .analysis
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            job.cancel();
            job.cancel_question();
            *job = Arc::new(job.with_net(net, plan));
        }
        drop(history);
        self.sim_changed();
        Ok(())
    }
}

/// A plan's policy (`None` when it has none) and rewards, resolved against an edited net.
#[derive(Debug)]
pub(crate) struct PlanFit {
    policy: Option<Arc<Policy>>,
    rewards: Vec<RewardSpec>,
}
