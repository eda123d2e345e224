//! How readable a layout is, measured as the page would draw it: nodes on top of each other,
//! arcs through nodes, arcs crossing arcs. One home for the rule that decides that a file's
//! positions are useless ([`useless`]) and for the numbers `docs/viewer.md` reports.

use crate::net::{ArcKind, Net, Position};

use super::Layout;

/// Radius of a place on the page (`R` in `app.js`).
const PLACE_R: f64 = 18.0;
/// Half the height of a transition on the page (`TH / 2` in `app.js`).
const TRANSITION_HH: f64 = 15.0;
/// The page scales a file's units so that the median distance to the nearest node is this
/// many pixels (`scaleCoordinates` in `app.js`), never below one pixel per unit.
const NEAREST_PX: f64 = 70.0;

/// What [`measure`] counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Quality {
    /// Pairs of nodes whose bodies overlap.
    pub overlaps: usize,
    /// Arc segments that pass through the body of a node other than their ends.
    pub through_nodes: usize,
    /// Pairs of arc segments that cross (segments of arcs sharing a node not counted where
    /// they meet at it).
    pub crossings: usize,
}

/// A node's body as the page draws it, in page pixels.
#[derive(Clone, Copy)]
struct Body {
    x: f64,
    y: f64,
    /// Half width and half height (a circle: both its radius).
    hw: f64,
    hh: f64,
    circle: bool,
}

/// The scale the page draws `layout` at (pixels per unit).
fn page_scale(layout: &Layout) -> f64 {
    let all: Vec<&Position> = layout
        .places
        .iter()
        .chain(&layout.transitions)
        .take(400)
        .collect();
    let mut nearest: Vec<f64> = all
        .iter()
        .filter_map(|a| {
            all.iter()
                .map(|b| (a.x - b.x).hypot(a.y - b.y))
                .filter(|&d| d > 0.0)
                .min_by(f64::total_cmp)
        })
        .collect();
    if nearest.is_empty() {
        return 1.0;
    }
    nearest.sort_by(f64::total_cmp);
    (NEAREST_PX / nearest[nearest.len() / 2]).max(1.0)
}

fn bodies(net: &Net, layout: &Layout, s: f64) -> Vec<Body> {
    let places = layout.places.iter().map(|p| Body {
        x: p.x * s,
        y: p.y * s,
        hw: PLACE_R,
        hh: PLACE_R,
        circle: true,
    });
    let transitions = net
        .transitions()
        .iter()
        .zip(&layout.transitions)
        .map(|(t, p)| Body {
            x: p.x * s,
            y: p.y * s,
            hw: if t.is_immediate() { 3.0 } else { 10.0 },
            hh: TRANSITION_HH,
            circle: false,
        });
    places.chain(transitions).collect()
}

/// Counts what makes `layout` of `net` hard to read (see [`Quality`]).
pub(crate) fn measure(net: &Net, layout: &Layout) -> Quality {
    let s = page_scale(layout);
    let body = bodies(net, layout, s);
    let np = net.place_count();
    let mut q = Quality::default();
    for (i, a) in body.iter().enumerate() {
        for b in &body[i + 1..] {
            if (a.x - b.x).abs() < a.hw + b.hw && (a.y - b.y).abs() < a.hh + b.hh {
                q.overlaps += 1;
            }
        }
    }
    // Every arc's segments, from the centre of its place to the centre of its transition
    // through its bends, with the nodes at its two ends.
    let mut segments: Vec<([f64; 2], [f64; 2], usize, usize)> = Vec::new();
    for (arc, bends) in net.arcs().iter().zip(&layout.arcs) {
        let (p, t) = (arc.place.index(), np + arc.transition.index());
        let mut pts = vec![[body[p].x, body[p].y]];
        let inner: Vec<[f64; 2]> = bends.iter().map(|b| [b.x * s, b.y * s]).collect();
        if arc.kind == ArcKind::Output {
            pts.extend(inner.iter().rev());
        } else {
            pts.extend(inner);
        }
        pts.push([body[t].x, body[t].y]);
        for w in pts.windows(2) {
            segments.push((w[0], w[1], p, t));
        }
    }
    for &(a, b, p, t) in &segments {
        for (k, n) in body.iter().enumerate() {
            if k != p && k != t && hits(a, b, n) {
                q.through_nodes += 1;
            }
        }
    }
    for (i, &(a, b, p, t)) in segments.iter().enumerate() {
        for &(c, d, p2, t2) in &segments[i + 1..] {
            // Segments of arcs at one node meet there: only a crossing elsewhere counts.
            let shared = p == p2 || t == t2;
            if crosses(a, b, c, d) && !(shared && touches_end(a, b, c, d)) {
                q.crossings += 1;
            }
        }
    }
    q
}

