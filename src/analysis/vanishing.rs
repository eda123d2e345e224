//! Elimination of vanishing markings: where each vanishing marking leads, as a probability
//! distribution over tangible states, and how often each immediate transition fires on the way.
//!
//! Vanishing markings are grouped into strongly connected components over their positive
//! probability arcs and solved sinks first (Tarjan's order). A component without a cycle is
//! a weighted sum of its successors' answers; a component with a cycle (a *vanishing loop*)
//! is an absorbing embedded chain, solved exactly by LU factorisation of `I − P` restricted to
//! the component. Every path is kept, so a loop tangible → vanishing → the same tangible state
//! keeps its probability. A component that no positive arc leaves is a timeless trap.

use rustc_hash::FxHashMap;

use crate::analysis::scc::tarjan;
use crate::analysis::state_space::explore::Raw;
use crate::analysis::state_space::table::MoveTable;
use crate::analysis::state_space::{AnalysisError, ImmediateFlow, Move};
use crate::net::{Net, TransitionId};

/// The tangible chain after elimination.
#[derive(Debug, Default)]
pub(crate) struct Eliminated {
    /// Moves of tangible states `0..T`, targets renumbered.
    pub(crate) moves: MoveTable,
    /// Expected immediate firings after each (state, exponential transition).
    pub(crate) flows: Vec<ImmediateFlow>,
    /// Initial distribution over tangible states.
    pub(crate) initial: Vec<(u32, f64)>,
}

/// A sparse vector accumulated in a dense scratch array.
struct Acc {
    dense: Vec<f64>,
    seen: Vec<bool>,
    touched: Vec<u32>,
}

impl Acc {
    fn new(n: usize) -> Acc {
        Acc {
            dense: vec![0.0; n],
            seen: vec![false; n],
            touched: Vec::new(),
        }
    }

    #[inline]
    fn add(&mut self, i: u32, x: f64) {
        if !self.seen[i as usize] {
            self.seen[i as usize] = true;
            self.touched.push(i);
        }
        self.dense[i as usize] += x;
    }

    /// The accumulated entries sorted by index; the scratch is cleared.
    fn take(&mut self) -> Vec<(u32, f64)> {
        self.touched.sort_unstable();
        let out = self
            .touched
            .iter()
            .map(|&i| {
                self.seen[i as usize] = false;
                (i, std::mem::take(&mut self.dense[i as usize]))
            })
            .filter(|&(_, x)| x > 1e-300)
            .collect();
        self.touched.clear();
        out
    }
}

/// Eliminates the vanishing markings of `raw`. `order[new] = raw id` lists tangible markings
/// first (`0..tangible`), `new_id` is its inverse.
pub(crate) fn eliminate(
    net: &Net,
    raw: &Raw,
    order: &[u32],
    new_id: &[u32],
    tangible: usize,
) -> Result<Eliminated, AnalysisError> {
    let vanishing = order.len() - tangible;
    let t_base = tangible as u32;
    let is_tangible = |raw_id: u32| raw.tangible[raw_id as usize];
    let local = |raw_id: u32| new_id[raw_id as usize] - t_base;
    let sccs = tarjan(vanishing, |v, out| {
        for m in raw.moves.group(order[tangible + v as usize] as usize) {
            if m.prob > 0.0 && !is_tangible(m.to) {
                out.push(local(m.to));
            }
        }
    });
    let mut dist: Vec<Vec<(u32, f64)>> = vec![Vec::new(); vanishing];
    let mut flow: Vec<Vec<(u32, f64)>> = vec![Vec::new(); vanishing];
    let mut acc_d = Acc::new(tangible);
    let mut acc_f = Acc::new(net.transition_count());
    for members in sccs.members().iter() {
        let single = members.len() == 1 && {
            let v = members[0];
            !raw.moves
                .group(order[tangible + v as usize] as usize)
                .iter()
                .any(|m| m.prob > 0.0 && !is_tangible(m.to) && local(m.to) == v)
        };
        if single {
            let v = members[0] as usize;
            for m in raw.moves.group(order[tangible + v] as usize) {
                if m.prob <= 0.0 {
                    continue;
                }
                acc_f.add(m.transition.0, m.prob);
                if is_tangible(m.to) {
                    acc_d.add(new_id[m.to as usize], m.prob);
                } else {
                    let w = local(m.to) as usize;
                    for &(s, q) in &dist[w] {
                        acc_d.add(s, m.prob * q);
                    }
                    for &(i, x) in &flow[w] {
                        acc_f.add(i, m.prob * x);
                    }
                }
            }
            dist[v] = acc_d.take();
            flow[v] = acc_f.take();
        } else {
            solve_loop(
                net,
                raw,
                order,
                new_id,
                tangible,
                members,
                &sccs.component,
                &mut dist,
                &mut flow,
            )?;
        }
    }
    let mut out = Eliminated::default();
    let mut group: Vec<Move> = Vec::new();
    for (s, &r) in order[..tangible].iter().enumerate() {
        group.clear();
        for m in raw.moves.group(r as usize) {
            if is_tangible(m.to) {
                group.push(Move {
                    to: new_id[m.to as usize],
                    ..*m
                });
                continue;
            }
            let w = local(m.to) as usize;
            for &(to, prob) in &dist[w] {
                group.push(Move {
                    transition: m.transition,
                    rate: m.rate,
                    to,
                    prob,
                });
            }
            for &(i, expected) in &flow[w] {
                out.flows.push(ImmediateFlow {
                    state: s as u32,
                    transition: m.transition,
                    immediate: TransitionId(i),
                    expected,
                });
            }
        }
        out.moves.push_group(&group);
    }
    out.moves.shrink();
    out.initial = if is_tangible(0) {
        vec![(new_id[0], 1.0)]
    } else {
        std::mem::take(&mut dist[local(0) as usize])
    };
    Ok(out)
}

