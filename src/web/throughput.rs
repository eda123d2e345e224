//! Throughput over time: each transition's firings counted per window of model time, for
//! the page's throughput curves (a replay's whole run, a live run's history so far).
//!
//! The window is a power of two seconds that doubles as the run grows, so that a run of
//! any length is at most [`BINS`] windows and the memory is `BINS` counts per transition that
//! fired, whatever the number of firings (issue 32: memory bounded by what is shown). The
//! page continues a live run's counts with the same rule (`plot.js`, `Throughput`).

use std::collections::BTreeMap;

use serde::Serialize;

/// Most windows kept: when a firing comes past them, the window doubles (pairs merged).
pub(crate) const BINS: usize = 128;

/// The first window: 2⁻¹⁰ s (about a millisecond).
const FIRST_WIDTH: f64 = 1.0 / 1024.0;

/// Firings per transition per window of `width` model seconds, window `k` being
/// `[k·width, (k+1)·width)`.
#[derive(Clone, Debug, Serialize)]
pub(crate) struct Throughput {
    width: f64,
    /// Per transition name (those that fired), its count per window, up to the last window
    /// with a firing of any transition.
    counts: BTreeMap<String, Vec<u64>>,
}

impl Default for Throughput {
    fn default() -> Self {
        Throughput {
            width: FIRST_WIDTH,
            counts: BTreeMap::new(),
        }
    }
}

impl Throughput {
    /// Counts a firing of `transition` at model time `t` (≥ 0).
    pub(crate) fn fired(&mut self, t: f64, transition: &str) {
        let t = t.max(0.0);
        if !t.is_finite() {
            return;
        }
        while t >= self.width * BINS as f64 {
            self.double();
        }
        let k = (t / self.width) as usize;
        let row = match self.counts.get_mut(transition) {
            Some(row) => row,
            None => self.counts.entry(transition.to_string()).or_default(),
        };
        if row.len() <= k {
            row.resize(k + 1, 0);
        }
        row[k] += 1;
    }

    /// Doubles the window: windows 2k and 2k+1 become window k.
    fn double(&mut self) {
        self.width *= 2.0;
        for row in self.counts.values_mut() {
            *row = row.chunks(2).map(|p| p.iter().sum()).collect();
        }
    }

    /// The window's width in model seconds.
    #[cfg(test)]
    pub(crate) fn width(&self) -> f64 {
        self.width
    }

    /// `transition`'s counts per window.
    #[cfg(test)]
    pub(crate) fn counts(&self, transition: &str) -> &[u64] {
        self.counts.get(transition).map_or(&[], Vec::as_slice)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn firings_are_counted_per_window_and_windows_double_as_the_run_grows() {
        let mut th = Throughput::default();
        th.fired(0.0, "a");
        th.fired(0.0005, "a");
        th.fired(0.001, "b");
        assert_eq!(th.width(), 1.0 / 1024.0);
        assert_eq!(th.counts("a"), &[2]);
        assert_eq!(th.counts("b"), &[0, 1]);
        // 10 s needs windows of 2⁻³ s (128 × 2⁻⁴ = 8 s is too short).
        th.fired(10.0, "a");
        assert_eq!(th.width(), 0.125);
        assert_eq!(th.counts("a").len(), 81);
        assert_eq!(th.counts("a")[0], 2);
        assert_eq!(th.counts("a")[80], 1);
        assert_eq!(th.counts("b"), &[1]);
        assert_eq!(th.counts("a").iter().sum::<u64>(), 3);
        assert!(th.counts("a").len() <= BINS);
    }
}
