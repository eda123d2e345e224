//! A sum tree over transition rates: O(log n) updates and ∝-rate sampling, so the race of
//! net-timed transitions costs the same on a ring of 4 places and one of 1000.

/// Rates per transition with their running sums.
#[derive(Clone, Debug)]
pub(crate) struct Race {
    leaves: usize,
    tree: Vec<f64>,
}

impl Race {
    pub(crate) fn new(n: usize) -> Race {
        let leaves = n.max(1).next_power_of_two();
        Race {
            leaves,
            tree: vec![0.0; 2 * leaves],
        }
    }

    /// Sets the rate of leaf `i`; returns true when it changed.
    #[inline]
    pub(crate) fn set(&mut self, i: usize, rate: f64) -> bool {
        let mut k = self.leaves + i;
        if self.tree[k] == rate {
            return false;
        }
        self.tree[k] = rate;
        while k > 1 {
            k /= 2;
            self.tree[k] = self.tree[2 * k] + self.tree[2 * k + 1];
        }
        true
    }

    #[inline]
    pub(crate) fn total(&self) -> f64 {
        self.tree[1]
    }

    /// The leaf where the cumulative sum passes `u` (0 ≤ u < total); never a zero-rate leaf.
    pub(crate) fn find(&self, mut u: f64) -> usize {
        let mut k = 1;
        while k < self.leaves {
            let left = self.tree[2 * k];
            if u < left || self.tree[2 * k + 1] <= 0.0 {
                k *= 2;
            } else {
                u -= left;
                k = 2 * k + 1;
            }
        }
        let i = k - self.leaves;
        if self.tree[k] > 0.0 {
            return i;
        }
        // Rounding put us on an empty leaf: take the nearest positive one.
        (0..self.leaves)
            .filter(|&j| self.tree[self.leaves + j] > 0.0)
            .min_by_key(|&j| j.abs_diff(i))
            .unwrap_or(i)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_leaves_in_proportion() {
        let mut r = Race::new(5);
        r.set(0, 1.0);
        r.set(3, 3.0);
        assert_eq!(r.total(), 4.0);
        assert_eq!(r.find(0.5), 0);
        assert_eq!(r.find(1.0), 3);
        assert_eq!(r.find(3.99), 3);
        r.set(3, 0.0);
        assert_eq!(r.find(0.9), 0);
        assert_eq!(r.total(), 1.0);
    }
}