/// Solves one vanishing component with a cycle: `x = P_in x + b`, i.e. `(I − P_in) X = B`,
/// for the tangible distribution and the immediate firing counts at once.
#[allow(clippy::too_many_arguments)]
fn solve_loop(
    net: &Net,
    raw: &Raw,
    order: &[u32],
    new_id: &[u32],
    tangible: usize,
    members: &[u32],
    component: &[u32],
    dist: &mut [Vec<(u32, f64)>],
    flow: &mut [Vec<(u32, f64)>],
) -> Result<(), AnalysisError> {
    let k = members.len();
    let comp = component[members[0] as usize];
    let t_base = tangible as u32;
    let pos: FxHashMap<u32, usize> = members.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    // Right-hand sides: column per tangible target, then per immediate transition.
    let mut cols_d: FxHashMap<u32, usize> = FxHashMap::default();
    let mut cols_f: FxHashMap<u32, usize> = FxHashMap::default();
    let mut a = vec![0.0f64; k * k];
    for i in 0..k {
        a[i * k + i] = 1.0;
    }
    let mut rhs_d: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    let mut rhs_f: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    let mut exit = false;
    for (i, &v) in members.iter().enumerate() {
        for m in raw.moves.group(order[tangible + v as usize] as usize) {
            if m.prob <= 0.0 {
                continue;
            }
            let n = cols_f.len();
            let c = *cols_f.entry(m.transition.0).or_insert(n);
            rhs_f[i].push((c, m.prob));
            if raw.tangible[m.to as usize] {
                exit = true;
                let n = cols_d.len();
                let c = *cols_d.entry(new_id[m.to as usize]).or_insert(n);
                rhs_d[i].push((c, m.prob));
                continue;
            }
            let w = new_id[m.to as usize] - t_base;
            if component[w as usize] == comp {
                a[i * k + pos[&w]] -= m.prob;
                continue;
            }
            exit = true;
            for &(s, q) in &dist[w as usize] {
                let n = cols_d.len();
                let c = *cols_d.entry(s).or_insert(n);
                rhs_d[i].push((c, m.prob * q));
            }
            for &(t, x) in &flow[w as usize] {
                let n = cols_f.len();
                let c = *cols_f.entry(t).or_insert(n);
                rhs_f[i].push((c, m.prob * x));
            }
        }
    }
    if !exit {
        let mut mk = vec![0u32; net.place_count()];
        raw.store
            .get(order[tangible + members[0] as usize] as usize, &mut mk);
        return Err(AnalysisError::TimelessTrap {
            marking: net.format_marking(&mk),
        });
    }
    let (nd, nf) = (cols_d.len(), cols_f.len());
    let nc = nd + nf;
    // Dense solve: k² + k·nc numbers. 64 M of them is 512 MB.
    if k.saturating_mul(k + nc) > 64 << 20 {
        return Err(AnalysisError::VanishingLoopTooLarge { markings: k });
    }
    let mut b = vec![0.0f64; k * nc];
    for i in 0..k {
        for &(c, x) in &rhs_d[i] {
            b[i * nc + c] += x;
        }
        for &(c, x) in &rhs_f[i] {
            b[i * nc + nd + c] += x;
        }
    }
    lu_solve(&mut a, k, &mut b, nc);
    let mut col_d: Vec<(u32, usize)> = cols_d.into_iter().collect();
    col_d.sort_unstable();
    let mut col_f: Vec<(u32, usize)> = cols_f.into_iter().collect();
    col_f.sort_unstable();
    for (i, &v) in members.iter().enumerate() {
        let row = &b[i * nc..(i + 1) * nc];
        dist[v as usize] = col_d
            .iter()
            .map(|&(s, c)| (s, row[c]))
            .filter(|&(_, x)| x > 1e-300)
            .collect();
        flow[v as usize] = col_f
            .iter()
            .map(|&(t, c)| (t, row[nd + c]))
            .filter(|&(_, x)| x > 1e-300)
            .collect();
    }
    Ok(())
}

/// Solves `A X = B` in place (`A` is `k×k`, `B` is `k×nc`, row-major), Gaussian elimination
/// with partial pivoting. `A = I − P` with `P` substochastic and transient, so it is regular.
pub(crate) fn lu_solve(a: &mut [f64], k: usize, b: &mut [f64], nc: usize) {
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
