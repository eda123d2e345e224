//! The generator in compressed sparse columns — what Gauss–Seidel reads (`π_j q_j = Σ_i π_i
//! Q_ij` gathers over column `j`) — built straight from rows, with the rates interned when a
//! chain has few distinct ones (a `u16` index per entry instead of an `f64`).
//!
//! A large chain is solved from this form alone: the row form is never built, so the steady
//! state of Kanban N = 4 (454,475 states, 4 M entries) needs 24 MB for its generator instead
//! of 96 MB for rows plus columns.

use rustc_hash::FxHashMap;

use super::SolveError;

/// Rates of the entries, interned or not.
#[derive(Debug)]
enum Rates {
    /// `values[index[k]]` is entry `k`'s rate.
    Interned { index: Vec<u16>, values: Vec<f64> },
    /// One `f64` per entry (more than 65,536 distinct rates).
    Plain(Vec<f64>),
}

/// Incoming entries of each state and every state's exit rate.
#[derive(Debug)]
pub(crate) struct Columns {
    n: usize,
    /// Column `j`'s entries are `ptr[j]..ptr[j + 1]`.
    ptr: Vec<usize>,
    /// Source state of each entry.
    rows: Vec<u32>,
    rates: Rates,
    /// Total outgoing rate of each state (self-loops excluded).
    pub(crate) exit: Vec<f64>,
}

impl Columns {
    /// Builds the columns of a chain over `0..n` given its rows: `row(i, out)` appends the
    /// `(to, rate)` entries of row `i` (called twice per row). Self-loops and zero rates are
    /// dropped; repeated `(i, j)` entries stay separate (they add up in every use).
    pub(crate) fn from_rows(n: usize, mut row: impl FnMut(usize, &mut Vec<(u32, f64)>)) -> Self {
        let mut ptr = vec![0usize; n + 1];
        let mut exit = vec![0.0; n];
        let mut buf = Vec::new();
        let mut intern: FxHashMap<u64, u16> = FxHashMap::default();
        let mut values: Vec<f64> = Vec::new();
        let mut interned = true;
        for (i, e) in exit.iter_mut().enumerate() {
            buf.clear();
            row(i, &mut buf);
            for &(j, q) in &buf {
                if j as usize == i || q <= 0.0 {
                    continue;
                }
                ptr[j as usize + 1] += 1;
                *e += q;
                if interned && !intern.contains_key(&q.to_bits()) {
                    if values.len() == usize::from(u16::MAX) + 1 {
                        interned = false;
                    } else {
                        intern.insert(q.to_bits(), values.len() as u16);
                        values.push(q);
                    }
                }
            }
        }
        for j in 0..n {
            ptr[j + 1] += ptr[j];
        }
        let nnz = ptr[n];
        let mut rows = vec![0u32; nnz];
        let mut index = if interned {
            vec![0u16; nnz]
        } else {
            Vec::new()
        };
        let mut plain = if interned { Vec::new() } else { vec![0.0; nnz] };
        for i in 0..n {
            buf.clear();
            row(i, &mut buf);
            for &(j, q) in &buf {
                if j as usize == i || q <= 0.0 {
                    continue;
                }
                // `ptr[j]` walks column `j`; shifted back below.
                let k = &mut ptr[j as usize];
                rows[*k] = i as u32;
                if interned {
                    index[*k] = intern[&q.to_bits()];
                } else {
                    plain[*k] = q;
                }
                *k += 1;
            }
        }
        for j in (1..=n).rev() {
            ptr[j] = ptr[j - 1];
        }
        ptr[0] = 0;
        let rates = if interned {
            Rates::Interned { index, values }
        } else {
            Rates::Plain(plain)
        };
        Columns {
            n,
            ptr,
            rows,
            rates,
            exit,
        }
    }

    /// Every state reaches `root`: a breadth-first search from `root` over incoming entries.
    pub(crate) fn all_reach(&self, root: u32) -> bool {
        let mut seen = vec![false; self.n];
        let mut queue: Vec<u32> = Vec::with_capacity(self.n);
        seen[root as usize] = true;
        queue.push(root);
        let mut head = 0;
        while head < queue.len() {
            let j = queue[head] as usize;
            head += 1;
            for &i in &self.rows[self.ptr[j]..self.ptr[j + 1]] {
                if !seen[i as usize] {
                    seen[i as usize] = true;
                    queue.push(i);
                }
            }
        }
        queue.len() == self.n
    }

    /// `Σ_i π_i Q_ij` over the incoming entries of `j`.
    #[inline]
    fn gather(&self, pi: &[f64], j: usize) -> f64 {
        let r = self.ptr[j]..self.ptr[j + 1];
        let rows = &self.rows[r.clone()];
        match &self.rates {
            Rates::Interned { index, values } => rows
                .iter()
                .zip(&index[r])
                .map(|(&i, &x)| pi[i as usize] * values[x as usize])
                .sum(),
            Rates::Plain(rates) => rows
                .iter()
                .zip(&rates[r])
                .map(|(&i, &q)| pi[i as usize] * q)
                .sum(),
        }
    }

