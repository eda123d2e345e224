//! A square sparse solve `A X = B` through faer's sparse LU (partial pivoting, with a
//! fill-reducing ordering): the one wrapper around it, for the chain's steady state and
//! limiting distribution, the queries, and the large systems of [`crate::analysis::linear`].

use faer::Mat;
use faer::linalg::solvers::Solve;
use faer::sparse::{CreationError, SparseColMat, Triplet};

/// Why a sparse solve failed, with faer's own error where it had one.
#[derive(Clone, Copy, Debug, thiserror::Error)]
pub(crate) enum LuError {
    /// The triplets do not make a `k × k` matrix (an index out of range, no memory).
    #[error("{0:?}")]
    Matrix(#[source] CreationError),
    /// The factorisation failed (structurally singular, no memory).
    #[error("{0:?}")]
    Factor(#[source] faer::sparse::linalg::LuError),
    /// The solution has non-finite numbers: the matrix is numerically singular.
    #[error("singular matrix")]
    Singular,
}

impl From<LuError> for super::SolveError {
    fn from(e: LuError) -> Self {
        super::SolveError::Factorization(e.to_string())
    }
}

/// Solves `A X = B` in place of `b` (row-major, `w` columns) for the `k × k` matrix given by
/// `(row, column, value)` triplets (repeated entries add up). Non-finite numbers in the
/// answer are [`LuError::Singular`].
pub(crate) fn solve_columns(
    k: usize,
    triplets: &[(usize, usize, f64)],
    b: &mut [f64],
    w: usize,
) -> Result<(), LuError> {
    let entries: Vec<Triplet<usize, usize, f64>> = triplets
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(k, k, &entries)
        .map_err(LuError::Matrix)?;
    let lu = a.sp_lu().map_err(LuError::Factor)?;
    let x = lu.solve(Mat::from_fn(k, w, |r, c| b[r * w + c]));
    for r in 0..k {
        for c in 0..w {
            b[r * w + c] = x[(r, c)];
        }
    }
    if b.iter().all(|v| v.is_finite()) {
        Ok(())
    } else {
        Err(LuError::Singular)
    }
}

/// Solves `A x = b` for one right-hand side (see [`solve_columns`]).
pub(crate) fn solve(
    n: usize,
    triplets: &[(usize, usize, f64)],
    b: &[f64],
) -> Result<Vec<f64>, LuError> {
    let mut x = b.to_vec();
    solve_columns(n, triplets, &mut x, 1)?;
    Ok(x)
}
