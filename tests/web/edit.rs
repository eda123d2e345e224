//! The editor (issue 15, item 7): the page adds and deletes places, transitions and arcs,
//! changes names, markings, rates, weights, priorities, servers, arc weights and kinds,
//! undoes and redoes; each edit is checked as the readers check a file and a refused one
//! leaves the net as it was; the token game and the analysis use the edited net; saving
//! writes PNPRO or PIPE XML only to the file named on the command line.
#![cfg(feature = "web")]

use crate::analysis::analyze_json;
use crate::api::call;
use crate::support as common;

use std::path::Path;

use assert_cmd::Command;
use axum::body::Body;
use axum::http::{Request, StatusCode, header};
use gspn::io::{ReadOptions, read_net};
use gspn::net::{ArcKind, Net, Servers, Timing};
use gspn::sim::Simulator;
use gspn::web::{WebState, router};
use serde_json::{Value, json};
use tower::ServiceExt;

const CYC3: &str = "greatspn/cyc3/cyc3.PNPRO";

fn cyc3_state() -> WebState {
    let path = common::fixture(CYC3);
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    WebState::new(net, None, 5).with_source(&path)
}

/// `POST /api/edit` with `op`: the status and the answer.
async fn edit(state: &WebState, op: Value) -> (StatusCode, Value) {
    call(state, "POST", "/api/edit", Some(op)).await
}

/// `POST /api/edit` that must succeed: the answer.
async fn edit_ok(state: &WebState, op: Value) -> Value {
    let (status, v) = edit(state, op.clone()).await;
    assert_eq!(status, StatusCode::OK, "{op} -> {v}");
    v
}

fn timing(net: &Net, name: &str) -> Timing {
    net.transition(net.transition_by_name(name).unwrap()).timing
}

/// `(kind, place, transition, weight)` of every arc, by name, sorted.
fn arcs(net: &Net) -> Vec<(ArcKind, String, String, u32)> {
    let mut v: Vec<_> = net
        .arcs()
        .iter()
        .map(|a| {
            (
                a.kind,
                net.place(a.place).name.clone(),
                net.transition(a.transition).name.clone(),
                a.weight,
            )
        })
        .collect();
    v.sort_by(|a, b| format!("{a:?}").cmp(&format!("{b:?}")));
    v
}

