//! A GreatSPN project the viewer was opened on, kept as its text: the look of its nodes
//! (transition rotation, name and rate label offsets), which the net does not hold, and
//! `save layout` by rewriting only the `x` and `y` attributes of its nodes — so constants,
//! templates, rotations, label positions, arcs' bends and everything else the file says are
//! written back as they were.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use serde_json::{Value, json};

use crate::io::xml::{XmlEvent, XmlStream, to_utf8};
use crate::net::{Net, Position};

/// What the file says about one node's look, and where its position is written.
#[derive(Clone, Debug, Default, PartialEq)]
struct NodeLook {
    /// Rotation in radians (GreatSPN's `rotation`), transitions only.
    rotation: Option<f64>,
    /// `label-x`, `label-y`: the name's offset from the centre, in the file's units.
    label: [Option<f64>; 2],
    /// `delay-x`/`delay-y` or `weight-x`/`weight-y`: the rate's offset.
    param: [Option<f64>; 2],
    /// `x` and `y`: the value and its byte range in the text, when present.
    x: Option<(f64, std::ops::Range<usize>)>,
    y: Option<(f64, std::ops::Range<usize>)>,
    /// Byte offset just past the element's name (`<place`), where missing attributes go.
    after_name: usize,
}

/// The project's text and, for the `<gspn>` page whose nodes are the net's, each node.
#[derive(Clone, Debug)]
pub(crate) struct Source {
    path: PathBuf,
    text: String,
    places: Vec<NodeLook>,
    transitions: Vec<NodeLook>,
}

impl Source {
    /// Reads `path` when it is a GreatSPN project (`.PNPRO`, any case) with a page whose
    /// places and transitions are exactly `net`'s (by name); `None` otherwise (another
    /// format, a net changed since, a file that cannot be read again).
    pub(crate) fn read(path: &Path, net: &Net) -> Option<Source> {
        let ext = path.extension()?.to_str()?;
        if !ext.eq_ignore_ascii_case("pnpro") {
            return None;
        }
        let bytes = std::fs::read(path).ok()?;
        let text = String::from_utf8(to_utf8(path, &bytes).ok()?.into_owned()).ok()?;
        for page in pages(path, &text)? {
            // Every place and transition of the net has its look on this page.
            let look = |place: bool, name: &str| page.get(&(place, name.to_string())).cloned();
            let places: Option<Vec<_>> = net.places().iter().map(|p| look(true, &p.name)).collect();
            let transitions: Option<Vec<_>> = net
                .transitions()
                .iter()
                .map(|t| look(false, &t.name))
                .collect();
            if let (Some(places), Some(transitions)) = (places, transitions)
                && page.len() == net.place_count() + net.transition_count()
            {
                return Some(Source {
                    path: path.to_path_buf(),
                    text,
                    places,
                    transitions,
                });
            }
        }
        None
    }

    /// The file.
    pub(crate) fn path(&self) -> &Path {
        &self.path
    }

    /// `{"rotation", "label": [dx, dy], "param": [dx, dy]}` (each only when the file gives
    /// it) for place `i` (`place`) or transition `i`.
    pub(crate) fn look_json(&self, place: bool, i: usize) -> Value {
        let n = if place {
            &self.places[i]
        } else {
            &self.transitions[i]
        };
        let mut v = json!({});
        if let Some(r) = n.rotation {
            v["rotation"] = json!(r);
        }
        if n.label.iter().any(Option::is_some) {
            v["label"] = json!(n.label);
        }
        if n.param.iter().any(Option::is_some) {
            v["param"] = json!(n.param);
        }
        v
    }

    /// The project with these positions (one per place, one per transition, in the file's
    /// units): only the nodes' `x` and `y` change; a value equal to the file's is kept as
    /// written.
    pub(crate) fn with_positions(&self, places: &[Position], transitions: &[Position]) -> String {
        let mut edits: Vec<(std::ops::Range<usize>, String)> = Vec::new();
        let nodes = self.places.iter().zip(places);
        for (n, p) in nodes.chain(self.transitions.iter().zip(transitions)) {
            let mut missing = String::new();
            for (have, v, key) in [(&n.x, p.x, "x"), (&n.y, p.y, "y")] {
                match have {
                    Some((old, r)) if *old != v => edits.push((r.clone(), number(v))),
                    Some(_) => {}
                    None => missing.push_str(&format!(" {key}=\"{}\"", number(v))),
                }
            }
            if !missing.is_empty() {
                edits.push((n.after_name..n.after_name, missing));
            }
        }
        edits.sort_by_key(|(r, _)| std::cmp::Reverse(r.start));
        let mut out = self.text.clone();
        for (r, s) in edits {
            out.replace_range(r, &s);
        }
        out
    }
}

/// A coordinate as GreatSPN writes it (`4.0`, `14.55`).
fn number(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e15 {
        format!("{v:.1}")
    } else {
        format!("{v}")
    }
}

/// Per `<gspn>` page of the project, its nodes by `(is a place, name)`; `None` when the text
/// is not well-formed XML.
fn pages(path: &Path, text: &str) -> Option<Vec<HashMap<(bool, String), NodeLook>>> {
    let mut x = XmlStream::new(path, text.as_bytes());
    let mut pages = Vec::new();
    let mut current: Option<HashMap<(bool, String), NodeLook>> = None;
    let mut gspn_depth = 0;
    while let Some(ev) = x.next().ok()? {
        let XmlEvent::Start(tag) = ev else {
            if current.is_some() && x.depth() < gspn_depth {
                pages.extend(current.take());
            }
            continue;
        };
        let name = tag.name().to_string();
        if name == "gspn" {
            gspn_depth = x.depth();
            current = Some(HashMap::new());
            continue;
        }
        let Some(page) = current.as_mut() else {
            continue;
        };
        let place = match name.as_str() {
            "place" => true,
            "transition" => false,
            _ => continue,
        };
        let attr = |key: &str| tag.attr(&x, key).ok().flatten();
        let num = |key: &str| attr(key).and_then(|v| v.text.parse::<f64>().ok());
        let pos = |key: &str| {
            let v = attr(key)?;
            let value = v.text.parse::<f64>().ok()?;
            let len = text[v.at..].find(['"', '\'']).unwrap_or(v.text.len());
            Some((value, v.at..v.at + len))
        };
        let Some(node_name) = attr("name") else {
            continue;
        };
        let look = NodeLook {
            rotation: if place { None } else { num("rotation") },
            label: [num("label-x"), num("label-y")],
            param: [
                num("delay-x").or_else(|| num("weight-x")),
                num("delay-y").or_else(|| num("weight-y")),
            ],
            x: pos("x"),
            y: pos("y"),
            after_name: tag.at + 1 + name.len(),
        };
        page.insert((place, node_name.text), look);
    }
    pages.extend(current.take());
    Some(pages)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_are_written_as_greatspn_does() {
        assert_eq!(number(4.0), "4.0");
        assert_eq!(number(14.55), "14.55");
        assert_eq!(number(-3.0), "-3.0");
    }
}
