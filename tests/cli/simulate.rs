//! `plan-runner simulate`: Monte-Carlo intervals that contain GreatSPN cyc3's exact answers,
//! byte-identical traces for a seed, plans, and bad input refused with exit code 2.

use crate::support::fixtures as shared_fixtures;

use assert_cmd::Command;
use serde_json::Value;
use shared_fixtures::fixture;

fn simulate(args: &[&str]) -> std::process::Output {
    Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("simulate")
        .args(args)
        .output()
        .unwrap()
}

fn json_of(out: &std::process::Output) -> Value {
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

fn interval(v: &Value, kind: &str, name: &str) -> (f64, f64) {
    let pair = &v["ci95"][kind][name];
    (pair[0].as_f64().unwrap(), pair[1].as_f64().unwrap())
}

fn contains(v: &Value, kind: &str, name: &str, x: f64) -> bool {
    let (lo, hi) = interval(v, kind, name);
    lo <= x && x <= hi
}

#[test]
fn single_server_cyc3_intervals_contain_the_exact_answers() {
    let net = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let out = simulate(&[
        net.to_str().unwrap(),
        "--runs",
        "200",
        "--until",
        "1000",
        "--json",
    ]);
    let v = json_of(&out);
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(
        keys,
        ["ci95", "firings", "mean_tokens", "runs", "throughput"]
    );
    assert_eq!(v["runs"], 200);
    // About 2 × 6/7 firings per unit of time (T1 and t2 and T3 each 6/7) over 200 × 1000.
    let firings = v["firings"].as_u64().unwrap() as f64;
    assert!((firings / 200_000.0 - 18.0 / 7.0).abs() < 0.05, "{firings}");
    assert!(
        contains(&v, "mean_tokens", "P1", 10.0 / 7.0),
        "{}",
        v["ci95"]
    );
    assert!(
        contains(&v, "mean_tokens", "P3", 4.0 / 7.0),
        "{}",
        v["ci95"]
    );
    assert_eq!(v["mean_tokens"]["P2"].as_f64(), Some(0.0));
    for t in ["T1", "t2", "T3"] {
        assert!(
            contains(&v, "throughput", t, 6.0 / 7.0),
            "{t}: {}",
            v["ci95"]
        );
    }
    let (lo, hi) = interval(&v, "mean_tokens", "P1");
    assert!(hi - lo < 0.02, "a tight interval: [{lo}, {hi}]");
}

#[test]
fn infinite_server_cyc3_interval_contains_four_thirds() {
    let net = fixture("greatspn/cyc3/cyc3.PNPRO");
    let out = simulate(&[
        net.to_str().unwrap(),
        "--runs",
        "200",
        "--until",
        "1000",
        "--json",
    ]);
    let v = json_of(&out);
    assert!(
        contains(&v, "mean_tokens", "P1", 4.0 / 3.0),
        "{}",
        v["ci95"]
    );
    assert!(
        contains(&v, "mean_tokens", "P3", 2.0 / 3.0),
        "{}",
        v["ci95"]
    );
    assert!(
        !contains(&v, "mean_tokens", "P1", 10.0 / 7.0),
        "not single-server"
    );
}

#[test]
fn same_seed_gives_a_byte_identical_trace() {
    let net = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let net = net.to_str().unwrap();
    let a = simulate(&[net, "--seed", "7", "--steps", "200"]);
    let b = simulate(&[net, "--seed", "7", "--steps", "200"]);
    let c = simulate(&[net, "--seed", "8", "--steps", "200"]);
    assert!(a.status.success());
    assert_eq!(a.stdout, b.stdout);
    assert_ne!(a.stdout, c.stdout);
    let text = String::from_utf8(a.stdout).unwrap();
    // Header, column names, the initial marking, 200 firings, the end line.
    assert_eq!(text.lines().count(), 204);
    assert!(text.lines().nth(2).unwrap().ends_with("P1=2"));
    assert!(text.lines().last().unwrap().contains("after 200 firings"));
    // Time-limited traces and JSON traces repeat too.
    let a = simulate(&[net, "--seed", "3", "--until", "50", "--json"]);
    let b = simulate(&[net, "--seed", "3", "--until", "50", "--json"]);
    assert_eq!(a.stdout, b.stdout);
    let v = json_of(&a);
    assert_eq!(v["time"].as_f64(), Some(50.0));
    let trace = v["trace"].as_array().unwrap();
    assert_eq!(trace.len() as u64, v["firings"].as_u64().unwrap());
    assert!(trace.iter().all(|s| s["time"].as_f64().unwrap() <= 50.0));
}

#[test]
fn a_plan_supplies_its_seed_and_firing_limit() {
    let net = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("cyc3.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\nseed = 5\n\n[stop]\nmax_firings = 20\n",
            net.to_str().unwrap()
        ),
    )
    .unwrap();
    let from_plan = simulate(&[plan.to_str().unwrap()]);
    let from_net = simulate(&[net.to_str().unwrap(), "--seed", "5", "--steps", "20"]);
    assert!(
        from_plan.status.success(),
        "{}",
        String::from_utf8_lossy(&from_plan.stderr)
    );
    assert_eq!(from_plan.stdout, from_net.stdout);
}

