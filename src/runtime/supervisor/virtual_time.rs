//! The supervisor's discrete-event clock ([`Mode::Virtual`](super::super::clock::Mode)): who
//! is running, who sleeps until when, and what arrived while actions were still busy.
//!
//! An action is *busy* from its start until it reports or asks to sleep; the model clock
//! moves only when no action is busy. Reports and output lines that arrive while some
//! action is busy wait here and are delivered together, in agent order, so what happens at
//! one model instant does not depend on which program answered first.
//!
//! A busy action in a place with an immediate output transition is *deciding*: its end at
//! this instant could make a decision ready, so nothing is chosen until it ends or sleeps.
//! Busy actions elsewhere can only add events at the end of the queue of reported ones, so
//! what was delivered before them may fire meanwhile — the same choices, in the same order,
//! whatever the timing.

use std::collections::BTreeMap;

use rustc_hash::FxHashMap;
use tokio::sync::oneshot;

use super::super::action::{ActionDone, OutputLine};
use super::super::clock::SleepRequest;
use super::super::id::AgentId;

/// A model instant as an ordered key (model times are ≥ 0, so their bits order like them).
fn key(t: f64) -> u64 {
    t.max(0.0).to_bits()
}

/// One running action.
#[derive(Debug)]
struct Activity {
    ticket: u64,
    /// Its place has an immediate output transition.
    decides: bool,
    /// Asleep until this instant (a key of `sleepers`).
    asleep: Option<u64>,
    /// Its timeout's instant (a key of `deadlines`) and how to stop it.
    deadline: Option<(u64, oneshot::Sender<()>)>,
    /// The waker of a sleep cut short by the timeout, held until the action reports, so
    /// the sleep never ends before the abort is seen.
    held: Option<oneshot::Sender<()>>,
}

/// What the discrete clock knows besides the engine; see the [module docs](self).
#[derive(Debug, Default)]
pub(super) struct VirtualTime {
    busy: usize,
    /// Busy actions that are deciding.
    deciding: usize,
    running: FxHashMap<AgentId, Activity>,
    sleepers: BTreeMap<(u64, AgentId), oneshot::Sender<()>>,
    deadlines: BTreeMap<(u64, AgentId), ()>,
    reports: Vec<ActionDone>,
    output: Vec<OutputLine>,
}

impl VirtualTime {
    /// True while some action is computing: the clock must not move.
    pub(super) fn busy(&self) -> bool {
        self.busy > 0
    }

    /// True while a deciding action is computing: nothing may be chosen.
    pub(super) fn deciding(&self) -> bool {
        self.deciding > 0
    }

    fn wake(&mut self, decides: bool) {
        self.busy += 1;
        self.deciding += usize::from(decides);
    }

    fn rest(&mut self, decides: bool) {
        self.busy -= 1;
        self.deciding -= usize::from(decides);
    }

    /// An action started at `now`; `deadline` is its timeout's instant and abort handle.
    pub(super) fn started(
        &mut self,
        agent: AgentId,
        ticket: u64,
        decides: bool,
        deadline: Option<(f64, oneshot::Sender<()>)>,
    ) {
        let deadline = deadline.map(|(t, abort)| {
            self.deadlines.insert((key(t), agent), ());
            (key(t), abort)
        });
        if let Some(old) = self.running.insert(
            agent,
            Activity {
                ticket,
                decides,
                asleep: None,
                deadline,
                held: None,
            },
        ) {
            // A restart replaces a run that already reported (retry): nothing was busy.
            self.forget(agent, old);
        }
        self.wake(decides);
    }

    fn forget(&mut self, agent: AgentId, a: Activity) {
        if let Some(k) = a.asleep {
            self.sleepers.remove(&(k, agent));
        } else {
            self.rest(a.decides);
        }
        if let Some((k, _)) = a.deadline {
            self.deadlines.remove(&(k, agent));
        }
    }

