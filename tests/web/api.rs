//! The viewer's server: its JSON API plays the same seeded token game as `plan-runner
//! simulate`, reports the file's positions, analyses the net, and serves a page that loads
//! nothing from another host.
#![cfg(feature = "web")]

use crate::support as common;

use std::path::Path;

use assert_cmd::Command;
use axum::body::Body;
use axum::http::{Request, StatusCode, header};
use gspn::io::{ReadOptions, read_net};
use gspn::sim::Simulator;
use gspn::web::{ASSETS, WebState, router, serve};
use serde_json::{Value, json};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tower::ServiceExt;

const PATROL: &str =
    "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml";

fn state_for(path: &Path, seed: u64) -> WebState {
    let loaded = read_net(path, &ReadOptions::default()).unwrap();
    WebState::new(loaded.net, None, seed)
}

/// One request through the router; the status and the body as JSON (or as a string).
pub(crate) async fn call(
    state: &WebState,
    method: &str,
    uri: &str,
    body: Option<Value>,
) -> (StatusCode, Value) {
    let mut req = Request::builder().method(method).uri(uri);
    // As the page does: every POST is JSON, `{}` when there is nothing to say.
    let body = match body {
        Some(v) => Some(v),
        None if method != "GET" => Some(json!({})),
        None => None,
    };
    let body = match body {
        Some(v) => {
            req = req.header(header::CONTENT_TYPE, "application/json");
            Body::from(v.to_string())
        }
        None => Body::empty(),
    };
    let res = router(state.clone())
        .oneshot(req.body(body).unwrap())
        .await
        .unwrap();
    let status = res.status();
    let bytes = axum::body::to_bytes(res.into_body(), usize::MAX)
        .await
        .unwrap();
    let text = String::from_utf8(bytes.to_vec()).unwrap();
    (
        status,
        serde_json::from_str(&text).unwrap_or(Value::String(text)),
    )
}

