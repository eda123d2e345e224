//! Place and transition invariants (Farkas' algorithm, minimal supports), the place bounds
//! they imply, and the token-conservation check the robot backends rely on.
//!
//! A P-invariant `y ≥ 0` satisfies `yᵀC = 0` (C the place × transition incidence matrix): the
//! weighted token sum `y·m` is the same in every reachable marking, so `m(p) ≤ y·m₀ / y(p)`.
//! A T-invariant `x ≥ 0` satisfies `Cx = 0`: firing each transition `x(t)` times returns to
//! the same marking. Inhibitor arcs and capacities do not change `C`.
//!
//! ```
//! use gspn::analysis::invariants::{p_invariants, structural_bounds};
//! use gspn::net::{NetBuilder, Servers};
//! let mut b = NetBuilder::new("cycle");
//! let p = b.place("p", 3);
//! let q = b.place("q", 0);
//! let t = b.exponential("t", 1.0, Servers::Single);
//! let u = b.exponential("u", 1.0, Servers::Single);
//! b.input(p, t, 1);
//! b.output(t, q, 1);
//! b.input(q, u, 1);
//! b.output(u, p, 1);
//! let net = b.build().unwrap();
//! let inv = p_invariants(&net, 1000);
//! assert_eq!(inv.vectors, vec![vec![1, 1]]);
//! assert_eq!(structural_bounds(&net), vec![Some(3), Some(3)]);
//! ```

use crate::net::{Net, PlaceId, TransitionId};

/// Rows kept during Farkas' algorithm before it gives up (the answer is then incomplete).
pub const DEFAULT_CAP: usize = 2000;

/// One invariant: a non-negative integer vector kept as its non-zero entries in index order,
/// so a net of n places with n invariants (n isolated places) takes O(n) memory, not O(n²).
/// It compares equal to the dense vector with the same entries (`inv == vec![1, 1, 0]`), and
/// orders like the dense vectors would.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Default)]
pub struct Invariant(Vec<(u32, u64)>);

impl Invariant {
    /// The non-zero entries `(index, weight)`, by increasing index.
    pub fn entries(&self) -> &[(u32, u64)] {
        &self.0
    }

    /// The weight at `index` (0 off the support).
    pub fn get(&self, index: usize) -> u64 {
        self.0
            .binary_search_by_key(&(index as u32), |&(i, _)| i)
            .map_or(0, |k| self.0[k].1)
    }

    /// The indices with a non-zero weight, in order.
    pub fn support(&self) -> impl Iterator<Item = usize> + '_ {
        self.0.iter().map(|&(i, _)| i as usize)
    }

    /// The dense vector of length `n`.
    pub fn to_dense(&self, n: usize) -> Vec<u64> {
        let mut v = vec![0; n];
        for &(i, w) in &self.0 {
            v[i as usize] = w;
        }
        v
    }
}

impl PartialEq<Vec<u64>> for Invariant {
    fn eq(&self, dense: &Vec<u64>) -> bool {
        self.0
            .iter()
            .all(|&(i, w)| dense.get(i as usize) == Some(&w))
            && dense.iter().filter(|&&w| w != 0).count() == self.0.len()
    }
}

impl Ord for Invariant {
    /// The order of the dense vectors: at the first index where they differ, the larger
    /// weight is the larger vector.
    fn cmp(&self, other: &Self) -> std::cmp::Ordering {
        let (a, b) = (&self.0, &other.0);
        let (mut i, mut k) = (0, 0);
        loop {
            match (a.get(i), b.get(k)) {
                (None, None) => return std::cmp::Ordering::Equal,
                // Past its end a vector is 0 where the other is non-zero.
                (None, Some(_)) => return std::cmp::Ordering::Less,
                (Some(_), None) => return std::cmp::Ordering::Greater,
                (Some(&(x, v)), Some(&(y, w))) => {
                    if x == y {
                        if v != w {
                            return v.cmp(&w);
                        }
                        i += 1;
                        k += 1;
                    } else if x < y {
                        // `a` is non-zero at x, `b` is 0 there.
                        return std::cmp::Ordering::Greater;
                    } else {
                        return std::cmp::Ordering::Less;
                    }
                }
            }
        }
    }
}

impl PartialOrd for Invariant {
    fn partial_cmp(&self, other: &Self) -> Option<std::cmp::Ordering> {
        Some(self.cmp(other))
    }
}

/// Minimal-support invariants.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Invariants {
    /// Each invariant (per place for P-invariants, per transition for T-invariants), entries
    /// with gcd 1, sorted.
    pub vectors: Vec<Invariant>,
    /// False when the computation hit its size cap or overflowed; `vectors` is then empty.
    pub complete: bool,
}

impl Invariants {
    /// True when every index `0..n` lies in the support of some invariant (the net is covered).
    pub fn covers_all(&self, n: usize) -> bool {
        let mut covered = vec![false; n];
        for v in &self.vectors {
            for i in v.support() {
                if let Some(c) = covered.get_mut(i) {
                    *c = true;
                }
            }
        }
        covered.into_iter().all(|c| c)
    }
}

