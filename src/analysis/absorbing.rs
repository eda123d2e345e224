//! Chains of instant steps resolved exactly: where a state that time does not leave ends up
//! (a distribution over exits) and what fires on the way (expected counts).
//!
//! The one solver for loops of immediate transitions. [`vanishing`](crate::analysis::vanishing)
//! eliminates the vanishing markings of a CTMC with it; synthesis eliminates uncontrolled
//! vanishing markings (weighted races) and resolves the decision states under a fixed policy.
//! States are grouped into strongly connected components and solved sinks first: a component
//! without a cycle is a weighted sum of its successors' answers, a component with a cycle is
//! an absorbing chain solved by LU of `I − P` restricted to it ([`linear`]: dense when small,
//! sparse above), exits and counts as right-hand-side columns.

use rustc_hash::FxHashMap;

use crate::analysis::linear::{self, SolveError, solve_block};
use crate::analysis::scc::tarjan;
use crate::analysis::state_space::AnalysisError;

/// Where an arc leads: an exit (kept state) or another local state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) enum Target {
    /// A state outside the chain.
    Out(u32),
    /// Local state of the chain.
    In(u32),
}

/// Per local state: exit distribution and expected counts, both sorted by index.
#[derive(Debug, Default)]
pub(crate) struct Absorbed {
    pub(crate) dist: Vec<Vec<(u32, f64)>>,
    pub(crate) counts: Vec<Vec<(u32, f64)>>,
}

/// A sparse vector accumulated in a dense scratch array (grown on demand).
#[derive(Default)]
struct Acc {
    dense: Vec<f64>,
    seen: Vec<bool>,
    touched: Vec<u32>,
}