#[tokio::test]
async fn five_seeded_steps_give_the_marking_of_plan_runner_simulate() {
    let path = common::fixture(PATROL);
    let state = state_for(&path, 0);
    let seed = 11;
    let (status, _) = call(
        &state,
        "POST",
        "/api/sim/reset",
        Some(json!({ "seed": seed })),
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    let mut last = Value::Null;
    for _ in 0..5 {
        let (status, v) = call(&state, "POST", "/api/sim/step", Some(json!({ "n": 1 }))).await;
        assert_eq!(status, StatusCode::OK, "{v}");
        assert_eq!(v["fired"], 1);
        last = v;
    }
    assert_eq!(last["seed"], seed);
    assert_eq!(last["firings"], 5);

    // The library's token game with the same seed.
    let net = state.net();
    let mut sim = Simulator::new(net.clone(), seed);
    sim.run_steps(5).unwrap();
    let tokens: Vec<u32> = serde_json::from_value(last["tokens"].clone()).unwrap();
    assert_eq!(tokens, sim.marking().as_slice());
    assert_eq!(last["time"].as_f64().unwrap(), sim.time());
    for (p, place) in net.places().iter().enumerate() {
        assert_eq!(last["marking"][&place.name], sim.marking().as_slice()[p]);
    }

    // The command line, with the same seed.
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args([
            "simulate",
            path.to_str().unwrap(),
            "--seed",
            "11",
            "--steps",
            "5",
            "--json",
        ])
        .output()
        .unwrap();
    assert!(out.status.success());
    let cli: Value = serde_json::from_slice(&out.stdout).unwrap();
    let cli_trace = cli["trace"].as_array().unwrap();
    assert_eq!(cli_trace.len(), 5);
    assert_eq!(cli_trace[4]["marking"], last["text"]);
    let page_trace = last["trace"].as_array().unwrap();
    for (a, b) in cli_trace.iter().zip(page_trace) {
        assert_eq!(a["transition"], b["transition"]);
        assert_eq!(a["time"], b["time"]);
    }
}

#[tokio::test]
async fn stepping_in_one_request_equals_stepping_one_by_one() {
    let state = state_for(&common::fixture(PATROL), 4);
    let (_, many) = call(&state, "POST", "/api/sim/step", Some(json!({ "n": 40 }))).await;
    call(&state, "POST", "/api/sim/reset", Some(json!({}))).await;
    let mut one = Value::Null;
    for _ in 0..40 {
        one = call(&state, "POST", "/api/sim/step", None).await.1;
    }
    assert_eq!(many["tokens"], one["tokens"]);
    assert_eq!(many["time"], one["time"]);
    assert_eq!(many["firings"], 40);
}

#[tokio::test]
async fn firing_by_hand_needs_a_firable_transition() {
    let state = state_for(&common::fixture("greatspn/cyc3/cyc3_ss.PNPRO"), 1);
    let (status, v) = call(
        &state,
        "POST",
        "/api/sim/fire",
        Some(json!({"transition": "T3"})),
    )
    .await;
    assert_eq!(status, StatusCode::CONFLICT, "{v}");
    let (status, _) = call(
        &state,
        "POST",
        "/api/sim/fire",
        Some(json!({"transition": "zz"})),
    )
    .await;
    assert_eq!(status, StatusCode::NOT_FOUND);
    let (status, v) = call(
        &state,
        "POST",
        "/api/sim/fire",
        Some(json!({"transition": "T1"})),
    )
    .await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(v["text"], "P1=1,P2=1");
    assert_eq!(v["firable"], json!(["t2"]));
    assert_eq!(v["vanishing"], true);
    assert_eq!(v["trace"][0]["manual"], true);
    let (_, v) = call(&state, "GET", "/api/sim/state", None).await;
    assert_eq!(v["tokens"], json!([1, 1, 0]));
}

#[tokio::test]
async fn net_positions_are_the_files_and_nets_without_them_get_a_layout() {
    let path = common::fixture("thesis/caldeira_2020_dev/example_gspn.xml");
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let state = state_for(&path, 0);
    let (status, v) = call(&state, "GET", "/api/net", None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(v["layout"], "file");
    let places = v["places"].as_array().unwrap();
    assert_eq!(places.len(), net.place_count());
    for (p, j) in net.places().iter().zip(places) {
        let pos = p.position.unwrap();
        assert_eq!(j["name"], p.name.as_str());
        assert_eq!(j["tokens"], p.initial);
        assert_eq!(
            (j["x"].as_f64().unwrap(), j["y"].as_f64().unwrap()),
            (pos.x, pos.y)
        );
    }
    for (t, j) in net
        .transitions()
        .iter()
        .zip(v["transitions"].as_array().unwrap())
    {
        let pos = t.position.unwrap();
        assert_eq!(
            (j["x"].as_f64().unwrap(), j["y"].as_f64().unwrap()),
            (pos.x, pos.y)
        );
    }
    let arcs = v["arcs"].as_array().unwrap();
    assert_eq!(arcs.len(), net.arcs().len());
    let bends: usize = arcs
        .iter()
        .map(|a| a["points"].as_array().unwrap().len())
        .sum();
    assert_eq!(
        bends,
        net.arcs().iter().map(|a| a.points.len()).sum::<usize>()
    );

    // The temperature patrol file has no positions: a layered layout, no two nodes on one spot.
    let state = state_for(&common::fixture(PATROL), 0);
    let (_, v) = call(&state, "GET", "/api/net", None).await;
    assert_eq!(v["layout"], "layered");
    let mut spots: Vec<(i64, i64)> = v["places"]
        .as_array()
        .unwrap()
        .iter()
        .chain(v["transitions"].as_array().unwrap())
        .map(|n| {
            (
                n["x"].as_f64().unwrap() as i64,
                n["y"].as_f64().unwrap() as i64,
            )
        })
        .collect();
    let n = spots.len();
    assert_eq!(n, 16 + 24);
    spots.sort_unstable();
    spots.dedup();
    assert_eq!(spots.len(), n);
    let t = &v["transitions"].as_array().unwrap()[0];
    assert!(t["kind"] == "exponential" || t["kind"] == "immediate");
}

#[tokio::test]
async fn analysis_reports_properties_measures_and_dead_markings() {
    // cyc3, single server: E[P1] = 10/7, every throughput 6/7.
    let state = state_for(&common::fixture("greatspn/cyc3/cyc3_ss.PNPRO"), 0);
    let (status, v) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(
        (v["tangible"].as_u64(), v["vanishing"].as_u64()),
        (Some(3), Some(2))
    );
    assert_eq!(v["deadlock_free"], true);
    let mean = v["steady"]["mean_tokens"]["P1"].as_f64().unwrap();
    assert!((mean - 10.0 / 7.0).abs() < 1e-9, "{mean}");
    let thr = v["steady"]["throughput"]["t2"].as_f64().unwrap();
    assert!((thr - 6.0 / 7.0).abs() < 1e-9, "{thr}");

    // pipediag: two dead markings, each with the firing sequence that reaches it.
    let path = common::fixture("thesis/azevedo_2018/pipediag.xml");
    let state = state_for(&path, 0);
    let (_, v) = call(&state, "GET", "/api/analysis", None).await;
    let dead = v["dead_markings"].as_array().unwrap();
    assert_eq!(dead.len(), 2, "{v}");
    let net = state.net();
    for d in dead {
        let mut m = net.initial_marking();
        for name in d["path"].as_array().unwrap() {
            let t = net.transition_by_name(name.as_str().unwrap()).unwrap();
            assert!(net.firable(&m).contains(&t));
            net.fire(&mut m, t).unwrap();
        }
        assert_eq!(net.format_marking(&m), d["text"].as_str().unwrap());
        assert!(net.firable(&m).is_empty());
    }
}

#[tokio::test]
async fn an_unbounded_net_is_an_analysis_error_in_json() {
    let mut b = gspn::net::NetBuilder::new("grow");
    let p = b.place("p", 0);
    let t = b.exponential("t", 1.0, gspn::net::Servers::Single);
    b.output(t, p, 1);
    let state = WebState::new(b.build().unwrap(), None, 0);
    let (status, v) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY);
    assert_eq!(v["kind"], "unbounded");
    assert_eq!(v["places"], json!(["p"]));
}

/// Every `http://` or `https://` in `text`, minus XML namespace names (never fetched).
fn foreign_urls(text: &str) -> Vec<String> {
    const NAMESPACES: &[&str] = &["http://www.w3.org/2000/svg"];
    let mut out = Vec::new();
    for scheme in ["http://", "https://"] {
        let mut rest = text;
        while let Some(i) = rest.find(scheme) {
            let url: String = rest[i..]
                .chars()
                .take_while(|c| !c.is_whitespace() && !"'\"<>)".contains(*c))
                .collect();
            if !NAMESPACES.contains(&url.as_str()) {
                out.push(url);
            }
            rest = &rest[i + scheme.len()..];
        }
    }
    out
}

#[tokio::test]
async fn the_page_is_served_from_the_binary_and_loads_nothing_from_elsewhere() {
    // A real server on a free port, spoken to over TCP.
    let state = state_for(&common::fixture(PATROL), 0);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(serve(listener, state));
    for asset in ASSETS {
        let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
        let req = format!(
            "GET {} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n",
            asset.path
        );
        stream.write_all(req.as_bytes()).await.unwrap();
        let mut res = String::new();
        stream.read_to_string(&mut res).await.unwrap();
        let (head, body) = res.split_once("\r\n\r\n").unwrap();
        assert!(head.starts_with("HTTP/1.1 200"), "{head}");
        let head = head.to_ascii_lowercase();
        assert!(
            head.contains("content-security-policy: default-src 'self'"),
            "{head}"
        );
        assert!(
            head.contains(&format!("content-type: {}", asset.mime)),
            "{head}"
        );
        assert_eq!(body, asset.body);
        assert_eq!(foreign_urls(body), Vec::<String>::new(), "{}", asset.path);
    }
    server.abort();

    let html = ASSETS.iter().find(|a| a.path == "/").unwrap().body;
    for id in ["step", "step-n", "run", "reset", "seed", "trace"] {
        assert!(html.contains(&format!("id=\"{id}\"")), "#{id} missing");
    }
    assert!(html.contains("src=\"/app.js\""));
    let js: String = ASSETS
        .iter()
        .filter(|a| a.path.ends_with(".js"))
        .map(|a| a.body)
        .collect();
    for script in ASSETS.iter().filter(|a| a.path.ends_with(".js")) {
        assert!(
            html.contains(&format!("src=\"{}\"", script.path)),
            "the page never loads {}",
            script.path
        );
    }
    for hook in [
        "'data-place'",
        "'data-tokens'",
        "'data-transition'",
        "'data-enabled'",
    ] {
        assert!(js.contains(hook), "{hook} missing from the scripts");
    }
    for api in [
        "/api/net",
        "/api/sim/state",
        "/api/sim/step",
        "/api/sim/reset",
        "/api/sim/fire",
        "/api/analysis",
        "/api/analysis/start",
        "/api/analysis/progress",
        "/api/analysis/cancel",
        "/api/live/ws",
        "/api/live/stop",
        "/api/replay",
        "/api/replay/window",
    ] {
        assert!(js.contains(api), "the page never calls {api}");
    }
}

#[tokio::test]
async fn save_layout_gives_a_pnpro_with_the_moved_positions() {
    let state = state_for(&common::fixture("greatspn/cyc3/cyc3_ss.PNPRO"), 0);
    let places = json!([[1.0, 2.0], [5.5, 2.0], [9.0, 4.0]]);
    let transitions = json!([[3.0, 1.0], [7.0, 1.5], [6.0, 8.0]]);
    let (status, v) = call(
        &state,
        "POST",
        "/api/layout",
        Some(json!({ "places": places, "transitions": transitions })),
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{v}");
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("cyc3.PNPRO");
    std::fs::write(&file, v["pnpro"].as_str().unwrap()).unwrap();
    let back = read_net(&file, &ReadOptions::default()).unwrap().net;
    assert!(
        back.diff(state.net()).is_empty(),
        "{:?}",
        back.diff(state.net())
    );
    for (p, want) in back.places().iter().zip(places.as_array().unwrap()) {
        let pos = p.position.unwrap();
        assert_eq!(json!([pos.x, pos.y]), *want, "{}", p.name);
    }
    for (t, want) in back
        .transitions()
        .iter()
        .zip(transitions.as_array().unwrap())
    {
        let pos = t.position.unwrap();
        assert_eq!(json!([pos.x, pos.y]), *want, "{}", t.name);
    }
    let (status, _) = call(
        &state,
        "POST",
        "/api/layout",
        Some(json!({ "places": [[0.0, 0.0]], "transitions": [] })),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
}

/// A GreatSPN project saved from the page is the same file with only the moved nodes'
/// `x` and `y` changed: its constants, rotations, label offsets and arcs' bends survive, and
/// it reads back as the same net with the new positions.
#[tokio::test]
async fn save_layout_of_a_greatspn_project_changes_only_the_positions() {
    let path = common::fixture("greatspn/greatspn_examples/fms.PNPRO");
    let original = std::fs::read_to_string(&path).unwrap();
    let state = state_for(&path, 0).with_source(&path);
    let (_, net) = call(&state, "GET", "/api/net", None).await;
    // The look the file gives: `load` turned half a round, `repM2`'s name moved.
    let load = &net["transitions"]
        .as_array()
        .unwrap()
        .iter()
        .find(|t| t["name"] == "load")
        .unwrap()["look"];
    assert_eq!(load["rotation"], json!(std::f64::consts::PI));
    assert_eq!(load["label"], json!([1.625, -0.75]));
    assert_eq!(load["param"], json!([0.25, null]));
    let at = |kind: &str| -> Vec<[f64; 2]> {
        net[kind]
            .as_array()
            .unwrap()
            .iter()
            .map(|n| [n["x"].as_f64().unwrap(), n["y"].as_f64().unwrap()])
            .collect()
    };
    let (mut places, transitions) = (at("places"), at("transitions"));
    // Unmoved: the very same file.
    let body = json!({ "places": places, "transitions": transitions });
    let (status, v) = call(&state, "POST", "/api/layout", Some(body)).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(v["pnpro"].as_str().unwrap(), original);
    assert_eq!(v["file"], "fms.PNPRO");
    // `Pallets` moved: one line changes, and only its position.
    places[0] = [21.5, 3.0];
    let body = json!({ "places": places, "transitions": transitions });
    let (_, v) = call(&state, "POST", "/api/layout", Some(body)).await;
    let saved = v["pnpro"].as_str().unwrap();
    let changed: Vec<(&str, &str)> = original
        .lines()
        .zip(saved.lines())
        .filter(|(a, b)| a != b)
        .collect();
    assert_eq!(
        changed,
        vec![(
            r#"      <place marking="N" name="Pallets" x="20.0" y="4.0"/>"#,
            r#"      <place marking="N" name="Pallets" x="21.5" y="3.0"/>"#
        )]
    );
    assert_eq!(original.lines().count(), saved.lines().count());
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("fms.PNPRO");
    std::fs::write(&file, saved).unwrap();
    let back = read_net(&file, &ReadOptions::default()).unwrap().net;
    assert!(
        back.diff(state.net()).is_empty(),
        "{:?}",
        back.diff(state.net())
    );
    let pallets = back.places()[0].position.unwrap();
    assert_eq!((pallets.x, pallets.y), (21.5, 3.0));
    for (a, b) in back.places().iter().zip(state.net().places()).skip(1) {
        assert_eq!(a.position, b.position, "{}", a.name);
    }
    for (a, b) in back.transitions().iter().zip(state.net().transitions()) {
        assert_eq!(a.position, b.position, "{}", a.name);
    }
}

#[test]
fn serve_refuses_bad_input_with_exit_code_2() {
    let bad = common::fixture("thesis/azevedo_2020/ros/gspn_thesis_test_case.xml");
    for file in [bad.to_str().unwrap(), "/nonexistent/net.xml"] {
        let out = Command::cargo_bin("plan-runner")
            .unwrap()
            .args(["serve", file, "--addr", "127.0.0.1:0"])
            .output()
            .unwrap();
        assert_eq!(out.status.code(), Some(2), "{file}");
        assert!(String::from_utf8_lossy(&out.stderr).contains("error"));
    }
}

/// Polls `GET /api/analysis/progress` until `done(progress)` holds (at most ~60 s).
async fn progress_until(state: &WebState, done: impl Fn(&Value) -> bool) -> Value {
    for _ in 0..12_000 {
        let (status, p) = call(state, "GET", "/api/analysis/progress", None).await;
        assert_eq!(status, StatusCode::OK);
        if done(&p) {
            return p;
        }
        tokio::time::sleep(std::time::Duration::from_millis(5)).await;
    }
    panic!("the analysis progress never reached the expected state");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_long_analysis_shows_progress_and_can_be_cancelled() {
    // Kanban N = 4: 454,475 tangible markings, seconds of work.
    let state = state_for(&common::fixture("kanban/kanban_gspn_N4.pnml"), 0);
    let (_, p) = call(&state, "GET", "/api/analysis/progress", None).await;
    assert_eq!(p["state"], "idle");

    let (status, p) = call(&state, "POST", "/api/analysis/start", None).await;
    assert_eq!(status, StatusCode::OK);
    assert_eq!(p["state"], "running", "{p}");
    // The search reports the markings it has found while it runs.
    let seen = progress_until(&state, |p| p["markings"].as_u64().unwrap_or(0) > 0).await;
    assert_eq!(seen["state"], "running", "{seen}");
    let phases = ["state space", "properties", "steady state"];
    assert!(phases.contains(&seen["phase"].as_str().unwrap()), "{seen}");

    let (status, p) = call(&state, "POST", "/api/analysis/cancel", None).await;
    assert_eq!(status, StatusCode::OK);
    assert!(
        p["state"] == "cancelling" || p["state"] == "cancelled",
        "{p}"
    );
    let end = progress_until(&state, |p| p["state"] != "cancelling").await;
    assert_eq!(end["state"], "cancelled", "{end}");
    assert!(end["markings"].as_u64().unwrap() >= seen["markings"].as_u64().unwrap());

    // Started again and cancelled at once: the search stops before its first markings'
    // successors are all stored, far from the 454,475 of the whole graph.
    let (_, p) = call(&state, "POST", "/api/analysis/start", None).await;
    assert_eq!(p["state"], "running", "{p}");
    call(&state, "POST", "/api/analysis/cancel", None).await;
    let end = progress_until(&state, |p| p["state"] != "cancelling").await;
    assert_eq!(end["state"], "cancelled", "{end}");
    assert_eq!(end["phase"], "state space", "{end}");
    assert!(end["markings"].as_u64().unwrap() < 454_475, "{end}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancel_during_the_steady_state_stops_the_solver() {
    // Kanban N = 4 again: once the search is over, the Gauss–Seidel sweeps take seconds;
    // a cancel then ends the job in the steady-state phase, with every marking counted. A
    // solver that ignored the cancel would finish, and the job would end `done`.
    let state = state_for(&common::fixture("kanban/kanban_gspn_N4.pnml"), 0);
    call(&state, "POST", "/api/analysis/start", None).await;
    let solving = progress_until(&state, |p| {
        p["phase"] == "steady state" || p["state"] != "running"
    })
    .await;
    assert_eq!(solving["state"], "running", "{solving}");
    call(&state, "POST", "/api/analysis/cancel", None).await;
    let end = progress_until(&state, |p| p["state"] != "cancelling").await;
    assert_eq!(end["state"], "cancelled", "{end}");
    assert_eq!(end["phase"], "steady state", "{end}");
    assert_eq!(end["markings"], 454_475, "{end}");
}

#[tokio::test]
async fn a_finished_analysis_is_reported_done_and_kept() {
    let state = state_for(&common::fixture(PATROL), 0);
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{a}");
    let (_, p) = call(&state, "GET", "/api/analysis/progress", None).await;
    assert_eq!(p["state"], "done", "{p}");
    assert_eq!(p["markings"], a["reachable"]);
    // Starting or cancelling a finished analysis changes nothing.
    let (_, p) = call(&state, "POST", "/api/analysis/cancel", None).await;
    assert_eq!(p["state"], "done");
    let (_, p) = call(&state, "POST", "/api/analysis/start", None).await;
    assert_eq!(p["state"], "done");
    let (_, again) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(again, a);
}
