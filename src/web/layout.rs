//! Where the viewer draws each place and transition: the file's positions when it gives one
//! for every node, otherwise an automatic layered layout with its arcs routed.
//!
//! The layered layout (Sugiyama's method): the arcs that close a cycle in a depth-first walk
//! from the marked places are turned round; each node's layer is one past its furthest
//! predecessor; an arc spanning several layers gets a placeholder in each layer it crosses;
//! each layer is ordered by the mean position of its neighbours (sweeps down and up, keeping
//! the order with the fewest crossings); rows are pulled towards the neighbours' rows. Layers
//! become columns folded into bands that run left to right, then right to left, so a long
//! cycle is drawn as a loop. Arcs leave and enter nodes horizontally and change row in the
//! middle of the gap between two columns (one lane per arc), which the names under the nodes
//! leave free: they never pass through a node and rarely through a name.

use std::collections::HashMap;

use serde::Serialize;

use crate::net::{ArcKind, Net, NetBuilder, NetError, Place, Position, Transition};

/// Horizontal distance between layers (at least; more for long names, see [`layer_gap`]).
const DX: f64 = 90.0;
/// Width of one character of a label on the page (11 px sans-serif), for [`layer_gap`].
const CHAR_WIDTH: f64 = 6.2;
/// Vertical distance between nodes of one layer.
const DY: f64 = 70.0;
/// Width of the lanes where arcs change row, between two columns.
const LANES: f64 = 30.0;
/// Most distance between two lanes.
const LANE: f64 = 6.0;
/// Width over height the bands aim at (the page's drawing area).
const ASPECT: f64 = 1.3;

/// Where the positions came from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LayoutSource {
    /// Every node had a position in the file.
    File,
    /// Computed by [`layout`].
    Layered,
}

/// One position per place and per transition, indexed like the net.
#[derive(Clone, Debug, PartialEq)]
pub struct Layout {
    /// Position of each place.
    pub places: Vec<Position>,
    /// Position of each transition.
    pub transitions: Vec<Position>,
    /// Bends of each arc (indexed like the net's arcs), from its source to its target: the
    /// file's for [`LayoutSource::File`], the routed ones for [`LayoutSource::Layered`].
    pub arcs: Vec<Vec<Position>>,
    /// Where they came from.
    pub source: LayoutSource,
}

/// The file's positions if every node has one, otherwise a layered layout.
///
/// ```
/// use gspn::net::{NetBuilder, Servers};
/// use gspn::web::layout::{LayoutSource, layout};
/// let mut b = NetBuilder::new("chain");
/// let (p, q) = (b.place("p", 1), b.place("q", 0));
/// let t = b.exponential("t", 1.0, Servers::Single);
/// b.input(p, t, 1);
/// b.output(t, q, 1);
/// let l = layout(&b.build().unwrap());
/// assert_eq!(l.source, LayoutSource::Layered);
/// assert!(l.places[0].x < l.transitions[0].x && l.transitions[0].x < l.places[1].x);
/// ```
pub fn layout(net: &Net) -> Layout {
    let from_file: Option<(Vec<Position>, Vec<Position>)> = net
        .places()
        .iter()
        .map(|p| p.position)
        .collect::<Option<Vec<_>>>()
        .zip(
            net.transitions()
                .iter()
                .map(|t| t.position)
                .collect::<Option<Vec<_>>>(),
        );
    match from_file {
        Some((places, transitions)) => Layout {
            places,
            transitions,
            arcs: net.arcs().iter().map(|a| a.points.clone()).collect(),
            source: LayoutSource::File,
        },
        None => layered(net),
    }
}

/// `net` with the given positions (one per place, one per transition, as in [`Layout`]);
/// `None` when the counts do not match the net.
pub fn with_positions(
    net: &Net,
    places: &[Position],
    transitions: &[Position],
) -> Option<Result<Net, NetError>> {
    if places.len() != net.place_count() || transitions.len() != net.transition_count() {
        return None;
    }
    let mut b = NetBuilder::new(net.name());
    for (p, &pos) in net.places().iter().zip(places) {
        b.add_place(Place {
            position: Some(pos),
            ..p.clone()
        });
    }
    for (t, &pos) in net.transitions().iter().zip(transitions) {
        b.add_transition(Transition {
            position: Some(pos),
            ..t.clone()
        });
    }
    for a in net.arcs() {
        b.arc(a.kind, a.place, a.transition, a.weight, a.points.clone());
    }
    Some(b.build())
}

