//! Bad input is refused with exit code 2 and a message naming the file, the line, the
//! column and the offending name — never a panic. One test per case; each also checks the
//! library's `LoadError` (span and kind).

use crate::support::fixtures as shared_fixtures;

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use gspn::io::{LoadError, LoadErrorKind, ReadOptions, Span, read_net};
use shared_fixtures::{data, fixture};

fn bad(name: &str) -> PathBuf {
    data(&format!("bad/{name}"))
}

/// Runs `plan-runner check FILE`, asserts exit code 2 and that stderr holds `needles`
/// (the file, `line:column`, the name); returns the library's error.
fn refused(path: &Path, needles: &[&str]) -> LoadError {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(path)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    let shown = path.display().to_string();
    assert!(stderr.contains(&shown), "file name missing: {stderr}");
    for n in needles {
        assert!(stderr.contains(n), "`{n}` missing from: {stderr}");
    }
    read_net(path, &ReadOptions::default()).expect_err("the library refuses it too")
}

fn at(line: u32, column: u32) -> Option<Span> {
    Some(Span { line, column })
}

#[test]
fn arc_to_a_missing_node_names_it_with_its_line_and_column() {
    let f = fixture("thesis/azevedo_2020/ros/gspn_thesis_test_case.xml");
    let e = refused(&f, &[":206:68:", "p3:CleanL3", "does not exist"]);
    assert_eq!(e.span, at(206, 68));
    assert_eq!(
        e.kind,
        LoadErrorKind::UnknownNode {
            what: "node",
            name: "p3:CleanL3".into()
        }
    );
}

#[test]
fn pnml_arc_to_a_missing_node_names_it() {
    let e = refused(&bad("pnml_missing_node.pnml"), &[":8:39:", "`q`"]);
    assert_eq!(e.span, at(8, 39));
}

#[test]
fn duplicate_ids_are_refused_at_the_second_one() {
    let e = refused(&bad("duplicate_id.xml"), &[":12:14:", "duplicate id `p1`"]);
    assert_eq!(e.span, at(12, 14));
    assert_eq!(
        e.kind,
        LoadErrorKind::Duplicate {
            what: "id",
            name: "p1".into()
        }
    );
}

fn rate_refused(file: &str, value: &str) {
    let e = refused(&bad(file), &[":16:18:", "rate of `slow`", value, "> 0"]);
    assert_eq!(e.span, at(16, 18));
    assert!(
        matches!(&e.kind, LoadErrorKind::OutOfRange { what: "rate", name, value: v, .. }
            if name == "slow" && v == value),
        "{:?}",
        e.kind
    );
}

#[test]
fn negative_rate_is_refused() {
    rate_refused("negative_rate.xml", "-1.5");
}

#[test]
fn nan_rate_is_refused() {
    rate_refused("nan_rate.xml", "NaN");
}

#[test]
fn infinite_rate_is_refused() {
    rate_refused("infinite_rate.xml", "inf");
}

#[test]
fn zero_rate_is_refused() {
    rate_refused("zero_rate.xml", "0");
}

#[test]
fn negative_marking_is_refused() {
    let e = refused(
        &bad("negative_marking.xml"),
        &[":10:28:", "initial marking of `buffer`", "-2"],
    );
    assert_eq!(e.span, at(10, 28));
}

#[test]
fn non_numeric_arc_weight_is_refused() {
    let e = refused(
        &bad("non_numeric_weight.xml"),
        &[
            ":14:66:",
            "arc weight of `p1 to t1`",
            "`Default,two` is not a number",
        ],
    );
    assert_eq!(e.span, at(14, 66));
    assert!(matches!(e.kind, LoadErrorKind::NotANumber { .. }));
}

#[test]
fn malformed_xml_is_refused_where_the_tags_mismatch() {
    let e = refused(
        &bad("malformed.xml"),
        &[":13:", "malformed XML", "transition"],
    );
    assert_eq!(e.span.map(|s| s.line), Some(13));
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)));
}

#[test]
fn truncated_xml_is_refused_at_the_end_of_the_file() {
    let e = refused(&bad("truncated.xml"), &[":14:", "malformed XML"]);
    assert_eq!(e.span.map(|s| s.line), Some(14));
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)));
}

#[test]
fn empty_file_is_refused() {
    let e = refused(&bad("empty.xml"), &["empty"]);
    assert_eq!(e.kind, LoadErrorKind::Empty);
    // At its first character, where the content should start (issue 32).
    assert_eq!(e.span.map(|s| (s.line, s.column)), Some((1, 1)));
}

#[test]
fn unknown_extension_is_refused() {
    let e = refused(&bad("net.txt"), &["unknown format `txt`"]);
    assert_eq!(e.kind, LoadErrorKind::UnknownFormat("txt".into()));
}

#[test]
fn coloured_pnml_dialect_is_refused_naming_its_net_type() {
    let e = refused(
        &bad("symmetric_net.pnml"),
        &[":3:43:", "symmetricnet", "only place/transition nets"],
    );
    assert_eq!(e.span, at(3, 43));
    assert!(matches!(e.kind, LoadErrorKind::Unsupported(_)));
}

#[test]
fn viptool_dialect_of_azevedo_2018_is_read_not_refused() {
    // The issue allows "read it, or say what is missing": gspn reads it (two places, two
    // transitions, ids as names), so `check` succeeds.
    let f = fixture("thesis/azevedo_2018/test.pnml");
    Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(&f)
        .assert()
        .code(0);
    let l = read_net(&f, &ReadOptions::default()).unwrap();
    assert_eq!(l.net.place_count(), 2);
}
