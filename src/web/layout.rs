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

mod bands;
mod group;
mod order;
pub(crate) mod quality;

use bands::{Bands, spaced};
#[cfg(test)]
use order::inversions;
use order::{back_edges, first_seen_order, group_bands, layers, order_layers, tighten};

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
/// How many crossings (between neighbouring layers) keeping the groups together may cost:
/// at most `a × free + b`, `free` those of the order found without groups. (Measured:
/// GSPNR's `home_timeouts_meeting` went from 15 to 47 crossings grouped, for 2 fewer nodes
/// in another location's box; the patrol from 19 to 15, 14 fewer.)
const GROUPED_CROSSINGS: (f64, f64) = (1.25, 4.0);
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

/// Which positions to draw: the viewer's `layout` control.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Choice {
    /// The file's positions unless they are useless ([`quality::useless`]), else automatic.
    #[default]
    Default,
    /// The file's positions whenever every node has one.
    File,
    /// The automatic layout, whatever the file says.
    Automatic,
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

/// The file's positions if every node has one and they are worth drawing
/// ([`quality::useless`]), otherwise a layered layout.
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
    choose(net, Choice::Default).0
}

/// The layout `choice` asks for, with the reason the file's positions were set aside when
/// they were (the default choice on useless positions).
pub fn choose(net: &Net, choice: Choice) -> (Layout, Option<String>) {
    match (file_layout(net), choice) {
        (Some(f), Choice::File) => (f, None),
        (Some(f), Choice::Default) => match quality::useless(net, &f) {
            Some(why) => (layered(net), Some(why)),
            None => (f, None),
        },
        _ => (layered(net), None),
    }
}

/// Whether every node of `net` has a position in its file.
pub fn has_positions(net: &Net) -> bool {
    net.places().iter().all(|p| p.position.is_some())
        && net.transitions().iter().all(|t| t.position.is_some())
}

