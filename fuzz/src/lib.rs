//! What each fuzz target does with its bytes: one function per reader of gspn, each calling
//! the library's public read or parse function exactly as the CLI does. The fuzz targets
//! (`fuzz_targets/*.rs`) call these, and so does the stable-toolchain replay of the corpus
//! (`tests/io/fuzz_corpus.rs` includes this file), so a crash found here is replayed there.
//!
//! A target passes when it returns: any `Err` is a fine answer to bad bytes; a panic, an
//! abort or a stack overflow is a bug.

use std::path::Path;
use std::sync::OnceLock;

use gspn::io::expr::Expr;
use gspn::io::{ReadOptions, pipe, pnml, pnpro};
use gspn::net::Net;
use gspn::net::predicate::Predicate;
use gspn::plan::{PlanFile, thesis};

/// What a target does with its bytes.
pub type Target = fn(&[u8]);

/// Every target, by name (the directory of its corpus).
pub const TARGETS: &[(&str, Target)] = &[
    ("pipe_xml", pipe_xml),
    ("pnml", pnml),
    ("pnpro", pnpro),
    ("plan_toml", plan_toml),
    ("thesis_json", thesis_json),
    ("predicate", predicate),
    ("expr", expr),
    ("journal", journal),
    #[cfg(feature = "ros2")]
    ("rtps", rtps),
];

/// The net that plans, predicates and journals are checked against: the repository's cyc3
/// (`plans/nets/cyc3_ss.PNPRO`, places `P1 P2 P3`, transitions `T1 t2 T3`).
fn cyc3() -> &'static Net {
    static NET: OnceLock<Net> = OnceLock::new();
    NET.get_or_init(|| {
        let opts = ReadOptions {
            page: Some("cyc3".into()),
            ..ReadOptions::default()
        };
        let text = include_bytes!("../../plans/nets/cyc3_ss.PNPRO");
        pnpro::read(Path::new("cyc3_ss.PNPRO"), text, &opts)
            .expect("the repository's cyc3 loads")
            .net
    })
}

/// A PIPE XML net; what loads is written back out.
pub fn pipe_xml(data: &[u8]) {
    if let Ok(loaded) = pipe::read(Path::new("fuzz.xml"), data, &ReadOptions::default()) {
        let _ = pipe::write(&loaded.net);
    }
}

/// An ISO PNML net; what loads is written back out.
pub fn pnml(data: &[u8]) {
    if let Ok(loaded) = pnml::read(Path::new("fuzz.pnml"), data, &ReadOptions::default()) {
        let _ = pnml::write(&loaded.net);
    }
}

/// A GreatSPN project: its pages, its first page as a net, written back out.
pub fn pnpro(data: &[u8]) {
    let path = Path::new("fuzz.PNPRO");
    let _ = pnpro::pages(path, data);
    if let Ok(loaded) = pnpro::read(path, data, &ReadOptions::default()) {
        let _ = pnpro::write(&loaded.net);
    }
}

/// A plan's TOML, parsed and then checked against cyc3.
pub fn plan_toml(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.toml");
    if let Ok(file) = PlanFile::parse(path, text) {
        let _ = file.resolve(path, text, cyc3().clone());
    }
}

/// A thesis execution input (`plan-runner import-thesis`): JSON with Python literals.
pub fn thesis_json(data: &[u8]) {
    let _ = thesis::parse_input(Path::new("fuzz.json"), data);
}

/// A `stop.when` / `--prob` predicate over cyc3, evaluated on a few markings.
pub fn predicate(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(p) = Predicate::parse(cyc3(), text) {
        for m in [[0, 0, 0], [2, 0, 0], [u32::MAX, 1, u32::MAX]] {
            let _ = p.eval(&m);
        }
        let _ = p.places();
    }
}

/// A PNPRO expression, evaluated with every name worth 2.5.
pub fn expr(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(e) = Expr::parse(text) {
        let _ = e.eval(&mut |_: &str, _| Ok::<f64, ()>(2.5));
    }
}

/// A run's journal (JSON Lines) of cyc3, played back (`plan-runner replay`).
pub fn journal(data: &[u8]) {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let _ = gspn::runtime::journal::read_journal(text, cyc3());
}

/// One UDP datagram through RustDDS's receive path (`vendor/rustdds`, gspn's patched copy):
/// its message receiver, with the built-in readers and the user readers the datagram names
/// matched with its writers, then Discovery's deserializers on the built-in topics' payloads
/// (`rustdds::fuzzing::receive`).
#[cfg(feature = "ros2")]
pub fn rtps(data: &[u8]) {
    rustdds::fuzzing::receive(data);
}
