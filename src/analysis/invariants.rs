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

/// Minimal-support invariants.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Invariants {
    /// Each invariant as a dense non-negative vector (per place for P-invariants, per
    /// transition for T-invariants), entries with gcd 1, sorted.
    pub vectors: Vec<Vec<u64>>,
    /// False when the computation hit its size cap or overflowed; `vectors` is then empty.
    pub complete: bool,
}

impl Invariants {
    /// True when every index `0..n` lies in the support of some invariant (the net is covered).
    pub fn covers_all(&self, n: usize) -> bool {
        (0..n).all(|i| self.vectors.iter().any(|v| v[i] > 0))
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
    let (np, nt) = (net.place_count(), net.transition_count());
    let mut c = vec![vec![0i64; nt]; np];
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            c[p.index()][t.index()] = d;
        }
    }
    farkas(c, nt, cap)
}

/// T-invariants of `net`: non-negative `x` with `Cx = 0`, minimal supports.
pub fn t_invariants(net: &Net, cap: usize) -> Invariants {
    let (np, nt) = (net.place_count(), net.transition_count());
    let mut c = vec![vec![0i64; np]; nt];
    for t in net.transition_ids() {
        for &(p, d) in net.delta(t) {
            c[t.index()][p.index()] = d;
        }
    }
    farkas(c, np, cap)
}

fn gcd(mut a: u64, mut b: u64) -> u64 {
    while b != 0 {
        (a, b) = (b, a % b);
    }
    a
}

/// One row of the Farkas tableau: the remaining matrix part and the combination of
/// original rows (non-negative), with its support as a bitset.
#[derive(Clone, Debug)]
struct Row {
    c: Vec<i64>,
    y: Vec<u64>,
    support: Vec<u64>,
}

fn support_of(y: &[u64]) -> Vec<u64> {
    let mut s = vec![0u64; y.len().div_ceil(64)];
    for (i, &v) in y.iter().enumerate() {
        if v > 0 {
            s[i / 64] |= 1 << (i % 64);
        }
    }
    s
}

fn subset(a: &[u64], b: &[u64]) -> bool {
    a.iter().zip(b).all(|(&x, &y)| x & !y == 0)
}

/// Combines rows `p` (positive in column j) and `n` (negative) so column j cancels.
fn combine(p: &Row, n: &Row, j: usize) -> Option<Row> {
    let (a, b) = (n.c[j].unsigned_abs(), p.c[j] as u64);
    let (a, b) = (a / gcd(a, b), b / gcd(a, b));
    let mut c = Vec::with_capacity(p.c.len());
    for (&x, &z) in p.c.iter().zip(&n.c) {
        let v = (x as i128) * a as i128 + (z as i128) * b as i128;
        c.push(i64::try_from(v).ok()?);
    }
    let mut y = Vec::with_capacity(p.y.len());
    for (&x, &z) in p.y.iter().zip(&n.y) {
        y.push(x.checked_mul(a)?.checked_add(z.checked_mul(b)?)?);
    }
    let g = c
        .iter()
        .map(|v| v.unsigned_abs())
        .chain(y.iter().copied())
        .fold(0, gcd);
    if g > 1 {
        c.iter_mut().for_each(|v| *v /= g as i64);
        y.iter_mut().for_each(|v| *v /= g);
    }
    let support = support_of(&y);
    Some(Row { c, y, support })
}

/// Farkas' algorithm on the `n × m` matrix `c`: non-negative integer `y` with `yᵀc = 0`.
fn farkas(c: Vec<Vec<i64>>, m: usize, cap: usize) -> Invariants {
    let n = c.len();
    let mut rows: Vec<Row> = c
        .into_iter()
        .enumerate()
        .map(|(i, c)| {
            let mut y = vec![0u64; n];
            y[i] = 1;
            let support = support_of(&y);
            Row { c, y, support }
        })
        .collect();
    let mut done = vec![false; m];
    for _ in 0..m {
        // Next column: the one creating the fewest combinations.
        let Some(j) = (0..m).filter(|&j| !done[j]).min_by_key(|&j| {
            let pos = rows.iter().filter(|r| r.c[j] > 0).count();
            let neg = rows.iter().filter(|r| r.c[j] < 0).count();
            pos * neg
        }) else {
            break;
        };
        done[j] = true;
        let (mut keep, mut pos, mut neg) = (Vec::new(), Vec::new(), Vec::new());
        for r in rows {
            match r.c[j].signum() {
                0 => keep.push(r),
                1 => pos.push(r),
                _ => neg.push(r),
            }
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
                let (si, sk) = (&keep[i].support, &keep[k].support);
                if subset(sk, si) && (si != sk || k < i) {
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
    let mut vectors: Vec<Vec<u64>> = rows
        .into_iter()
        .map(|r| r.y)
        .filter(|y| y.iter().any(|&v| v > 0))
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
            .iter()
            .zip(&m0)
            .map(|(&a, &b)| a as u128 * b as u128)
            .sum();
        for (p, &w) in y.iter().enumerate() {
            if w > 0 {
                let b = u64::try_from(total / w as u128).unwrap_or(u64::MAX);
                bounds[p] = Some(bounds[p].map_or(b, |old| old.min(b)));
            }
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
