//! `plan-runner analyze`: JSON values on cyc3 and a non-ergodic net, transient entries,
//! predicate probabilities, PRISM export, unbounded nets reported (exit 0), too many states
//! (exit 1) and bad input (exit 2).

use crate::support::fixtures as shared_fixtures;

use assert_cmd::Command;
use serde_json::Value;
use shared_fixtures::fixture;

fn analyze(args: &[&str]) -> (i32, Value, String) {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("analyze")
        .args(args)
        .output()
        .unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    let json = serde_json::from_str(&stdout).unwrap_or(Value::Null);
    (
        out.status.code().unwrap_or(-1),
        json,
        String::from_utf8_lossy(&out.stderr).to_string(),
    )
}

fn close(v: &Value, x: f64) -> bool {
    (v.as_f64().expect("a number") - x).abs() < 1e-9
}

#[test]
fn cyc3_json_has_state_space_steady_state_and_transient() {
    let f = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let (code, j, err) = analyze(&[
        f.to_str().unwrap(),
        "--steady",
        "--transient",
        "0,1",
        "--json",
        "--prob",
        "P3>0",
    ]);
    assert_eq!(code, 0, "{err}");
    let ss = &j["state_space"];
    for key in [
        "reachable",
        "tangible",
        "vanishing",
        "edges",
        "dead_markings",
        "bounded",
        "unbounded_places",
        "place_bounds",
        "max_tokens_in_place",
        "max_tokens_per_marking",
        "safe",
        "reversible",
        "deadlock_free",
        "live_transitions",
        "dead_transitions",
        "p_invariants",
        "t_invariants",
    ] {
        assert!(ss.get(key).is_some(), "state_space.{key} missing");
    }
    assert_eq!(
        (ss["reachable"].as_u64(), ss["tangible"].as_u64()),
        (Some(5), Some(3))
    );
    assert_eq!(ss["vanishing"], 2);
    assert_eq!(ss["bounded"], true);
    assert_eq!(ss["place_bounds"]["P1"], 2);
    assert_eq!(ss["deadlock_free"], true);
    assert_eq!(ss["reversible"], true);
    let st = &j["steady_state"];
    assert_eq!(st["ergodic"], true);
    assert!(close(&st["mean_tokens"]["P1"], 10.0 / 7.0));
    assert!(close(&st["mean_tokens"]["P3"], 4.0 / 7.0));
    assert!(close(&st["prob_nonempty"]["P3"], 3.0 / 7.0));
    for t in ["T1", "t2", "T3"] {
        assert!(close(&st["throughput"][t], 6.0 / 7.0));
    }
    // Little: E[P1] / X(T1) = (10/7) / (6/7).
    assert!(close(&st["mean_wait"]["P1"], 10.0 / 6.0));
    assert!(close(&st["probability"]["P3>0"], 3.0 / 7.0));
    let tr = j["transient"].as_array().unwrap();
    assert_eq!(tr.len(), 2);
    assert!(close(&tr[0]["t"], 0.0) && close(&tr[0]["mean_tokens"]["P1"], 2.0));
    assert!(close(&tr[1]["t"], 1.0));
    assert!(tr[1]["throughput"]["T3"].as_f64().unwrap() > 0.0);
}

