//! `plan-runner import-thesis`: every JSON execution input of the thesis framework either
//! becomes a plan that loads, with rules naming the right transitions, or is refused as bad
//! input with the file, line, column and the offending name.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use gspn::io::LoadErrorKind;
use gspn::net::{NetBuilder, Servers};
use gspn::plan::Plan;
use gspn::plan::thesis::{ImportOptions, KeyItem, import, plan_text, read_input};
use gspn::policy::Pattern;
use gspn::runtime::Role;

fn fixtures() -> PathBuf {
    crate::support::fixtures::root()
}

fn thesis(rel: &str) -> PathBuf {
    fixtures().join("thesis").join(rel)
}

fn import_to(
    input: &Path,
    net: Option<PathBuf>,
) -> (tempfile::TempDir, Result<Plan, gspn::io::LoadError>) {
    let dir = tempfile::tempdir().unwrap();
    let r = import(
        input,
        &ImportOptions {
            out: dir.path().join("out"),
            net,
            project_path: None,
        },
    )
    .map(|i| i.plan);
    (dir, r)
}

/// The transitions each rule gives positive probability, by name, in rule order.
fn rule_choices(plan: &Plan) -> Vec<Vec<String>> {
    plan.policy
        .rules()
        .iter()
        .map(|r| {
            r.choose
                .iter()
                .map(|&(t, _)| plan.net.transition(t).name.clone())
                .collect()
        })
        .collect()
}

#[test]
fn reads_the_python_literals_of_the_temperature_patrol_input() {
    let input = read_input(&thesis(
        "caldeira_2020_package/ros_TemperaturePatrolV2/temperature_patrol_input.json",
    ))
    .unwrap();
    assert_eq!(input.places.len(), 16);
    assert_eq!(input.places[1].name, "p2:Alarm_L1");
    assert_eq!(input.policy.len(), 8);
    assert_eq!(input.actions.len(), 16);
    assert_eq!(input.actions[0].action, "action_server_1");
    assert_eq!(input.actions[0].action_type.as_deref(), Some("ExecGSPN"));
    assert!(input.resources.is_empty());
    assert_eq!(input.full_synchronization, Some(true));
    let first = &input.policy[0];
    assert_eq!(first.key.len(), 16);
    assert_eq!(first.key[2], KeyItem::Count(1));
    assert_eq!(first.key[4], KeyItem::Count(0));
    assert_eq!(first.key[0], KeyItem::Free);
    assert_eq!(first.choose[0].0.name, "t6:Go_Check_L2");
    assert_eq!(first.choose[0].1, 1.0);
    // Positions are in the JSON file: line 5, inside the policy_dictionary string.
    assert_eq!(first.span.line, 5);
}

#[test]
fn a_string_count_is_read_as_a_number_with_a_warning() {
    let input = read_input(&thesis(
        "caldeira_2020_package/ros_Example/example_input.json",
    ))
    .unwrap();
    assert_eq!(input.policy[1].key[0], KeyItem::Count(1));
    assert_eq!(input.resources[0].name, "p4");
    assert!(
        input.warnings.iter().any(|w| w.contains("'1' is a string")),
        "{:?}",
        input.warnings
    );
}