#[test]
fn bad_input_exits_with_code_2() {
    let net = fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let net = net.to_str().unwrap();
    for args in [
        vec![net, "--runs", "0"],
        vec![net, "--until", "-1"],
        vec![net, "--until", "NaN"],
        vec!["/nonexistent/net.PNPRO"],
    ] {
        let out = simulate(&args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        assert!(!out.stderr.is_empty());
    }
    let bad = fixture("thesis/azevedo_2020/ros/gspn_thesis_test_case.xml");
    let out = simulate(&[bad.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));

    // Two immediate transitions passing a token back and forth: a timeless trap.
    let dir = tempfile::tempdir().unwrap();
    let trap = dir.path().join("trap.PNPRO");
    std::fs::write(
        &trap,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<project name="trap" version="121">
  <gspn name="trap">
    <nodes>
      <place marking="1" name="P" x="1" y="1"/>
      <place name="Q" x="5" y="1"/>
      <transition name="there" type="IMM" x="3" y="0"/>
      <transition name="back" type="IMM" x="3" y="2"/>
    </nodes>
    <edges>
      <arc head="there" kind="INPUT" tail="P"/>
      <arc head="Q" kind="OUTPUT" tail="there"/>
      <arc head="back" kind="INPUT" tail="Q"/>
      <arc head="P" kind="OUTPUT" tail="back"/>
    </edges>
  </gspn>
</project>
"#,
    )
    .unwrap();
    let out = simulate(&[trap.to_str().unwrap(), "--until", "1"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("timeless trap at time 0"), "{err}");
}

/// Issue 30, snag 7: `simulate --runs` on a plan with `[rewards]` did not estimate them.
/// Each run's rate is its place rewards over time plus its impulses, so with `per_token`
/// rewards the estimate is the same combination of the mean-token and throughput
/// estimates, and its interval holds the exact rate `analyze` gives.
#[test]
fn monte_carlo_estimates_the_plans_rewards() {
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("patrol.toml");
    std::fs::write(
        &plan,
        format!(
            "net = {:?}\n\n[places.Charger]\nrole = \"resource\"\n\n[rewards.work]\nper_token = {{ Patrol_A = 1.0, Patrol_B = 2.0 }}\ntransitions = {{ T_charged = 3.0 }}\n",
            format!("{}/plans/nets/two_robot_patrol.xml", env!("CARGO_MANIFEST_DIR"))
        ),
    )
    .unwrap();
    let v = json_of(&simulate(&[
        plan.to_str().unwrap(),
        "--runs",
        "40",
        "--until",
        "200",
        "--seed",
        "3",
        "--json",
    ]));
    let x = |kind: &str, name: &str| v[kind][name].as_f64().unwrap();
    let rate = x("rewards", "work");
    let combined = x("mean_tokens", "Patrol_A")
        + 2.0 * x("mean_tokens", "Patrol_B")
        + 3.0 * x("throughput", "T_charged");
    assert!((rate - combined).abs() < 1e-9, "{rate} vs {combined}");
    let (lo, hi) = interval(&v, "rewards", "work");
    let exact = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["analyze", plan.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let exact: Value = serde_json::from_slice(&exact.stdout).unwrap();
    let exact = exact["steady_state"]["rewards"]["work"]["rate"]
        .as_f64()
        .unwrap_or_else(|| panic!("{exact}"));
    assert!(lo <= exact && exact <= hi, "{exact} not in [{lo}, {hi}]");
}
