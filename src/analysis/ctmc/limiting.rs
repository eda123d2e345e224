//! The limiting distribution of any chain from an initial distribution: strongly connected
//! components ([`tarjan`](crate::analysis::scc::tarjan)), the probability of being
//! absorbed into each bottom component, and each bottom component's own steady state.

use super::{Ctmc, SolveError, SteadyOptions, lu};
use crate::analysis::scc::tarjan;

/// The limiting distribution `lim π(t)` from an initial distribution.
#[derive(Clone, Debug, PartialEq)]
pub struct Limiting {
    /// Probability of each state in the long run (0 on transient states).
    pub pi: Vec<f64>,
    /// The chain is irreducible (one strongly connected component): π does not depend on the
    /// initial distribution.
    pub ergodic: bool,
    /// The bottom strongly connected components, each as its states.
    pub bottom: Vec<Vec<u32>>,
    /// Probability of ending in each bottom component (same order as `bottom`).
    pub absorption: Vec<f64>,
}

impl Ctmc {
    /// The limiting distribution from `initial` (`(state, probability)` pairs): for an
    /// irreducible chain its steady state; otherwise the absorption probability into each
    /// bottom strongly connected component times that component's steady state.
    pub fn limiting(
        &self,
        initial: &[(u32, f64)],
        opts: &SteadyOptions,
    ) -> Result<Limiting, SolveError> {
        let n = self.n;
        let sccs = tarjan(n, |v, out| {
            let r = self.row_ptr[v as usize]..self.row_ptr[v as usize + 1];
            out.extend_from_slice(&self.cols[r]);
        });
        let (comp, count) = (sccs.component, sccs.count);
        if count <= 1 {
            let pi = self.steady_state(opts)?;
            return Ok(Limiting {
                pi,
                ergodic: true,
                bottom: vec![(0..n as u32).collect()],
                absorption: vec![1.0],
            });
        }
        let mut members: Vec<Vec<u32>> = vec![Vec::new(); count];
        for s in 0..n {
            members[comp[s] as usize].push(s as u32);
        }
        let mut is_bottom = vec![true; count];
        for i in 0..n {
            for (j, _) in self.row(i) {
                if comp[j as usize] != comp[i] {
                    is_bottom[comp[i] as usize] = false;
                }
            }
        }
        // Mass entering each state: the initial distribution, then the flow x_i·Q_ij out of
        // transient states, pushed in topological order (highest component number first).
        let mut inflow = vec![0.0; n];
        for &(s, p) in initial {
            inflow[s as usize] += p;
        }
        for c in (0..count).rev() {
            if is_bottom[c] {
                continue;
            }
            let states = &members[c];
            if states.iter().all(|&s| inflow[s as usize] == 0.0) {
                continue;
            }
            let x = self.sojourn(states, &inflow)?;
            for (&i, &xi) in states.iter().zip(&x) {
                for (j, q) in self.row(i as usize) {
                    if comp[j as usize] as usize != c {
                        inflow[j as usize] += xi * q;
                    }
                }
            }
        }
        let mut pi = vec![0.0; n];
        let mut bottom = Vec::new();
        let mut absorption = Vec::new();
        for c in 0..count {
            if !is_bottom[c] {
                continue;
            }
            let states = &members[c];
            let mass: f64 = states.iter().map(|&s| inflow[s as usize]).sum();
            if mass > 0.0 {
                let local = self.restrict(states).steady_state(opts)?;
                for (&s, p) in states.iter().zip(local) {
                    pi[s as usize] = mass * p;
                }
            }
            bottom.push(states.clone());
            absorption.push(mass);
        }
        Ok(Limiting {
            pi,
            ergodic: false,
            bottom,
            absorption,
        })
    }

    /// Expected time spent in each state of a transient component: solves
    /// `x_j·q_j − Σ_{i in C} x_i·Q_ij = inflow_j` for `j` in `states`.
    fn sojourn(&self, states: &[u32], inflow: &[f64]) -> Result<Vec<f64>, SolveError> {
        let exit: Vec<f64> = states.iter().map(|&s| self.exit_rate(s as usize)).collect();
        let rhs: Vec<f64> = states.iter().map(|&s| inflow[s as usize]).collect();
        if states.len() == 1 {
            return Ok(vec![rhs[0] / exit[0]]);
        }
        let sub = self.restrict(states);
        if states.len() <= 20_000 {
            let mut triplets = Vec::with_capacity(sub.nnz() + sub.n);
            for (i, &q) in exit.iter().enumerate() {
                triplets.push((i, i, q));
                for (j, q) in sub.row(i) {
                    triplets.push((j as usize, i, -q));
                }
            }
            if let Ok(x) = lu::solve(sub.n, &triplets, &rhs) {
                return Ok(x);
            }
        }
        // Gauss–Seidel on a nonsingular M-matrix: converges.
        let (ptr, rows, rates) = sub.incoming();
        let mut x = vec![0.0; sub.n];
        for sweep in 1..=200_000 {
            let mut change = 0.0f64;
            let mut size = 0.0f64;
            for j in 0..sub.n {
                let mut s = rhs[j];
                for k in ptr[j]..ptr[j + 1] {
                    s += x[rows[k] as usize] * rates[k];
                }
                let v = s / exit[j];
                change = change.max((v - x[j]).abs());
                size = size.max(v.abs());
                x[j] = v;
            }
            if change <= 1e-15 * size {
                return Ok(x);
            }
            if sweep == 200_000 {
                return Err(SolveError::NotConverged {
                    iterations: sweep,
                    residual: change,
                });
            }
        }
        Ok(x)
    }
}