/// A transition that changes the token count over the places that are kept.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TokenLeak {
    /// The transition.
    pub transition: TransitionId,
    /// Tokens it adds (positive) or removes (negative) over the kept places.
    pub delta: i64,
}

/// P-invariants of `net`: non-negative `y` with `yᵀC = 0`, minimal supports. `cap` bounds the
/// rows kept during the computation.
pub fn p_invariants(net: &Net, cap: usize) -> Invariants {
    let np = net.place_count();
    let mut c: Vec<Vec<(u32, i64)>> = vec![Vec::new(); np];
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            c[p.index()].push((t.0, d));
        }
    }
    farkas(c, net.transition_count(), cap)
}

/// T-invariants of `net`: non-negative `x` with `Cx = 0`, minimal supports.
pub fn t_invariants(net: &Net, cap: usize) -> Invariants {
    let c: Vec<Vec<(u32, i64)>> = net
        .transition_ids()
        .map(|t| net.delta(t).iter().map(|&(p, d)| (p.0, d)).collect())
        .collect();
    farkas(c, net.place_count(), cap)
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// One row of the Farkas tableau, sparse: the remaining matrix part (non-zero columns, in
/// order) and the combination of original rows (non-negative, its indices are the support).
#[derive(Clone, Debug)]
struct Row {
    c: Vec<(u32, i64)>,
    y: Vec<(u32, u64)>,
}

impl Row {
    fn at(&self, j: u32) -> i64 {
        self.c
            .binary_search_by_key(&j, |&(k, _)| k)
            .map_or(0, |k| self.c[k].1)
    }
}

/// True when the support of `a` lies within the support of `b` (both sorted).
fn subset(a: &[(u32, u64)], b: &[(u32, u64)]) -> bool {
    if a.len() > b.len() {
        return false;
    }
    if a.len() * 16 < b.len() {
        // A small support against a large one: look each index up.
        return a
            .iter()
            .all(|&(i, _)| b.binary_search_by_key(&i, |&(k, _)| k).is_ok());
    }
    let mut it = b.iter().map(|&(i, _)| i);
    a.iter().all(|&(i, _)| it.by_ref().any(|k| k == i))
}

/// `x·a + z·b` over two sparse vectors, zeros dropped; `None` on overflow.
fn merge<T: Copy>(
    a: &[(u32, T)],
    b: &[(u32, T)],
    f: impl Fn(Option<T>, Option<T>) -> Option<i128>,
    back: impl Fn(i128) -> Option<T>,
) -> Option<Vec<(u32, T)>> {
    let mut out = Vec::with_capacity(a.len() + b.len());
    let (mut i, mut k) = (0, 0);
    while i < a.len() || k < b.len() {
        let (j, x, z) = match (a.get(i), b.get(k)) {
            (Some(&(p, x)), Some(&(q, z))) if p == q => {
                i += 1;
                k += 1;
                (p, Some(x), Some(z))
            }
            (Some(&(p, x)), Some(&(q, _))) if p < q => {
                i += 1;
                (p, Some(x), None)
            }
            (Some(&(p, x)), None) => {
                i += 1;
                (p, Some(x), None)
            }
            (_, Some(&(q, z))) => {
                k += 1;
                (q, None, Some(z))
            }
            (None, None) => unreachable!("loop condition"),
        };
        let v = f(x, z)?;
        if v != 0 {
            out.push((j, back(v)?));
        }
    }
    Some(out)
}

/// Combines rows `p` (positive in column j) and `n` (negative) so column j cancels.
fn combine(p: &Row, n: &Row, j: u32) -> Option<Row> {
    let (a, b) = (n.at(j).unsigned_abs(), p.at(j) as u64);
    let (a, b) = (a / gcd(a, b), b / gcd(a, b));
    let lin = |x: Option<i64>, z: Option<i64>| {
        Some(x.unwrap_or(0) as i128 * a as i128 + z.unwrap_or(0) as i128 * b as i128)
    };
    let mut c = merge(&p.c, &n.c, lin, |v| i64::try_from(v).ok())?;
    let lin_y = |x: Option<u64>, z: Option<u64>| {
        Some(x.unwrap_or(0) as i128 * a as i128 + z.unwrap_or(0) as i128 * b as i128)
    };
    let mut y = merge(&p.y, &n.y, lin_y, |v| u64::try_from(v).ok())?;
    let g = c
        .iter()
        .map(|&(_, v)| v.unsigned_abs())
        .chain(y.iter().map(|&(_, v)| v))
        .fold(0, gcd);
    if g > 1 {
        c.iter_mut().for_each(|(_, v)| *v /= g as i64);
        y.iter_mut().for_each(|(_, v)| *v /= g);
    }
    Some(Row { c, y })
}

/// Farkas' algorithm on the sparse `n × m` matrix `c` (row i: its non-zero columns in
/// order): non-negative integer `y` with `yᵀc = 0`. Memory and time per step follow the
/// non-zero entries, not n × m.
fn farkas(c: Vec<Vec<(u32, i64)>>, m: usize, cap: usize) -> Invariants {
    let mut rows: Vec<Row> = c
        .into_iter()
        .enumerate()
        .map(|(i, mut c)| {
            c.sort_unstable_by_key(|&(j, _)| j);
            Row {
                c,
                y: vec![(i as u32, 1)],
            }
        })
        .collect();
    let mut done = vec![false; m];
    // Per column: rows positive and negative there (reset after each step).
    let (mut pos_count, mut neg_count) = (vec![0usize; m], vec![0usize; m]);
    let mut touched: Vec<u32> = Vec::new();
    loop {
        // Next column: among those some row still has, the one creating the fewest
        // combinations (ties: the lowest index).
        for r in &rows {
            for &(j, v) in &r.c {
                let j = j as usize;
                if pos_count[j] == 0 && neg_count[j] == 0 {
                    touched.push(j as u32);
                }
                if v > 0 {
                    pos_count[j] += 1;
                } else {
                    neg_count[j] += 1;
                }
            }
        }
        let next = touched
            .iter()
            .copied()
            .filter(|&j| !done[j as usize])
            .min_by_key(|&j| (pos_count[j as usize] * neg_count[j as usize], j));
        for &j in &touched {
            pos_count[j as usize] = 0;
            neg_count[j as usize] = 0;
        }
        touched.clear();
        let Some(j) = next else {
            break;
        };
        done[j as usize] = true;
        let (mut keep, mut pos, mut neg) = (Vec::new(), Vec::new(), Vec::new());
        for r in rows {
            match r.at(j).signum() {
                0 => keep.push(r),
                1 => pos.push(r),
                _ => neg.push(r),
            }
        }
        // Every combination is held until the minimality check: refuse before allocating
        // far more of them than the cap allows to keep.
        if pos.len().saturating_mul(neg.len()) > 4 * cap.max(16) {
            return Invariants::default();
        }
        let base = keep.len();
        for p in &pos {
            for q in &neg {
                let Some(r) = combine(p, q, j) else {
                    return Invariants::default();
                };
                keep.push(r);
            }
        }
        // Minimal supports: drop a new row whose support contains another row's support.
        let mut alive = vec![true; keep.len()];
        for i in base..keep.len() {
            for k in 0..keep.len() {
                if k == i || !alive[k] {
                    continue;
                }
                let (si, sk) = (&keep[i].y, &keep[k].y);
                if subset(sk, si) && (sk.len() != si.len() || k < i) {
                    alive[i] = false;
                    break;
                }
            }
        }
        rows = keep
            .into_iter()
            .zip(alive)
            .filter_map(|(r, a)| a.then_some(r))
            .collect();
        if rows.len() > cap {
            return Invariants::default();
        }
    }
    let mut vectors: Vec<Invariant> = rows
        .into_iter()
        .filter(|r| !r.y.is_empty())
        .map(|r| Invariant(r.y))
        .collect();
    vectors.sort();
    vectors.dedup();
    Invariants {
        vectors,
        complete: true,
    }
}

/// Upper bound on each place's tokens implied by the P-invariants and capacities (`None`:
/// no invariant covers the place and it has no capacity).
pub fn structural_bounds(net: &Net) -> Vec<Option<u64>> {
    let inv = p_invariants(net, DEFAULT_CAP);
    let m0: Vec<u64> = net.places().iter().map(|p| p.initial as u64).collect();
    let mut bounds: Vec<Option<u64>> = net
        .places()
        .iter()
        .map(|p| p.capacity.map(u64::from))
        .collect();
    for y in &inv.vectors {
        let total: u128 = y
            .entries()
            .iter()
            .map(|&(p, a)| a as u128 * m0[p as usize] as u128)
            .sum();
        for &(p, w) in y.entries() {
            let p = p as usize;
            let b = u64::try_from(total / w as u128).unwrap_or(u64::MAX);
            bounds[p] = Some(bounds[p].map_or(b, |old| old.min(b)));
        }
    }
    bounds
}

/// Checks that every transition keeps the token count over the places not in `removed`
/// (robots are tokens: a plan must neither create nor lose one). Structural, so it runs in
/// milliseconds; a transition that can never fire is still reported — when that matters,
/// compare with [`Properties::liveness`](crate::analysis::properties::Properties::liveness).
pub fn conserves_tokens(net: &Net, removed: &[PlaceId]) -> Result<(), Vec<TokenLeak>> {
    let mut skip = vec![false; net.place_count()];
    for p in removed {
        if let Some(s) = skip.get_mut(p.index()) {
            *s = true;
        }
    }
    let leaks: Vec<TokenLeak> = net
        .transition_ids()
        .filter_map(|t| {
            let delta: i64 = net
                .delta(t)
                .iter()
                .filter(|(p, _)| !skip[p.index()])
                .map(|&(_, d)| d)
                .sum();
            (delta != 0).then_some(TokenLeak {
                transition: t,
                delta,
            })
        })
        .collect();
    if leaks.is_empty() { Ok(()) } else { Err(leaks) }
}