#[test]
fn translation_to_toml_on_a_built_net() {
    // p1 -t1(imm)-> p2 ; p2 -T2(exp)-> p1, with the input's names.
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("in.json");
    std::fs::write(
        &json,
        r#"{ "gspn": "/home/x/net.xml",
  "place_to_function_mapping": "{'p1': 'f.work', 'p2': \"f.rest\"}",
  "resources_list": "['p2']",
  "places_tuple": "('p1', 'p2')",
  "policy_dictionary": "{(1, 0): {'t1': 1}, ('-', 0): {'t1': 1.0}}"
}"#,
    )
    .unwrap();
    let mut b = NetBuilder::new("n");
    let p1 = b.place("p1", 1);
    let p2 = b.place("p2", 0);
    let t1 = b.immediate("t1", 1.0, 1);
    let t2 = b.exponential("T2", 1.0, Servers::Single);
    b.input(p1, t1, 1);
    b.output(t1, p2, 1);
    b.input(p2, t2, 1);
    b.output(t2, p1, 1);
    let net = b.build().unwrap();
    let input = read_input(&json).unwrap();
    let (text, warnings) = plan_text(&input, &net, "net.xml", ".").unwrap();
    assert!(text.contains("net = \"net.xml\""), "{text}");
    assert!(
        text.contains(
            "[places.p1]\naction = { worker = \"functions\", name = \"f.work\" }   # place_to_function_mapping"
        ),
        "{text}"
    );
    assert!(
        text.contains(
            "[workers.functions]\ncommand = [\"python3\", \"thesis_functions.py\", \".\"]"
        ),
        "{text}"
    );
    assert!(text.contains("[places.p2]\nrole = \"resource\""), "{text}");
    assert!(
        warnings.iter().any(|w| w.contains("resource")),
        "{warnings:?}"
    );
    // The plan resolves against the same net: one exact rule, one partial.
    let plan_path = dir.path().join("plan.toml");
    let file = gspn::plan::PlanFile::parse(&plan_path, &text).unwrap();
    let plan = file.resolve(&plan_path, &text, net).unwrap();
    assert_eq!(plan.policy.rules()[0].pattern, Pattern::Exact(vec![1, 0]));
    assert_eq!(
        plan.policy.rules()[1].pattern,
        Pattern::Partial(vec![(p2, 0)])
    );
    assert_eq!(
        plan.roles[0],
        Some(Role::Action {
            name: "worker `functions` action `f.work`".into(),
            timeout: None,
            on_failure: Default::default(),
            robot: None,
        })
    );
    assert_eq!(plan.roles[1], Some(Role::Resource));
}

#[test]
fn python_syntax_errors_point_into_the_json_file() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("in.json");
    std::fs::write(
        &json,
        "{ \"gspn\": \"n.xml\",\n  \"places_tuple\": \"('p1', p2)\",\n  \"policy_dictionary\": \"{}\" }",
    )
    .unwrap();
    let e = read_input(&json).unwrap_err();
    let s = e.span.unwrap();
    assert_eq!((s.line, s.column), (2, 27));
    assert!(e.to_string().contains("not a literal"), "{e}");
}

#[test]
fn every_thesis_input_that_names_real_nodes_imports_to_a_loading_plan() {
    let cases: &[(&str, usize, &[&[&str]])] = &[
        (
            "caldeira_2020_package/ros_Example/example_input.json",
            7,
            &[&["t5"], &["t6"], &["t5"]],
        ),
        (
            "caldeira_2020_package/ros_NoGazeboTokens/no_gazebo_t_input.json",
            7,
            &[&["t5"], &["t6"], &["t5"]],
        ),
        (
            "caldeira_2020_package/ros_ImmediateTransitions/input_immediate_transitions.json",
            3,
            &[&["t1"], &["t2"]],
        ),
        (
            "caldeira_2020_package/ros_TemperaturePatrolV2/temperature_patrol_input.json",
            16,
            &[
                &["t6:Go_Check_L2"],
                &["t4:Go_Wait_L1"],
                &["t12:Go_Check_L3"],
                &["t10:Go_Wait_L2"],
                &["t18:Go_Check_L4"],
                &["t16:Go_Wait_L3"],
                &["t24:Go_Check_L1"],
                &["t22:Go_Wait_L4"],
            ],
        ),
        (
            "azevedo_2020/gspn_execution_input.json",
            6,
            &[&["t4"], &["t5"]],
        ),
        // Their policies only name exponential transitions: dropped, with warnings.
        (
            "caldeira_2020_package/ros_NoGazeboPlaces/no_gazebo_p_input.json",
            16,
            &[],
        ),
        (
            "caldeira_2020_package/ros_NoGazeboPlacesOneToken/no_gazebo_p_1_t_input.json",
            100,
            &[],
        ),
    ];
    for &(rel, roles, rules) in cases {
        let (_dir, plan) = import_to(&thesis(rel), None);
        let plan = plan.unwrap_or_else(|e| panic!("{rel}: {e}"));
        assert_eq!(plan.roles.iter().flatten().count(), roles, "{rel}");
        let want: Vec<Vec<String>> = rules
            .iter()
            .map(|r| r.iter().map(|s| s.to_string()).collect())
            .collect();
        assert_eq!(rule_choices(&plan), want, "{rel}");
    }
}

