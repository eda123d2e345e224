//! Deeply nested input is refused with a located error (exit code 2, file, line, column),
//! never a stack overflow (issue 14, defect 4: `delay` with 5,000 nested parentheses or
//! 100,000 leading `-`/`!`, `stop.when` / `--prob` with 5,000 levels, 9,000 nested `<page>`
//! elements used to abort with exit 134). Every input is generated here.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use gspn::io::expr::{self, Expr};
use gspn::io::pnpro::MAX_CONSTANT_CHAIN;
use gspn::io::{LoadErrorKind, MAX_XML_DEPTH, ReadOptions, Span, read_net};
use gspn::net::predicate::{self, Predicate};

/// The transition line of [`pnpro`] up to the opening quote of `delay`.
const DELAY_PREFIX: &str = r#"      <transition name="T1" type="EXP" delay=""#;

/// A one-place, one-transition PNPRO project whose transition's delay is `delay` (line 6)
/// and whose constants are `constants` (lines 7...).
fn pnpro(delay: &str, constants: &str) -> String {
    format!(
        "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n\
         <project name=\"deep\" version=\"121\">\n\
         \x20 <gspn name=\"deep\">\n\
         \x20   <nodes>\n\
         \x20     <place marking=\"1\" name=\"P1\"/>\n\
         {DELAY_PREFIX}{delay}\"/>\n\
         {constants}\
         \x20   </nodes>\n\
         \x20   <edges>\n\
         \x20     <arc head=\"T1\" kind=\"INPUT\" tail=\"P1\"/>\n\
         \x20     <arc head=\"P1\" kind=\"OUTPUT\" tail=\"T1\"/>\n\
         \x20   </edges>\n\
         \x20 </gspn>\n\
         </project>\n"
    )
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Runs `plan-runner ARGS`; asserts exit code 2, no panic or abort, and that stderr holds
/// every needle. Returns stderr.
fn refused(args: &[&str], needles: &[&str]) -> String {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "exit code; stderr: {stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert!(!stderr.contains("overflow"), "{stderr}");
    for n in needles {
        assert!(stderr.contains(n), "`{n}` missing from: {stderr}");
    }
    stderr
}

/// `plan-runner check` refuses the PNPRO file whose delay is `delay` at line 6, column
/// `column`, and the library says the same.
fn delay_refused_at(delay: &str, column: u32) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "deep.PNPRO", &pnpro(delay, ""));
    let shown = path.display().to_string();
    let located = format!("{shown}:6:{column}:");
    refused(
        &["check", &shown],
        &[&located, "nests deeper than 256 levels", "`T1`"],
    );
    let e = read_net(&path, &ReadOptions::default()).unwrap_err();
    assert_eq!(e.span, Some(Span { line: 6, column }));
    assert!(
        matches!(&e.kind, LoadErrorKind::Expression { name, reason, .. }
            if name == "T1" && reason.contains("deeper than 256")),
        "{:?}",
        e.kind
    );
}

/// Column (from 1) of the character at byte `offset` of the delay's value.
fn delay_column(offset: usize) -> u32 {
    (DELAY_PREFIX.len() + offset + 1) as u32
}

#[test]
fn a_delay_with_5000_nested_parentheses_is_refused_at_the_257th() {
    let delay = format!("{}1{}", "(".repeat(5000), ")".repeat(5000));
    delay_refused_at(&delay, delay_column(expr::MAX_DEPTH));
}

#[test]
fn a_delay_with_100000_leading_minus_or_not_signs_is_refused_at_the_257th() {
    delay_refused_at(
        &format!("{}1", "-".repeat(100_000)),
        delay_column(expr::MAX_DEPTH),
    );
    delay_refused_at(
        &format!("{}1", "!".repeat(100_000)),
        delay_column(expr::MAX_DEPTH),
    );
}

#[test]
fn a_delay_that_chains_100000_additions_is_refused_at_the_257th_plus() {
    // `1+1+…` builds a tree as deep as its operators: evaluating or dropping it recursed once
    // per `+`. The 257th `+` would make the tree 257 deep; it sits at byte 2·257 − 1.
    let delay = vec!["1"; 100_000].join("+");
    delay_refused_at(&delay, delay_column(2 * (expr::MAX_DEPTH + 1) - 1));
}

#[test]
fn expressions_at_the_depth_limit_still_parse_and_evaluate() {
    let n = expr::MAX_DEPTH;
    let parens = format!("{}2{}", "(".repeat(n), ")".repeat(n));
    let minus = format!("{}2", "-".repeat(n));
    let chain = vec!["1"; n + 1].join("+");
    let none = &mut |_: &str, _| Err::<f64, ()>(());
    assert_eq!(Expr::parse(&parens).unwrap().eval(none), Ok(2.0));
    assert_eq!(Expr::parse(&minus).unwrap().eval(none), Ok(2.0));
    assert_eq!(Expr::parse(&chain).unwrap().eval(none), Ok((n + 1) as f64));
    let e = Expr::parse(&format!("{}2", "-".repeat(n + 1))).unwrap_err();
    assert_eq!(e.at, n);
}

