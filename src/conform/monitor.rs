//! The live check: [`Monitor`] follows a run firing by firing and reports a [`Drift`]
//!
//! - when an exponential transition's rate over a block of its firings leaves the net's
//!   (consecutive, disjoint blocks of [`MonitorOptions::block`] firings; the exact test: under
//!   the model the enabled server-time between two firings is exponential, so a block's is
//!   Gamma-distributed);
//! - when a place's time-average tokens over a window of batches (of
//!   [`MonitorOptions::batch_firings`] firings each) leave the steady state's
//!   ([`Monitor::with_mean_tokens`]; the `mean_tokens` row, ratio batch means, Student t), on
//!   consecutive disjoint windows of [`MonitorOptions::batches`] batches —
//!
//! once per transition or place until it returns (p back above [`MonitorOptions::back`]).
//!
//! **False alarms, by design.** An item's tests are numbered k = 1, 2, … and the k-th is at
//! level `alpha / (k (k + 1))` ([`level`]): the levels add up to `alpha`, so on a run that
//! follows the model each item raises at most `alpha` false alarms on average *per run*, however
//! long it is (Bonferroni over the item's tests; alpha spending). A sliding window tested at
//! every firing at a fixed level instead raised alarms in proportion to the run's length
//! (issue 32: 83 over 61 million firings of the model itself). The transitions' test is exact,
//! so their rate is met; the places' Student t on batch means is an approximation (the
//! batches of one run are not quite independent nor normal).
//! The table shown beside the run ([`Monitor::statistics`]) is still the sliding window's.
//! It is a [`Watcher`]: given to [`crate::runtime::RuntimeBuilder::watch`], its drifts become
//! `drift` events of the run (journal, bus, viewer, ROS 2).

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

use serde::Serialize;

use super::{active_servers, stats};
use crate::net::{Net, PlaceId, Timing, TransitionId};
use crate::runtime::{Drift, Monitored, Watcher};

/// Window and level of the live check.
#[derive(Clone, Debug, PartialEq)]
pub struct MonitorOptions {
    /// Firings per transition in the sliding window.
    pub window: usize,
    /// Fewest firings in the window before the transition's rate is shown.
    pub min_firings: usize,
    /// Firings of a transition per tested block (the blocks are disjoint).
    pub block: usize,
    /// Expected false alarms per monitored item per run: the k-th test of an item is at
    /// level `alpha / (k (k + 1))` (see the module).
    pub alpha: f64,
    /// A drifting transition or place has returned when its p-value is back above this
    /// (hysteresis: no alarm storm around the threshold).
    pub back: f64,
    /// Firings (of any transition) per batch of the places' time averages.
    pub batch_firings: u64,
    /// Batches in the places' sliding window; places are tested once it is full.
    pub batches: usize,
}

impl Default for MonitorOptions {
    /// A window of 200 firings shown from 50 on; blocks of 50 firings; 10⁻³ false alarms
    /// per item per run; back below drift once p ≥ 0.05; places over windows of 10 batches
    /// of 100 firings.
    fn default() -> Self {
        MonitorOptions {
            window: 200,
            min_firings: 50,
            block: 50,
            alpha: 1e-3,
            back: 0.05,
            batch_firings: 100,
            batches: 10,
        }
    }
}

/// The places' batches: token-time integrals per place and batch lengths, the last
/// [`MonitorOptions::batches`] of them.
#[derive(Clone, Debug)]
struct PlaceBatches {
    predicted: Vec<f64>,
    open: Vec<f64>,
    opened: f64,
    firings: u64,
    closed: Vec<VecDeque<f64>>,
    lengths: VecDeque<f64>,
    drifting: Vec<bool>,
    /// Each place's statistic at the last full window.
    last: Vec<Option<Statistic>>,
    /// Batches closed since the places were last tested.
    fresh: usize,
    /// Windows of batches tested so far (every place is tested on each).
    tests: u64,
}

/// A transition's block under way: firings, enabled server-time, and blocks tested so far.
#[derive(Clone, Debug, Default)]
struct Block {
    firings: u64,
    exposure: f64,
    tests: u64,
}

/// The level of an item's `k`-th test (k ≥ 1) when its tests together may raise `alpha`
/// false alarms: `alpha / (k (k + 1))`, which add up to `alpha` over k = 1, 2, ….
pub(crate) fn level(alpha: f64, k: u64) -> f64 {
    let k = k.max(1) as f64;
    alpha / (k * (k + 1.0))
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
    blocks: Vec<Block>,
    drifting: Vec<bool>,
    places: Option<PlaceBatches>,
}

