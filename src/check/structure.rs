//! Structural facts about a net, found without building its state space: which transitions
//! could ever fire, and bounds on every place's token count in any reachable marking.
//!
//! Everything here over-approximates the reachable markings, so a "never" is a proof: a
//! transition reported dead is dead in every run, a bound holds in every reachable marking.

use crate::net::{Net, PlaceId, TransitionId};

/// Most rows the P-invariant (Farkas) elimination may hold before it gives up; bounds then
/// come from the simpler producer analysis only.
const MAX_FARKAS_ROWS: usize = 2_000;

/// Structural bounds and the transitions that may fire.
#[derive(Clone, Debug, PartialEq)]
pub struct Structure {
    /// Per place, the most tokens it can hold in a reachable marking; `None` = no bound found.
    pub upper: Vec<Option<u64>>,
    /// Per place, the fewest tokens it can hold in a reachable marking.
    pub lower: Vec<u64>,
    /// Per transition, false when it can never fire (structurally).
    pub may_fire: Vec<bool>,
    /// Semi-positive P-invariants found (`y ≥ 0`, `y·C = 0`), as weights per place; every
    /// reachable marking `m` has `y·m = y·m0`.
    pub invariants: Vec<Vec<u64>>,
}

impl Structure {
    /// Analyses `net`: P-invariants (when the elimination stays small), then the least fixed
    /// point of "transitions that may fire" with the bounds it implies.
    ///
    /// The fixed point is a worklist over arcs: a transition is looked at again only when one
    /// of its input places may gain tokens or one of its inhibitor places may lose some, so
    /// the whole analysis is linear in the net's size (a 100,000-place chain used to take one
    /// full pass per transition).
    pub fn of(net: &Net) -> Structure {
        let invariants = p_invariants(net).unwrap_or_default();
        let m0: Vec<u64> = net.places().iter().map(|p| p.initial as u64).collect();
        let mut inv_bound: Vec<Option<u64>> = vec![None; net.place_count()];
        for y in &invariants {
            let total = weighted(y, &m0);
            for (p, &w) in y.iter().enumerate() {
                if let Some(b) = total.checked_div(w) {
                    inv_bound[p] = Some(inv_bound[p].map_or(b, |c: u64| c.min(b)));
                }
            }
        }
        for p in net.place_ids() {
            if let Some(cap) = net.place(p).capacity {
                let b = cap as u64;
                let i = p.index();
                inv_bound[i] = Some(inv_bound[i].map_or(b, |c| c.min(b)).max(m0[i].min(b)));
            }
        }

        let n = net.place_count();
        // Per place: the transitions reading it through an input or an inhibitor arc.
        let mut readers: Vec<Vec<TransitionId>> = vec![Vec::new(); n];
        for t in net.transition_ids() {
            for &(p, _) in net.inputs(t).iter().chain(net.inhibitors(t)) {
                readers[p.index()].push(t);
            }
        }
        let mut may_fire = vec![false; net.transition_count()];
        let mut upper: Vec<Option<u64>> = m0.iter().map(|&k| Some(k)).collect();
        let mut lower: Vec<u64> = m0.clone();
        let (mut increased, mut decreased) = (vec![false; n], vec![false; n]);
        let mut queued = vec![true; net.transition_count()];
        let mut work: Vec<TransitionId> = net.transition_ids().collect();
        work.reverse();
        while let Some(t) = work.pop() {
            queued[t.index()] = false;
            if may_fire[t.index()] || !could_fire(net, t, &upper, &lower) {
                continue;
            }
            may_fire[t.index()] = true;
            for &(p, d) in net.delta(t) {
                let i = p.index();
                let changed = if d > 0 {
                    !std::mem::replace(&mut increased[i], true)
                } else {
                    !std::mem::replace(&mut decreased[i], true)
                };
                if !changed {
                    continue;
                }
                if d > 0 {
                    upper[i] = inv_bound[i];
                } else {
                    lower[i] = 0;
                }
                for &u in &readers[i] {
                    if !may_fire[u.index()] && !queued[u.index()] {
                        queued[u.index()] = true;
                        work.push(u);
                    }
                }
            }
        }
        // Lower bounds from invariants: y·m = y·m0 with the other places at their upper
        // bounds gives y_p·m(p) ≥ y·m0 − Σ_{q≠p} y_q·ub(q).
        for y in &invariants {
            let total = weighted(y, &m0);
            let support: Vec<usize> = (0..n).filter(|&q| y[q] > 0).collect();
            for &p in &support {
                let mut others = 0u64;
                let mut bounded = true;
                for &q in support.iter().filter(|&&q| q != p) {
                    match upper[q] {
                        Some(u) => others = others.saturating_add(y[q].saturating_mul(u)),
                        None => bounded = false,
                    }
                }
                if bounded && total > others {
                    lower[p] = lower[p].max((total - others).div_ceil(y[p]));
                }
            }
        }
        Structure {
            upper,
            lower,
            may_fire,
            invariants,
        }
    }

