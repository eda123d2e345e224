//! The analysis panel's job: one analysis at a time on a blocking thread, with its progress
//! (phase, markings found, seconds) and a cancel that stops the state-space search within
//! one block of markings ([`Monitor`]).
//!
//! States: `idle` → `running` → `done` (the result is kept) or, after a cancel,
//! `cancelling` → `cancelled` (start it again to retry). A result that is an error of the net
//! (unbounded, too many states) is `done` too: the panel shows it.
//!
//! A question on the finished analysis (transient points, predicates: [`AnalysisJob::ask`])
//! is a phase of its own, one at a time, with the same states: its progress is the time
//! point the transient solver works towards and its iterations done of planned (the same
//! [`Monitor`]), and a cancel stops the solver within one iteration. A new question cancels
//! a running one; so does the page that asked it going away.

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::{Arc, Mutex, MutexGuard};
use std::time::Instant;

use serde_json::{Value, json};
use tokio::sync::watch;

use crate::analysis::decision::RewardSpec;
use crate::analysis::state_space::Monitor;
use crate::net::Net;
use crate::policy::Policy;
use crate::web::report::{Kept, QueryError};

/// What the analysis is doing, for the progress line.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u8)]
pub(crate) enum Phase {
    /// Bounds, then the breadth-first search of the reachable markings.
    StateSpace = 0,
    /// Safeness, reversibility, liveness, dead markings.
    Properties = 1,
    /// The CTMC's steady state and the measures.
    SteadyState = 2,
}

impl Phase {
    fn name(self) -> &'static str {
        match self {
            Phase::StateSpace => "state space",
            Phase::Properties => "properties",
            Phase::SteadyState => "steady state",
        }
    }

    fn from_u8(v: u8) -> Phase {
        match v {
            0 => Phase::StateSpace,
            1 => Phase::Properties,
            _ => Phase::SteadyState,
        }
    }
}

/// Shared between the job's thread and the requests asking about it.
#[derive(Debug, Default)]
pub(crate) struct Progress {
    /// The search's count and cancel flag.
    pub(crate) monitor: Arc<Monitor>,
    phase: AtomicU8,
}

impl Progress {
    /// Enters `phase`; `false` when the job was cancelled (stop now).
    pub(crate) fn enter(&self, phase: Phase) -> bool {
        self.phase.store(phase as u8, Ordering::Relaxed);
        !self.monitor.is_cancelled()
    }

    fn phase(&self) -> Phase {
        Phase::from_u8(self.phase.load(Ordering::Relaxed))
    }
}

#[derive(Debug)]
enum State {
    Idle,
    Running {
        progress: Arc<Progress>,
        started: Instant,
        max_states: usize,
    },
    Done {
        value: Arc<Value>,
        kept: Option<Arc<Kept>>,
        seconds: f64,
        max_states: usize,
    },
    Cancelled {
        markings: usize,
        phase: Phase,
        seconds: f64,
        max_states: usize,
    },
}

/// The analysis of one net (under its plan's policy, with its rewards), run at most once at
/// a time.
#[derive(Debug)]
pub(crate) struct AnalysisJob {
    net: Arc<Net>,
    policy: Arc<Policy>,
    rewards: Vec<RewardSpec>,
    /// The limit of the next run when the page does not give one.
    max_states: usize,
    state: Mutex<State>,
    /// Bumped whenever the job ends (done or cancelled).
    ended: watch::Sender<u64>,
    /// The last question asked of the finished analysis.
    question: Mutex<Question>,
}

/// A question on the finished analysis: under way, or how it ended.
#[derive(Debug)]
enum Question {
    Idle,
    Running {
        monitor: Arc<Monitor>,
        /// The transient times asked, in the order the solver reaches them.
        times: Vec<f64>,
        started: Instant,
    },
    Done {
        seconds: f64,
    },
    Cancelled {
        progress: Value,
    },
}

/// How a question ended.
pub(crate) enum Answer {
    /// `{steady_state: {probability}, transient}` ([`crate::web::report::query`]).
    Done(Value),
    /// A bad time or predicate: the message names it.
    Refused(String),
    /// Cancelled before it finished: the progress as it stopped.
    Cancelled(Value),
    /// Its thread failed (a bug).
    Failed(String),
}

/// Cancels the question it watches when dropped before [`Self::finish`]: a request that
/// goes away (the page reloaded) stops its question.
struct CancelOnDrop(Option<Arc<Monitor>>);

impl CancelOnDrop {
    fn finish(mut self) {
        self.0 = None;
    }
}

impl Drop for CancelOnDrop {
    fn drop(&mut self) {
        if let Some(m) = &self.0 {
            m.cancel();
        }
    }
}

/// How a wait for the result ended.
pub(crate) enum Outcome {
    /// The analysis (or the net's error, as `{error, kind}`).
    Done(Arc<Value>),
    /// Cancelled before it finished: the progress as it stopped.
    Cancelled(Value),
}

