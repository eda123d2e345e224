//! Transient distribution π(t) by uniformization, with Fox–Glynn truncation of the Poisson
//! weights.

use std::sync::Arc;

use super::{Ctmc, SolveError};
use crate::analysis::state_space::Monitor;

/// Poisson(`qt`) weights truncated so that the mass left out is at most `eps`, normalised to
/// sum 1 (Fox–Glynn: computed relative to the mode, so nothing underflows for large `qt`).
/// Returns the first index kept and the weights from there on.
pub fn poisson_weights(qt: f64, eps: f64) -> (usize, Vec<f64>) {
    if qt <= 0.0 || !qt.is_finite() {
        return (0, vec![1.0]);
    }
    let eps = eps.max(1e-300);
    let mode = qt.floor() as usize;
    // Right of the mode: w_{k+1} = w_k·qt/(k+1); the tail after k is at most w_k·r/(1−r)
    // with r = qt/(k+1), since the ratios decrease.
    let mut right = vec![1.0f64];
    let mut k = mode;
    let mut w = 1.0;
    loop {
        let r_next = qt / (k as f64 + 1.0);
        if r_next < 1.0 && w * r_next / (1.0 - r_next) <= eps / 4.0 {
            break;
        }
        w *= qt / (k as f64 + 1.0);
        k += 1;
        right.push(w);
    }
    // Left of the mode: w_{k-1} = w_k·k/qt; the tail below k is at most w_k·r/(1−r) with
    // r = k/qt.
    let mut left = Vec::new();
    let mut k = mode;
    let mut w = 1.0;
    while k > 0 {
        let r_next = k as f64 / qt;
        if r_next < 1.0 && w * r_next / (1.0 - r_next) <= eps / 4.0 {
            break;
        }
        w *= k as f64 / qt;
        k -= 1;
        left.push(w);
    }
    let first = k;
    let mut weights: Vec<f64> = left.into_iter().rev().chain(right).collect();
    let total: f64 = weights.iter().sum();
    weights.iter_mut().for_each(|v| *v /= total);
    (first, weights)
}

/// The default error bound of each transient distribution ([`TransientOptions::eps`]).
pub const TRANSIENT_EPS: f64 = 1e-12;

/// How [`Ctmc::transient`] computes.
#[derive(Clone, Debug)]
pub struct TransientOptions {
    /// The total error allowed in each π(t) (default [`TRANSIENT_EPS`]).
    pub eps: f64,
    /// Watches the solver from another thread (default: none): it publishes the time point
    /// it works towards (in increasing time order) and its iterations done of planned
    /// ([`Monitor::transient_progress`]), and stops within one iteration (one product with
    /// the generator) of [`Monitor::cancel`] with [`SolveError::Cancelled`].
    pub monitor: Option<Arc<Monitor>>,
}

impl Default for TransientOptions {
    fn default() -> Self {
        TransientOptions {
            eps: TRANSIENT_EPS,
            monitor: None,
        }
    }
}

