//! GreatSPN editor projects (`.PNPRO`): reader and writer.
//!
//! A project holds one or more `<gspn>` pages; [`ReadOptions::page`] picks one by name (the
//! first by default). Within a page:
//!
//! - `<place name marking x y>`: `marking` is an expression (a number, a constant, a template
//!   parameter...), a whole number ≥ 0.
//! - `<transition name type delay weight priority nservers x y>`: `type="EXP"` has `delay`,
//!   which is the **rate** (default 1), and `nservers` — absent or `Infinite` is
//!   infinite-server, `1` or `Single` single-server, `k` k-server. `type="IMM"` has `weight`
//!   (default 1; 0 is kept: a choice left to the policy) and `priority` (default 1).
//!   General (`GEN`) and fluid (`CONT`) transitions are refused.
//! - `<arc head tail kind="INPUT|OUTPUT|INHIBITOR" mult>` with optional `<point>` bend
//!   points; `mult` is an expression (default 1).
//! - `<constant name consttype value>` and `<template name type last-binding>`: names that
//!   expressions use. A template is a free parameter: `--param NAME=VALUE`
//!   ([`ReadOptions::params`]) sets it, else the file's `last-binding` does.
//!
//! Coloured (SWN) pages — a place with `domain=` — are refused with the place's name and
//! position. The file streams through quick-xml; only the selected page's nodes are kept.
//! Expressions are described in [`crate::io::expr`].
//!
//! ```
//! use gspn::io::{pnpro, ReadOptions};
//! let text = r#"<project name="p"><gspn name="cyc">
//!   <nodes>
//!     <place name="P1" marking="N"/><place name="P2"/>
//!     <transition name="T1" type="EXP" delay="2*lambda"/>
//!     <constant name="lambda" consttype="REAL" value="0.5"/>
//!     <template name="N" type="INTEGER" last-binding="3"/>
//!   </nodes>
//!   <edges><arc head="T1" kind="INPUT" tail="P1"/><arc head="P2" kind="OUTPUT" tail="T1"/></edges>
//! </gspn></project>"#;
//! let opts = ReadOptions { page: None, params: vec![("N".into(), "5".into())] };
//! let loaded = pnpro::read("cyc.PNPRO".as_ref(), text.as_bytes(), &opts).unwrap();
//! let net = &loaded.net;
//! assert_eq!(net.initial_tokens(), 5);
//! assert_eq!(
//!     net.transitions()[0].timing,
//!     gspn::net::Timing::Exponential { rate: 1.0, servers: gspn::net::Servers::Infinite }
//! );
//! ```

mod build;
mod scan;
mod write;

pub use build::MAX_CONSTANT_CHAIN;

use std::path::Path;

use super::{LoadError, LoadErrorKind, Loaded, ReadOptions, Span};
use crate::net::Net;

/// Reads the page `opts.page` (default: the first) of the project in `bytes`.
pub fn read(path: &Path, bytes: &[u8], opts: &ReadOptions) -> Result<Loaded, LoadError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(LoadError::empty(path));
    }
    let text = utf8(path, bytes)?;
    let scanned = scan::scan(path, text, opts)?;
    build::build(path, text, &scanned, opts)
}

/// `bytes` as text, or the position of the first byte that is not UTF-8.
fn utf8<'a>(path: &Path, bytes: &'a [u8]) -> Result<&'a str, LoadError> {
    std::str::from_utf8(bytes).map_err(|e| {
        LoadError::at(
            path,
            Span::locate(bytes, e.valid_up_to()),
            LoadErrorKind::Xml(format!("the file is not valid UTF-8: {e}")),
        )
    })
}

/// The names of the `<gspn>` pages of a project, in file order.
pub fn pages(path: &Path, bytes: &[u8]) -> Result<Vec<String>, LoadError> {
    let text = utf8(path, bytes)?;
    Ok(scan::scan(path, text, &ReadOptions::default())?.pages)
}

/// Writes `net` as a one-page project that GreatSPN's editor opens: positions (a grid where
/// the net has none), explicit `nservers` (`1`, `k` or `Infinite`), weights, priorities,
/// multiplicities, inhibitor arcs and bend points. PNPRO has no place capacities: a net with
/// some gets a comment saying they were left out.
pub fn write(net: &Net) -> String {
    write::write(net)
}