    /// `‖πQ‖∞`.
    pub(crate) fn residual(&self, pi: &[f64]) -> f64 {
        (0..self.n).fold(0.0f64, |m, j| {
            m.max((self.gather(pi, j) - pi[j] * self.exit[j]).abs())
        })
    }

    /// SOR sweeps over `π_j q_j = Σ_i π_i Q_ij` in state order, normalising after each
    /// sweep; checks the residual when a sweep changes little (and every 50 sweeps). Returns
    /// the number of sweeps.
    pub(crate) fn sor(
        &self,
        pi: &mut [f64],
        omega: f64,
        tol: f64,
        max_iterations: usize,
    ) -> Result<usize, SolveError> {
        let exit = &self.exit;
        let mut residual = f64::INFINITY;
        let mut threshold = tol;
        let mut sweeps = 0;
        while sweeps < max_iterations {
            // The largest change `q_j·|Δπ_j|` of a sweep estimates the residual; the real one is
            // computed only once the estimate is small (it costs a sweep).
            let mut change = 0.0f64;
            for j in 0..self.n {
                let s = self.gather(pi, j);
                let new = if exit[j] > 0.0 { s / exit[j] } else { pi[j] };
                let next = (1.0 - omega) * pi[j] + omega * new;
                change = change.max(exit[j] * (next - pi[j]).abs());
                pi[j] = next;
            }
            sweeps += 1;
            let sum: f64 = pi.iter().sum();
            if !(sum.is_finite() && sum > 0.0) {
                break;
            }
            let inv = 1.0 / sum;
            pi.iter_mut().for_each(|v| *v *= inv);
            if change <= threshold || sweeps % 50 == 0 || sweeps == max_iterations {
                residual = self.residual(pi);
                if residual <= tol {
                    return Ok(sweeps);
                }
                if !residual.is_finite() {
                    break;
                }
                if change <= threshold {
                    threshold *= 0.5;
                }
            }
        }
        if residual <= tol {
            return Ok(sweeps);
        }
        Err(SolveError::NotConverged {
            iterations: sweeps,
            residual,
        })
    }

    /// Gauss–Seidel, then under-relaxed SOR (ω = 0.7) when it does not converge, from the
    /// uniform distribution; `‖πQ‖∞ ≤ tol` on success.
    pub(crate) fn gauss_seidel(
        &self,
        tol: f64,
        max_iterations: usize,
        fallback: bool,
    ) -> Result<Vec<f64>, SolveError> {
        let mut pi = vec![1.0 / self.n as f64; self.n];
        match self.sor(&mut pi, 1.0, tol, max_iterations) {
            Ok(_) => Ok(pi),
            Err(e) if !fallback => Err(e),
            Err(_) => {
                pi.fill(1.0 / self.n as f64);
                self.sor(&mut pi, 0.7, tol, max_iterations).map(|_| pi)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn many_distinct_rates_are_stored_plainly_and_solve_the_same() {
        // A ring of 70,000 states with 70,000 distinct rates: the interned table overflows.
        let n = 70_000;
        let rate = |i: usize| 1.0 + i as f64 * 1e-3;
        let c = Columns::from_rows(n, |i, out| out.push((((i + 1) % n) as u32, rate(i))));
        assert!(matches!(c.rates, Rates::Plain(_)));
        assert_eq!(c.rows.len(), n);
        let pi = c.gauss_seidel(1e-12, 10, false).unwrap();
        // π_i ∝ 1/rate(i) on a ring.
        let z: f64 = (0..n).map(|i| 1.0 / rate(i)).sum();
        for i in [0, 1, n / 2, n - 1] {
            assert!((pi[i] - 1.0 / rate(i) / z).abs() < 1e-12, "state {i}");
        }
    }

    #[test]
    fn few_rates_are_interned() {
        // 0 ⇄ 1 with rates 1 and 2, a self-loop and a zero rate dropped: π = (2/3, 1/3).
        let c = Columns::from_rows(2, |i, out| {
            out.extend(match i {
                0 => [(1, 1.0), (0, 5.0)],
                _ => [(0, 2.0), (1, 0.0)],
            })
        });
        assert!(matches!(&c.rates, Rates::Interned { values, .. } if values.len() == 2));
        assert_eq!(c.exit, [1.0, 2.0]);
        let pi = c.gauss_seidel(1e-14, 100, true).unwrap();
        assert!((pi[0] - 2.0 / 3.0).abs() < 1e-12);
        assert!(c.residual(&pi) < 1e-14);
    }
}