#[tokio::test]
async fn each_operation_changes_the_served_net_and_its_token_game() {
    let state = cyc3_state();
    let v = edit_ok(
        &state,
        json!({"op": "add_place", "name": "P4", "tokens": 2, "x": 6.0, "y": 8.0}),
    )
    .await;
    // The answer carries the net to draw (with its version) and the restarted token game.
    assert_eq!(v["net"]["version"], 1);
    assert_eq!(v["history"]["undo"], "add place P4");
    assert_eq!(v["state"]["net_version"], 1);
    assert_eq!(v["state"]["marking"]["P4"], 2);
    assert_eq!(v["state"]["firings"], 0);
    let p4 = &v["net"]["places"][3];
    assert_eq!(
        (p4["name"].clone(), p4["x"].clone()),
        (json!("P4"), json!(6.0))
    );

    // A transition with default names and parameters, then every kind of arc.
    let v = edit_ok(
        &state,
        json!({"op": "add_transition", "kind": "immediate", "x": 2, "y": 8}),
    )
    .await;
    assert_eq!(v["history"]["undo"], "add transition T4");
    edit_ok(
        &state,
        json!({"op": "add_arc", "from": {"transition": "T1"}, "to": {"place": "P4"}}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "add_arc", "from": {"place": "P4"}, "to": {"transition": "T4"}, "weight": "2"}),
    )
    .await;
    let v = edit_ok(
        &state,
        json!({"op": "add_arc", "from": {"place": "P3"}, "to": {"transition": "T4"}, "inhibitor": true}),
    )
    .await;
    assert_eq!(v["history"]["undo"], "add inhibitor arc P3 ⊸ T4");
    let net = state.current_net();
    assert_eq!(
        timing(&net, "T4"),
        Timing::Immediate {
            weight: 1.0,
            priority: 1
        }
    );
    let added: Vec<_> = arcs(&net)
        .into_iter()
        .filter(|a| a.1 == "P4" || a.2 == "T4")
        .collect();
    assert_eq!(
        added,
        vec![
            (ArcKind::Inhibitor, "P3".into(), "T4".into(), 1),
            (ArcKind::Input, "P4".into(), "T4".into(), 2),
            (ArcKind::Output, "P4".into(), "T1".into(), 1),
        ]
    );

    // Names, markings, capacities, rates, servers, weights, priorities, arc weights and kinds.
    edit_ok(
        &state,
        json!({"op": "set_place", "place": "P4", "name": "Buffer", "tokens": 1, "capacity": 3}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T1", "rate": 2.5, "servers": "infinite"}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T4", "name": "drain", "weight": "0.5", "priority": 3}),
    )
    .await;
    let v = edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T3", "kind": "immediate"}),
    )
    .await;
    assert_eq!(
        v["history"]["undo"],
        "change transition T3 (immediate, weight 1, priority 1)"
    );
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T3", "kind": "exponential", "rate": 4, "servers": 2}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_arc", "place": "Buffer", "transition": "drain", "kind": "input", "weight": 3}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_arc", "place": "P3", "transition": "drain", "kind": "inhibitor", "new_kind": "input", "weight": 2}),
    )
    .await;
    let net = state.current_net();
    let buffer = net.place(net.place_by_name("Buffer").unwrap());
    assert_eq!((buffer.initial, buffer.capacity), (1, Some(3)));
    assert_eq!(
        timing(&net, "T1"),
        Timing::Exponential {
            rate: 2.5,
            servers: Servers::Infinite
        }
    );
    assert_eq!(
        timing(&net, "drain"),
        Timing::Immediate {
            weight: 0.5,
            priority: 3
        }
    );
    assert_eq!(
        timing(&net, "T3"),
        Timing::Exponential {
            rate: 4.0,
            servers: Servers::K(2)
        }
    );
    let into_drain: Vec<_> = arcs(&net).into_iter().filter(|a| a.2 == "drain").collect();
    assert_eq!(
        into_drain,
        vec![
            (ArcKind::Input, "Buffer".into(), "drain".into(), 3),
            (ArcKind::Input, "P3".into(), "drain".into(), 2),
        ]
    );

    // Capacity back to unbounded, an arc deleted, a node moved, a node deleted with its arcs.
    edit_ok(
        &state,
        json!({"op": "set_place", "place": "Buffer", "capacity": null}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "delete_arc", "place": "P3", "transition": "drain", "kind": "input"}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "move", "places": {"Buffer": [7.5, 9.0]}}),
    )
    .await;
    let v = edit_ok(
        &state,
        json!({"op": "delete", "node": {"transition": "drain"}}),
    )
    .await;
    assert_eq!(v["history"]["undo"], "delete transition drain and its arc");
    let net = state.current_net();
    let buffer = net.place(net.place_by_name("Buffer").unwrap());
    assert_eq!(buffer.capacity, None);
    assert_eq!(buffer.position.map(|p| (p.x, p.y)), Some((7.5, 9.0)));
    assert_eq!(net.transition_count(), 3);
    assert_eq!(net.arcs().len(), 7);
    // The opened net is still the file's; /api/net draws the edited one, with the file's
    // look kept for the nodes it has.
    assert_eq!(state.net().place_count(), 3);
    let (_, drawn) = call(&state, "GET", "/api/net", None).await;
    assert_eq!(drawn["places"].as_array().unwrap().len(), 4);
    assert_eq!(drawn["version"], 16);

    // The token game plays the edited net: 20 steps are the library's on that net.
    let (_, s) = call(&state, "POST", "/api/sim/step", Some(json!({"n": 20}))).await;
    let mut sim = Simulator::new(net.clone(), 5);
    sim.run_steps(20).unwrap();
    let tokens: Vec<u32> = serde_json::from_value(s["tokens"].clone()).unwrap();
    assert_eq!(tokens, sim.marking().as_slice());
    assert_eq!(s["time"].as_f64().unwrap(), sim.time());
}

