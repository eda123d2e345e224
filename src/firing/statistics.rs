//! Time-weighted statistics of one run: mean tokens per place and throughput per transition
//! over `[0, T]`.
//!
//! The integral of `m(p)` is kept lazily: a place's area is brought up to date only when its
//! count changes (and when the statistics are read), so a firing costs `O(|delta(t)|)`, not
//! `O(places)`.

use crate::net::{Net, PlaceId, TokenOverflow, TransitionId};

/// Running integrals, updated by the simulator at each firing.
#[derive(Clone, Debug)]
pub(crate) struct Tally {
    /// ∫ m(p) dt from 0 to `since[p]`.
    area: Vec<f64>,
    /// When `area[p]` was last brought up to date.
    since: Vec<f64>,
    /// Firings per transition.
    fired: Vec<u64>,
}

impl Tally {
    pub(crate) fn new(net: &Net) -> Tally {
        Tally {
            area: vec![0.0; net.place_count()],
            since: vec![0.0; net.place_count()],
            fired: vec![0; net.transition_count()],
        }
    }

    /// Fires `t` at `time` on `m`, bringing the areas of the places it changes up to date
    /// first (one pass over `delta(t)` for both).
    #[inline]
    pub(crate) fn fire(
        &mut self,
        net: &Net,
        m: &mut [u32],
        t: TransitionId,
        time: f64,
    ) -> Result<(), TokenOverflow> {
        debug_assert!(net.is_enabled(m, t), "fired a disabled transition");
        if let Some(o) = net.overflow(m, t) {
            return Err(o);
        }
        for &(p, d) in net.delta(t) {
            let i = p.index();
            let k = m[i];
            self.area[i] += k as f64 * (time - self.since[i]);
            self.since[i] = time;
            m[i] = (k as i64 + d) as u32;
        }
        self.fired[t.index()] += 1;
        Ok(())
    }

    /// The statistics over `[0, time]` with `m` the marking since the last firing.
    pub(crate) fn read(&self, m: &[u32], time: f64) -> Statistics {
        let mean_tokens = (0..self.area.len())
            .map(|i| {
                if time > 0.0 {
                    (self.area[i] + m[i] as f64 * (time - self.since[i])) / time
                } else {
                    m[i] as f64
                }
            })
            .collect();
        let throughput = self
            .fired
            .iter()
            .map(|&k| if time > 0.0 { k as f64 / time } else { 0.0 })
            .collect();
        Statistics {
            time,
            mean_tokens,
            throughput,
            fired: self.fired.clone(),
        }
    }
}

/// What one run measured over `[0, time]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Statistics {
    /// The length of the observed interval (the simulator's clock).
    pub time: f64,
    /// Time-average tokens per place, indexed by [`PlaceId::index`]; the current marking
    /// when `time` is 0.
    pub mean_tokens: Vec<f64>,
    /// Firings per unit of time per transition, indexed by [`TransitionId::index`]; 0 when
    /// `time` is 0.
    pub throughput: Vec<f64>,
    /// Firings per transition.
    pub fired: Vec<u64>,
}

impl Statistics {
    /// Mean tokens in place `p`.
    pub fn mean_tokens_of(&self, p: PlaceId) -> f64 {
        self.mean_tokens[p.index()]
    }

    /// Throughput of transition `t`.
    pub fn throughput_of(&self, t: TransitionId) -> f64 {
        self.throughput[t.index()]
    }
}
