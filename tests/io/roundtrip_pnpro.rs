//! Writing PNPRO and reading it back gives the same net: every fixture page, plus nets built
//! in code with every server kind, inhibitors, weights, priorities and awkward names.

use std::path::{Path, PathBuf};

use gspn::io::{Format, LoadErrorKind, ReadOptions, pnpro, read_net, write_net};
use gspn::net::{Net, NetBuilder, Position, Servers};

fn shared() -> PathBuf {
    crate::support::fixtures::root().join("..")
}

fn all_pnpro(dir: &Path, out: &mut Vec<PathBuf>) {
    let mut entries: Vec<_> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            all_pnpro(&p, out);
        } else if p.extension().is_some_and(|e| e == "PNPRO") {
            out.push(p);
        }
    }
}

/// Writes `net`, reads it back, and checks names, markings, timings, arcs, positions and
/// bend points.
fn round_trip(net: &Net, what: &str) -> Net {
    let text = pnpro::write(net);
    let back = pnpro::read(
        Path::new("back.PNPRO"),
        text.as_bytes(),
        &ReadOptions::default(),
    )
    .unwrap_or_else(|e| panic!("{what}: {e}\n{text}"))
    .net;
    assert_eq!(net.diff(&back), Vec::<String>::new(), "{what}");
    assert_eq!(back.name(), net.name(), "{what}");
    for (p, q) in net.places().iter().zip(back.places()) {
        if p.position.is_some() {
            assert_eq!(p.position, q.position, "{what}: place {}", p.name);
        }
    }
    for (t, u) in net.transitions().iter().zip(back.transitions()) {
        if t.position.is_some() {
            assert_eq!(t.position, u.position, "{what}: transition {}", t.name);
        }
    }
    for (a, b) in net.arcs().iter().zip(back.arcs()) {
        assert_eq!(a.points, b.points, "{what}");
    }
    back
}

#[test]
fn every_fixture_page_round_trips() {
    let mut files = Vec::new();
    all_pnpro(&shared().join("fixtures/greatspn"), &mut files);
    let mut pages_done = 0;
    for f in &files {
        let pages = pnpro::pages(f, &std::fs::read(f).unwrap()).unwrap();
        for page in pages {
            let opts = ReadOptions {
                page: Some(page.clone()),
                params: Vec::new(),
            };
            match read_net(f, &opts) {
                Ok(l) => {
                    round_trip(&l.net, &format!("{}#{page}", f.display()));
                    pages_done += 1;
                }
                // Coloured pages are refused on read (tests/io/pnpro.rs covers the message).
                Err(e) => assert!(matches!(e.kind, LoadErrorKind::Unsupported(_)), "{e}"),
            }
        }
    }
    assert_eq!(pages_done, 52);
}

#[test]
fn parameters_are_baked_into_the_written_net() {
    let fms = shared().join("fixtures/greatspn/greatspn_examples/fms.PNPRO");
    let opts = ReadOptions {
        page: None,
        params: vec![("N".into(), "7".into())],
    };
    let net = read_net(&fms, &opts).unwrap().net;
    let back = round_trip(&net, "fms N=7");
    assert_eq!(back.initial_tokens(), 14);
}

#[test]
fn code_built_net_round_trips_with_every_feature() {
    let mut b = NetBuilder::new("robots & <tasks>");
    let idle = b.place("Idle:robot \"1\"", 3);
    let busy = b.place("Busy", 0);
    let lock = b.place("lock", 1);
    let start = b.exponential("start", 0.1, Servers::K(2));
    let work = b.exponential("work", 1.0 / 3.0, Servers::Single);
    let spin = b.exponential("spin", 1e-9, Servers::Infinite);
    let pick = b.immediate("pick", 0.0, 3);
    let drop = b.immediate("drop\tit\nnow", 2.5, 1);
    b.input(idle, start, 2);
    b.output(start, busy, 2);
    b.input(busy, work, 1);
    b.output(work, idle, 1);
    b.inhibitor(lock, start, 3);
    b.input(lock, spin, 1);
    b.output(spin, lock, 1);
    b.input(busy, pick, 1);
    b.output(pick, idle, 1);
    b.input(idle, drop, 1);
    b.output(drop, busy, 1);
    b.set_place_position(idle, Position { x: 1.5, y: -2.25 });
    b.set_transition_position(start, Position { x: 7.0, y: 0.1 });
    let net = b.build().unwrap();
    let text = pnpro::write(&net);
    assert!(text.contains("nservers=\"2\""), "{text}");
    assert!(text.contains("nservers=\"1\""), "{text}");
    assert!(text.contains("nservers=\"Infinite\""), "{text}");
    assert!(text.contains("kind=\"INHIBITOR\" mult=\"3\""), "{text}");
    let back = round_trip(&net, "code-built");
    // Nodes without a position get one, so the editor can draw them.
    assert!(back.places().iter().all(|p| p.position.is_some()));
    assert!(back.transitions().iter().all(|t| t.position.is_some()));
}

/// The PIPE and PNML fixtures (as tests/io/roundtrip_xml.rs lists them), minus the bad one.
fn xml_fixtures() -> Vec<PathBuf> {
    let root = shared().join("fixtures");
    let mut files = Vec::new();
    for (dir, exts) in [
        ("thesis", &[".xml", ".pnml"][..]),
        ("generated", &[".xml"][..]),
        ("mcc", &["model.pnml"][..]),
        ("kanban", &[".pnml"][..]),
    ] {
        let mut stack = vec![root.join(dir)];
        while let Some(d) = stack.pop() {
            for e in std::fs::read_dir(&d).unwrap() {
                let p = e.unwrap().path();
                let name = p.file_name().unwrap().to_string_lossy().into_owned();
                if p.is_dir() {
                    stack.push(p);
                } else if exts.iter().any(|x| name.ends_with(x))
                    && name != "gspn_thesis_test_case.xml"
                {
                    files.push(p);
                }
            }
        }
    }
    files.sort();
    files
}

#[test]
fn every_pipe_and_pnml_fixture_survives_pnpro() {
    let files = xml_fixtures();
    assert_eq!(
        files.len(),
        52,
        "28 thesis, 4 generated, 17 MCC, 4 Kanban, minus the bad one"
    );
    for f in &files {
        let net = read_net(f, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .net;
        round_trip(&net, &f.display().to_string());
    }
}

#[test]
fn every_pnpro_fixture_page_survives_pnml_and_pipe() {
    let dir = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    all_pnpro(&shared().join("fixtures/greatspn"), &mut files);
    let mut done = 0;
    for f in &files {
        for page in pnpro::pages(f, &std::fs::read(f).unwrap()).unwrap() {
            let opts = ReadOptions {
                page: Some(page.clone()),
                params: Vec::new(),
            };
            let Ok(loaded) = read_net(f, &opts) else {
                continue; // coloured
            };
            let net = loaded.net;
            for (format, ext) in [(Format::Pnml, "pnml"), (Format::Pipe, "xml")] {
                let out = dir.path().join(format!("n{done}.{ext}"));
                write_net(&net, &out, format).unwrap();
                let back = read_net(&out, &ReadOptions::default())
                    .unwrap_or_else(|e| panic!("{}#{page} as {ext}: {e}", f.display()))
                    .net;
                assert_eq!(
                    net.diff(&back),
                    Vec::<String>::new(),
                    "{}#{page} via {ext}",
                    f.display()
                );
            }
            done += 1;
        }
    }
    assert_eq!(done, 52);
}
