//! The live check: [`Monitor`] follows a run firing by firing and reports a [`Drift`] when an
//! exponential transition's rate over its last firings leaves the net's (the `rate` row of
//! [`compare`](super::compare), on a sliding window, at a stricter level since it is tested
//! again at every firing) — once per transition until its rate returns (p back above
//! [`MonitorOptions::back`]).

use std::collections::VecDeque;

use serde::Serialize;

use super::{active_servers, stats};
use crate::net::{Net, Timing, TransitionId};

/// Window and level of the live check.
#[derive(Clone, Debug, PartialEq)]
pub struct MonitorOptions {
    /// Firings per transition in the sliding window.
    pub window: usize,
    /// Fewest firings in the window before the transition is tested.
    pub min_firings: usize,
    /// Level of each test (the test is repeated at every firing: keep it small).
    pub alpha: f64,
    /// A drifting transition has returned when its p-value is back above this (hysteresis:
    /// no alarm storm around the threshold).
    pub back: f64,
}

impl Default for MonitorOptions {
    /// A window of 200 firings, tested from 50 on, at the 10⁻⁵ level; back below drift
    /// once p ≥ 0.05.
    fn default() -> Self {
        MonitorOptions {
            window: 200,
            min_firings: 50,
            alpha: 1e-5,
            back: 0.05,
        }
    }
}

/// A transition whose recent rate left the net's.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Drift {
    /// The transition.
    pub transition: String,
    /// When it was found (model time).
    pub time: f64,
    /// Firings per unit of enabled time over the window.
    pub observed: f64,
    /// The net's rate.
    pub predicted: f64,
    /// The 95% score interval of the observed rate.
    pub interval: [f64; 2],
    /// Firings in the window.
    pub n: u64,
    /// The test's p-value.
    pub p_value: f64,
}

/// Follows one run (see the module).
#[derive(Clone, Debug)]
pub struct Monitor {
    net: Net,
    opts: MonitorOptions,
    marking: Vec<u32>,
    now: f64,
    open_gap: Vec<f64>,
    window: Vec<VecDeque<f64>>,
    drifting: Vec<bool>,
}

impl Monitor {
    /// A monitor of a run of `net` from `initial`.
    pub fn new(net: &Net, initial: Vec<u32>, opts: MonitorOptions) -> Monitor {
        let nt = net.transition_count();
        Monitor {
            net: net.clone(),
            opts,
            marking: initial,
            now: 0.0,
            open_gap: vec![0.0; nt],
            window: vec![VecDeque::new(); nt],
            drifting: vec![false; nt],
        }
    }

    /// The same monitor started at model time `time` (a run joined midway).
    pub fn at(mut self, time: f64) -> Monitor {
        self.now = time;
        self
    }

    /// Transitions drifting now.
    pub fn drifting(&self) -> impl Iterator<Item = TransitionId> + '_ {
        self.drifting
            .iter()
            .enumerate()
            .filter(|(_, d)| **d)
            .map(|(i, _)| TransitionId(i as u32))
    }

    /// `t` fired at `time`, leaving `marking`: a [`Drift`] when `t`'s rate over the window
    /// has just left the net's.
    pub fn fired(&mut self, time: f64, t: TransitionId, marking: &[u32]) -> Option<Drift> {
        let dt = time - self.now;
        if dt > 0.0 {
            for u in self.net.transition_ids() {
                let a = active_servers(&self.net, &self.marking, u);
                self.open_gap[u.index()] += a as f64 * dt;
            }
            self.now = time;
        }
        self.marking.clear();
        self.marking.extend_from_slice(marking);
        let Timing::Exponential { rate, .. } = self.net.transition(t).timing else {
            return None;
        };
        let i = t.index();
        let w = &mut self.window[i];
        w.push_back(std::mem::take(&mut self.open_gap[i]));
        if w.len() > self.opts.window {
            w.pop_front();
        }
        if w.len() < self.opts.min_firings {
            return None;
        }
        let (n, e) = (w.len() as u64, w.iter().sum::<f64>());
        let p = stats::rate_test(n, e, rate);
        let was = self.drifting[i];
        self.drifting[i] = if was {
            p < self.opts.back
        } else {
            p < self.opts.alpha
        };
        (self.drifting[i] && !was).then(|| {
            let (lo, hi) = stats::rate_interval(n, e);
            Drift {
                transition: self.net.transition(t).name.clone(),
                time,
                observed: n as f64 / e,
                predicted: rate,
                interval: [lo, hi],
                n,
                p_value: p,
            }
        })
    }
}
