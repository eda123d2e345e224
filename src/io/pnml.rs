//! ISO/IEC 15909-2 PNML place/transition nets, streamed (the MCC models load without a
//! DOM), with the `<timed>`/`<rate>` extension of the Kanban GSPN files.
//!
//! - `<place id>`: `name/text` (the name users see; the id when missing or repeated),
//!   `initialMarking/text`. Arcs refer to ids. Pages are flattened.
//! - `<transition id>`: without timing a P/T transition is exponential with rate 1,
//!   single-server (the reachability graph is unchanged). The extension, as in the Kanban
//!   files: `<timed><value>true|false</value></timed>`, `<rate><value>r</value></rate>`
//!   (the weight for immediate transitions), `<priority>`, `<infiniteServer>`, and gspn's
//!   `<servers>` (k) and place `<capacity>`.
//! - `<arc id source target>`: `inscription/text` weight; `<type value="inhibitor"/>`.
//! - Other net types (symmetric, high-level) are refused, naming the type. VipTool's
//!   dialect (`VIPschema.xsd`: no pages, `value` instead of `text`, blank names) is read.
//!
//! [`write`] writes the extension, so timing survives a round trip.

use std::fmt::Write;
use std::path::Path;

use rustc_hash::FxHashSet;

use super::xml::{Dialect, esc, node_ids};
use super::{LoadError, Loaded, ReadOptions};
use crate::net::{ArcKind, Net, Position, Servers, Timing};

/// The PNML 2009 grammar namespace.
pub const NAMESPACE: &str = "http://www.pnml.org/version-2009/grammar/pnml";
/// The net type of P/T nets.
pub const PTNET: &str = "http://www.pnml.org/version-2009/grammar/ptnet";

/// Reads a PNML net from the bytes of `path`.
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Loaded, LoadError> {
    super::xml::read(path, bytes, opts, Dialect::Pnml)
}

/// Opens a `<place>` or `<transition>` element: its id, name and position.
fn open_node(s: &mut String, tag: &str, id: &str, name: &str, p: Option<Position>) {
    let _ = writeln!(
        s,
        "      <{tag} id=\"{}\">\n        <name><text>{}</text></name>",
        esc(id),
        esc(name)
    );
    if let Some(p) = p {
        let _ = writeln!(
            s,
            "        <graphics><position x=\"{}\" y=\"{}\"/></graphics>",
            p.x, p.y
        );
    }
}

/// Writes `net` as PNML P/T with the timed extension on every transition.
pub fn write(net: &Net) -> String {
    let (pid, tid) = node_ids(net, true);
    let used: FxHashSet<&str> = pid.iter().chain(&tid).map(String::as_str).collect();
    let mut s = String::with_capacity(1024 + 300 * (net.place_count() + net.transition_count()));
    let _ = writeln!(
        s,
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n<pnml xmlns=\"{NAMESPACE}\">\n  \
         <net id=\"net\" type=\"{PTNET}\">\n    <name><text>{}</text></name>\n    <page id=\"page0\">",
        esc(net.name())
    );
    for (i, p) in net.places().iter().enumerate() {
        open_node(&mut s, "place", &pid[i], &p.name, p.position);
        if p.initial > 0 {
            let _ = writeln!(
                s,
                "        <initialMarking><text>{}</text></initialMarking>",
                p.initial
            );
        }
        if let Some(c) = p.capacity {
            let _ = writeln!(s, "        <capacity><value>{c}</value></capacity>");
        }
        s.push_str("      </place>\n");
    }
    for (i, t) in net.transitions().iter().enumerate() {
        open_node(&mut s, "transition", &tid[i], &t.name, t.position);
        match t.timing {
            Timing::Immediate { weight, priority } => {
                let _ = writeln!(
                    s,
                    "        <timed><value>false</value></timed><rate><value>{weight}</value></rate>\
                     <priority><value>{priority}</value></priority>"
                );
            }
            Timing::Exponential { rate, servers } => {
                let _ = write!(
                    s,
                    "        <timed><value>true</value></timed><rate><value>{rate}</value></rate>"
                );
                match servers {
                    Servers::Single => {}
                    Servers::Infinite => {
                        s.push_str("<infiniteServer><value>true</value></infiniteServer>")
                    }
                    Servers::K(k) => {
                        let _ = write!(s, "<servers><value>{k}</value></servers>");
                    }
                }
                s.push('\n');
            }
        }
        s.push_str("      </transition>\n");
    }
    for (i, a) in net.arcs().iter().enumerate() {
        let (p, t) = (&pid[a.place.index()], &tid[a.transition.index()]);
        let (src, dst) = match a.kind {
            ArcKind::Output => (t, p),
            ArcKind::Input | ArcKind::Inhibitor => (p, t),
        };
        let mut id = format!("a{i}");
        while used.contains(id.as_str()) {
            id.push('_');
        }
        let _ = writeln!(
            s,
            "      <arc id=\"{id}\" source=\"{}\" target=\"{}\">",
            esc(src),
            esc(dst)
        );
        if a.weight != 1 {
            let _ = writeln!(
                s,
                "        <inscription><text>{}</text></inscription>",
                a.weight
            );
        }
        if a.kind == ArcKind::Inhibitor {
            s.push_str("        <type value=\"inhibitor\"/>\n");
        }
        if !a.points.is_empty() {
            s.push_str("        <graphics>");
            for q in &a.points {
                let _ = write!(s, "<position x=\"{}\" y=\"{}\"/>", q.x, q.y);
            }
            s.push_str("</graphics>\n");
        }
        s.push_str("      </arc>\n");
    }
    s.push_str("    </page>\n  </net>\n</pnml>\n");
    s
}