/// Nodes are places `0..np` then transitions `np..np+nt`; every arc is an edge from its
/// source to its target (an inhibitor arc from its place).
fn layered(net: &Net) -> Layout {
    let np = net.place_count();
    let n = np + net.transition_count();
    let edges: Vec<(usize, usize)> = net
        .arcs()
        .iter()
        .map(|a| {
            let (p, t) = (a.place.index(), np + a.transition.index());
            match a.kind {
                ArcKind::Output => (t, p),
                ArcKind::Input | ArcKind::Inhibitor => (p, t),
            }
        })
        .collect();
    let marked: Vec<usize> = (0..np).filter(|&i| net.places()[i].initial > 0).collect();
    let reversed = back_edges(n, &edges, &marked);
    // The edges of the acyclic graph: back edges turned round.
    let dag: Vec<(usize, usize)> = edges
        .iter()
        .zip(&reversed)
        .map(|(&(u, v), &r)| if r { (v, u) } else { (u, v) })
        .collect();
    let layer = layers(n, &dag);

    let layer_count = layer.iter().map(|&l| l + 1).max().unwrap_or(0);

    // Slots: the nodes, then one placeholder per layer an arc passes through. An arc that was
    // turned round runs back through the layers it spans, or, when that is shorter, on to the
    // last layer and round to the first (the bands fold so that these are near each other):
    // the arc that closes a long cycle.
    let mut slot_layer: Vec<usize> = layer.clone();
    let mut chains: Vec<Vec<usize>> = Vec::with_capacity(edges.len());
    let mut flipped = vec![false; edges.len()];
    let through =
        |slot_layer: &mut Vec<usize>, chain: &mut Vec<usize>, ls: std::ops::Range<usize>| {
            for l in ls {
                chain.push(slot_layer.len());
                slot_layer.push(l);
            }
        };
    for (e, &(u, v)) in edges.iter().enumerate() {
        let (a, b) = (layer[u], layer[v]);
        let mut chain = Vec::new();
        if !reversed[e] {
            chain.push(u);
            through(&mut slot_layer, &mut chain, a + 1..b);
            chain.push(v);
        } else if layer_count - 1 - a + b < a - b - 1 {
            chain.push(u);
            through(&mut slot_layer, &mut chain, a + 1..layer_count);
            through(&mut slot_layer, &mut chain, 0..b);
            chain.push(v);
        } else {
            chain.push(v);
            through(&mut slot_layer, &mut chain, b + 1..a);
            chain.push(u);
            flipped[e] = true;
        }
        chains.push(chain);
    }
    let slots = slot_layer.len();
    let mut up: Vec<Vec<usize>> = vec![Vec::new(); slots];
    let mut down: Vec<Vec<usize>> = vec![Vec::new(); slots];
    for chain in &chains {
        for w in chain.windows(2) {
            down[w[0]].push(w[1]);
            up[w[1]].push(w[0]);
        }
    }
    let mut layers: Vec<Vec<usize>> = vec![Vec::new(); layer_count];
    for s in first_seen_order(slots, &down, &marked) {
        layers[slot_layer[s]].push(s);
    }
    order_layers(&mut layers, &up, &down, slots);

    // Rows: each layer keeps its order, nodes at least DY apart, pulled towards the rows of
    // their neighbours (a few sweeps each way).
    let mut y = vec![0.0; slots];
    for nodes in &layers {
        for (i, &s) in nodes.iter().enumerate() {
            y[s] = i as f64 * DY;
        }
    }
    for _ in 0..6 {
        for l in (1..layer_count).chain((0..layer_count.saturating_sub(1)).rev()) {
            let nodes = &layers[l];
            let target: Vec<f64> = nodes
                .iter()
                .map(|&s| {
                    let nb: Vec<usize> = up[s].iter().chain(&down[s]).copied().collect();
                    if nb.is_empty() {
                        y[s]
                    } else {
                        nb.iter().map(|&o| y[o]).sum::<f64>() / nb.len() as f64
                    }
                })
                .collect();
            for (s, v) in nodes.iter().zip(spaced(&target, DY)) {
                y[*s] = v;
            }
        }
    }

    // Layers become columns, folded into bands that run left to right, then right to left
    // (a serpentine: consecutive layers stay neighbours, a cycle closes on itself).
    let dx = layer_gap(net);
    let tallest = layers
        .iter()
        .map(|nodes| span(nodes, &y))
        .fold(0.0f64, f64::max)
        + 2.0 * DY;
    let per_band = ((ASPECT * layer_count as f64 * tallest / dx).sqrt().ceil() as usize)
        .max((1080.0 / dx).ceil() as usize)
        .clamp(1, layer_count.max(1));
    // An even number of bands ends on the left, where the first layer is.
    let mut bands = layer_count.div_ceil(per_band).max(1);
    if bands > 2 && bands % 2 == 1 {
        bands -= 1;
    }
    let per_band = layer_count.div_ceil(bands).max(1);
    let bands = layer_count.div_ceil(per_band).max(1);
    let band_of = |l: usize| l / per_band;
    let column = |l: usize| {
        let (b, c) = (l / per_band, l % per_band);
        if b % 2 == 0 { c } else { per_band - 1 - c }
    };
    let mut band_top = vec![40.0; bands + 1];
    for b in 0..bands {
        let members =
            &layers[(b * per_band).min(layer_count)..((b + 1) * per_band).min(layer_count)];
        if members.iter().all(Vec::is_empty) {
            band_top[b + 1] = band_top[b];
            continue;
        }
        let (lo, hi) = members
            .iter()
            .flatten()
            .fold((f64::MAX, f64::MIN), |(lo, hi), &s| {
                (lo.min(y[s]), hi.max(y[s]))
            });
        for &s in members.iter().flatten() {
            y[s] += band_top[b] - lo;
        }
        band_top[b + 1] = band_top[b] + (hi - lo) + 2.0 * DY;
    }
    let pos: Vec<Position> = (0..slots)
        .map(|s| Position {
            x: 40.0 + column(slot_layer[s]) as f64 * dx,
            y: y[s],
        })
        .collect();

    // Arcs: straight between neighbouring layers on one row; otherwise out along the row,
    // across in the middle of the gap between the columns (each arc in its own lane), and in
    // along the other row. Between bands the arc goes round the outside of the end column;
    // from the last layer to the first, round the outside of the drawing. Two arcs between
    // the same two slots on one row run side by side.
    let key = |a: usize, b: usize| (a.min(b), a.max(b));
    let mut parallel: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
    for chain in &chains {
        for w in chain.windows(2) {
            parallel.entry(key(w[0], w[1])).or_default().0 += 1;
        }
    }
    let wraps = |a: usize, b: usize| slot_layer[b] < slot_layer[a];
    let turns = |a: usize, b: usize| band_of(slot_layer[a]) != band_of(slot_layer[b]);
    // Per gap after a layer, the steps that change row there; the last gap also holds the
    // steps round the outside (lanes counted outwards from the end column).
    let mut lanes: Vec<Vec<(f64, usize, usize)>> = vec![Vec::new(); layer_count + 1];
    for (e, chain) in chains.iter().enumerate() {
        for (k, w) in chain.windows(2).enumerate() {
            let gap = if wraps(w[0], w[1]) {
                layer_count
            } else if (pos[w[0]].y - pos[w[1]].y).abs() > 1e-9 || turns(w[0], w[1]) {
                slot_layer[w[0]]
            } else {
                continue;
            };
            lanes[gap].push(((pos[w[0]].y + pos[w[1]].y) / 2.0, e, k));
        }
    }
    let mut lane_x: Vec<Vec<f64>> = chains.iter().map(|c| vec![0.0; c.len() - 1]).collect();
    for (l, gap) in lanes.iter_mut().enumerate() {
        gap.sort_by(|a, b| a.0.total_cmp(&b.0));
        let m = gap.len() as f64;
        let step = (LANES / m).min(LANE);
        for (j, &(_, e, k)) in gap.iter().enumerate() {
            lane_x[e][k] = if l == layer_count {
                j as f64 * LANE
            } else {
                (j as f64 - (m - 1.0) / 2.0) * step
            };
        }
    }
    let left = 40.0 - dx / 2.0;
    let right = 40.0 + (per_band - 1) as f64 * dx + dx / 2.0;
    let bottom = band_top[bands] - DY;
    let arcs: Vec<Vec<Position>> = chains
        .iter()
        .enumerate()
        .map(|(e, chain)| {
            let mut pts: Vec<Position> = Vec::new();
            for (k, w) in chain.windows(2).enumerate() {
                let (a, b) = (pos[w[0]], pos[w[1]]);
                if k > 0 {
                    pts.push(a);
                }
                let at = |x: f64, y: f64| Position { x, y };
                let lane = lane_x[e][k];
                if wraps(w[0], w[1]) {
                    if bands % 2 == 0 {
                        pts.extend([at(left - lane, a.y), at(left - lane, b.y)]);
                    } else {
                        let low = bottom + lane;
                        pts.extend([at(right + lane, a.y), at(right + lane, low)]);
                        pts.extend([at(left - lane, low), at(left - lane, b.y)]);
                    }
                    continue;
                }
                let xm = if turns(w[0], w[1]) {
                    let out = if band_of(slot_layer[w[0]]) % 2 == 0 {
                        1.0
                    } else {
                        -1.0
                    };
                    a.x + out * (dx / 2.0 + lane)
                } else if (a.y - b.y).abs() > 1e-9 {
                    (a.x + b.x) / 2.0 + lane
                } else {
                    let (count, seen) = parallel.get_mut(&key(w[0], w[1])).expect("counted");
                    if *count > 1 {
                        let o = (*seen as f64 - (*count - 1) as f64 / 2.0) * 8.0;
                        *seen += 1;
                        let d = (b.x - a.x) * 0.3;
                        pts.extend([at(a.x + d, a.y + o), at(b.x - d, b.y + o)]);
                    }
                    continue;
                };
                pts.extend([at(xm, a.y), at(xm, b.y)]);
            }
            if flipped[e] {
                pts.reverse();
            }
            pts
        })
        .collect();
    let mut nodes = pos;
    nodes.truncate(n);
    let transitions = nodes.split_off(np);
    Layout {
        places: nodes,
        transitions,
        arcs,
        source: LayoutSource::Layered,
    }
}