/// The file's positions, when it gives one for every node.
fn file_layout(net: &Net) -> Option<Layout> {
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
    from_file.map(|(places, transitions)| Layout {
        places,
        transitions,
        arcs: net.arcs().iter().map(|a| a.points.clone()).collect(),
        source: LayoutSource::File,
    })
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
/// source to its target (an inhibitor arc from its place). The phases of the module's
/// method, one function each: [`Slots::new`] (cycles broken, layers, placeholders),
/// [`Slots::order`] (order within the layers), [`Slots::rows`], [`Bands::fold`] (columns
/// and bands), [`Slots::route`] (the arcs).
fn layered(net: &Net) -> Layout {
    layered_with(net, true)
}

/// [`layered`], keeping the groups of the names together ([`group`]) or not.
fn layered_with(net: &Net, grouped: bool) -> Layout {
    let np = net.place_count();
    let n = np + net.transition_count();
    let slots = Slots::new(net, grouped);
    let layers = slots.order();
    let mut y = slots.rows(&layers);
    let bands = Bands::fold(&layers, &mut y, layer_gap(net));
    let pos: Vec<Position> = (0..slots.layer.len())
        .map(|s| Position {
            x: 40.0 + bands.column(slots.layer[s]) as f64 * bands.dx,
            y: y[s],
        })
        .collect();
    let arcs = slots.route(&bands, &pos);
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

/// The layered graph: the nodes, then one placeholder per layer an arc passes through.
struct Slots {
    /// The layer of each slot.
    layer: Vec<usize>,
    /// How many layers.
    layer_count: usize,
    /// Per arc, the slots it runs through, in layer order.
    chains: Vec<Vec<usize>>,
    /// Per arc, whether its chain runs against the arc (a turned-round arc drawn back).
    flipped: Vec<bool>,
    /// Per slot, the slots one layer before it on a chain.
    up: Vec<Vec<usize>>,
    /// Per slot, the slots one layer after it on a chain.
    down: Vec<Vec<usize>>,
    /// The marked places, where the walks start.
    marked: Vec<usize>,
    /// The group of each slot ([`group::groups`]: a node by its name, a placeholder by its
    /// arc's ends when they share one), when the names give groups.
    group: Option<Vec<Option<usize>>>,
}

impl Slots {
    /// Cycles broken (the back edges of a depth-first walk from the marked places turned
    /// round), each node one layer past its furthest predecessor, and a placeholder in each
    /// layer an arc crosses.
    fn new(net: &Net, grouped: bool) -> Slots {
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
        let mut layer = layers(n, &dag);
        tighten(&mut layer, &dag);
        let layer_count = layer.iter().map(|&l| l + 1).max().unwrap_or(0);

        // An arc that was turned round runs back through the layers it spans, or, when that
        // is shorter, on to the last layer and round to the first (the bands fold so that
        // these are near each other): the arc that closes a long cycle.
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
        let names = net.places().iter().map(|p| p.name.as_str());
        let group = group::groups(names.chain(net.transitions().iter().map(|t| t.name.as_str())))
            .filter(|_| grouped)
            .map(|mut g| {
                g.resize(slots, None);
                for chain in &chains {
                    let (a, b) = (chain[0], chain[chain.len() - 1]);
                    if g[a] == g[b] {
                        for &s in &chain[1..chain.len() - 1] {
                            g[s] = g[a];
                        }
                    }
                }
                g
            });
        let mut up: Vec<Vec<usize>> = vec![Vec::new(); slots];
        let mut down: Vec<Vec<usize>> = vec![Vec::new(); slots];
        for chain in &chains {
            for w in chain.windows(2) {
                down[w[0]].push(w[1]);
                up[w[1]].push(w[0]);
            }
        }
        Slots {
            layer: slot_layer,
            layer_count,
            chains,
            flipped,
            up,
            down,
            marked,
            group,
        }
    }

    /// The slots of each layer, ordered by the mean position of their neighbours; with
    /// groups, then again with each group's slots kept together — that order kept unless
    /// it crosses many more arcs ([`GROUPED_CROSSINGS`]).
    fn order(&self) -> Vec<Vec<usize>> {
        let slots = self.layer.len();
        let mut layers: Vec<Vec<usize>> = vec![Vec::new(); self.layer_count];
        for s in first_seen_order(slots, &self.down, &self.marked) {
            layers[self.layer[s]].push(s);
        }
        let free = order_layers(&mut layers, &self.up, &self.down, slots, None);
        if let Some(group) = &self.group {
            let band = group_bands(&layers, group, &self.up, &self.down);
            let mut grouped = layers.clone();
            let kept = order_layers(&mut grouped, &self.up, &self.down, slots, Some(&band));
            if kept as f64 <= GROUPED_CROSSINGS.0 * free as f64 + GROUPED_CROSSINGS.1 {
                return grouped;
            }
        }
        layers
    }

    /// Rows: each layer keeps its order, nodes at least DY apart, pulled towards the rows
    /// of their neighbours (a few sweeps each way).
    fn rows(&self, layers: &[Vec<usize>]) -> Vec<f64> {
        let layer_count = self.layer_count;
        let mut y = vec![0.0; self.layer.len()];
        for nodes in layers {
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
                        let nb: Vec<usize> =
                            self.up[s].iter().chain(&self.down[s]).copied().collect();
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
        y
    }

    /// Arcs: straight between neighbouring layers on one row; otherwise out along the row,
    /// across in the middle of the gap between the columns (each arc in its own lane), and
    /// in along the other row. Between bands the arc goes round the outside of the end
    /// column; from the last layer to the first, round the outside of the drawing. Two arcs
    /// between the same two slots on one row run side by side.
    fn route(&self, bands: &Bands, pos: &[Position]) -> Vec<Vec<Position>> {
        let slot_layer = &self.layer;
        let dx = bands.dx;
        let key = |a: usize, b: usize| (a.min(b), a.max(b));
        let mut parallel: HashMap<(usize, usize), (usize, usize)> = HashMap::new();
        for chain in &self.chains {
            for w in chain.windows(2) {
                parallel.entry(key(w[0], w[1])).or_default().0 += 1;
            }
        }
        let wraps = |a: usize, b: usize| slot_layer[b] < slot_layer[a];
        let turns =
            |a: usize, b: usize| bands.band_of(slot_layer[a]) != bands.band_of(slot_layer[b]);
        let lane_x = self.lanes(pos, &wraps, &turns);
        let left = 40.0 - dx / 2.0;
        let right = 40.0 + (bands.per_band - 1) as f64 * dx + dx / 2.0;
        let bottom = bands.top[bands.count] - DY;
        self.chains
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
                        if bands.count.is_multiple_of(2) {
                            pts.extend([at(left - lane, a.y), at(left - lane, b.y)]);
                        } else {
                            let low = bottom + lane;
                            pts.extend([at(right + lane, a.y), at(right + lane, low)]);
                            pts.extend([at(left - lane, low), at(left - lane, b.y)]);
                        }
                        continue;
                    }
                    let xm = if turns(w[0], w[1]) {
                        let out = if bands.band_of(slot_layer[w[0]]).is_multiple_of(2) {
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
                if self.flipped[e] {
                    pts.reverse();
                }
                pts
            })
            .collect()
    }

    /// Per arc and step of its chain, the offset of the lane where it changes row. Per gap
    /// after a layer, the steps that change row there; the last gap also holds the steps
    /// round the outside (lanes counted outwards from the end column).
    fn lanes(
        &self,
        pos: &[Position],
        wraps: &impl Fn(usize, usize) -> bool,
        turns: &impl Fn(usize, usize) -> bool,
    ) -> Vec<Vec<f64>> {
        let layer_count = self.layer_count;
        let mut lanes: Vec<Vec<(f64, usize, usize)>> = vec![Vec::new(); layer_count + 1];
        for (e, chain) in self.chains.iter().enumerate() {
            for (k, w) in chain.windows(2).enumerate() {
                let gap = if wraps(w[0], w[1]) {
                    layer_count
                } else if (pos[w[0]].y - pos[w[1]].y).abs() > 1e-9 || turns(w[0], w[1]) {
                    self.layer[w[0]]
                } else {
                    continue;
                };
                lanes[gap].push(((pos[w[0]].y + pos[w[1]].y) / 2.0, e, k));
            }
        }
        let mut lane_x: Vec<Vec<f64>> =
            self.chains.iter().map(|c| vec![0.0; c.len() - 1]).collect();
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
        lane_x
    }
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
mod tests;
