//! Reading GreatSPN `.PNPRO` projects: every fixture page, pages by name, constants,
//! templates and `--param`, expressions, and bad input refused with its line and column.

use std::path::{Path, PathBuf};

use gspn::io::{LoadError, LoadErrorKind, ReadOptions, Span, pnpro, read_net};
use gspn::net::{ArcKind, Net, Servers, Timing};

/// The shared directory: the parent of the fixture root.
fn shared() -> PathBuf {
    crate::support::fixtures::root().join("..")
}

fn greatspn(rel: &str) -> PathBuf {
    shared().join("fixtures/greatspn").join(rel)
}

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/pnpro")
        .join(name)
}

fn opts(page: Option<&str>, params: &[(&str, &str)]) -> ReadOptions {
    ReadOptions {
        page: page.map(str::to_string),
        params: params
            .iter()
            .map(|(k, v)| (k.to_string(), v.to_string()))
            .collect(),
    }
}

fn load(path: &Path, page: Option<&str>, params: &[(&str, &str)]) -> Net {
    read_net(path, &opts(page, params))
        .unwrap_or_else(|e| panic!("{e}"))
        .net
}

fn load_err(path: &Path, page: Option<&str>, params: &[(&str, &str)]) -> LoadError {
    match read_net(path, &opts(page, params)) {
        Ok(_) => panic!("{} loaded but should not", path.display()),
        Err(e) => e,
    }
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

fn timing(net: &Net, t: &str) -> Timing {
    net.transition(net.transition_by_name(t).unwrap()).timing
}

fn initial(net: &Net, p: &str) -> u32 {
    net.place(net.place_by_name(p).unwrap()).initial
}

fn weight(net: &Net, kind: ArcKind, p: &str, t: &str) -> u32 {
    let (p, t) = (
        net.place_by_name(p).unwrap(),
        net.transition_by_name(t).unwrap(),
    );
    net.arcs()
        .iter()
        .find(|a| a.kind == kind && a.place == p && a.transition == t)
        .unwrap()
        .weight
}

#[test]
fn every_fixture_page_loads_and_coloured_pages_are_refused() {
    let mut files = Vec::new();
    all_pnpro(&greatspn(""), &mut files);
    assert_eq!(files.len(), 22, "{files:?}");
    let (mut loaded, mut coloured) = (0, 0);
    for f in &files {
        let pages = pnpro::pages(f, &std::fs::read(f).unwrap()).unwrap();
        assert!(!pages.is_empty(), "{}", f.display());
        for page in &pages {
            match read_net(f, &opts(Some(page), &[])) {
                Ok(l) => {
                    loaded += 1;
                    assert_eq!(l.net.name(), page);
                }
                Err(e) => {
                    let LoadErrorKind::Unsupported(msg) = &e.kind else {
                        panic!("{e}");
                    };
                    assert!(msg.contains("colour domain"), "{e}");
                    assert!(e.span.is_some());
                    coloured += 1;
                }
            }
        }
    }
    assert_eq!((loaded, coloured), (52, 3));
}

#[test]
fn cyc3_is_infinite_server_without_nservers() {
    let net = load(&greatspn("cyc3/cyc3.PNPRO"), None, &[]);
    assert_eq!((net.place_count(), net.transition_count()), (3, 3));
    assert_eq!(net.initial_tokens(), 2);
    assert_eq!(initial(&net, "P1"), 2);
    assert_eq!(
        timing(&net, "T1"),
        Timing::Exponential {
            rate: 1.0,
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        timing(&net, "T3"),
        Timing::Exponential {
            rate: 2.0,
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        timing(&net, "t2"),
        Timing::Immediate {
            weight: 1.0,
            priority: 1
        }
    );
    assert_eq!(net.arcs().len(), 6);
    let p1 = net.place(net.place_by_name("P1").unwrap());
    assert_eq!(p1.position.map(|p| (p.x, p.y)), Some((2.0, 2.0)));
}

#[test]
fn cyc3_ss_is_single_server_with_nservers_1() {
    let net = load(&greatspn("cyc3/cyc3_ss.PNPRO"), None, &[]);
    assert_eq!((net.place_count(), net.transition_count()), (3, 3));
    assert_eq!(net.initial_tokens(), 2);
    for (t, rate) in [("T1", 1.0), ("T3", 2.0)] {
        assert_eq!(
            timing(&net, t),
            Timing::Exponential {
                rate,
                servers: Servers::Single
            }
        );
    }
    let net = load(&greatspn("cyc3/cyc3x_ss.PNPRO"), None, &[]);
    assert!(!net.has_immediate());
    assert_eq!(
        timing(&net, "t2"),
        Timing::Exponential {
            rate: 5.0,
            servers: Servers::Single
        }
    );
}

#[test]
fn editor_defaults_fill_missing_attributes() {
    // gspn_example: IMM without weight/priority, EXP without nservers.
    let net = load(&greatspn("gspn_example.PNPRO"), None, &[]);
    assert_eq!((net.place_count(), net.transition_count()), (4, 7));
    assert_eq!(net.initial_tokens(), 2);
    assert_eq!(
        timing(&net, "t1"),
        Timing::Immediate {
            weight: 1.0,
            priority: 1
        }
    );
    assert_eq!(
        timing(&net, "t4"),
        Timing::Exponential {
            rate: 1.0,
            servers: Servers::Infinite
        }
    );
    let arc = net
        .arcs()
        .iter()
        .find(|a| a.kind == ArcKind::Output && net.transition(a.transition).name == "t4")
        .unwrap();
    assert_eq!(arc.points.len(), 2);
    assert_eq!((arc.points[0].x, arc.points[0].y), (36.0, 1.5));
    // test_executable_with_result: EXP without delay has rate 1.
    let net = load(
        &greatspn("gspnr_toolbox/test_executable_with_result.PNPRO"),
        None,
        &[],
    );
    assert_eq!(
        timing(&net, "T0"),
        Timing::Exponential {
            rate: 1.0,
            servers: Servers::Infinite
        }
    );
}

#[test]
fn several_fixtures_have_the_counts_of_their_files() {
    let cases: [(&str, usize, usize, u64, usize); 7] = [
        ("hallway.PNPRO", 9, 12, 1, 24),
        ("inspection.PNPRO", 17, 19, 3, 44),
        ("greatspn_examples/phil4.PNPRO", 16, 12, 8, 40),
        ("greatspn_examples/multiproc_unf.PNPRO", 33, 40, 9, 144),
        ("greatspn_examples/polling_unf.PNPRO", 10, 10, 4, 26),
        ("gspnr_toolbox/execution.PNPRO", 5, 4, 2, 8),
        ("gspnr_toolbox/video_GSPNR.PNPRO", 21, 30, 3, 60),
    ];
    for (file, places, transitions, tokens, arcs) in cases {
        let net = load(&greatspn(file), None, &[]);
        assert_eq!(
            (
                net.place_count(),
                net.transition_count(),
                net.initial_tokens(),
                net.arcs().len()
            ),
            (places, transitions, tokens, arcs),
            "{file}"
        );
    }
    let net = load(&greatspn("greatspn_examples/polling_unf.PNPRO"), None, &[]);
    let inhibitors = net
        .arcs()
        .iter()
        .filter(|a| a.kind == ArcKind::Inhibitor)
        .count();
    assert_eq!(inhibitors, 2);
    // Rates through constants (lambda = mu = rho = 1).
    let net = load(&greatspn("greatspn_examples/phil4.PNPRO"), None, &[]);
    assert_eq!(
        timing(&net, "T0"),
        Timing::Exponential {
            rate: 1.0,
            servers: Servers::Infinite
        }
    );
}

#[test]
fn imm_weight_zero_is_kept_and_mult_is_read() {
    let net = load(&greatspn("gspnr_toolbox/execution.PNPRO"), None, &[]);
    assert_eq!(
        timing(&net, "t1"),
        Timing::Immediate {
            weight: 0.0,
            priority: 1
        }
    );
    assert_eq!(weight(&net, ArcKind::Input, "P0", "t2"), 2);
}

#[test]
fn names_keep_unescaped_characters() {
    let net = load(&greatspn("gspnr_toolbox/defaults.PNPRO"), None, &[]);
    assert!(net.transition_by_name("Arrived_<1>_<2>").is_some());
    let net = load(&data("expressions.PNPRO"), None, &[]);
    assert!(net.place_by_name("Idle:robot").is_some());
}

#[test]
fn pages_are_chosen_by_name() {
    let file = greatspn("gspnr_toolbox/video_GSPNR.PNPRO");
    let pages = pnpro::pages(&file, &std::fs::read(&file).unwrap()).unwrap();
    assert_eq!(pages.len(), 12);
    assert_eq!(pages[0], "GSPN");
    let first = read_net(&file, &ReadOptions::default()).unwrap();
    assert_eq!(first.net.name(), "GSPN");
    assert!(first.warnings[0].contains("of 12"), "{:?}", first.warnings);
    let team = load(&file, Some("heterogeneous_team"), &[]);
    assert_eq!((team.place_count(), team.transition_count()), (24, 0));
    let file = greatspn("gspnr_toolbox/test_executable_with_result.PNPRO");
    let exp = load(&file, Some("GSPN_exponential"), &[]);
    assert_eq!((exp.place_count(), exp.transition_count()), (6, 5));
    let immediates = exp
        .transitions()
        .iter()
        .filter(|t| t.is_immediate())
        .count();
    assert_eq!(immediates, 1);
    let coop = load(&file, Some("second_cooperation_test"), &[]);
    assert_eq!((coop.place_count(), coop.transition_count()), (8, 2));
}

#[test]
fn templates_default_to_last_binding_and_param_overrides() {
    let fms = greatspn("greatspn_examples/fms.PNPRO");
    let net = load(&fms, None, &[]);
    assert_eq!((net.place_count(), net.transition_count()), (22, 18));
    assert_eq!(initial(&net, "Pallets"), 3, "last-binding N=3");
    assert_eq!(net.initial_tokens(), 10);
    assert_eq!(
        timing(&net, "ew1"),
        Timing::Exponential {
            rate: 1.2,
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        timing(&net, "repM3"),
        Timing::Immediate {
            weight: 1.0,
            priority: 3
        }
    );
    let net = load(&fms, None, &[("N", "5")]);
    assert_eq!(initial(&net, "Pallets"), 5);
    assert_eq!(net.initial_tokens(), 12);

    // rw: constant N = 5 tokens in Think; template K (last-binding 1) is an arc multiplicity.
    let rw = greatspn("greatspn_examples/rw.PNPRO");
    let net = load(&rw, None, &[]);
    assert_eq!((net.place_count(), net.transition_count()), (7, 7));
    assert_eq!(initial(&net, "Think"), 5);
    assert_eq!(net.initial_tokens(), 6);
    assert_eq!(weight(&net, ArcKind::Input, "Choice", "is_read"), 1);
    assert_eq!(weight(&net, ArcKind::Inhibitor, "Reading", "startWrite"), 1);
    let net = load(&rw, None, &[("K", "2")]);
    assert_eq!(weight(&net, ArcKind::Input, "Choice", "is_read"), 2);
    assert_eq!(weight(&net, ArcKind::Input, "Choice", "is_write"), 2);
}

#[test]
fn expressions_combine_constants_templates_and_functions() {
    let file = data("expressions.PNPRO");
    let net = load(&file, None, &[]);
    // N = 4, K = Max[2, N - 1] = 3, speed = 1.5, base = 0.25.
    assert_eq!(initial(&net, "Idle:robot"), 6);
    assert_eq!(
        timing(&net, "start"),
        Timing::Exponential {
            rate: 1.875,
            servers: Servers::K(3)
        }
    );
    assert_eq!(
        timing(&net, "finish"),
        Timing::Exponential {
            rate: 0.5,
            servers: Servers::Single
        }
    );
    assert_eq!(
        timing(&net, "abort"),
        Timing::Immediate {
            weight: 0.0,
            priority: 2
        }
    );
    assert_eq!(weight(&net, ArcKind::Input, "Idle:robot", "start"), 3);
    assert_eq!(weight(&net, ArcKind::Inhibitor, "Idle:robot", "abort"), 4);
    let net = load(&file, None, &[("N", "6"), ("speed", "2")]);
    assert_eq!(initial(&net, "Idle:robot"), 10);
    assert_eq!(
        timing(&net, "start"),
        Timing::Exponential {
            rate: 2.5,
            servers: Servers::K(5)
        }
    );
    assert_eq!(weight(&net, ArcKind::Inhibitor, "Idle:robot", "abort"), 6);
}

fn at(e: &LoadError) -> (u32, u32) {
    let Span { line, column } = e.span.unwrap_or_else(|| panic!("no span: {e}"));
    (line, column)
}

#[test]
fn unknown_page_lists_the_pages() {
    let file = greatspn("gspnr_toolbox/creating_GSPNs.PNPRO");
    let e = load_err(&file, Some("Model3"), &[]);
    let LoadErrorKind::Invalid(msg) = &e.kind else {
        panic!("{e}");
    };
    assert!(msg.contains("`Model3` does not exist"), "{msg}");
    assert!(msg.contains("`Model`, `Model2`"), "{msg}");
    assert_eq!(at(&e), (2, 76));
}

#[test]
fn coloured_net_is_refused_naming_the_place() {
    let e = load_err(&greatspn("greatspn_examples/polling.PNPRO"), None, &[]);
    let LoadErrorKind::Unsupported(msg) = &e.kind else {
        panic!("{e}");
    };
    assert!(
        msg.contains("place `TokIn_C` has colour domain `L`"),
        "{msg}"
    );
    assert_eq!(at(&e), (6, 22));
    let e = load_err(&greatspn("greatspn_examples/multiproc.PNPRO"), None, &[]);
    assert!(e.to_string().contains("OwnMemAcc"), "{e}");
}

#[test]
fn bad_expression_is_refused_with_its_position() {
    let e = load_err(&data("bad_expression.PNPRO"), None, &[]);
    let LoadErrorKind::Expression { expr, name, reason } = &e.kind else {
        panic!("{e}");
    };
    assert_eq!((expr.as_str(), name.as_str()), ("2 * (lambda", "T1"));
    assert!(reason.contains("expected `)`"), "{reason}");
    // The value starts at column 26; the error is at its end (11 characters on).
    assert_eq!(at(&e), (6, 37));
}

#[test]
fn unknown_identifier_is_refused_with_its_position() {
    let e = load_err(&data("unknown_identifier.PNPRO"), None, &[]);
    let LoadErrorKind::Expression { expr, name, reason } = &e.kind else {
        panic!("{e}");
    };
    assert_eq!((expr.as_str(), name.as_str()), ("Kmax + 1", "P1 → T1"));
    assert!(reason.contains("unknown identifier `Kmax`"), "{reason}");
    assert_eq!(at(&e), (10, 41));
}

#[test]
fn unbound_template_asks_for_a_param() {
    let file = data("unbound_template.PNPRO");
    let e = load_err(&file, None, &[]);
    let LoadErrorKind::Expression { reason, .. } = &e.kind else {
        panic!("{e}");
    };
    assert!(reason.contains("--param N=VALUE"), "{reason}");
    assert_eq!(at(&e), (6, 23));
    let net = load(&file, None, &[("N", "7")]);
    assert_eq!(net.initial_tokens(), 7);
    let e = load_err(&file, None, &[("N", "2.5")]);
    assert!(e.to_string().contains("INTEGER"), "{e}");
}

#[test]
fn param_naming_no_template_is_refused() {
    let e = load_err(
        &greatspn("greatspn_examples/fms.PNPRO"),
        None,
        &[("M", "2")],
    );
    assert_eq!(
        e.kind,
        LoadErrorKind::UnknownNode {
            what: "template parameter",
            name: "M".into()
        }
    );
    let e = load_err(
        &greatspn("greatspn_examples/fms.PNPRO"),
        None,
        &[("N", "lots")],
    );
    assert!(matches!(e.kind, LoadErrorKind::NotANumber { .. }), "{e}");
}

#[test]
fn bad_values_are_refused_with_their_position() {
    let e = load_err(&data("negative_rate.PNPRO"), None, &[]);
    assert_eq!(
        e.kind,
        LoadErrorKind::OutOfRange {
            what: "rate",
            name: "T1".into(),
            value: "1 - mu = -2".into(),
            expected: "must be a finite number > 0",
        }
    );
    assert_eq!(at(&e), (6, 26));

    let e = load_err(&data("negative_marking.PNPRO"), None, &[]);
    assert!(
        matches!(&e.kind, LoadErrorKind::OutOfRange { what: "initial marking", name, .. } if name == "P1"),
        "{e}"
    );
    assert_eq!(at(&e), (5, 23));

    let e = load_err(&data("zero_multiplicity.PNPRO"), None, &[]);
    assert!(
        matches!(
            &e.kind,
            LoadErrorKind::OutOfRange {
                what: "arc multiplicity",
                ..
            }
        ),
        "{e}"
    );
    assert_eq!(at(&e), (9, 41));
}

#[test]
fn structural_errors_are_refused_with_their_position() {
    let e = load_err(&data("unknown_place.PNPRO"), None, &[]);
    assert_eq!(
        e.kind,
        LoadErrorKind::UnknownNode {
            what: "place",
            name: "P9".into()
        }
    );
    assert_eq!(at(&e), (10, 18));

    let e = load_err(&data("duplicate_place.PNPRO"), None, &[]);
    assert_eq!(
        e.kind,
        LoadErrorKind::Duplicate {
            what: "place",
            name: "P1".into()
        }
    );
    assert_eq!(at(&e), (6, 7));

    let e = load_err(&data("general_transition.PNPRO"), None, &[]);
    let LoadErrorKind::Unsupported(msg) = &e.kind else {
        panic!("{e}");
    };
    assert!(msg.contains("transition `Det` is general"), "{msg}");
    assert_eq!(at(&e), (6, 49));

    let e = load_err(&data("truncated.PNPRO"), None, &[]);
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)), "{e}");
    assert_eq!(at(&e).0, 8);
}

#[test]
fn files_that_are_not_projects_are_refused() {
    let e = load_err(&data("not_a_project.PNPRO"), None, &[]);
    let LoadErrorKind::Invalid(msg) = &e.kind else {
        panic!("{e}");
    };
    assert!(msg.contains("root element is `<pnml>`"), "{msg}");
    assert_eq!(at(&e), (2, 1));

    // An INPUT arc must go from a place to a transition.
    let e = load_err(&data("wrong_direction.PNPRO"), None, &[]);
    let LoadErrorKind::Invalid(msg) = &e.kind else {
        panic!("{e}");
    };
    assert_eq!(msg, "INPUT arc t1 → P1: `t1` is not a place");
    assert_eq!(at(&e), (9, 41));

    let empty = pnpro::read(Path::new("e.PNPRO"), b"  \n", &ReadOptions::default());
    assert_eq!(empty.unwrap_err().kind, LoadErrorKind::Empty);
    let e = pnpro::read(
        Path::new("b.PNPRO"),
        b"<project>\xff</project>",
        &ReadOptions::default(),
    )
    .unwrap_err();
    assert!(matches!(e.kind, LoadErrorKind::Xml(_)), "{e}");
    assert_eq!(at(&e), (1, 10));
}

#[test]
fn nan_infinite_and_zero_rates_are_refused() {
    for (delay, shown) in [("NaN", "NaN"), ("inf", "inf"), ("0", "0"), ("1/0", "")] {
        let text = format!(
            "<project name=\"p\">\n<gspn name=\"g\"><nodes>\n\
             <transition name=\"T\" type=\"EXP\" delay=\"{delay}\"/>\n\
             </nodes></gspn></project>"
        );
        let e = pnpro::read(
            Path::new("r.PNPRO"),
            text.as_bytes(),
            &ReadOptions::default(),
        )
        .unwrap_err();
        assert_eq!(at(&e), (3, 40), "{e}");
        match &e.kind {
            LoadErrorKind::OutOfRange { what, value, .. } => {
                assert_eq!((*what, value.as_str()), ("rate", shown));
            }
            LoadErrorKind::Expression { reason, .. } => {
                assert_eq!((delay, reason.as_str()), ("1/0", "division by zero"));
            }
            _ => panic!("{e}"),
        }
    }
}

/// Issue 30, snag 8: a GreatSPN editor file of format v100 spells the arc attributes
/// `type=` and `multiplicity=`; it was refused (`attribute 'kind' of <arc> is missing`).
/// Read with either spelling, the cleaning net (weights 2 and 4, an inhibitor) is the same.
#[test]
fn v100_arcs_with_type_and_multiplicity_read_as_kind_and_mult() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/cleaning/net.PNPRO");
    let text = std::fs::read_to_string(&path).unwrap();
    let v100 = text
        .replace(" kind=\"", " type=\"")
        .replace(" mult=\"", " multiplicity=\"");
    assert!(v100.contains("multiplicity=\"4\"") && v100.contains("type=\"INHIBITOR\""));
    assert!(!v100.contains(" kind=\""));
    let dir = tempfile::tempdir().unwrap();
    let copy = dir.path().join("v100.PNPRO");
    std::fs::write(&copy, v100).unwrap();
    let (a, b) = (load(&path, None, &[]), load(&copy, None, &[]));
    assert_eq!(b.arcs().len(), a.arcs().len());
    assert_eq!(
        gspn::runtime::journal::net_hash(&a),
        gspn::runtime::journal::net_hash(&b)
    );
    let w2 = b.arcs().iter().filter(|arc| arc.weight == 2).count();
    let w4 = b.arcs().iter().filter(|arc| arc.weight == 4).count();
    assert_eq!((w2 > 0, w4 > 0), (true, true));
}