/// Which edges to turn round so that the graph has no cycle: the edges that close a cycle in
/// a depth-first walk from the marked places (then from every node not reached yet), so the
/// drawing follows the tokens' direction.
fn back_edges(n: usize, edges: &[(usize, usize)], marked: &[usize]) -> Vec<bool> {
    let mut out: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (e, &(u, _)) in edges.iter().enumerate() {
        out[u].push(e);
    }
    // 0: not seen, 1: on the walk's stack, 2: done.
    let mut state = vec![0u8; n];
    let mut reversed = vec![false; edges.len()];
    let mut stack: Vec<(usize, usize)> = Vec::new();
    for root in marked.iter().copied().chain(0..n) {
        if state[root] != 0 {
            continue;
        }
        state[root] = 1;
        stack.push((root, 0));
        while let Some(top) = stack.last_mut() {
            let (v, next) = *top;
            if next == out[v].len() {
                state[v] = 2;
                stack.pop();
                continue;
            }
            top.1 += 1;
            let e = out[v][next];
            let w = edges[e].1;
            match state[w] {
                0 => {
                    state[w] = 1;
                    stack.push((w, 0));
                }
                1 => reversed[e] = true,
                _ => {}
            }
        }
    }
    reversed
}

/// The layer of each node in an acyclic graph: one past its furthest predecessor; a node
/// without predecessors sits just before its nearest successor (not at the far left).
fn layers(n: usize, dag: &[(usize, usize)]) -> Vec<usize> {
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut indeg = vec![0usize; n];
    for &(u, v) in dag {
        succ[u].push(v);
        indeg[v] += 1;
    }
    let mut layer = vec![0usize; n];
    let mut left = indeg.clone();
    let mut order: Vec<usize> = (0..n).filter(|&v| indeg[v] == 0).collect();
    let mut i = 0;
    while i < order.len() {
        let v = order[i];
        i += 1;
        for &w in &succ[v] {
            layer[w] = layer[w].max(layer[v] + 1);
            left[w] -= 1;
            if left[w] == 0 {
                order.push(w);
            }
        }
    }
    for &v in order.iter().rev() {
        if indeg[v] == 0
            && let Some(l) = succ[v].iter().map(|&w| layer[w]).min()
        {
            layer[v] = l - 1;
        }
    }
    layer
}

