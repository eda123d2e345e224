//! A square sparse solve `A x = b` through faer's sparse LU (partial pivoting).

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};

/// Solves `A x = b` where `A` is given as `(row, col, value)` triplets (duplicates summed).
pub(crate) fn solve(
    n: usize,
    triplets: &[(usize, usize, f64)],
    b: &[f64],
) -> Result<Vec<f64>, String> {
    let entries: Vec<Triplet<usize, usize, f64>> = triplets
        .iter()
        .map(|&(r, c, v)| Triplet::new(r, c, v))
        .collect();
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &entries)
        .map_err(|e| format!("{e:?}"))?;
    let lu = a.sp_lu().map_err(|e| format!("{e:?}"))?;
    let rhs = faer::col::Col::from_fn(n, |i| b[i]);
    let x = lu.solve(&rhs);
    let x: Vec<f64> = (0..n).map(|i| x[i]).collect();
    if x.iter().all(|v| v.is_finite()) {
        Ok(x)
    } else {
        Err("singular matrix".to_string())
    }
}
