//! The chain a path formula runs on: the tangible states, and two absorbing states — the
//! goal reached, the path failed (φ1 broken before φ2) — entered the moment a marking on the
//! full graph, vanishing ones included, says so.
//!
//! Vanishing markings where the path goes on are resolved as in the state space: each
//! leads, with probabilities, to tangible states or to the two sinks. Loops of them are
//! solved per strongly connected component by a sparse LU (faer) with one right-hand side
//! per way out.

use rustc_hash::FxHashMap;

use super::QueryError;
use crate::analysis::ctmc::{Ctmc, SolveError, lu};
use crate::analysis::scc::tarjan;
use crate::analysis::state_space::StateSpace;

/// Where a marking leaves a path formula.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Class {
    /// Neither reached nor failed: the path goes on.
    Go,
    /// The goal holds.
    Goal,
    /// The path failed.
    Fail,
}

/// Most entries (members × ways out) of the dense right-hand side of one vanishing loop.
const MAX_RHS: usize = 50_000_000;

/// The tangible chain with the goal and fail sinks.
#[derive(Debug)]
pub(super) struct Absorbing {
    /// States `0..n` tangible, [`Absorbing::goal`] and [`Absorbing::fail`] absorbing.
    pub(super) chain: Ctmc,
    /// The initial distribution over those states (a tangible goal or fail state is never
    /// entered: its entries go to the sink).
    pub(super) initial: Vec<(u32, f64)>,
}

impl Absorbing {
    /// The goal sink (the fail sink is the last state).
    pub(super) fn goal(&self) -> u32 {
        self.chain.n as u32 - 2
    }

    /// Builds it for `space`, `classify` telling each marking's class.
    pub(super) fn build(
        space: &StateSpace,
        places: usize,
        classify: impl Fn(&[u32]) -> Class,
    ) -> Result<Absorbing, QueryError> {
        let n = space.tangible_count();
        let total = space.reachable_count();
        let (goal, fail) = (n as u32, n as u32 + 1);
        let mut m = vec![0u32; places];
        let class: Vec<Class> = (0..total)
            .map(|g| {
                space.marking_into(g, &mut m);
                classify(&m)
            })
            .collect();
        // Where an arc into global marking g lands, for markings that are not vanishing Go.
        let direct = |g: usize| -> Option<u32> {
            match class[g] {
                Class::Goal => Some(goal),
                Class::Fail => Some(fail),
                Class::Go if g < n => Some(g as u32),
                Class::Go => None,
            }
        };
        let dist = resolve_vanishing(space, n, &class, &direct)?;
        let land = |g: usize, p: f64, out: &mut Vec<(u32, f64)>| match direct(g) {
            Some(s) => out.push((s, p)),
            None => out.extend(dist[g - n].iter().map(|&(s, q)| (s, p * q))),
        };
        let mut triplets = Vec::new();
        let mut row = Vec::new();
        let go = class[..n]
            .iter()
            .enumerate()
            .filter(|&(_, &c)| c == Class::Go);
        for (s, _) in go {
            for mv in space.arcs(s) {
                row.clear();
                land(mv.to as usize, mv.rate, &mut row);
                triplets.extend(row.iter().map(|&(to, r)| (s as u32, to, r)));
            }
        }
        let mut initial = Vec::new();
        land(space.initial_global(), 1.0, &mut initial);
        Ok(Absorbing {
            chain: Ctmc::from_triplets(n + 2, triplets),
            initial,
        })
    }
}