/// Slots in the order a depth-first walk along the edges meets them (from the marked places
/// first): the starting order within each layer, which keeps neighbours together.
fn first_seen_order(slots: usize, down: &[Vec<usize>], marked: &[usize]) -> Vec<usize> {
    let mut seen = vec![false; slots];
    let mut order = Vec::with_capacity(slots);
    let mut stack = Vec::new();
    for root in marked.iter().copied().chain(0..slots) {
        if seen[root] {
            continue;
        }
        stack.push(root);
        while let Some(v) = stack.pop() {
            if seen[v] {
                continue;
            }
            seen[v] = true;
            order.push(v);
            stack.extend(down[v].iter().rev().filter(|&&w| !seen[w]));
        }
    }
    order
}

/// Reorders each layer by the mean position of its neighbours, sweeping down and up, and
/// keeps the order with the fewest crossings.
fn order_layers(layers: &mut [Vec<usize>], up: &[Vec<usize>], down: &[Vec<usize>], slots: usize) {
    let mut index = vec![0usize; slots];
    let reindex = |layers: &[Vec<usize>], index: &mut [usize]| {
        for nodes in layers {
            for (i, &s) in nodes.iter().enumerate() {
                index[s] = i;
            }
        }
    };
    reindex(layers, &mut index);
    let mut best = layers.to_vec();
    let mut best_crossings = crossings(layers, down, &index);
    let sweeps = if slots > 20_000 { 4 } else { 24 };
    for sweep in 0..sweeps {
        let downwards = sweep % 2 == 0;
        let order: Vec<usize> = if downwards {
            (1..layers.len()).collect()
        } else {
            (0..layers.len().saturating_sub(1)).rev().collect()
        };
        for l in order {
            let nb = if downwards { up } else { down };
            let mut keyed: Vec<(f64, usize)> = layers[l]
                .iter()
                .map(|&s| {
                    let key = if nb[s].is_empty() {
                        index[s] as f64
                    } else {
                        nb[s].iter().map(|&o| index[o] as f64).sum::<f64>() / nb[s].len() as f64
                    };
                    (key, s)
                })
                .collect();
            keyed.sort_by(|a, b| a.0.total_cmp(&b.0));
            layers[l] = keyed.into_iter().map(|(_, s)| s).collect();
            for (i, &s) in layers[l].iter().enumerate() {
                index[s] = i;
            }
        }
        let c = crossings(layers, down, &index);
        if c < best_crossings {
            best_crossings = c;
            best = layers.to_vec();
        }
    }
    layers.clone_from_slice(&best);
}

