//! Writes a [`Net`] as a one-page GreatSPN project the editor opens.

use std::fmt::Write;

use std::borrow::Cow;

use quick_xml::escape;

use crate::net::{ArcKind, Net, Position, Servers, Timing};

/// An attribute value: XML-escaped, and with tabs and line breaks as character references,
/// which attribute-value normalisation would otherwise turn into spaces.
fn attr(s: &str) -> Cow<'_, str> {
    let e = escape::escape(s);
    if e.contains(['\n', '\r', '\t']) {
        Cow::Owned(
            e.replace('\n', "&#10;")
                .replace('\r', "&#13;")
                .replace('\t', "&#9;"),
        )
    } else {
        e
    }
}

/// Where nodes without a position go: places on one row, transitions on the next.
fn default_position(row: f64, i: usize) -> Position {
    Position {
        x: 4.0 + 6.0 * (i % 20) as f64,
        y: row + 12.0 * (i / 20) as f64,
    }
}

/// A number the editor reads back exactly (Rust prints the shortest round-trip form and never
/// uses exponents, which the editor's grammar would reject for whole numbers).
fn num(v: f64) -> String {
    format!("{v}")
}

fn coords(out: &mut String, p: Position) {
    let _ = write!(out, " x=\"{}\" y=\"{}\"", num(p.x), num(p.y));
}

pub(super) fn write(net: &Net) -> String {
    let mut out = String::with_capacity(256 + 160 * (net.place_count() + net.arcs().len()));
    let name = attr(net.name());
    out.push_str("<?xml version=\"1.0\" encoding=\"UTF-8\" standalone=\"no\"?>\n");
    out.push_str("<!-- Written by gspn (plan-runner) -->\n");
    let _ = writeln!(out, "<project name=\"{name}\" version=\"121\">");
    let _ = writeln!(
        out,
        "  <gspn name=\"{name}\" show-color-cmd=\"false\" show-fluid-cmd=\"false\">"
    );
    for p in net.places().iter().filter(|p| p.capacity.is_some()) {
        // PNPRO has no place capacities; say so rather than drop them silently.
        let _ = writeln!(
            out,
            "    <!-- place {} had capacity {}: PNPRO has no capacities, it was left out -->",
            p.name.replace("--", "- -").replace(['\n', '\r'], " "),
            p.capacity.unwrap_or_default()
        );
    }
    out.push_str("    <nodes>\n");
    for (i, p) in net.places().iter().enumerate() {
        out.push_str("      <place");
        if p.initial > 0 {
            let _ = write!(out, " marking=\"{}\"", p.initial);
        }
        let _ = write!(out, " name=\"{}\"", attr(p.name.as_str()));
        coords(
            &mut out,
            p.position.unwrap_or_else(|| default_position(2.0, i)),
        );
        out.push_str("/>\n");
    }
    for (i, t) in net.transitions().iter().enumerate() {
        let _ = write!(out, "      <transition name=\"{}\"", attr(t.name.as_str()));
        match t.timing {
            Timing::Exponential { rate, servers } => {
                let servers = match servers {
                    Servers::Single => "1".to_string(),
                    Servers::K(k) => k.to_string(),
                    Servers::Infinite => "Infinite".to_string(),
                };
                let _ = write!(
                    out,
                    " type=\"EXP\" delay=\"{}\" nservers=\"{servers}\"",
                    num(rate)
                );
            }
            Timing::Immediate { weight, priority } => {
                let _ = write!(
                    out,
                    " type=\"IMM\" weight=\"{}\" priority=\"{priority}\"",
                    num(weight)
                );
            }
        }
        coords(
            &mut out,
            t.position.unwrap_or_else(|| default_position(8.0, i)),
        );
        out.push_str("/>\n");
    }
    out.push_str("    </nodes>\n    <edges>\n");
    for a in net.arcs() {
        let place = attr(net.place(a.place).name.as_str());
        let trans = attr(net.transition(a.transition).name.as_str());
        let (head, tail, kind) = match a.kind {
            ArcKind::Input => (trans, place, "INPUT"),
            ArcKind::Output => (place, trans, "OUTPUT"),
            ArcKind::Inhibitor => (trans, place, "INHIBITOR"),
        };
        let _ = write!(out, "      <arc head=\"{head}\" kind=\"{kind}\"");
        if a.weight != 1 {
            let _ = write!(out, " mult=\"{}\"", a.weight);
        }
        let _ = write!(out, " tail=\"{tail}\"");
        if a.points.is_empty() {
            out.push_str("/>\n");
        } else {
            out.push_str(">\n");
            for &p in &a.points {
                out.push_str("        <point");
                coords(&mut out, p);
                out.push_str("/>\n");
            }
            out.push_str("      </arc>\n");
        }
    }
    out.push_str("    </edges>\n  </gspn>\n</project>\n");
    out
}
