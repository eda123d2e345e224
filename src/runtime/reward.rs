//! Rewards earned by a run: the plan's `[rewards.NAME]` place rates integrated over model
//! time (`per_token`: rate × tokens, `marked`: rate while the place holds a token) plus the
//! impulses of the transitions fired — the same [`RewardSpec`] the decision model and
//! `analyze` evaluate, so a run's rate can be set beside the predicted one.
//!
//! The rate comes with a 95% interval from batch means over the run: model time is cut into
//! at most [`MAX_BATCHES`] batches of equal length, the length doubling (neighbours merged)
//! whenever they are all used, so the run's length need not be known in advance.

use std::collections::BTreeMap;

use serde::Serialize;

use crate::analysis::decision::RewardSpec;
use crate::net::{Net, TransitionId};

/// Most batches kept; when a run outgrows them, neighbours merge and the length doubles.
pub(crate) const MAX_BATCHES: usize = 64;

/// The first batch length (model time); it doubles as the run goes on.
const FIRST_LENGTH: f64 = 1e-3;

/// What one reward structure earned over a run.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Earned {
    /// Total reward over `[0, time]`.
    pub total: f64,
    /// `total / time` (0 when no time passed).
    pub rate: f64,
    /// Half-width of the 95% interval of `rate` (Student t over the batch means of the
    /// complete batches); `None` with fewer than 2 complete batches.
    pub half_width: Option<f64>,
    /// Complete batches behind the interval.
    pub batches: usize,
}

/// Accumulates the rewards of a run, firing by firing.
#[derive(Clone, Debug)]
pub(crate) struct Meter {
    specs: Vec<RewardSpec>,
    /// Per spec, per transition: the impulse of one firing.
    impulse: Vec<Vec<f64>>,
    /// Per spec: the rate of the current marking.
    rate: Vec<f64>,
    /// Per spec: earned up to `since`.
    total: Vec<f64>,
    since: f64,
    /// Per spec: earned in each batch; the last one is still open.
    batches: Vec<Vec<f64>>,
    length: f64,
}

impl Meter {
    pub(crate) fn new(net: &Net, specs: Vec<RewardSpec>, m: &[u32]) -> Meter {
        let impulse = specs.iter().map(|s| s.impulses(net)).collect();
        let rate = specs.iter().map(|s| s.place_rate(m)).collect();
        let n = specs.len();
        Meter {
            specs,
            impulse,
            rate,
            total: vec![0.0; n],
            since: 0.0,
            batches: vec![vec![0.0]; n],
            length: FIRST_LENGTH,
        }
    }

    /// Brings the place rewards up to model time `now` (the marking unchanged since the last
    /// call), closing batches on the way.
    fn advance(&mut self, now: f64) {
        if self.specs.is_empty() || now <= self.since {
            return;
        }
        let mut from = self.since;
        while from < now {
            let open = self.batches[0].len() - 1;
            let end = ((open + 1) as f64 * self.length).min(now);
            for k in 0..self.specs.len() {
                let x = self.rate[k] * (end - from);
                self.total[k] += x;
                self.batches[k][open] += x;
            }
            from = end;
            if end >= (open + 1) as f64 * self.length {
                self.close_batch();
            }
        }
        self.since = now;
    }

    /// Opens the next batch; when all are used, merges neighbours and doubles the length.
    fn close_batch(&mut self) {
        if self.batches[0].len() == MAX_BATCHES {
            for b in &mut self.batches {
                let mut merged: Vec<f64> = b.chunks(2).map(|c| c.iter().sum()).collect();
                merged.push(0.0);
                *b = merged;
            }
            self.length *= 2.0;
        } else {
            for b in &mut self.batches {
                b.push(0.0);
            }
        }
    }

    /// Transition `t` fired at `now`; `m` is the marking after it.
    pub(crate) fn fired(&mut self, t: TransitionId, now: f64, m: &[u32]) {
        if self.specs.is_empty() {
            return;
        }
        self.advance(now);
        let open = self.batches[0].len() - 1;
        for k in 0..self.specs.len() {
            let x = self.impulse[k][t.index()];
            self.total[k] += x;
            self.batches[k][open] += x;
            self.rate[k] = self.specs[k].place_rate(m);
        }
    }

    /// What each structure earned over `[0, now]`, by name.
    pub(crate) fn read(&self, now: f64) -> BTreeMap<String, Earned> {
        let mut m = self.clone();
        m.advance(now);
        let complete = m.batches.first().map_or(0, |b| b.len() - 1);
        m.specs
            .iter()
            .enumerate()
            .map(|(k, s)| {
                let rates: Vec<f64> = m.batches[k][..complete]
                    .iter()
                    .map(|x| x / m.length)
                    .collect();
                let half_width = (complete >= 2).then(|| crate::stats::estimate(&rates).half_width);
                let total = m.total[k];
                let earned = Earned {
                    total,
                    rate: if now > 0.0 { total / now } else { 0.0 },
                    half_width,
                    batches: complete,
                };
                (s.name.clone(), earned)
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::analysis::decision::PlaceMode;
    use crate::net::{NetBuilder, Servers};

    fn net() -> (Net, RewardSpec) {
        let mut b = NetBuilder::new("n");
        let p = b.place("P", 1);
        let q = b.place("Q", 0);
        let t = b.exponential("t", 1.0, Servers::Single);
        b.input(p, t, 1);
        b.output(t, q, 2);
        let net = b.build().unwrap();
        let spec = RewardSpec {
            name: "r".into(),
            places: vec![(p, 2.0, PlaceMode::Marked), (q, 1.0, PlaceMode::PerToken)],
            transitions: vec![(t, 5.0)],
        };
        (net, spec)
    }

    #[test]
    fn rates_integrate_and_impulses_add() {
        let (net, spec) = net();
        let mut m = Meter::new(&net, vec![spec], &[1, 0]);
        // P marked over [0, 3): 2 × 3; t fires at 3 (+5); Q holds 2 tokens over [3, 10): 14.
        m.fired(TransitionId(0), 3.0, &[0, 2]);
        let e = &m.read(10.0)["r"];
        assert!((e.total - 25.0).abs() < 1e-12, "{e:?}");
        assert!((e.rate - 2.5).abs() < 1e-12);
    }

    #[test]
    fn batches_double_and_keep_the_total() {
        let (net, spec) = net();
        let mut m = Meter::new(&net, vec![spec], &[1, 0]);
        // A constant rate of 2 over [0, 1000]: every batch mean is 2, the interval is 0.
        let e = &m.read(1000.0)["r"];
        assert!((e.total - 2000.0).abs() < 1e-9);
        assert!(
            e.batches >= MAX_BATCHES / 2 && e.batches < MAX_BATCHES,
            "{e:?}"
        );
        assert!(e.half_width.unwrap() < 1e-9);
        m.advance(1000.0);
        let sum: f64 = m.batches[0].iter().sum();
        assert!((sum - 2000.0).abs() < 1e-9);
    }
}
