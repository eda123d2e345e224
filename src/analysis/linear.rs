//! Square linear systems `A X = B` with a few right-hand sides, as the exact solvers meet
//! them: a component of a chain (a vanishing loop, a policy's strongly connected component)
//! whose matrix is sparse.
//!
//! Small systems go to a dense LU (no set-up cost), larger ones to faer's sparse LU, whose
//! fill-reducing ordering keeps a loop of thousands of markings to milliseconds where the
//! dense O(k³) elimination took minutes (docs/benchmarks.md, "Vanishing loops"). The one limit
//! is memory: the right-hand sides and the solution are dense `k × w` blocks.

/// Systems up to this many unknowns are solved by dense LU; larger ones by sparse LU.
pub(crate) const DENSE: usize = 48;

/// The most numbers a solve may hold in dense blocks (the `k × w` right-hand sides, and the
/// `k × k` matrix below [`DENSE`]): 64 M of them is 512 MB.
pub(crate) const MAX_DENSE_NUMBERS: usize = 64 << 20;

/// Why a system was not solved.
#[derive(Debug)]
pub(crate) enum SolveError {
    /// Its dense blocks would pass [`MAX_DENSE_NUMBERS`].
    TooLarge,
    /// The factorisation failed or gave non-finite numbers (a singular matrix).
    Failed(String),
}

impl std::fmt::Display for SolveError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            SolveError::TooLarge => write!(f, "too large to hold in memory"),
            SolveError::Failed(e) => write!(f, "{e}"),
        }
    }
}

/// Solves `A·X = B` in place of `b` (row-major, `w` columns) for the `k × k` matrix given by
/// `(row, column, value)` entries (repeated entries add up).
pub(crate) fn solve_block(
    k: usize,
    entries: &[(usize, usize, f64)],
    b: &mut [f64],
    w: usize,
) -> Result<(), SolveError> {
    if k == 0 {
        return Ok(());
    }
    let dense = if k <= DENSE { k * k } else { 0 };
    if k.saturating_mul(w).saturating_add(dense) > MAX_DENSE_NUMBERS {
        return Err(SolveError::TooLarge);
    }
    if k <= DENSE {
        let mut a = vec![0.0f64; k * k];
        for &(i, j, x) in entries {
            a[i * k + j] += x;
        }
        lu_solve(&mut a, k, b, w);
    } else {
        crate::analysis::ctmc::lu::solve_columns(k, entries, b, w)
            .map_err(|e| SolveError::Failed(e.to_string()))?;
    }
    if b.iter().all(|x| x.is_finite()) {
        Ok(())
    } else {
        Err(SolveError::Failed("singular matrix".into()))
    }
}

/// Solves `A X = B` in place (`A` is `k×k`, `B` is `k×nc`, row-major), Gaussian elimination
/// with partial pivoting.
fn lu_solve(a: &mut [f64], k: usize, b: &mut [f64], nc: usize) {
    for col in 0..k {
        let piv = (col..k)
            .max_by(|&x, &y| a[x * k + col].abs().total_cmp(&a[y * k + col].abs()))
            .unwrap_or(col);
        if piv != col {
            for j in 0..k {
                a.swap(col * k + j, piv * k + j);
            }
            for j in 0..nc {
                b.swap(col * nc + j, piv * nc + j);
            }
        }
        let d = a[col * k + col];
        for r in col + 1..k {
            let f = a[r * k + col] / d;
            if f == 0.0 {
                continue;
            }
            for j in col..k {
                a[r * k + j] -= f * a[col * k + j];
            }
            for j in 0..nc {
                b[r * nc + j] -= f * b[col * nc + j];
            }
        }
    }
    for col in (0..k).rev() {
        let d = a[col * k + col];
        for j in 0..nc {
            b[col * nc + j] /= d;
        }
        for r in 0..col {
            let f = a[r * k + col];
            if f == 0.0 {
                continue;
            }
            for j in 0..nc {
                b[r * nc + j] -= f * b[col * nc + j];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same absorbing chain (a ring of `k` states, each leaving with 1/10) solved dense
    /// and sparse: x = 1 in every state, to 1e-12 both ways.
    #[test]
    fn dense_and_sparse_paths_agree_on_a_ring() {
        for k in [DENSE, DENSE + 1, 500] {
            let mut entries = Vec::new();
            for i in 0..k {
                entries.push((i, i, 1.0));
                entries.push((i, (i + 1) % k, -0.9));
            }
            let mut b = vec![0.1; k];
            solve_block(k, &entries, &mut b, 1).unwrap();
            assert!(b.iter().all(|x| (x - 1.0).abs() < 1e-12), "k = {k}: {b:?}");
        }
    }

    #[test]
    fn a_singular_system_is_an_error_and_a_huge_one_is_refused() {
        let mut b: Vec<f64> = std::iter::repeat_n(1.0, 60).collect();
        let entries: Vec<_> = (0..60).map(|i| (i, 0, 1.0)).collect();
        assert!(matches!(
            solve_block(60, &entries, &mut b, 1),
            Err(SolveError::Failed(_))
        ));
        let mut b: Vec<f64> = Vec::new();
        assert!(matches!(
            solve_block(1 << 20, &[], &mut b, 1 << 10),
            Err(SolveError::TooLarge)
        ));
    }
}