#[test]
fn non_ergodic_net_reports_its_limiting_distribution() {
    let f = fixture("thesis/caldeira_2020_package/standalone_example/example_gspn.xml");
    let (code, j, _) = analyze(&[f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    assert_eq!(j["state_space"]["dead_markings"][0], "p3=2");
    assert_eq!(j["state_space"]["deadlock_free"], false);
    assert_eq!(j["steady_state"]["ergodic"], false);
    assert!(close(&j["steady_state"]["mean_tokens"]["p3"], 2.0));
    assert_eq!(j["steady_state"]["mean_wait"]["p3"], Value::Null);
}

#[test]
fn unbounded_net_is_reported_with_its_places() {
    let f = fixture("thesis/caldeira_2020_package/ros_Example/example_gspn.xml");
    let (code, j, _) = analyze(&[f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0);
    assert_eq!(j["state_space"]["bounded"], false);
    assert_eq!(
        j["state_space"]["unbounded_places"],
        serde_json::json!(["p4"])
    );
}

#[test]
fn too_many_states_is_an_analysis_failure() {
    let f = fixture("generated/ring_K4_N100.xml");
    let (code, _, err) = analyze(&[f.to_str().unwrap(), "--max-states", "100"]);
    assert_eq!(code, 1);
    assert!(err.contains("more than 100"), "{err}");
}

#[test]
fn bad_input_exits_2() {
    let f = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let (code, _, err) = analyze(&[f.to_str().unwrap(), "--prob", "Nope > 0"]);
    assert_eq!(code, 2);
    assert!(err.contains("Nope"), "{err}");
    let (code, _, _) = analyze(&[f.to_str().unwrap(), "--transient", "-1"]);
    assert_eq!(code, 2);
    // A time uniformisation could never reach (Λ = 3: Λ·t iterations), refused before its
    // Poisson weights are allocated.
    let (code, _, err) = analyze(&[f.to_str().unwrap(), "--transient", "0.5,1e300"]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains(
            "--transient: t = 1e300 needs about 3.000e300 iterations of uniformisation (Λ·t, \
             Λ = 3, the largest exit rate); at most 1e11"
        ),
        "{err}"
    );
    let (code, _, _) = analyze(&["/nonexistent/net.xml"]);
    assert_eq!(code, 2);
}

#[test]
fn prism_export_writes_the_chain() {
    let dir = tempfile::tempdir().unwrap();
    let prefix = dir.path().join("cyc3");
    let f = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let (code, _, err) = analyze(&[
        f.to_str().unwrap(),
        "--export-prism",
        prefix.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let tra = std::fs::read_to_string(dir.path().join("cyc3.tra")).unwrap();
    assert_eq!(tra.lines().next(), Some("3 4"));
    let sta = std::fs::read_to_string(dir.path().join("cyc3.sta")).unwrap();
    assert_eq!(sta.lines().next(), Some("(P1,P2,P3)"));
    assert!(sta.contains("0:(2,0,0)"));
    let lab = std::fs::read_to_string(dir.path().join("cyc3.lab")).unwrap();
    assert!(lab.contains("0: 0"));
}

/// Issue 27: `--export-prism` writes each of the plan's reward structures as a PRISM state
/// reward file, impulses folded in at their firing rates. On cyc3 (tangible markings (2,0,0),
/// (1,0,1), (0,0,2); T3 fires at rate 2 while P3 is marked) with 1 per token in P1 and 3 per
/// firing of T3: 2, 1 + 2·3 = 7 and 0 + 2·3 = 6.
#[test]
fn prism_export_writes_a_reward_file_per_reward_structure() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\n\n[rewards.work]\nper_token = {{ P1 = 1.0 }}\ntransitions = {{ T3 = 3.0 }}\n",
            fixture("greatspn/cyc3/cyc3_ss.PNPRO")
        ),
    )
    .unwrap();
    let prefix = dir.path().join("cyc3");
    let (code, _, err) = analyze(&[
        plan.to_str().unwrap(),
        "--export-prism",
        prefix.to_str().unwrap(),
    ]);
    assert_eq!(code, 0, "{err}");
    let sta = std::fs::read_to_string(dir.path().join("cyc3.sta")).unwrap();
    let srew = std::fs::read_to_string(dir.path().join("cyc3.work.srew")).unwrap();
    let mut lines = srew.lines();
    assert_eq!(lines.next(), Some("3 3"), "{srew}");
    let reward: std::collections::HashMap<&str, f64> = lines
        .map(|l| {
            let (s, r) = l.split_once(' ').unwrap();
            (s, r.parse().unwrap())
        })
        .collect();
    let mut seen = 0;
    for line in sta.lines().skip(1) {
        let (s, marking) = line.split_once(':').unwrap();
        let want = match marking {
            "(2,0,0)" => 2.0,
            "(1,0,1)" => 7.0,
            "(0,0,2)" => 6.0,
            other => panic!("unexpected tangible marking {other}"),
        };
        assert!((reward[s] - want).abs() < 1e-12, "{s} {marking}: {srew}");
        seen += 1;
    }
    assert_eq!(seen, 3);
}

/// Issue 30, snag 8: two edge counts, each named for what it is. On Eratosthenes-PT-010
/// the labelled count (one per marking and fired transition) is the fixture oracle's
/// `TRANSITIONS 120`; `t6.2` and `t6.3` both remove `p6`, so the distinct successor
/// pairs are fewer: 80 (by enumeration of the 32 markings; on PT-020 the same two counts
/// are 23,040 and 11,264).
#[test]
fn analyze_reports_labelled_edges_and_distinct_successor_pairs() {
    let f = fixture("mcc/Eratosthenes-PT-010/model.pnml");
    let oracle = std::fs::read_to_string(fixture(
        "mcc/Eratosthenes-PT-010/StateSpace-oracle-2021.out",
    ))
    .unwrap();
    assert!(oracle.contains("STATE_SPACE TRANSITIONS 120 "), "{oracle}");
    let (code, j, err) = analyze(&[f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let ss = &j["state_space"];
    assert_eq!(ss["reachable"], 32);
    assert_eq!(ss["edges"], 120);
    assert_eq!(ss["successor_pairs"], 80);
}

/// Issue 30, snag 7: `--transient 5` also printed the steady state (with --prob); a time
/// asks for that time only, the steady state comes with --steady.
#[test]
fn transient_alone_prints_no_steady_state() {
    let f = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let (code, j, err) = analyze(&[
        f.to_str().unwrap(),
        "--transient",
        "5",
        "--prob",
        "P3>0",
        "--json",
    ]);
    assert_eq!(code, 0, "{err}");
    assert_eq!(j["steady_state"], Value::Null, "{j}");
    let tr = j["transient"].as_array().unwrap();
    assert_eq!(tr.len(), 1);
    assert!(close(&tr[0]["t"], 5.0));
    let p = tr[0]["probability"]["P3>0"].as_f64().unwrap();
    assert!(p > 0.0 && p < 1.0, "{p}");
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["analyze", f.to_str().unwrap(), "--transient", "5"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(!text.contains("steady state"), "{text}");
    let (_, j, _) = analyze(&[
        f.to_str().unwrap(),
        "--transient",
        "5",
        "--steady",
        "--json",
    ]);
    assert!(close(&j["steady_state"]["mean_tokens"]["P1"], 10.0 / 7.0));
}

/// Issue 33: `--states-only` answers the cheapest question (counts, bounds, dead markings)
/// from a search that stores no arc: FMS-PT-00002's oracle (3,444 states, 16,311
/// transitions, at most 3 tokens in a place and 12 in a marking), and on Eratosthenes-PT-010
/// the same successor pairs, bounds and dead markings as the full analysis.
#[test]
fn states_only_gives_the_oracles_counts_without_storing_arcs() {
    let f = fixture("mcc/FMS-PT-00002/model.pnml");
    let oracle =
        std::fs::read_to_string(fixture("mcc/FMS-PT-00002/StateSpace-oracle-2021.out")).unwrap();
    assert!(oracle.contains("STATE_SPACE STATES 3444 "), "{oracle}");
    assert!(
        oracle.contains("STATE_SPACE TRANSITIONS 16311 "),
        "{oracle}"
    );
    let (code, j, err) = analyze(&[f.to_str().unwrap(), "--states-only", "--json"]);
    assert_eq!(code, 0, "{err}");
    let ss = &j["state_space"];
    assert_eq!(ss["reachable"], 3444);
    assert_eq!(ss["vanishing"], 0);
    assert_eq!(ss["edges"], 16311);
    assert_eq!(ss["max_tokens_in_place"], 3);
    assert_eq!(ss["max_tokens_per_marking"], 12);
    assert_eq!(j["steady_state"], Value::Null);
    assert_eq!(ss["reversible"], Value::Null);
    let f = fixture("mcc/Eratosthenes-PT-010/model.pnml");
    let (code, only, err) = analyze(&[f.to_str().unwrap(), "--states-only", "--json"]);
    assert_eq!(code, 0, "{err}");
    let (code, full, err) = analyze(&[f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let (only, full) = (&only["state_space"], &full["state_space"]);
    for key in [
        "reachable",
        "edges",
        "successor_pairs",
        "place_bounds",
        "dead_markings",
        "deadlock_free",
        "max_tokens_per_marking",
    ] {
        assert_eq!(only[key], full[key], "{key}");
    }
    assert_eq!(only["successor_pairs"], 80);
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["analyze", f.to_str().unwrap(), "--states-only"])
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("32 reachable markings (32 tangible, 0 vanishing), 120 labelled arcs (80 distinct successor pairs)"),
        "{text}"
    );
}

/// A net with immediate transitions: the census counts the full graph (vanishing markings
/// included) and leaves out the edges after elimination, which need the arcs; what needs
/// a solver is refused with exit code 2.
#[test]
fn states_only_counts_vanishing_markings_and_refuses_solver_options() {
    let f = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let (code, only, err) = analyze(&[f.to_str().unwrap(), "--states-only", "--json"]);
    assert_eq!(code, 0, "{err}");
    let (code, full, err) = analyze(&[f.to_str().unwrap(), "--json"]);
    assert_eq!(code, 0, "{err}");
    let (only, full) = (&only["state_space"], &full["state_space"]);
    assert_eq!(
        (&only["reachable"], &only["tangible"]),
        (&Value::from(5), &Value::from(3))
    );
    for key in [
        "vanishing",
        "successor_pairs",
        "place_bounds",
        "dead_markings",
    ] {
        assert_eq!(only[key], full[key], "{key}");
    }
    assert_eq!(only["edges"], Value::Null);
    let (code, _, err) = analyze(&[
        f.to_str().unwrap(),
        "--states-only",
        "--steady",
        "--prob",
        "P1>0",
    ]);
    assert_eq!(code, 2, "{err}");
    assert!(
        err.contains("--states-only stores no arc and solves nothing: --steady, --prob cannot be answered with it"),
        "{err}"
    );
}