    /// True when a marking with `k` tokens in `p` is structurally possible.
    pub fn allows(&self, p: PlaceId, k: u32) -> bool {
        let k = k as u64;
        k >= self.lower[p.index()] && self.upper[p.index()].is_none_or(|u| k <= u)
    }
}

/// Whether `t` could be enabled given the place bounds.
fn could_fire(net: &Net, t: TransitionId, upper: &[Option<u64>], lower: &[u64]) -> bool {
    net.inputs(t)
        .iter()
        .all(|&(p, w)| upper[p.index()].is_none_or(|u| u >= w as u64))
        && net
            .inhibitors(t)
            .iter()
            .all(|&(p, w)| lower[p.index()] < w as u64)
}

/// Semi-positive P-invariants by Farkas' elimination; `None` when the net is large or the
/// elimination grows past [`MAX_FARKAS_ROWS`] (some nets have exponentially many minimal
/// invariants) or its coefficients overflow. Rows are combinations of places, so every row
/// left at the end is a true invariant; pruning only loses invariants, never invents one.
fn p_invariants(net: &Net) -> Option<Vec<Vec<u64>>> {
    let n = net.place_count();
    let m = net.transition_count();
    if n > MAX_FARKAS_ROWS / 4 {
        return None;
    }
    // Each row: (incidence row over transitions, combination over places).
    let mut rows: Vec<(Vec<i64>, Vec<i64>)> = (0..n)
        .map(|p| {
            let mut y = vec![0i64; n];
            y[p] = 1;
            (vec![0i64; m], y)
        })
        .collect();
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            rows[p.index()].0[t.index()] = d;
        }
    }
    for j in 0..m {
        let (mut next, nonzero): (Vec<_>, Vec<_>) = rows.into_iter().partition(|r| r.0[j] == 0);
        let (pos, neg): (Vec<_>, Vec<_>) = nonzero.into_iter().partition(|r| r.0[j] > 0);
        for a in &pos {
            for b in &neg {
                next.push(combine(a, b, j)?);
                if next.len() > MAX_FARKAS_ROWS {
                    return None;
                }
            }
        }
        rows = minimal_supports(next);
    }
    Some(
        rows.into_iter()
            .map(|(_, y)| y.into_iter().map(i64::unsigned_abs).collect())
            .collect(),
    )
}

/// `|b_j|·a + a_j·b`, which cancels column `j`, divided by the gcd of its entries.
fn combine(
    a: &(Vec<i64>, Vec<i64>),
    b: &(Vec<i64>, Vec<i64>),
    j: usize,
) -> Option<(Vec<i64>, Vec<i64>)> {
    let (ca, cb) = (-b.0[j], a.0[j]);
    let lin = |x: &[i64], z: &[i64]| -> Option<Vec<i64>> {
        x.iter()
            .zip(z)
            .map(|(&x, &z)| ca.checked_mul(x)?.checked_add(cb.checked_mul(z)?))
            .collect()
    };
    let mut c = lin(&a.0, &b.0)?;
    let mut y = lin(&a.1, &b.1)?;
    let g = c.iter().chain(&y).fold(0i64, |g, &v| gcd(g, v.abs()));
    if g > 1 {
        c.iter_mut().chain(y.iter_mut()).for_each(|v| *v /= g);
    }
    Some((c, y))
}