#[test]
fn a_chain_of_constants_longer_than_the_limit_is_refused_at_its_last_use() {
    // C0 = C1 + 1, C1 = C2 + 1, …: each link evaluates the next inside itself.
    let consts = |n: usize| -> String {
        (0..n)
            .map(|i| {
                let value = if i + 1 < n {
                    format!("C{} + 1", i + 1)
                } else {
                    "1".into()
                };
                format!("      <constant consttype=\"REAL\" name=\"C{i}\" value=\"{value}\"/>\n")
            })
            .collect()
    };
    let dir = tempfile::tempdir().unwrap();
    let ok = write(
        dir.path(),
        "ok.PNPRO",
        &pnpro("C0", &consts(MAX_CONSTANT_CHAIN)),
    );
    let net = read_net(&ok, &ReadOptions::default()).unwrap().net;
    let gspn::net::Timing::Exponential { rate, .. } = net.transitions()[0].timing else {
        panic!("T1 is exponential")
    };
    // A PNPRO `delay` is the rate: C0 = C1 + 1 = … = 16.
    assert_eq!(rate, MAX_CONSTANT_CHAIN as f64);

    let long = write(dir.path(), "long.PNPRO", &pnpro("C0", &consts(10_000)));
    let shown = long.display().to_string();
    // C15's value `C16 + 1` is on line 7 + 15; `C16` starts right after `value="`.
    let line = 7 + (MAX_CONSTANT_CHAIN - 1);
    let column = r#"      <constant consttype="REAL" name="C15" value=""#.len() + 1;
    let located = format!("{shown}:{line}:{column}:");
    refused(
        &["check", &shown],
        &[&located, "chain of more than 16 constants"],
    );
    let e = read_net(&long, &ReadOptions::default()).unwrap_err();
    assert_eq!(
        e.span,
        Some(Span {
            line: line as u32,
            column: column as u32
        })
    );
}

#[test]
fn pipe_xml_with_9000_nested_pages_is_refused_at_the_first_too_deep() {
    let dir = tempfile::tempdir().unwrap();
    let text = format!(
        "<?xml version=\"1.0\"?>\n<pnml>\n<net id=\"n\">\n{}{}\n</net>\n</pnml>\n",
        "<page>".repeat(9000),
        "</page>".repeat(9000)
    );
    let path = write(dir.path(), "deep.xml", &text);
    // `<pnml>` and `<net>` are open, so page k is element k + 2: the page that would be
    // element MAX_XML_DEPTH + 1 is refused, on line 4 at its `<`.
    let k = MAX_XML_DEPTH + 1 - 2;
    let column = (k - 1) * "<page>".len() + 1;
    let shown = path.display().to_string();
    let located = format!("{shown}:4:{column}:");
    refused(
        &["check", &shown],
        &[&located, "nested deeper than 256 levels"],
    );
    let e = read_net(&path, &ReadOptions::default()).unwrap_err();
    assert_eq!(
        e.span,
        Some(Span {
            line: 4,
            column: column as u32
        })
    );
}

/// A plan over the [`pnpro`] net whose `stop.when` is `when`, on line 3.
fn plan_with_stop_when(dir: &Path, when: &str) -> PathBuf {
    write(dir, "deep.PNPRO", &pnpro("1", ""));
    write(
        dir,
        "plan.toml",
        &format!("net = \"deep.PNPRO\"\n[stop]\nwhen = \"{when}\"\n"),
    )
}

#[test]
fn a_stop_when_with_5000_levels_is_refused_in_the_plan_at_the_257th() {
    let dir = tempfile::tempdir().unwrap();
    for (when, what) in [
        (
            format!("{}P1 > 0{}", "(".repeat(5000), ")".repeat(5000)),
            "parentheses",
        ),
        (format!("{}P1 > 0", "!".repeat(5000)), "negations"),
        (format!("{}P1 > 0", "-".repeat(5000)), "minus signs"),
    ] {
        let plan = plan_with_stop_when(dir.path(), &when);
        let shown = plan.display().to_string();
        // `when = "` is 8 characters; the 257th opening character is at offset 256.
        let located = format!("{shown}:3:{}:", 8 + predicate::MAX_DEPTH + 1);
        let stderr = refused(
            &["check", &shown],
            &[&located, "stop.when", "nests deeper than 256 levels"],
        );
        assert!(stderr.len() < 2_000, "{what}: {}", stderr.len());
    }
}

#[test]
fn a_prob_predicate_with_5000_levels_is_refused_with_its_column() {
    let dir = tempfile::tempdir().unwrap();
    let net = write(dir.path(), "deep.PNPRO", &pnpro("1", ""));
    let prob = format!("{}P1 > 0{}", "(".repeat(5000), ")".repeat(5000));
    refused(
        &["analyze", &net.display().to_string(), "--prob", &prob],
        &["--prob", "column 257:", "nests deeper than 256 levels"],
    );
}

#[test]
fn predicates_at_the_depth_limit_still_parse() {
    let mut b = gspn::net::NetBuilder::new("n");
    b.place("P1", 1);
    let net = b.build().unwrap();
    let n = predicate::MAX_DEPTH;
    let parens = format!("{}P1 > 0{}", "(".repeat(n), ")".repeat(n));
    assert!(Predicate::parse(&net, &parens).unwrap().eval(&[1]));
    // An even number of `!`: the condition itself.
    let nots = format!("{}P1 > 0", "!".repeat(n));
    assert!(Predicate::parse(&net, &nots).unwrap().eval(&[1]));
    let e = Predicate::parse(&net, &format!("{}P1 > 0", "!".repeat(n + 1))).unwrap_err();
    assert_eq!(e.column, n + 1);
}
