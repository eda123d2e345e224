//! `plan-runner check FILE [--json]`: the summary's values for a thesis net and a plan, and
//! the structural warnings — transitions that can never fire, isolated places, policy rules
//! that can never apply. Bad input exits with 2.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use serde_json::{Value, json};

fn fixtures() -> PathBuf {
    crate::support::fixtures::root()
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

fn check_json(path: &Path) -> Value {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(path)
        .arg("--json")
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

const KEYS: [&str; 9] = [
    "format",
    "places",
    "transitions",
    "immediate",
    "exponential",
    "arcs",
    "inhibitor_arcs",
    "tokens",
    "warnings",
];

#[test]
fn the_temperature_patrol_net_summary() {
    let v =
        check_json(&fixtures().join(
            "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml",
        ));
    let keys: Vec<&str> = v.as_object().unwrap().keys().map(String::as_str).collect();
    let mut want = KEYS.to_vec();
    want.sort_unstable();
    let mut got = keys.clone();
    got.sort_unstable();
    assert_eq!(got, want);
    assert_eq!(v["format"], "pipe");
    assert_eq!(v["places"], 16);
    assert_eq!(v["transitions"], 24);
    assert_eq!(v["immediate"], 8);
    assert_eq!(v["exponential"], 16);
    assert_eq!(v["arcs"], 48);
    assert_eq!(v["inhibitor_arcs"], 0);
    assert_eq!(v["tokens"], 3);
    assert_eq!(v["warnings"], json!([]));
}

#[test]
fn the_quickstart_plan_summary() {
    let v = check_json(&repo("plans/quickstart.toml"));
    assert_eq!(v["format"], "plan");
    assert_eq!(
        [
            &v["places"],
            &v["transitions"],
            &v["immediate"],
            &v["exponential"],
            &v["arcs"],
            &v["tokens"]
        ],
        [
            &json!(5),
            &json!(6),
            &json!(3),
            &json!(3),
            &json!(14),
            &json!(3)
        ]
    );
    assert_eq!(v["warnings"], json!([]));
}

#[test]
fn dead_transitions_and_isolated_places_are_reported() {
    // Start(1) -go-> Mid -finish-> Done; `never` needs 2 tokens of Start, which nothing
    // refills; `blocked` is inhibited by Lock, which always holds 1; Spare has no arc.
    let dir = tempfile::tempdir().unwrap();
    let net = dir.path().join("net.PNPRO");
    std::fs::write(
        &net,
        r#"<?xml version="1.0" encoding="UTF-8" standalone="no"?>
<project name="dead" version="121">
  <gspn name="dead">
    <nodes>
      <place marking="1" name="Start" x="1.0" y="1.0"/>
      <place name="Mid" x="2.0" y="1.0"/>
      <place name="Done" x="3.0" y="1.0"/>
      <place marking="1" name="Lock" x="2.0" y="3.0"/>
      <place name="Spare" x="5.0" y="5.0"/>
      <transition name="go" type="EXP" delay="1.0" nservers="1" x="1.5" y="1.0"/>
      <transition name="finish" type="EXP" delay="1.0" nservers="1" x="2.5" y="1.0"/>
      <transition name="never" type="EXP" delay="1.0" nservers="1" x="1.5" y="2.0"/>
      <transition name="blocked" type="IMM" weight="1.0" priority="1" x="2.5" y="2.0"/>
    </nodes>
    <edges>
      <arc head="go" kind="INPUT" tail="Start"/>
      <arc head="Mid" kind="OUTPUT" tail="go"/>
      <arc head="finish" kind="INPUT" tail="Mid"/>
      <arc head="Done" kind="OUTPUT" tail="finish"/>
      <arc head="never" kind="INPUT" tail="Start" mult="2"/>
      <arc head="Done" kind="OUTPUT" tail="never"/>
      <arc head="blocked" kind="INPUT" tail="Mid"/>
      <arc head="blocked" kind="INHIBITOR" tail="Lock"/>
      <arc head="Done" kind="OUTPUT" tail="blocked"/>
    </edges>
  </gspn>
</project>
"#,
    )
    .unwrap();
    let v = check_json(&net);
    assert_eq!(v["format"], "pnpro");
    assert_eq!(v["arcs"], 9);
    assert_eq!(v["inhibitor_arcs"], 1);
    assert_eq!(
        v["warnings"],
        json!([
            "transition `never` can never fire: input place `Start` has 1 token(s), no transition that can fire adds to it, and the arc needs 2",
            "transition `blocked` can never fire: inhibitor place `Lock` always holds at least 1 token(s), the inhibitor arc's threshold is 1",
            "place `Spare` is isolated: no arc touches it",
        ])
    );
}

#[test]
fn policy_rules_that_can_never_apply_are_reported() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        repo("plans/nets/two_robot_patrol.xml"),
        dir.path().join("patrol.xml"),
    )
    .unwrap();
    let plan = dir.path().join("plan.toml");
    std::fs::write(
        &plan,
        r#"net = "patrol.xml"
# fine
[[policy]]
marking = { Decide = 1, Patrol_A = 0 }
partial = true
choose = { t_go_A = 1.0 }
# Charger + Charging = 1 in every reachable marking: Charger never holds 2.
[[policy]]
marking = { Charger = 2 }
partial = true
choose = { t_charge = 1.0 }
# No robot deciding: none of the decisions can be enabled.
[[policy]]
marking = { Decide = 0 }
partial = true
choose = { t_go_A = 0.5, t_go_B = 0.5 }
# 3 robots in an exact marking of a 2-robot net.
[[policy]]
marking = { Decide = 1, Patrol_A = 1, Patrol_B = 1, Charger = 1 }
choose = { t_go_B = 1.0 }
"#,
    )
    .unwrap();
    let v = check_json(&plan);
    assert_eq!(
        v["warnings"],
        json!([
            "policy rule 2 (line 8) can never apply: it asks for 2 token(s) in `Charger`, which always holds between 0 and 1",
            "policy rule 3 (line 13) can never apply: none of `t_go_A`, `t_go_B` can be enabled in a marking that matches it",
            "policy rule 4 (line 18) can never apply: its marking has Patrol_A + Patrol_B + Decide + Charging = 3, but every reachable marking has 2",
            "the plan has no stop condition and no dead marking is reachable: the net never stops firing: `run` goes on until Ctrl-C (add [stop] max_firings, time_limit or when)",
        ])
    );
}

#[test]
fn text_output_and_bad_input() {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(repo("plans/quickstart.toml"))
        .output()
        .unwrap();
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains(
            "5 places, 6 transitions (3 immediate, 3 exponential), 14 arcs (0 inhibitor), 3 tokens"
        ),
        "{text}"
    );
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(fixtures().join("thesis/azevedo_2020/ros/gspn_thesis_test_case.xml"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let dir = tempfile::tempdir().unwrap();
    let plan = dir.path().join("bad.toml");
    std::fs::write(&plan, "net = \"missing.xml\"\n").unwrap();
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .arg("check")
        .arg(&plan)
        .arg("--json")
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("bad.toml:1:7"));
}