#[test]
fn resource_places_and_exact_rules_are_kept() {
    let (_dir, plan) = import_to(
        &thesis("caldeira_2020_package/ros_Example/example_input.json"),
        None,
    );
    let plan = plan.unwrap();
    let p4 = plan.net.place_by_name("p4").unwrap();
    assert_eq!(plan.role(p4), Some(&Role::Resource));
    let (_dir, plan) = import_to(&thesis("azevedo_2020/gspn_execution_input.json"), None);
    let plan = plan.unwrap();
    assert_eq!(
        plan.policy.rules()[0].pattern,
        Pattern::Exact(vec![0, 0, 1, 1, 0, 0])
    );
}

/// Issue 30, snag 3: the thesis's own inputs name transitions their nets lack (the
/// standalone example's `t4`/`t5`); the 2020 framework ignored those rules, so the import
/// drops them with a warning naming each (entry, line, column) and keeps the rest.
#[test]
fn choices_of_missing_transitions_are_dropped_with_a_warning_naming_them() {
    // The input, the choices dropped (transition, line, column), the rules kept.
    type Dropped = (&'static str, u32, u32);
    let cases: [(&str, &[Dropped], usize); 3] = [
        (
            "caldeira_2020_package/standalone_example/gspn_execution_input.json",
            &[("t4", 5, 36), ("t5", 5, 55)],
            0,
        ),
        (
            "caldeira_2020_dev/gspn_execution_input.json",
            &[("t4", 4, 35), ("t5", 4, 44)],
            0,
        ),
        (
            "azevedo_2023/execution_input_parameters.json",
            &[("t19:Go_Check_L2", 5, 619)],
            7,
        ),
    ];
    for (rel, dropped, rules) in cases {
        let dir = tempfile::tempdir().unwrap();
        let imported = import(
            &thesis(rel),
            &ImportOptions {
                out: dir.path().join("out"),
                net: None,
                project_path: None,
            },
        )
        .unwrap_or_else(|e| panic!("{rel}: {e}"));
        let missing: Vec<&String> = imported
            .warnings
            .iter()
            .filter(|w| w.contains("which the net does not have"))
            .collect();
        let named: Vec<String> = dropped
            .iter()
            .map(|(t, l, c)| format!("(line {l}, column {c}) chooses `{t}`"))
            .collect();
        for n in &named {
            assert!(
                missing.iter().any(|w| w.contains(n.as_str())),
                "{rel}: {n} in {missing:?}"
            );
        }
        assert_eq!(missing.len(), named.len(), "{rel}: {missing:?}");
        assert_eq!(imported.plan.policy.rules().len(), rules, "{rel}");
    }
}

#[test]
fn an_input_naming_a_missing_place_is_bad_input_with_its_position() {
    let path = thesis("azevedo_2020/gspn_execution_input_2.json");
    let (_dir, r) = import_to(&path, None);
    let e = r.expect_err("p4");
    assert_eq!(e.path, path);
    let s = e.span.expect("a position");
    assert_eq!((s.line, s.column), (3, 39));
    assert_eq!(
        e.kind,
        LoadErrorKind::UnknownNode {
            what: "place",
            name: "p4".into()
        }
    );
}

#[test]
fn a_key_longer_than_places_tuple_is_refused() {
    let (_dir, r) = import_to(
        &thesis("azevedo_2020/ros/gspn_execution_input_simple.json"),
        None,
    );
    let e = r.unwrap_err();
    let s = e.span.unwrap();
    assert_eq!((s.line, s.column), (5, 26));
    assert!(
        e.to_string().contains("3 entries but places_tuple has 2"),
        "{e}"
    );
}

#[test]
fn a_net_that_is_not_beside_the_input_is_named_with_its_position_or_given_with_net() {
    let path = thesis("azevedo_2020/ros/gspn_execution_input.json");
    let (_dir, r) = import_to(&path, None);
    let e = r.unwrap_err();
    let s = e.span.unwrap();
    assert_eq!((s.line, s.column), (1, 10));
    assert!(e.to_string().contains("gspn_6_places.xml"), "{e}");
    let (_dir, r) = import_to(&path, Some(thesis("azevedo_2020/gspn_6_places.xml")));
    let plan = r.unwrap();
    assert_eq!(plan.policy.rules().len(), 4);
}

#[test]
fn the_cli_writes_plan_and_net_and_exits_2_on_bad_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("imported");
    Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["import-thesis"])
        .arg(thesis(
            "caldeira_2020_package/ros_Example/example_input.json",
        ))
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    assert!(out.join("plan.toml").is_file());
    assert!(out.join("example_gspn.xml").is_file());
    // The thesis's standalone example as shipped: its two rules name transitions the net
    // lacks; they are dropped with a warning each, exit 0.
    let assert = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["import-thesis"])
        .arg(thesis(
            "caldeira_2020_package/standalone_example/gspn_execution_input.json",
        ))
        .arg("--out")
        .arg(dir.path().join("standalone"))
        .assert()
        .success();
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(
        stderr.contains("gspn_execution_input.json: policy entry 1 (line 5, column 36) chooses `t4`, which the net does not have"),
        "{stderr}"
    );
    assert!(stderr.contains("0 policy rules"), "{stderr}");
    let assert = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["import-thesis"])
        .arg(thesis("azevedo_2020/gspn_execution_input_2.json"))
        .arg("--out")
        .arg(dir.path().join("bad"))
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(
        stderr.contains("gspn_execution_input_2.json:3:39: place `p4` does not exist"),
        "{stderr}"
    );
}