impl Monitor {
    /// A monitor of a run of `net` from `initial` (transitions only; see
    /// [`Monitor::with_mean_tokens`]).
    pub fn new(net: &Net, initial: Vec<u32>, opts: MonitorOptions) -> Monitor {
        let nt = net.transition_count();
        Monitor {
            net: net.clone(),
            opts,
            marking: initial,
            now: 0.0,
            open_gap: vec![0.0; nt],
            window: vec![VecDeque::new(); nt],
            blocks: vec![Block::default(); nt],
            drifting: vec![false; nt],
            places: None,
        }
    }

    /// The same monitor, also watching every place's mean tokens against `predicted` (per
    /// place, in net order: the steady state, [`super::steady_predictions`]).
    pub fn with_mean_tokens(mut self, predicted: Vec<f64>) -> Monitor {
        let np = self.net.place_count();
        self.places = (predicted.len() == np).then(|| PlaceBatches {
            predicted,
            open: vec![0.0; np],
            opened: self.now,
            firings: 0,
            closed: vec![VecDeque::new(); np],
            lengths: VecDeque::new(),
            drifting: vec![false; np],
            last: vec![None; np],
            fresh: 0,
            tests: 0,
        });
        self
    }

    /// The same monitor started at model time `time` (a run joined midway).
    pub fn at(mut self, time: f64) -> Monitor {
        self.now = time;
        if let Some(b) = &mut self.places {
            b.opened = time;
        }
        self
    }

    /// Transitions and places drifting now.
    pub fn drifting(&self) -> impl Iterator<Item = Monitored> + '_ {
        let ts = self
            .drifting
            .iter()
            .enumerate()
            .filter(|(_, d)| **d)
            .map(|(i, _)| Monitored::Transition(TransitionId(i as u32)));
        let ps = self.places.iter().flat_map(|b| {
            b.drifting
                .iter()
                .enumerate()
                .filter(|(_, d)| **d)
                .map(|(i, _)| Monitored::Place(PlaceId(i as u32)))
        });
        ts.chain(ps)
    }

    /// What the monitor sees now, item by item: every exponential transition's rate over its
    /// window (once it has [`MonitorOptions::min_firings`]), then every place's mean tokens
    /// over the last full window of batches — each with the model's value, the 95% interval,
    /// the test's p-value and whether it is drifting. What the viewer's table shows.
    pub fn statistics(&self) -> Vec<Statistic> {
        let ts = self
            .net
            .transition_ids()
            .filter_map(|t| self.transition_statistic(t));
        let ps = self
            .places
            .iter()
            .flat_map(|b| b.last.iter().flatten().cloned());
        ts.chain(ps).collect()
    }

    /// `t`'s rate over its window against the net's, once the window has enough firings.
    fn transition_statistic(&self, t: TransitionId) -> Option<Statistic> {
        let Timing::Exponential { rate, .. } = self.net.transition(t).timing else {
            return None;
        };
        let w = &self.window[t.index()];
        if w.len() < self.opts.min_firings {
            return None;
        }
        let (n, e) = (w.len() as u64, w.iter().sum::<f64>());
        let (lo, hi) = stats::rate_interval(n, e);
        Some(Statistic {
            figures: Drift {
                of: Monitored::Transition(t),
                observed: n as f64 / e,
                predicted: rate,
                interval: [lo, hi],
                n,
                p_value: stats::rate_test(n, e, rate),
            },
            drifting: self.drifting[t.index()],
        })
    }

    /// `t` fired at `time`, leaving `marking`: the drifts that have just begun — `t`'s rate
    /// over the window, then (when a batch closes) places' mean tokens.
    pub fn fired(&mut self, time: f64, t: TransitionId, marking: &[u32]) -> Vec<Drift> {
        let mut out = Vec::new();
        let dt = time - self.now;
        if dt > 0.0 {
            for u in self.net.transition_ids() {
                let a = active_servers(&self.net, &self.marking, u);
                self.open_gap[u.index()] += a as f64 * dt;
            }
            if let Some(b) = &mut self.places {
                for (x, &k) in b.open.iter_mut().zip(&self.marking) {
                    *x += k as f64 * dt;
                }
            }
            self.now = time;
        }
        self.marking.clear();
        self.marking.extend_from_slice(marking);
        out.extend(self.transition_drift(t));
        if let Some(b) = &mut self.places {
            b.firings += 1;
            if b.firings >= self.opts.batch_firings {
                out.extend(place_drifts(b, &self.opts, time));
            }
        }
        out
    }

    fn transition_drift(&mut self, t: TransitionId) -> Option<Drift> {
        if self.net.transition(t).is_immediate() {
            return None;
        }
        let Timing::Exponential { rate, .. } = self.net.transition(t).timing else {
            return None;
        };
        let i = t.index();
        let gap = std::mem::take(&mut self.open_gap[i]);
        let w = &mut self.window[i];
        w.push_back(gap);
        if w.len() > self.opts.window {
            w.pop_front();
        }
        let b = &mut self.blocks[i];
        b.firings += 1;
        b.exposure += gap;
        if b.firings < self.opts.block.max(1) as u64 {
            return None;
        }
        let (n, e) = (b.firings, b.exposure);
        b.tests += 1;
        b.firings = 0;
        b.exposure = 0.0;
        let p_value = stats::gamma_test(n, e, rate);
        let was = self.drifting[i];
        self.drifting[i] = if was {
            p_value < self.opts.back
        } else {
            p_value < level(self.opts.alpha, b.tests)
        };
        let (lo, hi) = stats::rate_interval(n, e);
        (self.drifting[i] && !was).then_some(Drift {
            of: Monitored::Transition(t),
            observed: n as f64 / e,
            predicted: rate,
            interval: [lo, hi],
            n,
            p_value,
        })
    }
}

