//! Transient distribution π(t) by uniformization, with Fox–Glynn truncation of the Poisson
//! weights.

use super::Ctmc;

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

impl Ctmc {
    /// π(t) for each time in `times` (any order, ≥ 0) from the initial distribution
    /// `initial` (`(state, probability)` pairs), with total error at most `eps` per time.
    pub fn transient(&self, initial: &[(u32, f64)], times: &[f64], eps: f64) -> Vec<Vec<f64>> {
        let n = self.n;
        let mut start = vec![0.0; n];
        for &(s, p) in initial {
            start[s as usize] += p;
        }
        let exit = self.exit_rates();
        let lambda = exit.iter().fold(0.0f64, |m, &x| m.max(x));
        let mut order: Vec<usize> = (0..times.len()).collect();
        order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
        let mut out = vec![Vec::new(); times.len()];
        let mut now = 0.0;
        let mut current = start;
        for idx in order {
            let t = times[idx].max(0.0);
            let dt = t - now;
            if dt > 0.0 && lambda > 0.0 {
                current = self.uniformize(&current, &exit, lambda, dt, eps);
            }
            now = t.max(now);
            out[idx] = current.clone();
        }
        out
    }

    /// One uniformization step over `dt` from `v`.
    fn uniformize(&self, v: &[f64], exit: &[f64], lambda: f64, dt: f64, eps: f64) -> Vec<f64> {
        let n = self.n;
        let (first, weights) = poisson_weights(lambda * dt, eps);
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
            for ((x, &c), &q) in next.iter_mut().zip(&cur).zip(exit) {
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
            std::mem::swap(&mut cur, &mut next);
        }
        acc
    }
}