impl Ctmc {
    /// π(t) for each time in `times` (any order, ≥ 0) from the initial distribution
    /// `initial` (`(state, probability)` pairs), with total error at most
    /// [`TransientOptions::eps`] per time. Fails only when [`TransientOptions::monitor`] is
    /// cancelled.
    ///
    /// ```
    /// use std::sync::Arc;
    /// use gspn::analysis::ctmc::{Ctmc, SolveError, TransientOptions};
    /// use gspn::analysis::state_space::Monitor;
    /// let c = Ctmc::from_triplets(2, vec![(0, 1, 1.0), (1, 0, 2.0)]);
    /// let at = c.transient(&[(0, 1.0)], &[0.5], &TransientOptions::default()).unwrap();
    /// let p0 = (2.0 + (-3.0f64 * 0.5).exp()) / 3.0;
    /// assert!((at[0][0] - p0).abs() < 1e-12);
    /// let monitor = Arc::new(Monitor::new());
    /// let opts = TransientOptions { monitor: Some(monitor.clone()), ..Default::default() };
    /// c.transient(&[(0, 1.0)], &[2.0, 0.5], &opts).unwrap();
    /// let (point, done, planned) = monitor.transient_progress();
    /// assert_eq!((point, done), (1, planned));
    /// monitor.cancel();
    /// let r = c.transient(&[(0, 1.0)], &[1e6], &opts);
    /// assert!(matches!(r, Err(SolveError::Cancelled { iterations: 0 })));
    /// ```
    pub fn transient(
        &self,
        initial: &[(u32, f64)],
        times: &[f64],
        opts: &TransientOptions,
    ) -> Result<Vec<Vec<f64>>, SolveError> {
        let monitor = opts.monitor.clone().unwrap_or_default();
        let eps = opts.eps;
        let n = self.n;
        let mut start = vec![0.0; n];
        for &(s, p) in initial {
            start[s as usize] += p;
        }
        let exit = self.exit_rates();
        let lambda = exit.iter().fold(0.0f64, |m, &x| m.max(x));
        let mut order: Vec<usize> = (0..times.len()).collect();
        order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
        // The Poisson weights of every step first, for the number of iterations planned.
        let mut now = 0.0;
        let steps: Vec<_> = order
            .into_iter()
            .map(|idx| {
                let t = times[idx].max(0.0);
                let dt = t - now;
                now = t.max(now);
                (
                    idx,
                    (dt > 0.0 && lambda > 0.0).then(|| poisson_weights(lambda * dt, eps)),
                )
            })
            .collect();
        let planned = steps
            .iter()
            .filter_map(|(_, w)| w.as_ref())
            .map(|(first, weights)| first + weights.len() - 1)
            .sum();
        monitor.set_transient_plan(planned);
        monitor.set_transient_iterations(0);
        let mut done = 0;
        let mut out = vec![Vec::new(); times.len()];
        let mut current = start;
        for (point, (idx, weights)) in steps.into_iter().enumerate() {
            monitor.set_transient_point(point);
            if let Some((first, weights)) = weights {
                current = self.uniformize(
                    &current,
                    &exit,
                    lambda,
                    (first, &weights),
                    &monitor,
                    &mut done,
                )?;
            }
            out[idx] = current.clone();
        }
        Ok(out)
    }

    /// One uniformization step from `v` with `(first, weights)`, the Poisson weights of the
    /// counts from `first` on; `done` counts the iterations of every step, for `monitor`.
    fn uniformize(
        &self,
        v: &[f64],
        exit: &[f64],
        lambda: f64,
        (first, weights): (usize, &[f64]),
        monitor: &Monitor,
        done: &mut usize,
    ) -> Result<Vec<f64>, SolveError> {
        let n = self.n;
        let mut acc = vec![0.0; n];
        let mut cur = v.to_vec();
        let mut next = vec![0.0; n];
        let inv = 1.0 / lambda;
        let last = first + weights.len() - 1;
        for k in 0..=last {
            if k >= first {
                let w = weights[k - first];
                acc.iter_mut().zip(&cur).for_each(|(a, c)| *a += w * c);
            }
            if k == last {
                break;
            }
            if monitor.is_cancelled() {
                return Err(SolveError::Cancelled { iterations: *done });
            }
            self.uniform_step(&cur, &mut next, exit, inv);
            std::mem::swap(&mut cur, &mut next);
            *done += 1;
            monitor.set_transient_iterations(*done);
        }
        Ok(acc)
    }

    /// One step of the uniformised chain: `next = cur·(I + Q/Λ)`, `inv` = 1/Λ, `exit` the
    /// exit rates.
    pub(crate) fn uniform_step(&self, cur: &[f64], next: &mut [f64], exit: &[f64], inv: f64) {
        for ((x, &c), &q) in next.iter_mut().zip(cur).zip(exit) {
            *x = c * (1.0 - q * inv);
        }
        for (i, &c) in cur.iter().enumerate() {
            let p = c * inv;
            if p == 0.0 {
                continue;
            }
            for (j, q) in self.row(i) {
                next[j as usize] += p * q;
            }
        }
    }
}
