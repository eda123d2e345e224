//! Karp–Miller coverability: decides whether a net is bounded and names the places that are
//! not, where plain state-space search would run forever.
//!
//! Markings carry ω (`u32::MAX`) for "as many tokens as you like". When a new marking
//! strictly covers an ancestor on its firing path, the firing sequence between them can be
//! repeated, and the places that grew become ω. GSPN rules (priorities, inhibitor arcs,
//! capacities) are not monotone, so a place is only accelerated when its count cannot change
//! what may fire: it has no capacity, inhibits nothing, and (in nets with immediate
//! transitions) feeds no immediate transition. When some growing place fails that test the
//! search does not accelerate and may hit its node limit: the answer is then
//! [`Coverability::Undecided`].
//!
//! ```
//! use gspn::analysis::coverability::{karp_miller, Coverability};
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("producer");
//! let idle = b.place("idle", 1);
//! let made = b.place("made", 0);
//! let t = b.exponential("produce", 1.0, Servers::Single);
//! b.input(idle, t, 1);
//! b.output(t, idle, 1);
//! b.output(t, made, 1);
//! let net = b.build().unwrap();
//! assert_eq!(karp_miller(&net, 1000), Coverability::Unbounded(vec![made]));
//! ```

use rustc_hash::FxHashSet;

use crate::net::{Net, PlaceId, Timing, TransitionId};

/// ω: unboundedly many tokens.
pub const OMEGA: u32 = u32::MAX;

/// What the coverability search found.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Coverability {
    /// Every reachable marking was enumerated: the most tokens each place ever holds.
    Bounded(Vec<u32>),
    /// These places can hold arbitrarily many tokens.
    Unbounded(Vec<PlaceId>),
    /// The node limit was reached before an answer (or acceleration was unsafe).
    Undecided,
}

/// Runs the Karp–Miller construction, visiting at most `node_limit` distinct ω-markings.
pub fn karp_miller(net: &Net, node_limit: usize) -> Coverability {
    let np = net.place_count();
    let accelerable: Vec<bool> = {
        let mut ok: Vec<bool> = net.places().iter().map(|p| p.capacity.is_none()).collect();
        for t in net.transition_ids() {
            for &(p, _) in net.inhibitors(t) {
                ok[p.index()] = false;
            }
            if net.transition(t).is_immediate() {
                for &(p, _) in net.inputs(t) {
                    ok[p.index()] = false;
                }
            }
        }
        ok
    };
    // Tree nodes: marking and parent.
    let mut nodes: Vec<(Vec<u32>, u32)> = vec![(net.initial_marking().into_vec(), u32::MAX)];
    let mut seen: FxHashSet<Vec<u32>> = FxHashSet::default();
    seen.insert(nodes[0].0.clone());
    let mut work = vec![0u32];
    let mut fire_buf = Vec::new();
    let mut omega = vec![false; np];
    let mut max = net.initial_marking().into_vec();
    // Ancestor comparisons allowed (place counts compared): keeps deep trees from taking
    // longer than the search the answer is meant to protect.
    let mut budget: u64 = 20 * node_limit as u64 * np.max(1) as u64;
    while let Some(i) = work.pop() {
        let m = nodes[i as usize].0.clone();
        firable(net, &m, &mut fire_buf);
        for &t in &fire_buf {
            let mut next = m.clone();
            for &(p, d) in net.delta(t) {
                let v = &mut next[p.index()];
                if *v != OMEGA {
                    *v = (*v as i64 + d).clamp(0, OMEGA as i64 - 1) as u32;
                }
            }
            if !accelerate(&nodes, i, &mut next, &accelerable, &mut budget) {
                return if omega.iter().any(|&o| o) {
                    unbounded(&omega)
                } else {
                    Coverability::Undecided
                };
            }
            for (p, &v) in next.iter().enumerate() {
                if v == OMEGA {
                    omega[p] = true;
                } else {
                    max[p] = max[p].max(v);
                }
            }
            if seen.contains(&next) {
                continue;
            }
            if nodes.len() >= node_limit {
                return if omega.iter().any(|&o| o) {
                    unbounded(&omega)
                } else {
                    Coverability::Undecided
                };
            }
            seen.insert(next.clone());
            nodes.push((next, i));
            work.push(nodes.len() as u32 - 1);
        }
    }
    if omega.iter().any(|&o| o) {
        unbounded(&omega)
    } else {
        Coverability::Bounded(max)
    }
}

fn unbounded(omega: &[bool]) -> Coverability {
    Coverability::Unbounded(
        omega
            .iter()
            .enumerate()
            .filter(|&(_, &o)| o)
            .map(|(p, _)| PlaceId(p as u32))
            .collect(),
    )
}

/// Sets ω where `next` strictly covers an ancestor of node `parent` (itself included) and all
/// growing places may be accelerated. False when the comparison budget ran out.
fn accelerate(
    nodes: &[(Vec<u32>, u32)],
    parent: u32,
    next: &mut [u32],
    accelerable: &[bool],
    budget: &mut u64,
) -> bool {
    let mut a = parent;
    while a != u32::MAX {
        let (anc, up) = &nodes[a as usize];
        let Some(left) = budget.checked_sub(anc.len() as u64 + 1) else {
            return false;
        };
        *budget = left;
        let covers = anc.iter().zip(next.iter()).all(|(&x, &y)| y >= x);
        if covers && anc.as_slice() != &*next {
            let safe = anc
                .iter()
                .zip(next.iter())
                .enumerate()
                .all(|(p, (&x, &y))| y == x || accelerable[p]);
            if safe {
                for (p, &x) in anc.iter().enumerate() {
                    if next[p] > x {
                        next[p] = OMEGA;
                    }
                }
            }
        }
        a = *up;
    }
    true
}

/// Transitions that may fire in ω-marking `m` under GSPN rules (ω enables every input arc and
/// disables every inhibitor arc).
fn firable(net: &Net, m: &[u32], out: &mut Vec<TransitionId>) {
    out.clear();
    let mut best = None;
    for t in net.transition_ids() {
        if let Timing::Immediate { priority, .. } = net.transition(t).timing
            && net.is_enabled(m, t)
        {
            if best.is_none_or(|b| priority > b) {
                best = Some(priority);
                out.clear();
            }
            if best == Some(priority) {
                out.push(t);
            }
        }
    }
    if best.is_some() {
        return;
    }
    out.extend(
        net.transition_ids()
            .filter(|&t| !net.transition(t).is_immediate() && net.is_enabled(m, t)),
    );
}
