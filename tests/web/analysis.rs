//! The analysis panel says what it analysed: for a plan, the net under the plan's policy
//! (the numbers of `plan-runner analyze PLAN`, not the bare net's 0.25 everywhere), labelled
//! "net under plan policy" or "bare net"; with place bounds, invariants by name and reward
//! rates; a "max states" limit the page sets; and the policy's choice shown on the decision
//! transitions of the current marking.
#![cfg(feature = "web")]

use crate::api::call;
use crate::browser::{BROWSER, WAIT, http_get, open, screenshot_path};
use crate::support::browser::Browser;
use crate::support::start_server;

use std::path::PathBuf;

use assert_cmd::Command;
use axum::http::StatusCode;
use gspn::io::ReadOptions;
use gspn::plan::Plan;
use gspn::web::{DEFAULT_MAX_STATES, WebState};
use serde_json::{Value, json};

pub(crate) fn patrol_plan_path() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature_patrol.toml")
}

pub(crate) fn patrol_plan() -> Plan {
    gspn::plan::open(&patrol_plan_path(), &ReadOptions::default())
        .unwrap()
        .into_plan()
}

/// The viewer of `plan` as `plan-runner serve PLAN` builds it.
pub(crate) fn plan_state(plan: Plan) -> WebState {
    let text = plan.text.clone().expect("read from its file");
    WebState::for_plan(
        plan.net,
        Some(plan.policy),
        plan.rewards,
        0,
        DEFAULT_MAX_STATES,
    )
    .with_plan(text)
}

/// `plan-runner analyze FILE --json`.
pub(crate) fn analyze_json(file: &std::path::Path) -> Value {
    analyze_json_with(file, &[])
}

/// `plan-runner analyze FILE --json ARGS…`.
pub(crate) fn analyze_json_with(file: &std::path::Path, args: &[&str]) -> Value {
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["analyze", file.to_str().unwrap(), "--json"])
        .args(args)
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    serde_json::from_slice(&out.stdout).unwrap()
}

