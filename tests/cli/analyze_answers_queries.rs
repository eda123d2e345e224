//! `plan-runner analyze --query Q`: Storm-syntax queries answered on cyc3 (values known in
//! closed form or from Storm), in text and JSON, in the order asked; a bad query refused with
//! a caret under its column (exit 2); `max`/`min` queries on a plan with controllable
//! transitions equal to `synthesize`; measures over time as CSV and SVG.

use crate::support::fixtures::fixture;

use std::path::Path;

use assert_cmd::Command;
use serde_json::Value;

fn run(args: &[&str]) -> (i32, String, String) {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).to_string(),
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

fn cyc3() -> String {
    fixture("greatspn/cyc3/cyc3_ss.PNPRO")
        .to_string_lossy()
        .into_owned()
}

#[test]
fn cyc3_queries_in_json_in_the_order_asked() {
    let f = cyc3();
    let (code, out, err) = run(&[
        "analyze",
        &f,
        "--json",
        "--query",
        "T=? [F P3=2]",
        "--query",
        "P=? [F<=1 P3>=2]",
        "--query",
        "S=? [P1==2]",
        "--query",
        "P=? [F P3=2]",
        "--query",
        "T=? [F P1=5]",
        "--query",
        "P=? [G<=1 P1>0]",
        "--query",
        "P=? [P1>0 U<=1 P3=2]",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    let q = j["queries"].as_array().unwrap();
    assert_eq!(q.len(), 7);
    let value = |i: usize| q[i]["value"].as_f64().unwrap();
    assert_eq!(q[0]["query"], "T=? [F P3=2]");
    // From (2,0,0): t0 = 1 + t1, t1 = 1/3 + 2/3·t0 ⇒ t0 = 4.
    assert!((value(0) - 4.0).abs() < 1e-9, "{}", value(0));
    // Storm 2.0.0 on the same file: 0.17773657609819044.
    assert!(
        (value(1) - 0.17773657609819044).abs() < 1e-9,
        "{}",
        value(1)
    );
    assert!((value(2) - 4.0 / 7.0).abs() < 1e-12);
    assert!((value(3) - 1.0).abs() < 1e-12);
    // P1 never holds 5 tokens: the expected time is infinite.
    assert_eq!(q[4]["value"], "inf");
    // G<=1 P1>0 misses only when both tokens have left P1: 1 − P[F<=1 P1=0].
    assert!(value(5) > 0.0 && value(5) < 1.0);
    // (0,0,2) is entered through the vanishing (0,1,1), where P1 = 0: the until fails.
    assert_eq!(value(6), 0.0);
}

#[test]
fn a_bad_query_points_at_its_column() {
    let f = cyc3();
    let (code, _, err) = run(&["analyze", &f, "--query", "P=? [F<=1 P9>=2]"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(
            "--query `P=? [F<=1 P9>=2]`: column 11: place `P9` does not exist\n  \
             P=? [F<=1 P9>=2]\n            ^"
        ),
        "{err}"
    );
    let (code, _, err) = run(&["analyze", &f, "--query", "P=? [F<=x P1=0]"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("column 9: expected a time ≥ 0 after `<=`"),
        "{err}"
    );
    // No controllable transition in cyc3: max/min is refused, not guessed.
    let (code, _, err) = run(&["analyze", &f, "--query", "Pmax=? [F P3=2]"]);
    assert_eq!(code, 2);
    assert!(err.contains("nothing is controllable"), "{err}");
}

fn synthesize_value(plan: &str, args: &[&str]) -> f64 {
    let mut all = vec!["synthesize", plan, "--json"];
    all.extend(args);
    let (code, out, err) = run(&all);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    j["value"].as_f64().unwrap()
}

#[test]
fn max_and_min_queries_are_the_synthesis_optimum() {
    let plan = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/home-cleaning/plan.toml");
    let plan = plan.to_str().unwrap();
    let (code, out, err) = run(&[
        "analyze",
        plan,
        "--json",
        "--query",
        "R{\"cleaning\"}max=? [S]",
        "--query",
        "Tmin=? [F L3>=1]",
        "--query",
        "Pmax=? [F Mopping_L3>=1]",
    ]);
    assert_eq!(code, 0, "{err}");
    let j: Value = serde_json::from_str(&out).unwrap();
    let value = |i: usize| j["queries"][i]["value"].as_f64().unwrap();
    let lra = synthesize_value(plan, &["--objective", "lra-max"]);
    let time = synthesize_value(plan, &["--objective", "time-min", "--goal", "L3 >= 1"]);
    // Both are the middle of an interval 1e-9 wide (relative): equal to within its width.
    assert!(
        (value(0) - lra).abs() < 1e-8 * lra.abs().max(1.0),
        "{} vs {lra}",
        value(0)
    );
    assert!(
        (value(1) - time).abs() < 1e-8 * time,
        "{} vs {time}",
        value(1)
    );
    assert!(time > 2.0, "two moves of mean 1 at least: {time}");
    assert!((value(2) - 1.0).abs() < 1e-9);
    // The engine has no time-bounded objective: refused with a message.
    let (code, _, err) = run(&["analyze", plan, "--query", "Pmax=? [F<=3 L3>=1]"]);
    assert_eq!(code, 2);
    assert!(
        err.contains("a time bound is not computed for max/min"),
        "{err}"
    );
}

#[test]
fn a_transient_sweep_is_written_as_csv_and_svg() {
    let f = cyc3();
    let dir = tempfile::tempdir().unwrap();
    let (csv, svg) = (dir.path().join("m.csv"), dir.path().join("m.svg"));
    let (code, _, err) = run(&[
        "analyze",
        &f,
        "--transient",
        "0:2:0.5",
        "--prob",
        "P3>0",
        "--query",
        "P=? [F<=1 P3>=2]",
        "--csv",
        csv.to_str().unwrap(),
        "--plot",
        svg.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let text = std::fs::read_to_string(&csv).unwrap();
    let lines: Vec<&str> = text.lines().collect();
    assert_eq!(lines[0], "t,E[P1],E[P2],E[P3],P(P3>0),P=? [F<=1 P3>=2]");
    assert_eq!(lines.len(), 6, "{text}");
    assert!(lines[1].starts_with("0,2,0,0,0,0"), "{text}");
    // The query's bound is each row's time: at t = 1 it is Storm's 0.17773657609819044.
    let at_1: Vec<f64> = lines[3].split(',').map(|x| x.parse().unwrap()).collect();
    assert_eq!(at_1[0], 1.0);
    assert!((at_1[5] - 0.17773657609819044).abs() < 1e-9, "{}", lines[3]);
    let picture = std::fs::read_to_string(&svg).unwrap();
    assert!(picture.starts_with("<svg"), "{picture}");
    assert!(picture.contains("P(P3&gt;0)") || picture.contains("P(P3>0)"));
    // Without times there is nothing to tabulate.
    let (code, _, err) = run(&["analyze", &f, "--csv", csv.to_str().unwrap()]);
    assert_eq!(code, 2);
    assert!(err.contains("give --transient times"), "{err}");
}
