//! A continuous-time Markov chain as a sparse generator, and its solvers.
//!
//! - [`Ctmc::steady_state`]: π with πQ = 0, Σπ = 1 for an irreducible chain — a sparse LU
//!   (faer) for small chains, Gauss–Seidel with a residual check for large ones.
//! - [`Ctmc::limiting`]: the limiting distribution from an initial distribution for any chain
//!   (bottom strongly connected components, absorption probabilities into each).
//! - [`Ctmc::transient`]: π(t) by uniformization with Fox–Glynn truncation.
//!
//! ```
//! use gspn::analysis::ctmc::{Ctmc, SteadyOptions};
//! // 0 ⇄ 1 with rates 1 and 2: π = (2/3, 1/3).
//! let c = Ctmc::from_triplets(2, vec![(0, 1, 1.0), (1, 0, 2.0)]);
//! let pi = c.steady_state(&SteadyOptions::default()).unwrap();
//! assert!((pi[0] - 2.0 / 3.0).abs() < 1e-12);
//! assert!(c.residual(&pi) < 1e-12);
//! let pt = c.transient(&[(0, 1.0)], &[0.5], &Default::default()).unwrap();
//! // p_00(t) = 2/3 + 1/3·e^{-3t}
//! assert!((pt[0][0] - (2.0 / 3.0 + (-1.5f64).exp() / 3.0)).abs() < 1e-11);
//! ```

mod columns;
mod limiting;
pub(crate) mod lu;
mod steady;
mod transient;

pub(crate) use columns::Columns;
pub use limiting::Limiting;
pub use steady::{Method, SolveError, SteadyOptions};
pub use transient::{TRANSIENT_EPS, TransientOptions, poisson_weights};

/// A CTMC over states `0..n`: off-diagonal rates in compressed sparse rows. The diagonal is
/// implied (minus the row's sum). Self-loops are not stored (they do not change π).
///
/// The fields are the crate's: every rate is > 0 and each row's columns are sorted, which
/// the solvers rely on, so a chain is made only by [`Ctmc::from_triplets`] (or derived from
/// one) and read through [`Ctmc::states`], [`Ctmc::row`] and [`Ctmc::exit_rate`].
#[derive(Clone, Debug, Default)]
pub struct Ctmc {
    /// Number of states.
    pub(crate) n: usize,
    /// Row `i`'s entries are `cols[row_ptr[i]..row_ptr[i+1]]` / `rates[..]`.
    pub(crate) row_ptr: Vec<usize>,
    /// Target state of each entry.
    pub(crate) cols: Vec<u32>,
    /// Rate of each entry (> 0).
    pub(crate) rates: Vec<f64>,
}

impl Ctmc {
    /// Builds the chain from `(from, to, rate)` triplets; duplicates are summed and self-loops
    /// dropped.
    pub fn from_triplets(n: usize, mut triplets: Vec<(u32, u32, f64)>) -> Ctmc {
        triplets.retain(|&(i, j, r)| i != j && r > 0.0);
        triplets.sort_unstable_by_key(|&(i, j, _)| (i, j));
        let mut row_ptr = vec![0usize; n + 1];
        let mut cols: Vec<u32> = Vec::with_capacity(triplets.len());
        let mut rates: Vec<f64> = Vec::with_capacity(triplets.len());
        let mut last: Option<(u32, u32)> = None;
        for (i, j, r) in triplets {
            if last == Some((i, j)) {
                *rates.last_mut().expect("an entry was pushed") += r;
                continue;
            }
            last = Some((i, j));
            cols.push(j);
            rates.push(r);
            row_ptr[i as usize + 1] += 1;
        }
        for i in 0..n {
            row_ptr[i + 1] += row_ptr[i];
        }
        Ctmc {
            n,
            row_ptr,
            cols,
            rates,
        }
    }

    /// Number of states.
    pub fn states(&self) -> usize {
        self.n
    }

    /// Total outgoing rate of state `i`.
    pub fn exit_rate(&self, i: usize) -> f64 {
        self.rates[self.row_ptr[i]..self.row_ptr[i + 1]]
            .iter()
            .sum()
    }

    /// The entries `(to, rate)` of row `i`.
    pub fn row(&self, i: usize) -> impl Iterator<Item = (u32, f64)> + '_ {
        let r = self.row_ptr[i]..self.row_ptr[i + 1];
        self.cols[r.clone()]
            .iter()
            .copied()
            .zip(self.rates[r].iter().copied())
    }

    /// Number of stored (off-diagonal) entries.
    pub fn nnz(&self) -> usize {
        self.cols.len()
    }

    /// `‖πQ‖∞`: how far `pi` is from stationary.
    pub fn residual(&self, pi: &[f64]) -> f64 {
        let mut r = vec![0.0; self.n];
        for i in 0..self.n {
            let mut out = 0.0;
            for (j, q) in self.row(i) {
                r[j as usize] += pi[i] * q;
                out += q;
            }
            r[i] -= pi[i] * out;
        }
        r.iter().fold(0.0f64, |m, x| m.max(x.abs()))
    }

    /// The chain restricted to `states` (in that order), dropping every edge that leaves it.
    pub fn restrict(&self, states: &[u32]) -> Ctmc {
        let mut index = vec![u32::MAX; self.n];
        for (k, &s) in states.iter().enumerate() {
            index[s as usize] = k as u32;
        }
        let mut row_ptr = Vec::with_capacity(states.len() + 1);
        row_ptr.push(0);
        let mut cols = Vec::new();
        let mut rates = Vec::new();
        for &s in states {
            for (j, q) in self.row(s as usize) {
                let k = index[j as usize];
                if k != u32::MAX {
                    cols.push(k);
                    rates.push(q);
                }
            }
            row_ptr.push(cols.len());
        }
        Ctmc {
            n: states.len(),
            row_ptr,
            cols,
            rates,
        }
    }

    /// The incoming entries, in compressed sparse columns: `(col_ptr, rows, rates)`.
    pub(crate) fn incoming(&self) -> (Vec<usize>, Vec<u32>, Vec<f64>) {
        let mut ptr = vec![0usize; self.n + 1];
        for &j in &self.cols {
            ptr[j as usize + 1] += 1;
        }
        for j in 0..self.n {
            ptr[j + 1] += ptr[j];
        }
        let mut fill = ptr.clone();
        let mut rows = vec![0u32; self.cols.len()];
        let mut rates = vec![0.0; self.cols.len()];
        for i in 0..self.n {
            for (j, q) in self.row(i) {
                let k = &mut fill[j as usize];
                rows[*k] = i as u32;
                rates[*k] = q;
                *k += 1;
            }
        }
        (ptr, rows, rates)
    }

    /// Exit rates of every state.
    pub(crate) fn exit_rates(&self) -> Vec<f64> {
        (0..self.n).map(|i| self.exit_rate(i)).collect()
    }
}