/// Closes the open batch at `time` and tests every place over the window.
fn place_drifts(b: &mut PlaceBatches, opts: &MonitorOptions, time: f64) -> Vec<Drift> {
    let length = time - b.opened;
    b.firings = 0;
    b.opened = time;
    if length <= 0.0 {
        return Vec::new();
    }
    b.lengths.push_back(length);
    for (w, x) in b.closed.iter_mut().zip(&mut b.open) {
        w.push_back(std::mem::take(x));
        if w.len() > opts.batches {
            w.pop_front();
        }
    }
    if b.lengths.len() > opts.batches {
        b.lengths.pop_front();
    }
    b.fresh += 1;
    if b.lengths.len() < opts.batches.max(2) {
        return Vec::new();
    }
    // The alarm test runs on disjoint windows: when every batch in it is new.
    let tested = b.fresh >= b.lengths.len();
    if tested {
        b.fresh = 0;
        b.tests += 1;
    }
    let alpha = level(opts.alpha, b.tests);
    let lengths: Vec<f64> = b.lengths.iter().copied().collect();
    let mut out = Vec::new();
    for (p, w) in b.closed.iter().enumerate() {
        let ints: Vec<f64> = w.iter().copied().collect();
        let est = stats::ratio_estimate(&ints, &lengths);
        let predicted = b.predicted[p];
        let pv = stats::t_test(&est, predicted, lengths.len() as u64 - 1);
        let was = b.drifting[p];
        if tested {
            b.drifting[p] = if was { pv < opts.back } else { pv < alpha };
        }
        let s = Statistic {
            figures: Drift {
                of: Monitored::Place(PlaceId(p as u32)),
                observed: est.mean,
                predicted,
                interval: [est.lo(), est.hi()],
                n: lengths.len() as u64,
                p_value: pv,
            },
            drifting: b.drifting[p],
        };
        if b.drifting[p] && !was {
            out.push(s.figures.clone());
        }
        b.last[p] = Some(s);
    }
    out
}

/// One monitored item now (see [`Monitor::statistics`]): the figures a [`Drift`] event
/// carries, and whether the item is drifting.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Statistic {
    /// The item, its observation, the model's value, the interval, the sample size and the
    /// test's p-value.
    #[serde(flatten)]
    pub figures: Drift,
    /// Drifting now (reported, not yet back).
    pub drifting: bool,
}

/// One [`Monitor`] shared between the run's supervisor (it is the run's [`Watcher`]) and
/// whoever shows its [`Monitor::statistics`] while the run goes on (the viewer).
#[derive(Clone, Debug)]
pub struct SharedMonitor(Arc<Mutex<Monitor>>);

impl SharedMonitor {
    /// Shares `monitor`.
    pub fn new(monitor: Monitor) -> Self {
        SharedMonitor(Arc::new(Mutex::new(monitor)))
    }

    /// The monitor's statistics now.
    pub fn statistics(&self) -> Vec<Statistic> {
        self.lock().statistics()
    }

    fn lock(&self) -> std::sync::MutexGuard<'_, Monitor> {
        self.0
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }
}

impl Watcher for SharedMonitor {
    fn fired(&mut self, time: f64, t: TransitionId, marking: &[u32]) -> Vec<Drift> {
        self.lock().fired(time, t, marking)
    }
}

impl Watcher for Monitor {
    fn fired(&mut self, time: f64, t: TransitionId, marking: &[u32]) -> Vec<Drift> {
        Monitor::fired(self, time, t, marking)
    }
}
