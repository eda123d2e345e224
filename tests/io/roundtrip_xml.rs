//! Every PIPE and PNML fixture survives PIPE → PNML → read and → PIPE → read unchanged
//! (`Net::diff` empty: places, markings, capacities, timing, arcs and weights); DOT output
//! names every place.

use crate::support::fixtures as shared_fixtures;

use std::path::PathBuf;

use gspn::io::{Format, ReadOptions, read_net, write_net};
use shared_fixtures::{data, files_under};

fn all_xml_fixtures() -> Vec<PathBuf> {
    let mut files = files_under("thesis", &[".xml", ".pnml"]);
    files.extend(files_under("generated", &[".xml"]));
    files.extend(files_under("mcc", &["model.pnml"]));
    files.extend(files_under("kanban", &[".pnml"]));
    files.push(data("pipe_weights.xml"));
    files.retain(|f| !f.ends_with("gspn_thesis_test_case.xml"));
    files
}

fn roundtrip(format: Format, ext: &str) {
    let dir = tempfile::tempdir().unwrap();
    let files = all_xml_fixtures();
    assert_eq!(
        files.len(),
        53,
        "25 + 3 thesis, 4 generated, 17 MCC, 4 Kanban, 1 local, minus the bad one"
    );
    for (i, f) in files.iter().enumerate() {
        let net = read_net(f, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{e}"))
            .net;
        let out = dir.path().join(format!("n{i}.{ext}"));
        write_net(&net, &out, format).unwrap();
        let back = read_net(&out, &ReadOptions::default())
            .unwrap_or_else(|e| panic!("{} written as {ext} does not read back: {e}", f.display()))
            .net;
        assert_eq!(back.place_count(), net.place_count());
        let diff = net.diff(&back);
        assert!(diff.is_empty(), "{} via {ext}: {diff:?}", f.display());
        let pos: Vec<_> = net.places().iter().map(|p| p.position).collect();
        let back_pos: Vec<_> = back.places().iter().map(|p| p.position).collect();
        if pos.iter().all(Option::is_some) {
            assert_eq!(pos, back_pos, "{}: positions", f.display());
        }
    }
}

#[test]
fn every_fixture_survives_a_pnml_round_trip() {
    roundtrip(Format::Pnml, "pnml");
}

#[test]
fn every_fixture_survives_a_pipe_round_trip() {
    roundtrip(Format::Pipe, "xml");
}

#[test]
fn pnml_to_pipe_to_pnml_keeps_timing_and_servers() {
    let net = read_net(&data("pipe_weights.xml"), &ReadOptions::default())
        .unwrap()
        .net;
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.pnml");
    write_net(&net, &a, Format::Pnml).unwrap();
    let text = std::fs::read_to_string(&a).unwrap();
    assert!(text.contains("<infiniteServer><value>true</value></infiniteServer>"));
    assert!(text.contains("<type value=\"inhibitor\"/>"));
    let b = dir.path().join("b.xml");
    write_net(
        &read_net(&a, &ReadOptions::default()).unwrap().net,
        &b,
        Format::Pipe,
    )
    .unwrap();
    let back = read_net(&b, &ReadOptions::default()).unwrap().net;
    assert!(net.diff(&back).is_empty(), "{:?}", net.diff(&back));
}

#[test]
fn dot_output_names_every_place_and_draws_kinds() {
    for f in all_xml_fixtures() {
        let net = read_net(&f, &ReadOptions::default()).unwrap().net;
        let dot = gspn::io::dot::write(&net);
        assert!(dot.starts_with("digraph "), "{}", f.display());
        assert!(dot.trim_end().ends_with('}'));
        for p in net.places() {
            assert!(dot.contains(&p.name), "{}: {} missing", f.display(), p.name);
        }
        let edges = dot.lines().filter(|l| l.contains(" -> ")).count();
        assert_eq!(edges, net.arcs().len(), "{}", f.display());
    }
    let net = read_net(&data("pipe_weights.xml"), &ReadOptions::default())
        .unwrap()
        .net;
    let dot = gspn::io::dot::write(&net);
    assert!(dot.contains("arrowhead=odot"), "inhibitor arc");
    assert!(dot.contains("label=\"3\""), "weight 3");
    assert!(dot.contains("fillcolor=black"), "immediate transition");
    assert!(dot.contains("λ=2.5 ∞"), "rate and infinite servers");
    assert!(dot.contains("●●●●●"), "5 tokens in Buffer");
}
