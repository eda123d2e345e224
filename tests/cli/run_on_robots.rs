//! `plan-runner run PLAN --robots N` on a plan with a `[map]`: the JSON summary gains `sim`
//! with exactly the documented keys; plans without a map and nets that would create robots
//! are refused with exit code 2.
#![cfg(feature = "sim")]

use std::path::PathBuf;
use std::process::Command;

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

#[test]
fn the_patrol_runs_on_two_robots_and_reports_the_world() {
    let plan = repo("plans/temperature-patrol/plan.toml");
    let out = bin()
        .args([
            "run",
            plan.to_str().unwrap(),
            "--robots",
            "2",
            "--until",
            "300",
            "--json",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["stopped"], "time_limit");
    assert_eq!(v["time"], 300.0);
    let sim = v["sim"].as_object().unwrap();
    let mut keys: Vec<&str> = sim.keys().map(String::as_str).collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "collisions",
            "cycles_per_robot",
            "min_separation_m",
            "order_violations",
            "real_time_factor",
            "robots",
            "sim_time_s",
            "stuck_events"
        ]
    );
    assert_eq!(sim["robots"], 2);
    assert_eq!(sim["collisions"], 0);
    assert_eq!(sim["order_violations"], 0);
    assert_eq!(sim["stuck_events"], 0);
    let t = sim["sim_time_s"].as_f64().unwrap();
    assert!((300.0..301.0).contains(&t), "{t}");
    let cycles: Vec<u64> = sim["cycles_per_robot"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| c.as_u64().unwrap())
        .collect();
    // A loop takes about a minute: five in 300 s, give or take one.
    assert_eq!(cycles.len(), 2);
    assert!(cycles.iter().all(|&c| (3..=6).contains(&c)), "{cycles:?}");
    // Four patrol legs per loop, and each leg is a Go_Check firing.
    let legs: f64 = [
        "t6:Go_Check_L2",
        "t12:Go_Check_L3",
        "t18:Go_Check_L4",
        "t24:Go_Check_L1",
    ]
    .iter()
    .map(|t| v["throughput"][t].as_f64().unwrap() * 300.0)
    .sum();
    let loops: u64 = cycles.iter().sum();
    assert!(legs >= 4.0 * loops as f64, "{legs} legs for {loops} loops");
}

#[test]
fn robots_need_a_map_and_at_least_one_robot() {
    let out = bin()
        .args([
            "run",
            repo("plans/quickstart.toml").to_str().unwrap(),
            "--robots",
            "3",
        ])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("--robots needs a plan with a [map]"),
        "{stderr}"
    );
    let plan = repo("plans/temperature-patrol/plan.toml");
    let out = bin()
        .args(["run", plan.to_str().unwrap(), "--robots", "0"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("at least 1"), "{stderr}");
}

#[test]
fn a_net_that_would_create_robots_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    // The patrol net with Go_Check_L2 producing two robots instead of one.
    let net =
        std::fs::read_to_string(repo("plans/temperature-patrol/temperature_patrol.xml")).unwrap();
    let plan = std::fs::read_to_string(repo("plans/temperature-patrol/plan.toml")).unwrap();
    let arc = "source=\"t6:Go_Check_L2\" target=\"p5:Check_Temperature_L2\"";
    let at = net.find(arc).expect("the arc");
    let weight = net[at..].find("<value>Default,1</value>").unwrap() + at;
    let forked = format!(
        "{}<value>Default,2</value>{}",
        &net[..weight],
        &net[weight + "<value>Default,1</value>".len()..]
    );
    assert_ne!(forked, net);
    std::fs::write(dir.path().join("temperature_patrol.xml"), forked).unwrap();
    let path = dir.path().join("plan.toml");
    std::fs::write(&path, plan).unwrap();
    let out = bin()
        .args(["run", path.to_str().unwrap(), "--robots", "4"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("transition `t6:Go_Check_L2` changes the number of robots by 1"),
        "{stderr}"
    );
}
