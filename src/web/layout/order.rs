//! The layered layout's graph steps: breaking cycles, assigning layers, ordering each layer
//! to keep crossings few.

/// Which edges to turn round so that the graph has no cycle: the edges that close a cycle in
/// a depth-first walk from the marked places (then from every node not reached yet), so the
/// drawing follows the tokens' direction.
pub(super) fn back_edges(n: usize, edges: &[(usize, usize)], marked: &[usize]) -> Vec<bool> {
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
pub(super) fn layers(n: usize, dag: &[(usize, usize)]) -> Vec<usize> {
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

/// Shortens the arcs of a layering (`layer` of an acyclic graph, each edge going down at
/// least one layer): a node with more incoming than outgoing edges moves up to just below its
/// lowest predecessor, one with more outgoing edges down to just above its highest
/// successor — each move shortens its edges in total, so there are fewer placeholders to
/// order and cross (a few passes, until nothing moves).
pub(super) fn tighten(layer: &mut [usize], dag: &[(usize, usize)]) {
    let n = layer.len();
    let mut pred: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut succ: Vec<Vec<usize>> = vec![Vec::new(); n];
    for &(u, v) in dag {
        if u != v {
            succ[u].push(v);
            pred[v].push(u);
        }
    }
    for _ in 0..8 {
        let mut moved = false;
        for v in 0..n {
            let (ins, outs) = (pred[v].len(), succ[v].len());
            let target = if ins > outs {
                pred[v].iter().map(|&u| layer[u] + 1).max()
            } else if outs > ins {
                succ[v].iter().map(|&w| layer[w]).min().map(|l| l - 1)
            } else {
                None
            };
            if let Some(t) = target
                && t != layer[v]
            {
                layer[v] = t;
                moved = true;
            }
        }
        if !moved {
            break;
        }
    }
}

/// Slots in the order a depth-first walk along the edges meets them (from the marked places
/// first): the starting order within each layer, which keeps neighbours together.
pub(super) fn first_seen_order(slots: usize, down: &[Vec<usize>], marked: &[usize]) -> Vec<usize> {
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

/// Reorders each layer by the mean position of its neighbours, sweeping down and up, then
/// swaps neighbours in a layer while that removes crossings (transposes, on nets small
/// enough); keeps the order with the fewest crossings. (The median instead of the mean drew
/// more crossings on Peterson and Dekker: docs/viewer.md.) Returns the crossings between
/// neighbouring layers of the order kept. With `band`, a layer is ordered
/// by each slot's band first (its group's rank, [`group_bands`]), so a group's slots stay
/// next to each other.
pub(super) fn order_layers(
    layers: &mut [Vec<usize>],
    up: &[Vec<usize>],
    down: &[Vec<usize>],
    slots: usize,
    band: Option<&[f64]>,
) -> u64 {
    let band_of = |s: usize| band.map_or(0.0, |b| b[s]);
    if band.is_some() {
        for nodes in layers.iter_mut() {
            nodes.sort_by(|&a, &b| band_of(a).total_cmp(&band_of(b)));
        }
    }
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
            let mut keyed: Vec<((f64, f64), usize)> = layers[l]
                .iter()
                .map(|&s| {
                    let key = if nb[s].is_empty() {
                        index[s] as f64
                    } else {
                        nb[s].iter().map(|&o| index[o] as f64).sum::<f64>() / nb[s].len() as f64
                    };
                    ((band_of(s), key), s)
                })
                .collect();
            keyed.sort_by(|a, b| a.0.0.total_cmp(&b.0.0).then(a.0.1.total_cmp(&b.0.1)));
            layers[l] = keyed.into_iter().map(|(_, s)| s).collect();
            for (i, &s) in layers[l].iter().enumerate() {
                index[s] = i;
            }
        }
        if slots <= TRANSPOSE_MAX {
            transpose(layers, up, down, &mut index, &band_of);
        }
        let c = crossings(layers, down, &index);
        if c < best_crossings {
            best_crossings = c;
            best = layers.to_vec();
        }
    }
    layers.clone_from_slice(&best);
    best_crossings
}

/// Each slot's band for [`order_layers`] from an order found without bands: the groups
/// ranked by the mean relative position of their slots in their layers; a slot of no group
/// (a placeholder between groups, a node no name places) takes the mean band of its
/// neighbours that have one, or else that of the slot before it in its layer.
pub(super) fn group_bands(
    layers: &[Vec<usize>],
    group: &[Option<usize>],
    up: &[Vec<usize>],
    down: &[Vec<usize>],
) -> Vec<f64> {
    let groups = group.iter().flatten().map(|&g| g + 1).max().unwrap_or(0);
    let mut sum = vec![(0.0, 0usize); groups];
    for nodes in layers {
        for (i, &s) in nodes.iter().enumerate() {
            if let Some(g) = group[s] {
                sum[g].0 += (i as f64 + 0.5) / nodes.len() as f64;
                sum[g].1 += 1;
            }
        }
    }
    let mut ranked: Vec<usize> = (0..groups).collect();
    let mean = |g: usize| sum[g].0 / sum[g].1.max(1) as f64;
    ranked.sort_by(|&a, &b| mean(a).total_cmp(&mean(b)));
    let mut rank = vec![0.0; groups];
    for (r, &g) in ranked.iter().enumerate() {
        rank[g] = r as f64;
    }
    let mut band: Vec<Option<f64>> = group.iter().map(|g| g.map(|g| rank[g])).collect();
    // Placeholders of an arc between two groups sit between their bands.
    for _ in 0..2 {
        for s in 0..group.len() {
            if group[s].is_some() {
                continue;
            }
            let known: Vec<f64> = up[s]
                .iter()
                .chain(&down[s])
                .filter_map(|&o| band[o])
                .collect();
            if !known.is_empty() {
                band[s] = Some(known.iter().sum::<f64>() / known.len() as f64);
            }
        }
    }
    let mut out = vec![0.0; group.len()];
    for nodes in layers {
        let mut before = 0.0;
        for &s in nodes {
            before = band[s].unwrap_or(before);
            out[s] = before;
        }
    }
    out
}

/// Most slots for which [`transpose`] runs (it looks at every neighbouring pair of a layer,
/// repeatedly).
const TRANSPOSE_MAX: usize = 5_000;

/// Swaps neighbouring slots of a layer while that lowers the crossings of their edges with
/// both neighbouring layers (at most a few passes).
fn transpose(
    layers: &mut [Vec<usize>],
    up: &[Vec<usize>],
    down: &[Vec<usize>],
    index: &mut [usize],
    band_of: &impl Fn(usize) -> f64,
) {
    // Crossings between the edges of `u` and of `v` when `u` is left of `v`.
    let pair = |u: usize, v: usize, index: &[usize]| -> usize {
        let mut c = 0;
        for nb in [up, down] {
            for &a in &nb[u] {
                c += nb[v].iter().filter(|&&b| index[a] > index[b]).count();
            }
        }
        c
    };
    for _ in 0..4 {
        let mut improved = false;
        for nodes in layers.iter_mut() {
            for i in 1..nodes.len() {
                let (u, v) = (nodes[i - 1], nodes[i]);
                if band_of(u) == band_of(v) && pair(v, u, index) < pair(u, v, index) {
                    nodes.swap(i - 1, i);
                    index[u] = i;
                    index[v] = i - 1;
                    improved = true;
                }
            }
        }
        if !improved {
            break;
        }
    }
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
pub(super) fn inversions(v: &mut [usize]) -> u64 {
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