fn assert_close_maps(page: &Value, cli: &Value, what: &str) {
    let (page, cli) = (page.as_object().unwrap(), cli.as_object().unwrap());
    assert_eq!(
        page.keys().collect::<Vec<_>>(),
        cli.keys().collect::<Vec<_>>(),
        "{what}"
    );
    for (name, v) in cli {
        let (a, b) = (page[name].as_f64().unwrap(), v.as_f64().unwrap());
        assert!((a - b).abs() < 1e-9, "{what} {name}: page {a}, analyze {b}");
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_plan_is_analysed_under_its_policy_with_the_numbers_of_analyze() {
    let cli = analyze_json(&patrol_plan_path());
    assert_eq!(cli["analysed"], "net under plan policy");
    let state = plan_state(patrol_plan());
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{a}");
    assert_eq!(a["analysed"], "net under plan policy");
    assert_eq!(a["reachable"], cli["state_space"]["reachable"]);
    assert_close_maps(
        &a["steady"]["mean_tokens"],
        &cli["steady_state"]["mean_tokens"],
        "mean tokens",
    );
    assert_close_maps(
        &a["steady"]["throughput"],
        &cli["steady_state"]["throughput"],
        "throughput",
    );
    assert_eq!(a["place_bounds"], cli["state_space"]["place_bounds"]);
    assert_eq!(a["p_invariants"], cli["state_space"]["p_invariants"]);
    assert_eq!(a["t_invariants"], cli["state_space"]["t_invariants"]);
    // The policy's numbers, not the bare net's: a robot waits far less than 1/4 of the time.
    let wait = a["steady"]["mean_tokens"]["p4:Wait_L1"].as_f64().unwrap();
    assert!((wait - 0.1026).abs() < 1e-4, "{wait}");
    // One P-invariant over the 16 places (3 robots): weights by place name.
    let pinv = a["p_invariants"].as_array().unwrap();
    assert_eq!(pinv.len(), 1, "{pinv:?}");
    assert_eq!(pinv[0].as_object().unwrap().len(), 16);
    assert_eq!(pinv[0]["p1:Check_Temperature_L1"], 1);

    // The net file alone: the bare net, as `analyze NET` says.
    let plan = patrol_plan();
    let net_path = plan.net_path.clone();
    let cli = analyze_json(&net_path);
    assert_eq!(cli["analysed"], "bare net");
    let state = WebState::new(plan.net, None, 0);
    let (_, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(a["analysed"], "bare net");
    assert_close_maps(
        &a["steady"]["mean_tokens"],
        &cli["steady_state"]["mean_tokens"],
        "bare mean tokens",
    );
    let wait = a["steady"]["mean_tokens"]["p4:Wait_L1"].as_f64().unwrap();
    assert!((wait - 0.25).abs() < 1e-9, "{wait}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_sets_the_max_states_and_a_larger_limit_analyses_again() {
    let state = plan_state(patrol_plan());
    let (_, p) = call(&state, "GET", "/api/analysis/progress", None).await;
    assert_eq!(p["state"], "idle");
    assert_eq!(p["max_states"], DEFAULT_MAX_STATES);
    let (status, v) = call(
        &state,
        "POST",
        "/api/analysis/start",
        Some(json!({ "max_states": 0 })),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");

    // 676 reachable markings: a limit of 100 is too small, and the message names the field.
    call(
        &state,
        "POST",
        "/api/analysis/start",
        Some(json!({ "max_states": 100 })),
    )
    .await;
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::UNPROCESSABLE_ENTITY, "{a}");
    assert_eq!(a["kind"], "too_many_states");
    assert_eq!(a["analysed"], "net under plan policy");
    let message = a["error"].as_str().unwrap();
    assert!(
        message.contains("more than 100 reachable markings"),
        "{message}"
    );
    assert!(message.contains("max states"), "{message}");
    assert!(!message.contains("--max-states"), "{message}");
    let (_, p) = call(&state, "GET", "/api/analysis/progress", None).await;
    assert_eq!(
        (p["state"].as_str(), p["max_states"].as_u64()),
        (Some("done"), Some(100))
    );

    // The same limit again keeps the result; a larger one analyses again.
    let (_, p) = call(
        &state,
        "POST",
        "/api/analysis/start",
        Some(json!({ "max_states": 100 })),
    )
    .await;
    assert_eq!(p["state"], "done", "{p}");
    call(
        &state,
        "POST",
        "/api/analysis/start",
        Some(json!({ "max_states": 1000 })),
    )
    .await;
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{a}");
    assert_eq!(a["reachable"], 676);
}

/// Steps the token game one firing at a time until the marking is one where the plan's
/// policy chooses; the state then.
async fn step_to_a_choice(state: &WebState) -> Value {
    for _ in 0..500 {
        let (status, s) = call(state, "POST", "/api/sim/step", Some(json!({ "n": 1 }))).await;
        assert_eq!(status, StatusCode::OK, "{s}");
        if !s["choice"].is_null() {
            return s;
        }
    }
    panic!("no marking where the policy chooses in 500 firings");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_token_game_shows_the_policy_choice_in_a_vanishing_marking() {
    let plan = patrol_plan();
    let (net, policy) = (plan.net.clone(), plan.policy.clone());
    let state = plan_state(plan);
    let (_, s) = call(&state, "GET", "/api/sim/state", None).await;
    assert!(
        s["choice"].is_null(),
        "the initial marking is tangible: {s}"
    );
    let s = step_to_a_choice(&state).await;
    assert_eq!(s["vanishing"], true);
    let m: Vec<u32> = serde_json::from_value(s["tokens"].clone()).unwrap();
    let firable = net.firable(&m);
    let (rule, _) = policy.rule_for(&m, &firable).unwrap();
    assert_eq!(s["choice"]["rule"], rule);
    let want: serde_json::Map<String, Value> = policy
        .distribution(&m, &firable)
        .unwrap()
        .into_iter()
        .map(|(t, p)| (net.transition(t).name.clone(), json!(p)))
        .collect();
    assert_eq!(s["choice"]["probabilities"], Value::Object(want));
    // The patrol's rules are deterministic: one transition, probability 1.
    assert_eq!(s["choice"]["probabilities"].as_object().unwrap().len(), 1);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_panel_labels_a_plan_analysis_and_shows_bounds_invariants_and_the_choice() {
    let _one = BROWSER.lock().await;
    let state = plan_state(patrol_plan());
    let (addr, server) = start_server(state).await;
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    // The field starts at the server's limit.
    let max = b
        .js(
            "return document.getElementById('max-states').value;",
            vec![],
        )
        .await;
    assert_eq!(max, json!(DEFAULT_MAX_STATES.to_string()));
    b.click("#analyze").await;
    b.wait_js(
        "return document.querySelector('#analysis [data-analysed]') !== null;",
        WAIT,
        "the analysis",
    )
    .await;
    let label = b
        .js(
            "return document.querySelector('#analysis [data-analysed]').textContent;",
            vec![],
        )
        .await;
    assert_eq!(label, json!("net under plan policy"));
    let a = http_get(addr, "/api/analysis").await;
    let bounds = b
        .js(
            "return [...document.querySelectorAll('#analysis [data-bound]')]\
               .map(tr => [tr.dataset.bound, Number(tr.lastChild.textContent)]);",
            vec![],
        )
        .await;
    let bounds = bounds.as_array().unwrap();
    assert_eq!(bounds.len(), 16);
    for pair in bounds {
        assert_eq!(a["place_bounds"][pair[0].as_str().unwrap()], pair[1]);
    }
    let invariants = b.text("#analysis .invariants").await;
    assert!(
        invariants.contains("p1:Check_Temperature_L1 + p2:Alarm_L1"),
        "{invariants}"
    );
    // The mean tokens shown are the policy's (0.1026 for a Wait place), not 0.25.
    let shown = b
        .js(
            "const tr = [...document.querySelectorAll('#analysis tr')]\
               .find(tr => tr.firstChild.textContent === 'p4:Wait_L1' && tr.querySelector('.bar'));\
             return tr.children[1].textContent;",
            vec![],
        )
        .await;
    assert_eq!(shown, json!("0.1026"));
    b.screenshot(&screenshot_path("analysis-under-policy.png"))
        .await;

    // Step to a marking where the policy chooses: the transition it picks says so.
    b.wait_js(
        "document.getElementById('n').value = '1';\
         const st = window.gspnState && window.gspnState();\
         if (st && st.choice) return true;\
         document.getElementById('step').click(); return false;",
        WAIT,
        "a marking where the policy chooses",
    )
    .await;
    let s = http_get(addr, "/api/sim/state").await;
    let (name, p) = s["choice"]["probabilities"]
        .as_object()
        .unwrap()
        .iter()
        .next()
        .unwrap();
    let on_page = b
        .js(
            "const g = document.querySelector('[data-transition=\"' + arguments[0] + '\"]');\
             return [g.getAttribute('data-policy'), g.querySelector('text.choice').firstChild.textContent];",
            vec![json!(name)],
        )
        .await;
    let shown: f64 = on_page[0].as_str().unwrap().parse().unwrap();
    assert_eq!(shown, p.as_f64().unwrap());
    assert_eq!(on_page[1], "policy 1");
    b.screenshot(&screenshot_path("policy-choice.png")).await;
    b.close().await;
    server.abort();
}