/// Pairs of edges that cross between neighbouring layers (`index`: position in the layer).
fn crossings(layers: &[Vec<usize>], down: &[Vec<usize>], index: &[usize]) -> u64 {
    let mut total = 0;
    for nodes in layers {
        let mut ends: Vec<(usize, usize)> = nodes
            .iter()
            .flat_map(|&u| down[u].iter().map(move |&v| (index[u], index[v])))
            .collect();
        ends.sort_unstable();
        let mut b: Vec<usize> = ends.into_iter().map(|(_, b)| b).collect();
        total += inversions(&mut b);
    }
    total
}

/// Pairs `i < j` with `v[i] > v[j]` (merge sort; `v` ends sorted).
fn inversions(v: &mut [usize]) -> u64 {
    if v.len() < 2 {
        return 0;
    }
    let mid = v.len() / 2;
    let mut count = inversions(&mut v[..mid]) + inversions(&mut v[mid..]);
    let mut merged = Vec::with_capacity(v.len());
    let (mut i, mut j) = (0, mid);
    while i < mid && j < v.len() {
        if v[j] < v[i] {
            count += (mid - i) as u64;
            merged.push(v[j]);
            j += 1;
        } else {
            merged.push(v[i]);
            i += 1;
        }
    }
    merged.extend_from_slice(&v[i..mid]);
    merged.extend_from_slice(&v[j..]);
    v.copy_from_slice(&merged);
    count
}

