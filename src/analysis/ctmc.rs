//! A continuous-time Markov chain as a sparse generator, and its solvers.

/// A CTMC over states `0..n`: off-diagonal rates in compressed sparse rows. The diagonal is
/// implied (minus the row's sum). Self-loops are not stored (they do not change π).
#[derive(Clone, Debug, Default)]
pub struct Ctmc {
    /// Number of states.
    pub n: usize,
    /// Row `i`'s entries are `cols[row_ptr[i]..row_ptr[i+1]]` / `rates[..]`.
    pub row_ptr: Vec<usize>,
    /// Target state of each entry.
    pub cols: Vec<u32>,
    /// Rate of each entry (> 0).
    pub rates: Vec<f64>,
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
}