impl AnalysisJob {
    pub(crate) fn new(
        net: Arc<Net>,
        policy: Arc<Policy>,
        rewards: Vec<RewardSpec>,
        max_states: usize,
    ) -> AnalysisJob {
        AnalysisJob {
            net,
            policy,
            rewards,
            max_states,
            state: Mutex::new(State::Idle),
            ended: watch::channel(0).0,
            question: Mutex::new(Question::Idle),
        }
    }

    /// A job for `net` (an edited version of this job's net) with this job's limit, and
    /// `plan`'s policy (none: the bare net) and rewards resolved against it — or this job's
    /// without `plan`; not started.
    pub(crate) fn with_net(
        &self,
        net: Arc<Net>,
        plan: Option<(Option<Arc<Policy>>, Vec<RewardSpec>)>,
    ) -> AnalysisJob {
        let (policy, rewards) = match plan {
            Some((policy, rewards)) => {
                (policy.unwrap_or_else(|| Arc::new(Policy::empty())), rewards)
            }
            None => (self.policy.clone(), self.rewards.clone()),
        };
        AnalysisJob::new(net, policy, rewards, self.max_states)
    }

    fn lock(&self) -> MutexGuard<'_, State> {
        self.state
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Starts the analysis unless it is running or done; returns the progress. Call inside a
    /// tokio runtime. With `max_states` (the page's field), a finished analysis that ran
    /// with another limit runs again with this one (a net with too many markings for the
    /// first limit can be retried with a larger one).
    pub(crate) fn start(self: &Arc<Self>, max_states: Option<usize>) -> Value {
        let mut s = self.lock();
        let again = match (&*s, max_states) {
            (State::Idle | State::Cancelled { .. }, _) => true,
            (
                State::Done {
                    max_states: used, ..
                },
                Some(m),
            ) => *used != m,
            _ => false,
        };
        if again {
            let max_states = max_states.unwrap_or(self.max_states);
            let progress = Arc::new(Progress::default());
            *s = State::Running {
                progress: progress.clone(),
                started: Instant::now(),
                max_states,
            };
            let job = self.clone();
            tokio::task::spawn_blocking(move || job.run(progress, max_states));
        }
        progress_json(&s, self.max_states)
    }

    fn run(&self, progress: Arc<Progress>, max_states: usize) {
        let started = Instant::now();
        let (value, kept) = crate::web::report::analyse(
            &self.net,
            &self.policy,
            &self.rewards,
            max_states,
            &progress,
        );
        let seconds = started.elapsed().as_secs_f64();
        {
            let mut s = self.lock();
            // Cancelled only when the analysis really stopped: a cancel that arrives after
            // the last phase finished keeps the finished result.
            *s = if value.get("kind").and_then(Value::as_str) == Some("cancelled") {
                State::Cancelled {
                    markings: progress.monitor.markings(),
                    phase: progress.phase(),
                    seconds,
                    max_states,
                }
            } else {
                State::Done {
                    value: Arc::new(value),
                    kept: kept.map(Arc::new),
                    seconds,
                    max_states,
                }
            };
        }
        self.ended.send_modify(|n| *n += 1);
    }

    /// Asks a running analysis to stop; returns the progress (`cancelling` until its thread
    /// has stopped, then `cancelled`).
    pub(crate) fn cancel(&self) -> Value {
        let s = self.lock();
        if let State::Running { progress, .. } = &*s {
            progress.monitor.cancel();
        }
        progress_json(&s, self.max_states)
    }

    /// The progress as JSON: `state`, and `phase`, `markings`, `seconds` where they apply.
    pub(crate) fn progress(&self) -> Value {
        progress_json(&self.lock(), self.max_states)
    }

    /// The net and what the finished analysis kept for questions: `None` while no analysis
    /// has finished, `Some(None)` when it finished without a state space and steady state
    /// (its result says why).
    pub(crate) fn kept(&self) -> Option<Option<(Arc<Net>, Arc<Kept>)>> {
        match &*self.lock() {
            State::Done { kept, .. } => Some(kept.clone().map(|k| (self.net.clone(), k))),
            _ => None,
        }
    }