    /// A report arrived: kept for delivery; the action is no longer busy.
    pub(super) fn report(&mut self, done: ActionDone) {
        if self
            .running
            .get(&done.agent)
            .is_some_and(|a| a.ticket == done.ticket)
            && let Some(a) = self.running.remove(&done.agent)
        {
            self.forget(done.agent, a);
        }
        self.reports.push(done);
    }

    /// An output line arrived: kept for delivery.
    pub(super) fn output(&mut self, line: OutputLine) {
        self.output.push(line);
    }

    /// An action asks to sleep until `now + seconds`. A request of a run that is over (a
    /// stale ticket, or a second sleep at once) is answered at once by dropping its waker.
    pub(super) fn sleep(&mut self, now: f64, req: SleepRequest) {
        let Some(a) = self.running.get_mut(&req.agent) else {
            return;
        };
        if a.ticket != req.ticket || a.asleep.is_some() {
            return;
        }
        let k = key(now + req.seconds);
        a.asleep = Some(k);
        let decides = a.decides;
        self.sleepers.insert((k, req.agent), req.wake);
        self.rest(decides);
    }

    /// True when reports or output lines wait for delivery.
    pub(super) fn has_mail(&self) -> bool {
        !self.reports.is_empty() || !self.output.is_empty()
    }

    /// The waiting output lines, then the waiting reports, each in agent order (an agent's
    /// own lines keep their order).
    pub(super) fn take_mail(&mut self) -> (Vec<OutputLine>, Vec<ActionDone>) {
        let mut out = std::mem::take(&mut self.output);
        out.sort_by_key(|o| o.agent);
        let mut reports = std::mem::take(&mut self.reports);
        reports.sort_by_key(|r| (r.agent, r.ticket));
        (out, reports)
    }

    /// The next instant something is due: a sleeper's wake-up or a timeout.
    pub(super) fn next_due(&self) -> Option<f64> {
        let s = self.sleepers.keys().next().map(|&(k, _)| k);
        let d = self.deadlines.keys().next().map(|&(k, _)| k);
        s.into_iter().chain(d).min().map(f64::from_bits)
    }

    /// The clock reached `at`: wakes the sleepers due then, in agent order, then stops the
    /// actions whose timeout is due and that still sleep. Returns how many were stopped.
    pub(super) fn wake_due(&mut self, at: f64) -> usize {
        let k = key(at);
        while let Some(entry) = self.sleepers.first_entry() {
            if entry.key().0 > k {
                break;
            }
            let ((_, agent), wake) = entry.remove_entry();
            let mut decides = false;
            if let Some(a) = self.running.get_mut(&agent) {
                a.asleep = None;
                decides = a.decides;
            }
            self.wake(decides);
            let _ = wake.send(());
        }
        let mut stopped = 0;
        let due: Vec<AgentId> = self
            .deadlines
            .range(..=(k, AgentId(u64::MAX)))
            .map(|(&(_, a), ())| a)
            .collect();
        for agent in due {
            let Some(a) = self.running.get_mut(&agent) else {
                continue;
            };
            let Some(asleep) = a.asleep else {
                continue; // woken at this instant: it may still end in time
            };
            if let Some((dk, abort)) = a.deadline.take() {
                let decides = a.decides;
                a.asleep = None;
                // The sleep does not end: only the abort does.
                a.held = self.sleepers.remove(&(asleep, agent));
                let _ = abort.send(());
                self.deadlines.remove(&(dk, agent));
                self.wake(decides);
                stopped += 1;
            }
        }
        stopped
    }

    /// The run is stopping: every sleeper wakes (its action sees the cancel token) and
    /// nothing more is held back.
    pub(super) fn release(&mut self) {
        let mut woken = Vec::new();
        for a in self.running.values_mut() {
            if a.asleep.take().is_some() {
                woken.push(a.decides);
            }
        }
        for decides in woken {
            self.wake(decides);
        }
        self.sleepers.clear();
        self.deadlines.clear();
    }
}
