//! Where the viewer draws each place and transition: the file's positions when it gives one
//! for every node, otherwise an automatic layered layout.
//!
//! The layered layout walks the net breadth-first along its arcs (place → transition through
//! input arcs, transition → place through output arcs), starting from the marked places
//! (then from any node not reached yet), so each node's layer is its distance from the
//! tokens. Layers become columns; a net with more layers than fit in a square wraps them
//! into bands one below the other, so a long ring is drawn as a block, not a line.

use std::collections::VecDeque;

use serde::Serialize;

use crate::net::{ArcKind, Net, NetBuilder, NetError, Place, Position, Transition};

/// Horizontal distance between layers (at least; more for long names, see [`layer_gap`]).
const DX: f64 = 90.0;
/// Width of one character of a label on the page (11 px sans-serif), for [`layer_gap`].
const CHAR_WIDTH: f64 = 6.2;
/// Vertical distance between nodes of one layer.
const DY: f64 = 70.0;

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

/// Nodes are places `0..np` then transitions `np..np+nt`.
fn layered(net: &Net) -> Layout {
    let np = net.place_count();
    let n = np + net.transition_count();
    let mut succ: Vec<Vec<u32>> = vec![Vec::new(); n];
    for a in net.arcs() {
        let (p, t) = (a.place.index(), np + a.transition.index());
        match a.kind {
            ArcKind::Input => succ[p].push(t as u32),
            ArcKind::Output => succ[t].push(p as u32),
            ArcKind::Inhibitor => {}
        }
    }
    let mut layer = vec![u32::MAX; n];
    let mut queue = VecDeque::new();
    let marked = net
        .places()
        .iter()
        .enumerate()
        .filter(|(_, p)| p.initial > 0)
        .map(|(i, _)| i);
    let mut roots: Vec<usize> = marked.collect();
    roots.extend(0..n);
    for root in roots {
        if layer[root] != u32::MAX {
            continue;
        }
        // A new component (or part not reached from the tokens) starts at layer 0.
        layer[root] = 0;
        queue.push_back(root);
        while let Some(v) = queue.pop_front() {
            for &w in &succ[v] {
                let w = w as usize;
                if layer[w] == u32::MAX {
                    layer[w] = layer[v] + 1;
                    queue.push_back(w);
                }
            }
        }
    }
    let layers = layer.iter().map(|&l| l as usize + 1).max().unwrap_or(0);
    let mut members: Vec<Vec<usize>> = vec![Vec::new(); layers];
    for (v, &l) in layer.iter().enumerate() {
        members[l as usize].push(v);
    }
    // Wrap the layers into bands of `per_band` columns, about as wide as the net is tall
    // (and at least about 1,100 units wide).
    let dx = layer_gap(net);
    let tallest = members.iter().map(Vec::len).max().unwrap_or(1).max(1);
    let per_band = ((n as f64 / tallest as f64 * DY / dx).sqrt().ceil() as usize)
        .max((1080.0 / dx).ceil() as usize);
    let band_height = tallest as f64 * DY + DY;
    let mut pos = vec![Position { x: 0.0, y: 0.0 }; n];
    for (l, nodes) in members.iter().enumerate() {
        let (band, col) = (l / per_band, l % per_band);
        for (row, &v) in nodes.iter().enumerate() {
            pos[v] = Position {
                x: 40.0 + col as f64 * dx,
                y: 40.0 + band as f64 * band_height + row as f64 * DY,
            };
        }
    }
    let transitions = pos.split_off(np);
    Layout {
        places: pos,
        transitions,
        source: LayoutSource::Layered,
    }
}

/// The distance between layers: [`DX`], or more when most names (nine in ten) would not fit
/// between neighbouring nodes (GreatSPN-style names like `p1:Check_Temperature_L1`).
fn layer_gap(net: &Net) -> f64 {
    let mut lengths: Vec<usize> = net
        .places()
        .iter()
        .map(|p| p.name.chars().count())
        .chain(net.transitions().iter().map(|t| t.name.chars().count()))
        .collect();
    if lengths.is_empty() {
        return DX;
    }
    lengths.sort_unstable();
    let typical = lengths[(lengths.len() - 1) * 9 / 10];
    (typical as f64 * CHAR_WIDTH + 16.0).clamp(DX, 3.0 * DX)
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
        assert!(width < 4000 && height < 8000, "{width} x {height}");
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
        // Lengths 22, 23, 28: the nine-in-ten one is the second, 23 characters.
        let gap = 23.0 * CHAR_WIDTH + 16.0;
        assert!((l.transitions[0].x - l.places[0].x - gap).abs() < 1e-9);
        assert!((l.places[1].x - l.transitions[0].x - gap).abs() < 1e-9);
    }
}
