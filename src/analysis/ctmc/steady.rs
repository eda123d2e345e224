//! Steady state of an irreducible chain: sparse LU for small chains, Gauss–Seidel (with
//! fallbacks) for large ones, always ending with a residual check `‖πQ‖∞ ≤ tolerance`.

use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

use super::{Columns, Ctmc, lu};

/// How [`Ctmc::steady_state`] solves πQ = 0.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum Method {
    /// Sparse LU up to [`SteadyOptions::direct_limit`] states, Gauss–Seidel above, with
    /// fallbacks (the other one, under-relaxed SOR, power iteration) until the residual check
    /// passes.
    #[default]
    Auto,
    /// Sparse LU (faer): one equation dropped, one unknown fixed, then normalised.
    Direct,
    /// Gauss–Seidel sweeps (SOR with factor 1).
    GaussSeidel,
    /// Power iteration on the uniformized chain `I + Q/Λ` (slow, but always converges on an
    /// irreducible chain).
    Power,
}

/// Options of the steady-state solvers.
#[derive(Clone, Debug)]
pub struct SteadyOptions {
    /// Which solver.
    pub method: Method,
    /// Required `‖πQ‖∞`, relative to the largest exit rate (when that is above 1).
    pub tolerance: f64,
    /// Most sweeps of an iterative solver.
    pub max_iterations: usize,
    /// Largest chain solved by sparse LU under [`Method::Auto`]. Small: the LU's fill
    /// grows with the chain's dimensions, not its size — Kanban N=2 (4,600 states) took
    /// 1.0 s and 105 MB by LU where Gauss–Seidel takes milliseconds (docs/benchmarks.md,
    /// "Kanban N=2"); a chain where Gauss–Seidel fails still falls back to LU.
    pub direct_limit: usize,
    /// Set to `true` (from another thread) to stop an iterative solver at its next sweep
    /// with [`SolveError::Cancelled`]; the viewer's cancel button uses it.
    pub cancel: Option<Arc<AtomicBool>>,
}

impl Default for SteadyOptions {
    fn default() -> Self {
        SteadyOptions {
            method: Method::Auto,
            tolerance: 1e-12,
            max_iterations: 50_000,
            direct_limit: 1_000,
            cancel: None,
        }
    }
}

/// Why a solver gave no answer.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum SolveError {
    /// The iterative solvers did not reach the tolerance.
    #[error(
        "the steady-state solver did not converge: residual {residual:e} after {iterations} sweeps"
    )]
    NotConverged {
        /// Sweeps done by the last solver tried.
        iterations: usize,
        /// Its final `‖πQ‖∞`.
        residual: f64,
    },
    /// [`SteadyOptions::cancel`] was raised, or the transient solver's
    /// [`Monitor`](crate::analysis::state_space::Monitor) was cancelled
    /// ([`TransientOptions::monitor`](super::TransientOptions::monitor)).
    #[error("the solver was cancelled after {iterations} iterations")]
    Cancelled {
        /// Sweeps (steady state) or products with the generator (transient) done.
        iterations: usize,
    },
    /// The sparse LU failed (a singular or non-finite system).
    #[error("sparse LU failed: {0}")]
    Factorization(String),
}

impl Ctmc {
    /// The incoming entries of every state, for Gauss–Seidel.
    pub(crate) fn columns(&self) -> Columns {
        Columns::from_rows(self.n, |i, out| out.extend(self.row(i)))
    }

