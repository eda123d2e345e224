//! A sum tree over non-negative weights: set one weight and draw an index with probability
//! ∝ weight, both in `O(log n)`.
//!
//! A complete binary tree stored in one array (leaves at `[size, 2·size)`). Each inner node
//! is recomputed from its two children on every update rather than adjusted by a delta, so
//! rounding never accumulates: after any sequence of updates the root is exactly the sum the
//! tree would have if built from scratch (a Fenwick tree of `f64` drifts).

/// Weights indexed `0..len`, with their sum and proportional sampling.
#[derive(Clone, Debug)]
pub(crate) struct SumTree {
    /// Number of leaves: a power of two ≥ the number of weights (at least 1).
    size: usize,
    /// `node[1]` is the root; `node[size + i]` is weight `i`; `node[0]` is unused, and so
    /// is `node[2·size..4·size]`: zeros that let [`SumTree::find`] read grandchildren of the
    /// last inner level without a bounds branch.
    node: Vec<f64>,
}

impl SumTree {
    /// A tree of `len` zero weights.
    pub(crate) fn new(len: usize) -> SumTree {
        let size = len.max(1).next_power_of_two();
        SumTree {
            size,
            node: vec![0.0; 4 * size],
        }
    }

    /// The sum of all weights.
    #[inline]
    pub(crate) fn total(&self) -> f64 {
        self.node[1]
    }

    /// Weight `i`.
    #[inline]
    pub(crate) fn get(&self, i: usize) -> f64 {
        self.node[self.size + i]
    }

    /// Sets weight `i` to `w` (≥ 0) and recomputes its ancestors.
    #[inline]
    pub(crate) fn set(&mut self, i: usize, w: f64) {
        // The new sum rides up in a register; the siblings' addresses are known in advance,
        // so the loads overlap and only the additions are chained. `+` is commutative in
        // IEEE arithmetic, so `v + sibling` is bit-identical to `left + right`.
        let mut k = self.size + i;
        let mut v = w;
        self.node[k] = v;
        while k > 1 {
            v += self.node[k ^ 1];
            k >>= 1;
            self.node[k] = v;
        }
    }

    /// The index `i` such that the weights before it sum to at most `u` and with it to more
    /// than `u`, for `0 ≤ u < total()`. Never returns a zero-weight index while the total is
    /// positive, even when rounding pushes `u` past a subtree's sum.
    #[inline]
    pub(crate) fn find(&self, mut u: f64) -> usize {
        // A random descent is a chain of dependent loads and compares. Branch-free, and with
        // the four grandchildren loaded before the children are compared, each level waits
        // for a compare and a select rather than for a load as well.
        let node = &self.node;
        let mut k = 1;
        let (mut left, mut right) = (node[2], node[3]);
        while k < self.size {
            let g: &[f64; 4] = node[4 * k..4 * k + 4].try_into().unwrap_or(&[0.0; 4]);
            // Going right into an empty subtree can only come from rounding: stay left.
            let go_right = (u >= left) & (right > 0.0);
            u -= if go_right { left } else { 0.0 };
            k = 2 * k + go_right as usize;
            (left, right) = if go_right { (g[2], g[3]) } else { (g[0], g[1]) };
        }
        k - self.size
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_and_finds_by_cumulative_weight() {
        let mut t = SumTree::new(5);
        for (i, w) in [1.0, 0.0, 2.0, 0.5, 0.0].into_iter().enumerate() {
            t.set(i, w);
        }
        assert_eq!(t.total(), 3.5);
        assert_eq!(t.find(0.0), 0);
        assert_eq!(t.find(0.999), 0);
        assert_eq!(t.find(1.0), 2);
        assert_eq!(t.find(2.999), 2);
        assert_eq!(t.find(3.0), 3);
        // Past the end by rounding: the last positive weight, never an empty one.
        assert_eq!(t.find(3.5), 3);
        t.set(2, 0.0);
        assert_eq!(t.total(), 1.5);
        assert_eq!(t.find(1.2), 3);
        assert_eq!(t.get(3), 0.5);
    }

    #[test]
    fn no_drift_after_many_updates() {
        let mut t = SumTree::new(3);
        for k in 0..10_000 {
            t.set(k % 3, 0.1 * (k % 7) as f64);
        }
        let exact = (0..3).map(|i| t.get(i)).fold(0.0, |a, b| a + b);
        assert!((t.total() - exact).abs() < 1e-15);
        for i in 0..3 {
            t.set(i, 0.0);
        }
        assert_eq!(t.total(), 0.0);
    }
}