#[test]
fn the_generated_ring_input_imports_with_an_explicit_net() {
    let path = fixtures().join("generated/ring_input_example.json");
    let (_dir, r) = import_to(&path, None);
    let e = r.unwrap_err();
    assert_eq!(e.span.map(|s| (s.line, s.column)), Some((2, 10)));
    assert!(e.to_string().contains("`ring.xml` not found"), "{e}");
    let (_dir, r) = import_to(&path, Some(fixtures().join("generated/ring_K4_N10.xml")));
    let plan = r.unwrap();
    assert!(plan.policy.is_empty());
    let p3 = plan.net.place_by_name("p3").unwrap();
    assert!(matches!(
        plan.role(p3),
        Some(Role::Action { name, .. }) if name == "worker `functions` action `ring_functions.work_p3`"
    ));
    assert_eq!(plan.roles.iter().flatten().count(), 4);
    assert_eq!(plan.net.initial_tokens(), 10);
}

#[test]
fn the_reachability_input_needs_its_net_and_then_has_a_key_too_long() {
    let path = thesis("azevedo_2020/ros/input_reachibility_graph_test.json");
    let (_dir, r) = import_to(&path, None);
    let e = r.unwrap_err();
    assert_eq!(e.span.map(|s| (s.line, s.column)), Some((1, 10)));
    assert!(e.to_string().contains("test_case_one_to_many.xml"), "{e}");
    let (_dir, r) = import_to(
        &path,
        Some(thesis("azevedo_2020/test_case_one_to_many.xml")),
    );
    let e = r.unwrap_err();
    assert_eq!(e.span.map(|s| (s.line, s.column)), Some((5, 26)));
}

/// Every JSON input under fixtures/thesis/ either imports to a plan that loads or is refused
/// with a position in the JSON file — never a panic, never a position-less error.
#[test]
fn every_thesis_json_input_is_imported_or_refused_with_a_position() {
    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        for e in std::fs::read_dir(dir).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(&p, out);
            } else if p.extension().and_then(|x| x.to_str()) == Some("json") {
                out.push(p);
            }
        }
    }
    let mut inputs = Vec::new();
    walk(&fixtures().join("thesis"), &mut inputs);
    inputs.sort();
    assert_eq!(inputs.len(), 14);
    let (mut imported, mut refused) = (0, 0);
    for path in &inputs {
        match import_to(path, None).1 {
            Ok(plan) => {
                assert!(plan.net.place_count() > 0);
                imported += 1;
            }
            Err(e) => {
                assert_eq!(&e.path, path);
                assert!(e.span.is_some(), "{e}");
                refused += 1;
            }
        }
    }
    // 10 import (3 of them, the standalone example, caldeira_2020_dev and azevedo_2023,
    // after dropping choices of transitions their nets lack); 4 are refused at a position.
    assert_eq!((imported, refused), (10, 4));
}