    /// The stationary distribution of an **irreducible** chain (use [`Ctmc::limiting`] for
    /// any chain). Checked: the answer has `‖πQ‖∞ ≤ tolerance·max(1, max exit rate)`.
    pub fn steady_state(&self, opts: &SteadyOptions) -> Result<Vec<f64>, SolveError> {
        if self.n == 0 {
            return Ok(Vec::new());
        }
        if self.n == 1 {
            return Ok(vec![1.0]);
        }
        let scale = (0..self.n)
            .map(|i| self.exit_rate(i))
            .fold(1.0f64, f64::max);
        let tol = opts.tolerance * scale;
        let mut last = SolveError::NotConverged {
            iterations: 0,
            residual: f64::INFINITY,
        };
        let plan: &[Method] = match opts.method {
            Method::Auto if self.n <= opts.direct_limit => {
                &[Method::Direct, Method::GaussSeidel, Method::Power]
            }
            Method::Auto => &[Method::GaussSeidel, Method::Direct, Method::Power],
            Method::Direct => &[Method::Direct],
            Method::GaussSeidel => &[Method::GaussSeidel],
            Method::Power => &[Method::Power],
        };
        for (k, &m) in plan.iter().enumerate() {
            // Under Auto, LU is the fallback for large chains only while it stays affordable.
            if opts.method == Method::Auto && k > 0 && m == Method::Direct && self.n > 200_000 {
                continue;
            }
            let attempt = match m {
                Method::Direct => self.direct(tol, opts),
                Method::GaussSeidel => self.columns().gauss_seidel(
                    tol,
                    opts.max_iterations,
                    opts.method == Method::Auto,
                    opts.cancel.as_deref(),
                ),
                Method::Power | Method::Auto => {
                    self.power(tol, opts.max_iterations * 20, opts.cancel.as_deref())
                }
            };
            match attempt {
                Ok(pi) => return Ok(pi),
                Err(e @ SolveError::Cancelled { .. }) => return Err(e),
                Err(e) => last = e,
            }
        }
        Err(last)
    }

    /// Sparse LU on Qᵀ with the last equation dropped and the last unknown fixed to 1, then
    /// normalised and polished by a few Gauss–Seidel sweeps if needed.
    fn direct(&self, tol: f64, opts: &SteadyOptions) -> Result<Vec<f64>, SolveError> {
        let n = self.n;
        let last = n - 1;
        let mut triplets = Vec::with_capacity(self.nnz() + n);
        let mut rhs = vec![0.0; last];
        for i in 0..n {
            let mut out = 0.0;
            for (j, q) in self.row(i) {
                out += q;
                let j = j as usize;
                if j == last {
                    continue;
                }
                if i == last {
                    rhs[j] -= q;
                } else {
                    triplets.push((j, i, q));
                }
            }
            if i != last {
                triplets.push((i, i, -out));
            }
        }
        let x = lu::solve(last, &triplets, &rhs)?;
        let mut pi: Vec<f64> = x.into_iter().chain(std::iter::once(1.0)).collect();
        for v in pi.iter_mut() {
            if *v < 0.0 {
                *v = 0.0;
            }
        }
        let sum: f64 = pi.iter().sum();
        if !(sum.is_finite() && sum > 0.0) {
            return Err(SolveError::Factorization("non-finite solution".into()));
        }
        pi.iter_mut().for_each(|v| *v /= sum);
        if self.residual(&pi) <= tol {
            return Ok(pi);
        }
        self.columns().sor(
            &mut pi,
            1.0,
            tol,
            opts.max_iterations.min(1_000),
            opts.cancel.as_deref(),
        )?;
        Ok(pi)
    }

    /// Power iteration on `P = I + Q/Λ`, `Λ = 1.05·max exit rate` (aperiodic by the self-loops).
    fn power(
        &self,
        tol: f64,
        max_iterations: usize,
        cancel: Option<&AtomicBool>,
    ) -> Result<Vec<f64>, SolveError> {
        let n = self.n;
        let exit = self.exit_rates();
        let lambda = 1.05 * exit.iter().fold(0.0f64, |m, &x| m.max(x));
        let mut pi = vec![1.0 / n as f64; n];
        let mut next = vec![0.0; n];
        let mut residual = f64::INFINITY;
        for it in 1..=max_iterations {
            if it % 50 == 0 && cancel.is_some_and(|c| c.load(Ordering::Relaxed)) {
                return Err(SolveError::Cancelled { iterations: it });
            }
            for ((x, &p), &q) in next.iter_mut().zip(&pi).zip(&exit) {
                *x = p * (1.0 - q / lambda);
            }
            for (i, &x) in pi.iter().enumerate() {
                let p = x / lambda;
                for (j, q) in self.row(i) {
                    next[j as usize] += p * q;
                }
            }
            std::mem::swap(&mut pi, &mut next);
            if it % 50 == 0 {
                let sum: f64 = pi.iter().sum();
                pi.iter_mut().for_each(|v| *v /= sum);
                residual = self.residual(&pi);
                if residual <= tol {
                    return Ok(pi);
                }
            }
        }
        Err(SolveError::NotConverged {
            iterations: max_iterations,
            residual,
        })
    }
}