/// Values as close as possible (least squares) to `target`, in the same order, each at
/// least `gap` above the one before (pool-adjacent-violators on `target[i] - i·gap`).
fn spaced(target: &[f64], gap: f64) -> Vec<f64> {
    // Blocks of (sum, count) of shifted targets, means non-decreasing.
    let mut blocks: Vec<(f64, usize)> = Vec::new();
    for (i, &t) in target.iter().enumerate() {
        blocks.push((t - i as f64 * gap, 1));
        while blocks.len() > 1 {
            let (s2, c2) = blocks[blocks.len() - 1];
            let (s1, c1) = blocks[blocks.len() - 2];
            if s1 / c1 as f64 <= s2 / c2 as f64 {
                break;
            }
            blocks.pop();
            *blocks.last_mut().expect("two blocks") = (s1 + s2, c1 + c2);
        }
    }
    let mut out = Vec::with_capacity(target.len());
    for (s, c) in blocks {
        for _ in 0..c {
            let i = out.len();
            out.push(s / c as f64 + i as f64 * gap);
        }
    }
    out
}

/// Height taken by the slots of one layer.
fn span(nodes: &[usize], y: &[f64]) -> f64 {
    let (lo, hi) = nodes.iter().fold((f64::MAX, f64::MIN), |(lo, hi), &s| {
        (lo.min(y[s]), hi.max(y[s]))
    });
    if nodes.is_empty() { 0.0 } else { hi - lo }
}

