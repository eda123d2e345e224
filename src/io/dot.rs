//! Graphviz DOT export: places are circles showing their tokens (dots up to five, a number
//! beyond), transitions are boxes — immediate ones thin and black, exponential ones white
//! with their rate (and `∞` / `k` servers) —, inhibitor arcs end in a small circle
//! (`arrowhead=odot`), weights above 1 are arc labels. Positions are not written: Graphviz
//! lays the net out.

use std::fmt::Write;

use crate::net::{ArcKind, Net, Servers, Timing};

/// A DOT double-quoted string.
fn quote(s: &str) -> String {
    let mut out = String::with_capacity(s.len() + 2);
    out.push('"');
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '\n' => out.push_str("\\n"),
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

fn tokens(k: u32) -> String {
    match k {
        0 => String::new(),
        1..=5 => "●".repeat(k as usize),
        k => k.to_string(),
    }
}

/// Renders `net` as a DOT digraph.
pub fn write(net: &Net) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "digraph {} {{", quote(net.name()));
    s.push_str(
        "  rankdir=LR;\n  node [fontname=\"Helvetica\"];\n  edge [fontname=\"Helvetica\"];\n",
    );
    for (i, p) in net.places().iter().enumerate() {
        let cap = p.capacity.map(|c| format!(" ≤{c}")).unwrap_or_default();
        let _ = writeln!(
            s,
            "  p{i} [shape=circle, fixedsize=true, width=0.6, label={}, xlabel={}];",
            quote(&tokens(p.initial)),
            quote(&format!("{}{cap}", p.name))
        );
    }
    for (i, t) in net.transitions().iter().enumerate() {
        match t.timing {
            Timing::Immediate { weight, priority } => {
                let extra = if weight != 1.0 || priority != 1 {
                    format!("\nw={weight} π={priority}")
                } else {
                    String::new()
                };
                let _ = writeln!(
                    s,
                    "  t{i} [shape=box, style=filled, fillcolor=black, width=0.08, height=0.5, \
                     label=\"\", xlabel={}];",
                    quote(&format!("{}{extra}", t.name))
                );
            }
            Timing::Exponential { rate, servers } => {
                let srv = match servers {
                    Servers::Single => String::new(),
                    Servers::Infinite => " ∞".into(),
                    Servers::K(k) => format!(" ×{k}"),
                };
                let _ = writeln!(
                    s,
                    "  t{i} [shape=box, style=filled, fillcolor=white, label={}];",
                    quote(&format!("{}\nλ={rate}{srv}", t.name))
                );
            }
        }
    }
    for a in net.arcs() {
        let (p, t) = (a.place.index(), a.transition.index());
        let mut attrs = Vec::new();
        if a.weight != 1 {
            attrs.push(format!("label=\"{}\"", a.weight));
        }
        let (from, to) = match a.kind {
            ArcKind::Input => (format!("p{p}"), format!("t{t}")),
            ArcKind::Output => (format!("t{t}"), format!("p{p}")),
            ArcKind::Inhibitor => {
                attrs.push("arrowhead=odot".into());
                (format!("p{p}"), format!("t{t}"))
            }
        };
        if attrs.is_empty() {
            let _ = writeln!(s, "  {from} -> {to};");
        } else {
            let _ = writeln!(s, "  {from} -> {to} [{}];", attrs.join(", "));
        }
    }
    s.push_str("}\n");
    s
}