    fn question(&self) -> MutexGuard<'_, Question> {
        self.question
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// Asks the finished analysis `kept` (of `net`, from [`AnalysisJob::kept`]) for the
    /// transient points at `times` and the probabilities of `prob` on a blocking thread, and
    /// waits for the answer; a running question is cancelled first. Call inside a tokio
    /// runtime.
    pub(crate) async fn ask(
        &self,
        net: Arc<Net>,
        kept: Arc<Kept>,
        times: Vec<f64>,
        prob: Vec<String>,
        queries: Vec<String>,
    ) -> Answer {
        let monitor = Arc::new(Monitor::new());
        let mut sorted = times.clone();
        sorted.sort_by(f64::total_cmp);
        let started = Instant::now();
        {
            let mut q = self.question();
            if let Question::Running { monitor: old, .. } = &*q {
                old.cancel();
            }
            *q = Question::Running {
                monitor: monitor.clone(),
                times: sorted.clone(),
                started,
            };
        }
        let guard = CancelOnDrop(Some(monitor.clone()));
        let m = monitor.clone();
        let answer = tokio::task::spawn_blocking(move || {
            crate::web::report::query(&net, &kept, &times, &prob, &queries, &m)
        })
        .await;
        guard.finish();
        let answer = match answer {
            Ok(Ok(v)) => Answer::Done(v),
            Ok(Err(QueryError::Bad(message))) => Answer::Refused(message),
            Ok(Err(QueryError::Cancelled)) => {
                let mut progress = running_json(&monitor, &sorted, started);
                progress["state"] = json!("cancelled");
                Answer::Cancelled(progress)
            }
            Err(e) => Answer::Failed(format!("the question failed: {e}")),
        };
        let mut q = self.question();
        // A newer question has replaced this one's progress: leave it.
        if matches!(&*q, Question::Running { monitor: m, .. } if Arc::ptr_eq(m, &monitor)) {
            *q = match &answer {
                Answer::Cancelled(progress) => Question::Cancelled {
                    progress: progress.clone(),
                },
                _ => Question::Done {
                    seconds: started.elapsed().as_secs_f64(),
                },
            };
        }
        answer
    }

    /// Asks a running question to stop; its progress (`cancelling` until its thread has
    /// stopped, then `cancelled`).
    pub(crate) fn cancel_question(&self) -> Value {
        let q = self.question();
        if let Question::Running { monitor, .. } = &*q {
            monitor.cancel();
        }
        question_json(&q)
    }

    /// The question's progress: `state` (`idle`, `running`, `cancelling`, `cancelled`,
    /// `done`) and, while it runs or as it stopped, `phase` (`transient t=…` or
    /// `probabilities`), `point` of `points` (the time points, 1 for the earliest),
    /// `iterations` done `of` planned, `seconds`.
    pub(crate) fn question_progress(&self) -> Value {
        question_json(&self.question())
    }

    /// Starts the analysis if needed and waits for it to end.
    pub(crate) async fn result(self: &Arc<Self>) -> Outcome {
        let mut ended = self.ended.subscribe();
        self.start(None);
        loop {
            {
                let s = self.lock();
                match &*s {
                    State::Done { value, .. } => return Outcome::Done(value.clone()),
                    State::Cancelled { .. } => {
                        return Outcome::Cancelled(progress_json(&s, self.max_states));
                    }
                    State::Idle | State::Running { .. } => {}
                }
            }
            if ended.changed().await.is_err() {
                return Outcome::Cancelled(self.progress());
            }
        }
    }
}

/// The progress of question `q`.
fn question_json(q: &Question) -> Value {
    match q {
        Question::Idle => json!({ "state": "idle" }),
        Question::Done { seconds } => json!({ "state": "done", "seconds": seconds }),
        Question::Cancelled { progress } => progress.clone(),
        Question::Running {
            monitor,
            times,
            started,
        } => running_json(monitor, times, *started),
    }
}

/// The progress of a question watched by `monitor`, on the transient `times` (sorted).
fn running_json(monitor: &Monitor, times: &[f64], started: Instant) -> Value {
    let (point, iterations, planned) = monitor.transient_progress();
    let phase = match times.get(point) {
        Some(t) => format!("transient t={t}"),
        None => "probabilities".to_string(),
    };
    json!({
        "state": if monitor.is_cancelled() { "cancelling" } else { "running" },
        "phase": phase,
        "point": (point + 1).min(times.len()),
        "points": times.len(),
        "iterations": iterations,
        "of": planned,
        "seconds": started.elapsed().as_secs_f64(),
    })
}

/// The progress of `s`; `max_states` is the limit an idle job would run with.
fn progress_json(s: &State, default_max: usize) -> Value {
    match s {
        State::Idle => json!({ "state": "idle", "max_states": default_max }),
        State::Running {
            progress,
            started,
            max_states,
        } => json!({
            "state": if progress.monitor.is_cancelled() { "cancelling" } else { "running" },
            "phase": progress.phase().name(),
            "markings": progress.monitor.markings(),
            "seconds": started.elapsed().as_secs_f64(),
            "max_states": max_states,
        }),
        State::Done {
            value,
            seconds,
            max_states,
            ..
        } => json!({
            "state": "done",
            "markings": value.get("reachable").cloned().unwrap_or(Value::Null),
            "seconds": seconds,
            "error": value.get("error").cloned().unwrap_or(Value::Null),
            "max_states": max_states,
        }),
        State::Cancelled {
            markings,
            phase,
            seconds,
            max_states,
        } => json!({
            "state": "cancelled",
            "phase": phase.name(),
            "markings": markings,
            "seconds": seconds,
            "max_states": max_states,
        }),
    }
}