/// Drops rows whose place support strictly contains another row's (and exact duplicates).
fn minimal_supports(rows: Vec<(Vec<i64>, Vec<i64>)>) -> Vec<(Vec<i64>, Vec<i64>)> {
    let supports: Vec<Vec<usize>> = rows
        .iter()
        .map(|r| (0..r.1.len()).filter(|&i| r.1[i] != 0).collect())
        .collect();
    let redundant = |i: usize| {
        (0..rows.len()).any(|k| {
            k != i
                && supports[k].iter().all(|x| supports[i].contains(x))
                && (supports[k].len() < supports[i].len() || (k < i && rows[k] == rows[i]))
        })
    };
    let keep: Vec<bool> = (0..rows.len()).map(|i| !redundant(i)).collect();
    rows.into_iter()
        .zip(keep)
        .filter_map(|(r, k)| k.then_some(r))
        .collect()
}

/// `y·m`, saturating (a bound that saturates is still a bound).
pub(crate) fn weighted(y: &[u64], m: &[u64]) -> u64 {
    y.iter()
        .zip(m)
        .fold(0u64, |acc, (a, b)| acc.saturating_add(a.saturating_mul(*b)))
}

fn gcd(a: i64, b: i64) -> i64 {
    if b == 0 { a } else { gcd(b, a % b) }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    #[test]
    fn a_cycle_is_bounded_by_its_invariant() {
        // P1 (2) -> T1 -> P2 -> t2 -> P3 -> T3 -> P1: P1+P2+P3 = 2.
        let mut b = NetBuilder::new("cyc3");
        let p: Vec<_> = (1..=3)
            .map(|i| b.place(format!("P{i}"), if i == 1 { 2 } else { 0 }))
            .collect();
        let t1 = b.exponential("T1", 1.0, Servers::Single);
        let t2 = b.immediate("t2", 1.0, 1);
        let t3 = b.exponential("T3", 2.0, Servers::Single);
        b.input(p[0], t1, 1);
        b.output(t1, p[1], 1);
        b.input(p[1], t2, 1);
        b.output(t2, p[2], 1);
        b.input(p[2], t3, 1);
        b.output(t3, p[0], 1);
        let s = Structure::of(&b.build().unwrap());
        assert_eq!(s.invariants, vec![vec![1, 1, 1]]);
        assert_eq!(s.upper, vec![Some(2), Some(2), Some(2)]);
        assert_eq!(s.lower, vec![0, 0, 0]);
        assert_eq!(s.may_fire, vec![true, true, true]);
    }

    #[test]
    fn starved_and_inhibited_transitions_never_fire() {
        let mut b = NetBuilder::new("n");
        let a = b.place("A", 1);
        let src = b.place("Empty", 0);
        let block = b.place("Block", 1);
        let t_ok = b.exponential("ok", 1.0, Servers::Single);
        let t_starved = b.exponential("starved", 1.0, Servers::Single);
        let t_inhibited = b.immediate("inhibited", 1.0, 1);
        let t_weight = b.exponential("heavy", 1.0, Servers::Single);
        b.moves(a, t_ok, a);
        b.input(src, t_starved, 1);
        b.input(a, t_inhibited, 1);
        b.inhibitor(block, t_inhibited, 1);
        b.input(a, t_weight, 2);
        let s = Structure::of(&b.build().unwrap());
        assert_eq!(s.may_fire, vec![true, false, false, false]);
        assert_eq!(s.upper[0], Some(1));
        assert_eq!(s.lower[2], 1);
    }
}