/// For each vanishing marking (global id `n + v`) where the path goes on: where it lands,
/// `(state, probability)` over tangible Go states and the sinks. Empty for the others.
fn resolve_vanishing(
    space: &StateSpace,
    n: usize,
    class: &[Class],
    direct: &dyn Fn(usize) -> Option<u32>,
) -> Result<Vec<Vec<(u32, f64)>>, QueryError> {
    let vanishing = class.len() - n;
    let inner = |g: u32| g as usize >= n && class[g as usize] == Class::Go;
    let sccs = tarjan(vanishing, |v, out| {
        let g = n + v as usize;
        if class[g] == Class::Go {
            out.extend(
                space
                    .arcs(g)
                    .iter()
                    .filter(|mv| mv.prob > 0.0 && inner(mv.to))
                    .map(|mv| mv.to - n as u32),
            );
        }
    });
    let mut dist: Vec<Vec<(u32, f64)>> = vec![Vec::new(); vanishing];
    let mut acc: FxHashMap<u32, f64> = FxHashMap::default();
    for members in sccs.members().iter() {
        let first = n + members[0] as usize;
        if class[first] != Class::Go {
            continue;
        }
        let looped = members.len() > 1
            || space
                .arcs(first)
                .iter()
                .any(|mv| mv.prob > 0.0 && mv.to as usize == first);
        if !looped {
            acc.clear();
            for mv in space.arcs(first) {
                if mv.prob <= 0.0 {
                    continue;
                }
                match direct(mv.to as usize) {
                    Some(s) => *acc.entry(s).or_insert(0.0) += mv.prob,
                    None => {
                        for &(s, q) in &dist[mv.to as usize - n] {
                            *acc.entry(s).or_insert(0.0) += mv.prob * q;
                        }
                    }
                }
            }
            dist[first - n] = sorted(&acc);
            continue;
        }
        solve_loop(space, n, members, &sccs.component, direct, &mut dist)?;
    }
    Ok(dist)
}

fn sorted(acc: &FxHashMap<u32, f64>) -> Vec<(u32, f64)> {
    let mut v: Vec<(u32, f64)> = acc
        .iter()
        .filter(|&(_, &p)| p > 1e-300)
        .map(|(&s, &p)| (s, p))
        .collect();
    v.sort_unstable_by_key(|e| e.0);
    v
}

/// A loop of vanishing markings: `(I − P_CC) X = B`, B the probabilities of leaving to each
/// way out, one sparse LU and one column per way out.
fn solve_loop(
    space: &StateSpace,
    n: usize,
    members: &[u32],
    component: &[u32],
    direct: &dyn Fn(usize) -> Option<u32>,
    dist: &mut [Vec<(u32, f64)>],
) -> Result<(), QueryError> {
    let k = members.len();
    let c = component[members[0] as usize];
    let mut local = FxHashMap::default();
    for (i, &v) in members.iter().enumerate() {
        local.insert(v, i);
    }
    let mut exits: FxHashMap<u32, usize> = FxHashMap::default();
    let mut a: Vec<(usize, usize, f64)> = Vec::new();
    let mut b: Vec<(usize, usize, f64)> = Vec::new();
    for (i, &v) in members.iter().enumerate() {
        a.push((i, i, 1.0));
        for mv in space.arcs(n + v as usize) {
            if mv.prob <= 0.0 {
                continue;
            }
            let mut out = |s: u32, p: f64| {
                let next = exits.len();
                let col = *exits.entry(s).or_insert(next);
                b.push((i, col, p));
            };
            match direct(mv.to as usize) {
                Some(s) => out(s, mv.prob),
                None => {
                    let w = mv.to - n as u32;
                    if component[w as usize] == c {
                        a.push((i, local[&w], -mv.prob));
                    } else {
                        for &(s, q) in &dist[w as usize] {
                            out(s, mv.prob * q);
                        }
                    }
                }
            }
        }
    }
    let e = exits.len();
    if k.saturating_mul(e) > MAX_RHS {
        return Err(QueryError::Unsupported(format!(
            "a loop of {k} vanishing markings with {e} ways out is too large to resolve \
             for this query ({} entries, at most {MAX_RHS})",
            k * e
        )));
    }
    // X (k × e, row-major): the probability of leaving the loop from each member by
    // each way out. A singular loop (non-finite X) is refused by the LU itself.
    let mut x = vec![0.0f64; k * e];
    for (i, col, p) in b {
        x[i * e + col] += p;
    }
    lu::solve_columns(k, &a, &mut x, e)
        .map_err(|err| SolveError::Factorization(format!("a loop of vanishing markings: {err}")))?;
    let mut by_col: Vec<u32> = vec![0; e];
    for (&s, &col) in &exits {
        by_col[col] = s;
    }
    for (i, &v) in members.iter().enumerate() {
        let mut row: Vec<(u32, f64)> = (0..e)
            .map(|col| (by_col[col], x[i * e + col]))
            .filter(|&(_, p)| p > 1e-300)
            .collect();
        row.sort_unstable_by_key(|e| e.0);
        dist[v as usize] = row;
    }
    Ok(())
}