#[tokio::test]
async fn a_refused_edit_says_why_and_leaves_the_net_as_it_was() {
    let state = cyc3_state();
    let before = state.current_net();
    let cases = [
        (
            json!({"op": "add_place", "name": "P2", "x": 0, "y": 0}),
            "duplicate place name `P2`",
        ),
        (
            json!({"op": "set_transition", "transition": "T1", "rate": -1}),
            "rate of `T1` is -1: must be a finite number > 0",
        ),
        (
            json!({"op": "set_transition", "transition": "T1", "rate": "fast"}),
            "rate of `T1`: `fast` is not a number",
        ),
        (
            json!({"op": "add_arc", "from": {"place": "P1"}, "to": {"place": "P2"}}),
            "an arc joins a place and a transition: `P1` and `P2` are both places",
        ),
        (
            json!({"op": "add_arc", "from": {"transition": "T1"}, "to": {"transition": "t2"}}),
            "`T1` and `t2` are both transitions",
        ),
        (
            json!({"op": "add_arc", "from": {"transition": "T1"}, "to": {"place": "P1"}, "inhibitor": true}),
            "an inhibitor arc runs from a place to a transition, not from transition `T1` to place `P1`",
        ),
        (
            json!({"op": "set_place", "place": "P1", "tokens": -1}),
            "initial marking of `P1` is -1: must be a whole number ≥ 0",
        ),
        (
            json!({"op": "set_place", "place": "P1", "tokens": "1.5"}),
            "initial marking of `P1` is 1.5: must be a whole number ≥ 0",
        ),
        (
            json!({"op": "set_place", "place": "P1", "capacity": 1}),
            "place `P1`: initial marking 2 exceeds its capacity 1",
        ),
        (
            json!({"op": "add_arc", "from": {"place": "P1"}, "to": {"transition": "T1"}, "weight": 0}),
            "arc multiplicity of `P1 → T1` is 0: must be a whole number ≥ 1",
        ),
        (
            json!({"op": "set_transition", "transition": "t2", "priority": 0}),
            "priority of `t2` is 0: must be a whole number ≥ 1",
        ),
        (
            json!({"op": "set_transition", "transition": "t2", "weight": -0.5}),
            "weight of `t2` is -0.5: must be a finite number ≥ 0",
        ),
        (
            json!({"op": "set_transition", "transition": "T1", "weight": 2}),
            "weight does not apply to exponential transition `T1`",
        ),
        (
            json!({"op": "set_transition", "transition": "T1", "servers": 0}),
            "number of servers of `T1` is 0: must be a whole number ≥ 1",
        ),
        (
            json!({"op": "set_place", "place": "P9", "tokens": 1}),
            "place `P9` does not exist",
        ),
        (
            json!({"op": "set_place", "place": "P1", "name": " P1"}),
            "place name \" P1\": a name cannot start or end with a space",
        ),
        (
            json!({"op": "add_transition", "name": "", "kind": "exponential", "x": 0, "y": 0}),
            "transition name \"\": a name cannot be empty",
        ),
        (
            json!({"op": "set_place", "place": "P1"}),
            "the edit changes nothing",
        ),
        (
            json!({"op": "delete_arc", "place": "P1", "transition": "t2", "kind": "input"}),
            "there is no input arc between place `P1` and transition `t2`",
        ),
        (
            json!({"op": "set_arc", "place": "P2", "transition": "T1", "kind": "output", "new_kind": "inhibitor"}),
            "an output arc cannot become an inhibitor arc",
        ),
        (
            json!({"op": "add_place", "x": "left", "y": 0}),
            "not an edit: invalid type",
        ),
        (
            json!({"op": "paint"}),
            "not an edit: unknown variant `paint`",
        ),
    ];
    for (op, message) in cases {
        let (status, v) = edit(&state, op.clone()).await;
        let expected = if v["error"].as_str().unwrap_or("").starts_with("not an edit") {
            StatusCode::BAD_REQUEST
        } else {
            StatusCode::UNPROCESSABLE_ENTITY
        };
        assert_eq!(status, expected, "{op} -> {v}");
        let error = v["error"].as_str().unwrap();
        assert!(error.contains(message), "{op}: {error:?} lacks {message:?}");
        assert!(state.current_net().diff(&before).is_empty(), "{op}");
    }
    let (_, h) = call(&state, "GET", "/api/edit", None).await;
    assert_eq!(h["history"]["version"], 0, "{h}");
    assert_eq!(h["history"]["undo"], Value::Null);
}