/// The distance between layers: room for the longest name (nodes' names are centred under
/// them, GreatSPN-style names like `p1:Check_Temperature_L1` are long) and for the lanes
/// between them; at least [`DX`], at most three times that.
fn layer_gap(net: &Net) -> f64 {
    let longest = net
        .places()
        .iter()
        .map(|p| p.name.chars().count())
        .chain(net.transitions().iter().map(|t| t.name.chars().count()))
        .max()
        .unwrap_or(0);
    (longest as f64 * CHAR_WIDTH + LANES + 16.0).clamp(DX, 3.0 * DX)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::net::{NetBuilder, Servers};

    #[test]
    fn ring_wraps_into_bands_without_overlaps() {
        let mut b = NetBuilder::new("ring");
        let n = 400;
        let places: Vec<_> = (0..n)
            .map(|i| b.place(format!("p{i}"), u32::from(i == 0)))
            .collect();
        for i in 0..n {
            let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
            b.input(places[i], t, 1);
            b.output(t, places[(i + 1) % n], 1);
        }
        let l = layout(&b.build().unwrap());
        let mut all: Vec<(i64, i64)> = l
            .places
            .iter()
            .chain(&l.transitions)
            .map(|p| (p.x as i64, p.y as i64))
            .collect();
        let width = all.iter().map(|p| p.0).max().unwrap();
        let height = all.iter().map(|p| p.1).max().unwrap();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 2 * n);
        assert!(width < 6000 && height < 8000, "{width} x {height}");
    }

    #[test]
    fn long_names_spread_the_layers() {
        let mut b = NetBuilder::new("names");
        let p = b.place("p1:Check_Temperature_L1", 1);
        let q = b.place("p2:Alarm_L1_with_a_long_name", 0);
        let t = b.exponential("t1:Temperature_High_L1", 1.0, Servers::Single);
        b.input(p, t, 1);
        b.output(t, q, 1);
        let l = layout(&b.build().unwrap());
        // The longest name has 28 characters.
        let gap = 28.0 * CHAR_WIDTH + LANES + 16.0;
        assert!((l.transitions[0].x - l.places[0].x - gap).abs() < 1e-9);
        assert!((l.places[1].x - l.transitions[0].x - gap).abs() < 1e-9);
        assert!(l.arcs.iter().all(Vec::is_empty), "{:?}", l.arcs);
    }

    /// A patrol of `k` locations like the thesis's: check (with an alarm loop), decide (with
    /// a wait loop), go to the next location.
    fn patrol(k: usize) -> Net {
        let mut b = NetBuilder::new("patrol");
        let mut checks = Vec::new();
        let mut decides = Vec::new();
        for i in 0..k {
            checks.push(b.place(format!("check{i}"), 1));
            decides.push(b.place(format!("decide{i}"), 0));
        }
        for i in 0..k {
            let alarm = b.place(format!("alarm{i}"), 0);
            let wait = b.place(format!("wait{i}"), 0);
            let loop2 = |b: &mut NetBuilder, from, to, name: &str| {
                let t = b.exponential(format!("{name}{i}"), 1.0, Servers::Single);
                b.input(from, t, 1);
                b.output(t, to, 1);
            };
            loop2(&mut b, checks[i], alarm, "high");
            loop2(&mut b, alarm, checks[i], "off");
            loop2(&mut b, checks[i], decides[i], "low");
            loop2(&mut b, decides[i], wait, "go_wait");
            loop2(&mut b, wait, decides[i], "done");
            loop2(&mut b, decides[i], checks[(i + 1) % k], "go");
        }
        b.build().unwrap()
    }

    /// The polyline of arc `i` between the centres of its nodes.
    fn polyline(net: &Net, l: &Layout, i: usize) -> Vec<Position> {
        let a = &net.arcs()[i];
        let (p, t) = (
            l.places[a.place.index()],
            l.transitions[a.transition.index()],
        );
        let (from, to) = if a.kind == ArcKind::Output {
            (t, p)
        } else {
            (p, t)
        };
        let mut pts = vec![from];
        pts.extend(l.arcs[i].iter().copied());
        pts.push(to);
        pts
    }

    /// Whether the segment a–b comes within `r` of `c`.
    fn near(a: Position, b: Position, c: Position, r: f64) -> bool {
        let (dx, dy) = (b.x - a.x, b.y - a.y);
        let len2 = dx * dx + dy * dy;
        let s = if len2 == 0.0 {
            0.0
        } else {
            (((c.x - a.x) * dx + (c.y - a.y) * dy) / len2).clamp(0.0, 1.0)
        };
        let (px, py) = (a.x + s * dx - c.x, a.y + s * dy - c.y);
        px * px + py * py < r * r
    }

    #[test]
    fn routed_arcs_miss_every_node_they_do_not_join() {
        for k in [1, 2, 4, 7] {
            let net = patrol(k);
            let l = layout(&net);
            let nodes: Vec<Position> = l.places.iter().chain(&l.transitions).copied().collect();
            let np = net.place_count();
            for (i, a) in net.arcs().iter().enumerate() {
                let own = [a.place.index(), np + a.transition.index()];
                let pts = polyline(&net, &l, i);
                for (v, &c) in nodes.iter().enumerate() {
                    if own.contains(&v) {
                        continue;
                    }
                    for w in pts.windows(2) {
                        assert!(!near(w[0], w[1], c, 20.0), "k={k}: arc {i} passes node {v}");
                    }
                }
                // Orthogonal: every bend changes only one coordinate.
                for w in pts[1..pts.len() - 1].windows(2) {
                    assert!(
                        w[0].x == w[1].x || w[0].y == w[1].y,
                        "k={k} arc {i}: {pts:?}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_cycle_closes_on_itself() {
        // The arc that closes the patrol's big cycle (`go3` → `check0`) runs round the side
        // of the drawing to the first column, not back along the whole cycle.
        let net = patrol(4);
        let l = layout(&net);
        let i = net
            .arcs()
            .iter()
            .position(|a| {
                net.transition(a.transition).name == "go3" && net.place(a.place).name == "check0"
            })
            .unwrap();
        let length: f64 = polyline(&net, &l, i)
            .windows(2)
            .map(|w| (w[1].x - w[0].x).abs() + (w[1].y - w[0].y).abs())
            .sum();
        let height = l.places.iter().map(|p| p.y).fold(0.0, f64::max);
        let width = l.places.iter().map(|p| p.x).fold(0.0, f64::max);
        assert!(
            length < height + width / 2.0,
            "{length}: {width} x {height}"
        );
    }

    #[test]
    fn helpers() {
        assert_eq!(inversions(&mut [3, 1, 2]), 2);
        assert_eq!(inversions(&mut [0, 1, 2]), 0);
        let y = spaced(&[0.0, 0.0, 100.0], 10.0);
        assert_eq!(y, vec![-5.0, 5.0, 100.0]);
    }
}
