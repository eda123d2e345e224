//! PIPE-style XML, as written by the thesis framework: `<pnml><net>` with `<place id>`
//! (`name/value`, `initialMarking/value` = `Default,k`, `capacity/value`, 0 = unbounded),
//! `<transition id>` (`timed/value`, `rate/value` = rate or weight, `infiniteServer/value`,
//! `priority/value`), `<arc id source target>` (`inscription/value` = `Default,k`,
//! `<type value="inhibitor"/>`, `<arcpath x y>` bend points), `graphics/position x y`.
//!
//! Arcs refer to ids; nets keep the `<name>` (the id where the name is missing or repeated).
//! Defaults: `infiniteServer` false or absent = single server; a transition without
//! `<timed>` is exponential with rate 1; priority 1. Gspn's own extension `servers/value` = k
//! keeps k-server transitions across a round trip.

use std::fmt::Write;
use std::path::Path;

use super::xml::{Dialect, esc, node_ids};
use super::{LoadError, Loaded, ReadOptions};
use crate::net::{ArcKind, Net, Position, Servers, Timing};

/// Reads a PIPE net from the bytes of `path`.
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Loaded, LoadError> {
    super::xml::read(path, bytes, opts, Dialect::Pipe)
}

/// A position for nodes the source file did not place: a grid, row by row.
fn grid(i: usize, row: f64) -> Position {
    Position {
        x: 60.0 + 90.0 * (i % 12) as f64,
        y: row + 90.0 * (i / 12) as f64,
    }
}

/// Writes `net` as PIPE XML (readable by the thesis framework and by [`read`]).
pub fn write(net: &Net) -> String {
    let (pid, tid) = node_ids(net, false);
    let mut s = String::with_capacity(1024 + 600 * (net.place_count() + net.transition_count()));
    s.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<pnml>\n");
    let _ = writeln!(s, "<net id=\"{}\" type=\"P/T net\">", esc(net.name()));
    s.push_str("  <token id=\"Default\" enabled=\"true\" red=\"0\" green=\"0\" blue=\"0\"/>\n");
    let trow = 120.0 + 90.0 * net.place_count().div_ceil(12) as f64;
    for (i, p) in net.places().iter().enumerate() {
        let pos = p.position.unwrap_or_else(|| grid(i, 60.0));
        let _ = write!(
            s,
            "  <place id=\"{}\">\n    <graphics>\n      <position x=\"{}\" y=\"{}\"/>\n    </graphics>\n    \
             <name>\n      <value>{}</value>\n    </name>\n    <initialMarking>\n      \
             <value>Default,{}</value>\n    </initialMarking>\n    <capacity>\n      \
             <value>{}</value>\n    </capacity>\n  </place>\n",
            esc(&pid[i]),
            pos.x,
            pos.y,
            esc(&p.name),
            p.initial,
            p.capacity.unwrap_or(0)
        );
    }
    for (i, t) in net.transitions().iter().enumerate() {
        let pos = t.position.unwrap_or_else(|| grid(i, trow));
        let (rate, timed, infinite, priority, k) = match t.timing {
            Timing::Immediate { weight, priority } => (weight, false, false, priority, None),
            Timing::Exponential { rate, servers } => match servers {
                Servers::Single => (rate, true, false, 1, None),
                Servers::Infinite => (rate, true, true, 1, None),
                Servers::K(k) => (rate, true, false, 1, Some(k)),
            },
        };
        let _ = write!(
            s,
            "  <transition id=\"{}\">\n    <graphics>\n      <position x=\"{}\" y=\"{}\"/>\n    \
             </graphics>\n    <name>\n      <value>{}</value>\n    </name>\n    <orientation>\n      \
             <value>0</value>\n    </orientation>\n    <rate>\n      <value>{}</value>\n    </rate>\n    \
             <timed>\n      <value>{}</value>\n    </timed>\n    <infiniteServer>\n      \
             <value>{}</value>\n    </infiniteServer>\n    <priority>\n      <value>{}</value>\n    \
             </priority>\n",
            esc(&tid[i]),
            pos.x,
            pos.y,
            esc(&t.name),
            rate,
            timed,
            infinite,
            priority
        );
        if let Some(k) = k {
            let _ = writeln!(s, "    <servers>\n      <value>{k}</value>\n    </servers>");
        }
        s.push_str("  </transition>\n");
    }
    for a in net.arcs() {
        let (p, t) = (&pid[a.place.index()], &tid[a.transition.index()]);
        let (src, dst) = match a.kind {
            ArcKind::Output => (t, p),
            ArcKind::Input | ArcKind::Inhibitor => (p, t),
        };
        let _ = write!(
            s,
            "  <arc id=\"{} to {}\" source=\"{}\" target=\"{}\">\n    <graphics/>\n    \
             <inscription>\n      <value>Default,{}</value>\n      <graphics/>\n    </inscription>\n    \
             <tagged>\n      <value>false</value>\n    </tagged>\n",
            esc(src),
            esc(dst),
            esc(src),
            esc(dst),
            a.weight
        );
        for (k, q) in a.points.iter().enumerate() {
            let _ = writeln!(
                s,
                "    <arcpath id=\"{k:03}\" x=\"{}\" y=\"{}\" curvePoint=\"false\"/>",
                q.x, q.y
            );
        }
        let ty = if a.kind == ArcKind::Inhibitor {
            "inhibitor"
        } else {
            "normal"
        };
        let _ = writeln!(s, "    <type value=\"{ty}\"/>\n  </arc>");
    }
    s.push_str("</net>\n</pnml>\n");
    s
}