/// How well `layout` keeps the groups of `net`'s names together ([`super::group`]): the
/// nodes whose centre lies in the bounding box (of the bodies) of a group they are not in,
/// counted once per such box, and the number of groups; `None` when the names give none.
#[cfg(test)]
pub(crate) fn group_mixing(net: &Net, layout: &Layout) -> Option<(usize, usize)> {
    let names = net.places().iter().map(|p| p.name.as_str());
    let group =
        super::group::groups(names.chain(net.transitions().iter().map(|t| t.name.as_str())))?;
    let body = bodies(net, layout, page_scale(layout));
    let groups = group.iter().flatten().map(|&g| g + 1).max().unwrap_or(0);
    let mut boxes = vec![[f64::MAX, f64::MAX, f64::MIN, f64::MIN]; groups];
    for (b, g) in body.iter().zip(&group) {
        if let Some(g) = *g {
            let bx = &mut boxes[g];
            *bx = [
                bx[0].min(b.x - b.hw),
                bx[1].min(b.y - b.hh),
                bx[2].max(b.x + b.hw),
                bx[3].max(b.y + b.hh),
            ];
        }
    }
    let foreign = boxes
        .iter()
        .enumerate()
        .map(|(g, bx)| {
            body.iter()
                .zip(&group)
                .filter(|(b, h)| {
                    **h != Some(g)
                        && (bx[0]..=bx[2]).contains(&b.x)
                        && (bx[1]..=bx[3]).contains(&b.y)
                })
                .count()
        })
        .sum();
    Some((foreign, groups))
}

/// Why the file's positions of `net` are not worth drawing, or `None` when they are: most
/// nodes on a few points (MCC's nets put every node at (100, 100)), nodes on top of each
/// other, or straight arcs drawn through other nodes (the grid positions of GSPNR's plans).
pub(crate) fn useless(net: &Net, layout: &Layout) -> Option<String> {
    let n = layout.places.len() + layout.transitions.len();
    if n < 2 {
        return None;
    }
    let mut points: Vec<(i64, i64)> = layout
        .places
        .iter()
        .chain(&layout.transitions)
        .map(|p| ((p.x * 1e3).round() as i64, (p.y * 1e3).round() as i64))
        .collect();
    points.sort_unstable();
    points.dedup();
    if points.len() * 2 <= n {
        return Some(format!(
            "the file puts its {n} nodes on {} point{}",
            points.len(),
            if points.len() == 1 { "" } else { "s" }
        ));
    }
    let q = measure(net, layout);
    if q.overlaps > 0 {
        return Some(format!(
            "{} pair{} of nodes overlap at the file's positions",
            q.overlaps,
            if q.overlaps == 1 { "" } else { "s" }
        ));
    }
    // One arc through a node can be an accident of an otherwise drawn net; several are a
    // grid nobody arranged.
    if q.through_nodes >= 3 {
        return Some(format!(
            "{} arc segments pass through other nodes at the file's positions",
            q.through_nodes
        ));
    }
    None
}

/// Does the segment a–b meet the node's body (shrunk by a pixel, so that grazing is not
/// counted)?
fn hits(a: [f64; 2], b: [f64; 2], n: &Body) -> bool {
    if n.circle {
        let (dx, dy) = (b[0] - a[0], b[1] - a[1]);
        let l2 = dx * dx + dy * dy;
        let u = if l2 > 0.0 {
            (((n.x - a[0]) * dx + (n.y - a[1]) * dy) / l2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        return (a[0] + u * dx - n.x).hypot(a[1] + u * dy - n.y) < n.hw - 1.0;
    }
    // Liang–Barsky against the box.
    let (x0, x1) = (n.x - n.hw + 1.0, n.x + n.hw - 1.0);
    let (y0, y1) = (n.y - n.hh + 1.0, n.y + n.hh - 1.0);
    let d = [b[0] - a[0], b[1] - a[1]];
    let (mut t0, mut t1) = (0.0f64, 1.0f64);
    for (p, q) in [
        (-d[0], a[0] - x0),
        (d[0], x1 - a[0]),
        (-d[1], a[1] - y0),
        (d[1], y1 - a[1]),
    ] {
        if p == 0.0 {
            if q < 0.0 {
                return false;
            }
            continue;
        }
        let r = q / p;
        if p < 0.0 {
            t0 = t0.max(r);
        } else {
            t1 = t1.min(r);
        }
        if t0 > t1 {
            return false;
        }
    }
    true
}

fn orient(a: [f64; 2], b: [f64; 2], c: [f64; 2]) -> f64 {
    (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
}

/// Do the segments a–b and c–d cross properly (each one's ends strictly on both sides of
/// the other)?
fn crosses(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let eps = 1e-6;
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    ((o1 > eps && o2 < -eps) || (o1 < -eps && o2 > eps))
        && ((o3 > eps && o4 < -eps) || (o3 < -eps && o4 > eps))
}

/// Do the two segments share an end point?
fn touches_end(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> bool {
    let same = |p: [f64; 2], q: [f64; 2]| (p[0] - q[0]).abs() < 1e-6 && (p[1] - q[1]).abs() < 1e-6;
    same(a, c) || same(a, d) || same(b, c) || same(b, d)
}