#[tokio::test]
async fn undo_and_redo_step_through_the_versions() {
    let state = cyc3_state();
    let opened = state.current_net();
    edit_ok(
        &state,
        json!({"op": "add_place", "name": "A", "x": 0, "y": 0}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T1", "rate": 3}),
    )
    .await;
    edit_ok(&state, json!({"op": "delete", "node": {"place": "P3"}})).await;
    let last = state.current_net();

    let (status, v) = call(&state, "POST", "/api/edit/undo", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(v["history"]["redo"], "delete place P3 and its 2 arcs");
    assert_eq!(v["history"]["undo"], "change transition T1 (rate 3)");
    assert_eq!(state.current_net().place_count(), 4);
    call(&state, "POST", "/api/edit/undo", None).await;
    assert_eq!(
        timing(&state.current_net(), "T1"),
        timing(&opened, "T1"),
        "the rate is back"
    );
    call(&state, "POST", "/api/edit/undo", None).await;
    assert!(state.current_net().diff(&opened).is_empty());
    // The token game and the page follow each undo too.
    let (_, s) = call(&state, "GET", "/api/sim/state", None).await;
    assert_eq!(s["net_version"], 6);
    let (status, v) = call(&state, "POST", "/api/edit/undo", None).await;
    assert_eq!(
        (status, v["error"].clone()),
        (StatusCode::CONFLICT, json!("nothing to undo"))
    );

    for _ in 0..3 {
        let (status, _) = call(&state, "POST", "/api/edit/redo", None).await;
        assert_eq!(status, StatusCode::OK);
    }
    assert!(state.current_net().diff(&last).is_empty());
    let (status, v) = call(&state, "POST", "/api/edit/redo", None).await;
    assert_eq!(
        (status, v["error"].clone()),
        (StatusCode::CONFLICT, json!("nothing to redo"))
    );

    // A new edit after an undo drops what was undone.
    call(&state, "POST", "/api/edit/undo", None).await;
    let v = edit_ok(
        &state,
        json!({"op": "set_place", "place": "P3", "tokens": 1}),
    )
    .await;
    assert_eq!(v["history"]["redo"], Value::Null);
    assert_eq!(v["history"]["edits"], 3);
}

/// The panel's steady-state numbers equal `analyze`'s to 1e-9, name by name.
pub(crate) fn assert_same_analysis(page: &Value, cli: &Value) {
    assert_eq!(page["reachable"], cli["state_space"]["reachable"]);
    for key in ["mean_tokens", "throughput"] {
        let (a, b) = (&page["steady"][key], &cli["steady_state"][key]);
        let (a, b) = (a.as_object().unwrap(), b.as_object().unwrap());
        assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
        for (name, v) in b {
            let (x, y) = (a[name].as_f64().unwrap(), v.as_f64().unwrap());
            assert!((x - y).abs() < 1e-9, "{key} {name}: page {x}, analyze {y}");
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_analysis_is_the_edited_nets_and_save_writes_only_the_named_file() {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("edited.PNPRO");
    let state = cyc3_state().saving_to(target.clone()).unwrap();
    let (_, before) = call(&state, "GET", "/api/analysis", None).await;
    edit_ok(
        &state,
        json!({"op": "add_place", "name": "P4", "x": 10, "y": 5}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "add_arc", "from": {"transition": "T1"}, "to": {"place": "P4"}}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "add_arc", "from": {"place": "P4"}, "to": {"transition": "t2"}}),
    )
    .await;
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "T1", "rate": 3}),
    )
    .await;
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{a}");
    assert!(a["steady"]["mean_tokens"].get("P4").is_some(), "{a}");
    assert_ne!(
        a["steady"]["throughput"]["T1"],
        before["steady"]["throughput"]["T1"]
    );

    // A save names no file: the request cannot choose one.
    let (status, v) = call(
        &state,
        "POST",
        "/api/edit/save",
        Some(json!({"path": "/tmp/elsewhere.PNPRO"})),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
    assert!(!target.exists());
    // A page from another origin cannot save at all.
    let req = Request::builder()
        .method("POST")
        .uri("/api/edit/save")
        .header(header::CONTENT_TYPE, "application/json")
        .header(header::ORIGIN, "http://evil.example")
        .body(Body::from("{}"))
        .unwrap();
    let res = router(state.clone()).oneshot(req).await.unwrap();
    assert_eq!(res.status(), StatusCode::FORBIDDEN);
    assert!(!target.exists());

    let (status, v) = call(&state, "POST", "/api/edit/save", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(v["format"], "pnpro");
    let saved = read_net(&target, &ReadOptions::default()).unwrap().net;
    assert!(
        saved.diff(&state.current_net()).is_empty(),
        "{:?}",
        saved.diff(&state.current_net())
    );
    assert_same_analysis(&a, &analyze_json(&target));

    // PIPE XML, through the download: the same net.
    let (status, v) = call(
        &state,
        "POST",
        "/api/edit/export",
        Some(json!({"format": "pipe"})),
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(v["file"], "cyc3.xml");
    let pipe = dir.path().join("edited.xml");
    std::fs::write(&pipe, v["text"].as_str().unwrap()).unwrap();
    let back = read_net(&pipe, &ReadOptions::default()).unwrap().net;
    assert!(
        back.diff(&state.current_net()).is_empty(),
        "{:?}",
        back.diff(&state.current_net())
    );
    assert_same_analysis(&a, &analyze_json(&pipe));
}

#[tokio::test]
async fn a_pipe_file_is_saved_as_pipe_and_a_net_without_positions_keeps_its_drawing() {
    // cyc3 built in code has no positions: the page draws the automatic layout, and the
    // first edit keeps every node where it was drawn.
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("edited.xml");
    let state = WebState::new(common::cyc3(Servers::Single), None, 1)
        .saving_to(target.clone())
        .unwrap();
    let (_, drawn) = call(&state, "GET", "/api/net", None).await;
    assert_eq!(drawn["layout"], "layered");
    let v = edit_ok(
        &state,
        json!({"op": "set_place", "place": "P1", "tokens": 3}),
    )
    .await;
    assert_eq!(v["net"]["layout"], "file");
    for key in ["places", "transitions"] {
        for (a, b) in drawn[key]
            .as_array()
            .unwrap()
            .iter()
            .zip(v["net"][key].as_array().unwrap())
        {
            assert_eq!((&a["x"], &a["y"]), (&b["x"], &b["y"]), "{}", a["name"]);
        }
    }
    let (status, v) = call(&state, "POST", "/api/edit/save", None).await;
    assert_eq!(
        (status, v["format"].clone()),
        (StatusCode::OK, json!("pipe")),
        "{v}"
    );
    let back = read_net(&target, &ReadOptions::default()).unwrap();
    assert_eq!(back.format, gspn::io::Format::Pipe);
    assert!(back.net.diff(&state.current_net()).is_empty());
    assert_eq!(back.net.place(gspn::net::PlaceId(0)).initial, 3);
}

#[tokio::test]
async fn nets_that_cannot_be_edited_or_saved_say_so() {
    // No `--save-to`: the page downloads instead.
    let state = cyc3_state();
    let (status, v) = call(&state, "POST", "/api/edit/save", None).await;
    assert_eq!(status, StatusCode::CONFLICT, "{v}");
    assert!(v["error"].as_str().unwrap().contains("--save-to"), "{v}");
    let e = cyc3_state().saving_to("net.dot".into()).unwrap_err();
    assert_eq!(
        e.to_string(),
        "net.dot: the editor saves GreatSPN projects (.PNPRO) and PIPE nets (.xml)"
    );

    // A policy given without its plan file (it cannot be checked against an edit); a
    // recorded run.
    let plan = gspn::plan::open(
        &Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature_patrol.toml"),
        &ReadOptions::default(),
    )
    .unwrap()
    .into_plan();
    let states = [
        WebState::for_plan(plan.net.clone(), Some(plan.policy), plan.rewards, 0, 1000),
        WebState::for_replay(plan.net, Vec::new()),
    ];
    for (state, why) in states.iter().zip([
        "policy or rewards given without their plan file",
        "recorded run",
    ]) {
        let (_, s) = call(state, "GET", "/api/edit", None).await;
        assert_eq!(s["editable"], false);
        let (status, v) = edit(
            state,
            json!({"op": "add_place", "name": "X", "x": 0, "y": 0}),
        )
        .await;
        assert_eq!(status, StatusCode::CONFLICT, "{v}");
        assert!(v["error"].as_str().unwrap().contains(why), "{v}");
    }

    // The command line refuses a save file it cannot write, before it listens.
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["serve", common::fixture(CYC3).to_str().unwrap()])
        .args(["--addr", "127.0.0.1:0", "--save-to", "out.dot"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("out.dot: the editor saves GreatSPN projects"),
        "{err}"
    );
}

/// A plan over the GSPNR home model (one robot, `gspnr/home_n01`) whose policy chooses in
/// each room and whose rewards name places and a decision transition.
const HOME_PLAN: &str = r#"net = "net.PNPRO"
seed = 3

[[policy]]
marking = { L1 = 1 }
partial = true
choose = { Mop_L1 = 0.7, Vacuum_L1 = 0.1, Go_L1_L2 = 0.2 }

[[policy]]
marking = { L2 = 1 }
partial = true
choose = { Mop_L2 = 0.5, Vacuum_L2 = 0.2, Go_L2_L1 = 0.1, Go_L2_L3 = 0.2 }

[[policy]]
marking = { L3 = 1 }
partial = true
choose = { Mop_L3 = 0.3, Vacuum_L3 = 0.3, Go_L3_L2 = 0.4 }

[rewards.cleaning]
marked = { Mopping_L1 = 1.0, Mopping_L2 = 1.0, Mopping_L3 = 1.0, Vacuuming_L1 = 0.5, Vacuuming_L2 = 0.5, Vacuuming_L3 = 0.5 }
transitions = { Mop_L2 = 2.0 }
"#;

/// The panel's numbers equal `analyze PLAN`'s under the plan's policy, its reward too.
fn assert_same_plan_analysis(page: &Value, cli: &Value) {
    assert_eq!(page["analysed"], "net under plan policy", "{page}");
    assert_eq!(cli["analysed"], "net under plan policy");
    assert_same_analysis(page, cli);
    let (a, b) = (
        page["steady"]["rewards"]["cleaning"]["rate"]
            .as_f64()
            .unwrap(),
        cli["steady_state"]["rewards"]["cleaning"]["rate"]
            .as_f64()
            .unwrap(),
    );
    assert!((a - b).abs() < 1e-9, "reward: page {a}, analyze {b}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_net_of_a_plan_is_edited_under_its_policy_and_an_edit_that_breaks_the_plan_is_refused()
{
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(
        common::fixture("gspnr/home_n01/net.PNPRO"),
        dir.path().join("net.PNPRO"),
    )
    .unwrap();
    let plan_path = dir.path().join("plan.toml");
    std::fs::write(&plan_path, HOME_PLAN).unwrap();
    let plan = gspn::plan::read_plan(&plan_path, &ReadOptions::default()).unwrap();
    let saved = dir.path().join("edited.PNPRO");
    let state = WebState::for_plan(
        plan.net.clone(),
        Some(plan.policy.clone()),
        plan.rewards.clone(),
        0,
        gspn::web::DEFAULT_MAX_STATES,
    )
    .with_source(&plan.net_path)
    .with_plan(plan.text.clone().unwrap())
    .saving_to(saved.clone())
    .unwrap();
    let (_, s) = call(&state, "GET", "/api/edit", None).await;
    assert_eq!(
        (s["editable"].clone(), s["reason"].clone()),
        (json!(true), Value::Null)
    );
    let cli_before = analyze_json(&plan_path);
    let (status, before) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{before}");
    assert_same_plan_analysis(&before, &cli_before);

    // An edit that keeps the policy and the rewards valid: mopping L2 ends 5 times faster.
    edit_ok(
        &state,
        json!({"op": "set_transition", "transition": "FinishedMop_L2", "rate": 0.5}),
    )
    .await;
    // The token game plays the edited net under the plan's policy: in L1 it chooses as the
    // first rule says.
    let (_, s) = call(&state, "GET", "/api/sim/state", None).await;
    assert_eq!(s["vanishing"], true, "{s}");
    assert_eq!(
        s["choice"]["probabilities"],
        json!({"Mop_L1": 0.7, "Vacuum_L1": 0.1, "Go_L1_L2": 0.2}),
        "{s}"
    );

    // Edits that would break the plan are refused with the plan reader's message: the
    // plan's line and column, the node, and that line of the plan.
    let refused = [
        (
            json!({"op": "delete", "node": {"transition": "Mop_L3"}}),
            "plan.toml:17:12: transition `Mop_L3` does not exist \
             (`choose = { Mop_L3 = 0.3, Vacuum_L3 = 0.3, Go_L3_L2 = 0.4 }`)",
        ),
        (
            json!({"op": "set_transition", "transition": "Go_L3_L2", "kind": "exponential", "rate": 1}),
            "plan.toml:17:43: policy chooses `Go_L3_L2`, an exponential transition: a policy \
             chooses among immediate transitions",
        ),
        (
            json!({"op": "set_place", "place": "Vacuuming_L2", "name": "Vac_L2"}),
            "plan.toml:20:86: place `Vacuuming_L2` does not exist",
        ),
        (
            json!({"op": "delete", "node": {"transition": "Mop_L2"}}),
            "plan.toml:12:12: transition `Mop_L2` does not exist",
        ),
    ];
    for (op, want) in refused {
        let (status, v) = edit(&state, op.clone()).await;
        assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{op} -> {v}");
        let e = v["error"].as_str().unwrap();
        assert!(e.starts_with("the plan would no longer load: "), "{e}");
        assert!(e.contains(want), "{op}: {e}\n  wanted: {want}");
    }
    let (_, s) = call(&state, "GET", "/api/edit", None).await;
    assert_eq!(s["history"]["edits"], 1, "{s}");
    assert!(state.current_net().transition_by_name("Mop_L3").is_some());

    // The analysis is the edited net's under the policy: `analyze` of a copy of the plan
    // whose net file is the saved one.
    let (status, after) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{after}");
    let (status, v) = call(&state, "POST", "/api/edit/save", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    let copy = dir.path().join("edited-plan.toml");
    std::fs::write(
        &copy,
        HOME_PLAN.replace("net = \"net.PNPRO\"", "net = \"edited.PNPRO\""),
    )
    .unwrap();
    let cli_after = analyze_json(&copy);
    assert_same_plan_analysis(&after, &cli_after);
    let reward = |a: &Value| a["steady"]["rewards"]["cleaning"]["rate"].as_f64().unwrap();
    assert!(
        (reward(&after) - reward(&before)).abs() > 1e-3,
        "{} vs {}",
        reward(&after),
        reward(&before)
    );

    // Undo takes the edit back (the analysis is the plan's own again); redo does it again.
    let (status, v) = call(&state, "POST", "/api/edit/undo", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert!(state.current_net().diff(&plan.net).is_empty());
    let (_, undone) = call(&state, "GET", "/api/analysis", None).await;
    assert_same_plan_analysis(&undone, &cli_before);
    let (status, v) = call(&state, "POST", "/api/edit/redo", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    let (_, redone) = call(&state, "GET", "/api/analysis", None).await;
    assert_same_plan_analysis(&redone, &cli_after);

    // `serve PLAN --save-to` without a path saves to the net file the plan names (refused
    // here, before it listens, for the non-loopback address: the message names the file).
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["serve", plan_path.to_str().unwrap()])
        .args(["--addr", "0.0.0.0:0", "--allow-remote", "--save-to"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2), "{out:?}");
    let err = String::from_utf8_lossy(&out.stderr);
    let net_file = dir.path().join("net.PNPRO");
    assert!(
        err.contains(&format!("could overwrite {}", net_file.display())),
        "{err}"
    );
}

/// `plan-runner serve`, killed when dropped.
struct Served(std::process::Child);

impl Drop for Served {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn serve_plan_save_to_writes_the_net_file_the_plan_names() {
    use crate::security::{JSON, request};
    use std::io::{BufRead, BufReader};
    let dir = tempfile::tempdir().unwrap();
    let net_file = dir.path().join("net.PNPRO");
    std::fs::copy(common::fixture("gspnr/home_n01/net.PNPRO"), &net_file).unwrap();
    let plan_path = dir.path().join("plan.toml");
    std::fs::write(&plan_path, HOME_PLAN).unwrap();
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("plan-runner"))
        .args(["serve", plan_path.to_str().unwrap()])
        .args(["--addr", "127.0.0.1:0", "--save-to"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let (out, err) = (child.stdout.take().unwrap(), child.stderr.take().unwrap());
    let served = Served(child);
    let mut warning = String::new();
    BufReader::new(err).read_line(&mut warning).unwrap();
    assert!(
        warning.starts_with(&format!(
            "warning: `save` replaces {} itself",
            net_file.display()
        )),
        "{warning}"
    );
    let mut url = String::new();
    BufReader::new(out).read_line(&mut url).unwrap();
    let addr: std::net::SocketAddr = url
        .trim()
        .rsplit_once("http://")
        .and_then(|(_, a)| a.trim_end_matches('/').parse().ok())
        .unwrap_or_else(|| panic!("no address in {url:?}"));

    let post = |path: &'static str, body: Value| async move {
        let (status, _, v) = request(addr, "POST", path, &[JSON], &body.to_string()).await;
        (status, v)
    };
    let (status, v) = post(
        "/api/edit",
        json!({"op": "set_transition", "transition": "FinishedMop_L2", "rate": 0.5}),
    )
    .await;
    assert_eq!(status, 200, "{v}");
    let (status, v) = post(
        "/api/edit",
        json!({"op": "delete", "node": {"transition": "Mop_L3"}}),
    )
    .await;
    assert_eq!(status, 422, "{v}");
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .contains("plan.toml:17:12: transition `Mop_L3` does not exist"),
        "{v}"
    );
    let (status, _, page) = request(addr, "GET", "/api/analysis", &[], "").await;
    assert_eq!(status, 200, "{page}");
    let (status, v) = post("/api/edit/save", json!({})).await;
    assert_eq!(status, 200, "{v}");
    assert_eq!(v["saved"], net_file.display().to_string());
    drop(served);
    // The plan itself now reads the edited net: `analyze PLAN` gives the page's numbers.
    let saved = read_net(&net_file, &ReadOptions::default()).unwrap().net;
    assert_eq!(
        timing(&saved, "FinishedMop_L2"),
        Timing::Exponential {
            rate: 0.5,
            servers: Servers::Single
        }
    );
    assert_same_plan_analysis(&page, &analyze_json(&plan_path));
}

// ---- in the browser ------------------------------------------------------------------------

use crate::browser::{BROWSER, WAIT, analyse_on_page, http_get, open, screenshot_path};
use crate::support::browser::Browser;
use crate::support::start_server;
use fantoccini::Locator;

/// A click at the page's point `(x, y)` (window pixels) on whatever is drawn there, as the
/// net's handlers see a real one: `mousedown` on the element, `mouseup` on the window.
async fn click_at(b: &Browser, x: f64, y: f64) {
    b.js(
        "const [x, y] = [arguments[0], arguments[1]];\
         const o = {clientX: x, clientY: y, bubbles: true, button: 0};\
         document.elementFromPoint(x, y).dispatchEvent(new MouseEvent('mousedown', o));\
         window.dispatchEvent(new MouseEvent('mouseup', o));",
        vec![json!(x), json!(y)],
    )
    .await;
}

/// The window point at the centre of the node drawn for `name` (`place` or `transition`).
async fn node_centre(b: &Browser, what: &str, name: &str) -> (f64, f64) {
    let v = b
        .js(
            &format!(
                "const r = document.querySelector('[data-{what}=\"' + arguments[0] + '\"]')\
                   .getBoundingClientRect(); return [r.left + r.width / 2, r.top + r.height / 2];"
            ),
            vec![json!(name)],
        )
        .await;
    (v[0].as_f64().unwrap(), v[1].as_f64().unwrap())
}

async fn click_node(b: &Browser, what: &str, name: &str) {
    let (x, y) = node_centre(b, what, name).await;
    click_at(b, x, y).await;
}

/// Waits until `script` (an expression) is true on the page; a timeout says what the
/// editor last said.
async fn wait_for(b: &Browser, script: &str, what: &str) {
    let start = std::time::Instant::now();
    while b.js(&format!("return !!({script});"), vec![]).await != json!(true) {
        if start.elapsed() > WAIT {
            let said = b.text("#edit-msg").await;
            let props = b
                .js("return document.getElementById('props').outerHTML;", vec![])
                .await;
            panic!("timed out waiting for {what}; the editor said {said:?}; {props}");
        }
        tokio::time::sleep(std::time::Duration::from_millis(20)).await;
    }
}

/// Waits until the element `#id` is shown (or hidden).
async fn wait_shown(b: &Browser, id: &str, shown: bool) {
    let script =
        format!("document.getElementById('{id}').classList.contains('hidden') !== {shown}");
    wait_for(b, &script, &format!("#{id} shown: {shown}")).await;
}

/// Waits until the page draws a place called `name` (or none).
async fn wait_place(b: &Browser, name: &str, drawn: bool) {
    let script =
        format!("(document.querySelector('[data-place=\"{name}\"]') !== null) === {drawn}");
    wait_for(b, &script, &format!("place {name} drawn: {drawn}")).await;
}

/// Types `text` into the properties field `name` (clearing it first), as a user does.
async fn type_field(b: &Browser, name: &str, text: &str) {
    let f = b
        .client
        .find(Locator::Css(&format!("#props [name=\"{name}\"]")))
        .await
        .unwrap();
    f.clear().await.unwrap();
    f.send_keys(text).await.unwrap();
}

fn t1_rate(net: &Net) -> f64 {
    match timing(net, "T1") {
        Timing::Exponential { rate, .. } => rate,
        t => panic!("T1 is {t:?}"),
    }
}

async fn keys(b: &Browser, key: &str, ctrl: bool, shift: bool) {
    b.js(
        "document.body.dispatchEvent(new KeyboardEvent('keydown', \
           {key: arguments[0], ctrlKey: arguments[1], shiftKey: arguments[2], bubbles: true}));",
        vec![json!(key), json!(ctrl), json!(shift)],
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_edit_in_the_browser_saved_and_reloaded_analyses_as_plan_runner_analyze() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let saved = dir.path().join("cyc3-edited.PNPRO");
    let state = cyc3_state().saving_to(saved.clone()).unwrap();
    let (addr, server) = start_server(state.clone()).await;
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;

    // The editor's tool bar (key e), then a place where nothing is drawn: under P1.
    wait_shown(&b, "edit-mode", true).await;
    keys(&b, "e", false, false).await;
    wait_shown(&b, "edit-bar", true).await;
    b.click("[data-tool=place]").await;
    let (x, y) = node_centre(&b, "place", "P1").await;
    click_at(&b, x, y + 110.0).await;
    wait_place(&b, "P4", true).await;

    // Two arcs with the arc tool: T1 → P4 and P4 → t2.
    b.click("[data-tool=arc]").await;
    for (from, to) in [
        (("transition", "T1"), ("place", "P4")),
        (("place", "P4"), ("transition", "t2")),
    ] {
        click_node(&b, from.0, from.1).await;
        click_node(&b, to.0, to.1).await;
    }
    wait_for(&b, "net.arcs.length === 8", "the two new arcs").await;

    // T1's rate in the properties panel.
    b.click("[data-tool=select]").await;
    click_node(&b, "transition", "T1").await;
    wait_for(
        &b,
        "document.querySelector('#props [name=rate]') !== null",
        "T1's properties",
    )
    .await;
    type_field(&b, "rate", "3").await;
    b.click("#props-apply").await;
    wait_for(&b, "net.transitions[0].rate === 3", "the new rate").await;
    b.screenshot(&screenshot_path("editor.png")).await;

    // A negative rate is refused with the reader's words, and nothing changes.
    click_node(&b, "transition", "T1").await;
    type_field(&b, "rate", "-2").await;
    b.click("#props-apply").await;
    wait_for(
        &b,
        "document.getElementById('edit-msg').classList.contains('error')",
        "the refusal",
    )
    .await;
    assert_eq!(
        b.text("#edit-msg").await,
        "rate of `T1` is -2: must be a finite number > 0"
    );
    assert_eq!(t1_rate(&state.current_net()), 3.0);
    b.screenshot(&screenshot_path("editor-refused.png")).await;

    // The editor's keys are listed under `?`.
    keys(&b, "?", false, false).await;
    wait_shown(&b, "help", true).await;
    let help = b.text("#help-keys").await;
    for k in [
        "Ctrl-Z",
        "Ctrl-Shift-Z",
        "edit the net",
        "add inhibitor arcs",
        "Del",
    ] {
        assert!(help.contains(k), "{k} not in {help:?}");
    }
    b.screenshot(&screenshot_path("editor-keys.png")).await;
    keys(&b, "Escape", false, false).await;
    wait_shown(&b, "help", false).await;

    // Ctrl-Z takes the rate back, Ctrl-Shift-Z does it again.
    keys(&b, "z", true, false).await;
    wait_for(&b, "net.transitions[0].rate === 1", "the undone rate").await;
    assert_eq!(t1_rate(&state.current_net()), 1.0);
    keys(&b, "Z", true, true).await;
    wait_for(&b, "net.transitions[0].rate === 3", "the redone rate").await;

    // Another page's edit shows here too.
    let (status, _) = edit(
        &state,
        json!({"op": "add_place", "name": "elsewhere", "x": 20, "y": 8}),
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    wait_place(&b, "elsewhere", true).await;
    keys(&b, "z", true, false).await;
    wait_place(&b, "elsewhere", false).await;

    // The token game plays the edited net: P4 holds T1's tokens until t2 takes them.
    b.click("#step").await;
    wait_for(
        &b,
        "document.querySelector('[data-place=\"P4\"]').getAttribute('data-tokens') === '1'",
        "a token in P4",
    )
    .await;

    // Save: the file given to `serve --save-to`, read back as the net the page edited.
    b.click("#edit-save").await;
    wait_for(
        &b,
        "document.getElementById('edit-msg').textContent.startsWith('saved')",
        "the save",
    )
    .await;
    let back = read_net(&saved, &ReadOptions::default()).unwrap().net;
    let edited = state.current_net();
    assert!(back.diff(&edited).is_empty(), "{:?}", back.diff(&edited));
    assert_eq!(back.place_count(), 4);
    assert_eq!(t1_rate(&back), 3.0);

    // The page's analysis of the edited net.
    analyse_on_page(&b).await;
    let page = http_get(addr, "/api/analysis").await;
    let cli = analyze_json(&saved);
    assert_same_analysis(&page, &cli);
    b.screenshot(&screenshot_path("editor-analysed.png")).await;
    server.abort();

    // The saved file opened again, analysed in the page: the numbers of `analyze` on it.
    let reopened = WebState::new(back, None, 0).with_source(&saved);
    let (addr, server) = start_server(reopened).await;
    open(&b, addr).await;
    analyse_on_page(&b).await;
    assert!(b.text("#analysis").await.contains("P4"));
    let page = http_get(addr, "/api/analysis").await;
    assert_same_analysis(&page, &cli);
    // Mean tokens of P4 equal P2's: it holds each token that T1 moved until t2 fires.
    let mean = &page["steady"]["mean_tokens"];
    assert!((mean["P4"].as_f64().unwrap() - mean["P2"].as_f64().unwrap()).abs() < 1e-12);
    b.screenshot(&screenshot_path("editor-reloaded.png")).await;
    // The editor in the dark theme, an inhibitor arc on its way (dashed source).
    b.client
        .goto(&format!("http://{addr}/?theme=dark"))
        .await
        .unwrap();
    wait_shown(&b, "edit-mode", true).await;
    keys(&b, "e", false, false).await;
    keys(&b, "h", false, false).await;
    click_node(&b, "place", "P4").await;
    wait_for(
        &b,
        "document.querySelector('[data-place=\"P4\"]').dataset.editSelected === 'arc-from'",
        "the arc's source",
    )
    .await;
    b.screenshot(&screenshot_path("editor-dark.png")).await;
    server.abort();
    b.close().await;
}