impl Acc {
    #[inline]
    fn add(&mut self, i: u32, x: f64) {
        let at = i as usize;
        if at >= self.dense.len() {
            self.dense.resize(at + 1, 0.0);
            self.seen.resize(at + 1, false);
        }
        if !self.seen[at] {
            self.seen[at] = true;
            self.touched.push(i);
        }
        self.dense[at] += x;
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

/// Why a chain was not resolved.
#[derive(Debug, PartialEq)]
pub(crate) enum AbsorbError {
    /// The component of this local state has no way out (a timeless trap).
    Trap(u32),
    /// A component of this many states is too large to solve in memory
    /// ([`linear::MAX_DENSE_NUMBERS`]).
    TooLarge(usize),
    /// The LU of a component of this many states failed.
    Failed(usize, String),
}

impl AbsorbError {
    /// The error as the analysis reports it; `marking(v)` names local state `v`'s marking.
    pub(crate) fn into_analysis(self, marking: impl FnOnce(u32) -> String) -> AnalysisError {
        match self {
            AbsorbError::Trap(v) => AnalysisError::TimelessTrap {
                marking: marking(v),
            },
            AbsorbError::TooLarge(markings) => AnalysisError::VanishingLoopTooLarge { markings },
            AbsorbError::Failed(markings, reason) => {
                AnalysisError::VanishingLoopFailed { markings, reason }
            }
        }
    }
}

/// Resolves local states `0..n`. `arcs(v, out)` gives v's arcs with their probabilities (sum
/// 1); `own(v, out)` the counts of v's own step.
pub(crate) fn absorb(
    n: usize,
    mut arcs: impl FnMut(u32, &mut Vec<(Target, f64)>),
    mut own: impl FnMut(u32, &mut Vec<(u32, f64)>),
) -> Result<Absorbed, AbsorbError> {
    let mut buf = Vec::new();
    let sccs = tarjan(n, |v, out| {
        buf.clear();
        arcs(v, &mut buf);
        out.extend(buf.iter().filter_map(|&(t, p)| match t {
            Target::In(w) if p > 0.0 => Some(w),
            _ => None,
        }));
    });
    let mut res = Absorbed {
        dist: vec![Vec::new(); n],
        counts: vec![Vec::new(); n],
    };
    let (mut acc_d, mut acc_c) = (Acc::default(), Acc::default());
    let mut steps = Vec::new();
    for members in sccs.members().iter() {
        let v = members[0];
        buf.clear();
        arcs(v, &mut buf);
        let looped = members.len() > 1
            || buf
                .iter()
                .any(|&(t, p)| p > 0.0 && matches!(t, Target::In(w) if w == v));
        if !looped {
            steps.clear();
            own(v, &mut steps);
            for &(i, x) in &steps {
                acc_c.add(i, x);
            }
            for &(t, p) in &buf {
                if p <= 0.0 {
                    continue;
                }
                match t {
                    Target::Out(k) => acc_d.add(k, p),
                    Target::In(w) => {
                        for &(k, q) in &res.dist[w as usize] {
                            acc_d.add(k, p * q);
                        }
                        for &(i, x) in &res.counts[w as usize] {
                            acc_c.add(i, p * x);
                        }
                    }
                }
            }
            res.dist[v as usize] = acc_d.take();
            res.counts[v as usize] = acc_c.take();
            continue;
        }
        solve_component(members, &sccs.component, &mut arcs, &mut own, &mut res)?;
    }
    Ok(res)
}

/// One component with a cycle: `(I − P_in) X = B`, exits and counts as columns.
fn solve_component(
    members: &[u32],
    component: &[u32],
    arcs: &mut impl FnMut(u32, &mut Vec<(Target, f64)>),
    own: &mut impl FnMut(u32, &mut Vec<(u32, f64)>),
    res: &mut Absorbed,
) -> Result<(), AbsorbError> {
    let k = members.len();
    let comp = component[members[0] as usize];
    let pos: FxHashMap<u32, usize> = members.iter().enumerate().map(|(i, &v)| (v, i)).collect();
    let mut cols_d: FxHashMap<u32, usize> = FxHashMap::default();
    let mut cols_c: FxHashMap<u32, usize> = FxHashMap::default();
    let mut a: Vec<(usize, usize, f64)> = (0..k).map(|i| (i, i, 1.0)).collect();
    let mut rhs_d: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    let mut rhs_c: Vec<Vec<(usize, f64)>> = vec![Vec::new(); k];
    let mut exit = false;
    let (mut buf, mut steps) = (Vec::new(), Vec::new());
    for (i, &v) in members.iter().enumerate() {
        steps.clear();
        own(v, &mut steps);
        for &(c, x) in &steps {
            let n = cols_c.len();
            let col = *cols_c.entry(c).or_insert(n);
            rhs_c[i].push((col, x));
        }
        buf.clear();
        arcs(v, &mut buf);
        for &(t, p) in &buf {
            if p <= 0.0 {
                continue;
            }
            match t {
                Target::Out(s) => {
                    exit = true;
                    let n = cols_d.len();
                    let col = *cols_d.entry(s).or_insert(n);
                    rhs_d[i].push((col, p));
                }
                Target::In(w) if component[w as usize] == comp => {
                    a.push((i, pos[&w], -p));
                }
                Target::In(w) => {
                    exit = true;
                    for &(s, q) in &res.dist[w as usize] {
                        let n = cols_d.len();
                        let col = *cols_d.entry(s).or_insert(n);
                        rhs_d[i].push((col, p * q));
                    }
                    for &(c, x) in &res.counts[w as usize] {
                        let n = cols_c.len();
                        let col = *cols_c.entry(c).or_insert(n);
                        rhs_c[i].push((col, p * x));
                    }
                }
            }
        }
    }
    if !exit {
        return Err(AbsorbError::Trap(members[0]));
    }
    let (nd, nc) = (cols_d.len(), cols_c.len());
    let w = nd + nc;
    if k.saturating_mul(w) > linear::MAX_DENSE_NUMBERS {
        return Err(AbsorbError::TooLarge(k));
    }
    let mut b = vec![0.0f64; k * w];
    for i in 0..k {
        for &(c, x) in &rhs_d[i] {
            b[i * w + c] += x;
        }
        for &(c, x) in &rhs_c[i] {
            b[i * w + nd + c] += x;
        }
    }
    solve_block(k, &a, &mut b, w).map_err(|e| match e {
        SolveError::TooLarge => AbsorbError::TooLarge(k),
        SolveError::Failed(e) => AbsorbError::Failed(k, e),
    })?;
    let mut col_d: Vec<(u32, usize)> = cols_d.into_iter().collect();
    col_d.sort_unstable();
    let mut col_c: Vec<(u32, usize)> = cols_c.into_iter().collect();
    col_c.sort_unstable();
    for (i, &v) in members.iter().enumerate() {
        let row = &b[i * w..(i + 1) * w];
        res.dist[v as usize] = col_d
            .iter()
            .map(|&(s, c)| (s, row[c]))
            .filter(|&(_, x)| x > 1e-300)
            .collect();
        res.counts[v as usize] = col_c
            .iter()
            .map(|&(t, c)| (t, row[nd + c]))
            .filter(|&(_, x)| x > 1e-300)
            .collect();
    }
    Ok(())
}
