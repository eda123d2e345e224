//! Questions in the analysis panel: `--prob`-style predicates (steady state and at times t)
//! and expected tokens at times t, on the analysed state space (for a plan: the net under its
//! policy) — the numbers of `plan-runner analyze PLAN --json --transient … --prob …` to
//! 1e-9; bad questions refused naming what is wrong. And the panel's dead markings replay
//! their firing sequences on the net.
#![cfg(feature = "web")]

use crate::analysis::{analyze_json_with, patrol_plan, patrol_plan_path, plan_state};
use crate::api::call;
use crate::browser::{
    BROWSER, WAIT, analyse_on_page, marking_of, open, page_marking, screenshot_path,
};
use crate::support::browser::Browser;
use crate::support::start_server;

use std::time::Duration;

use axum::http::StatusCode;
use gspn::net::{NetBuilder, Servers};
use gspn::web::WebState;
use serde_json::{Value, json};

const WAIT_L1: &str = "p4:Wait_L1 > 0";
const TWO_CHECKING: &str = "p1:Check_Temperature_L1 + p5:Check_Temperature_L2 + p9:Check_Temperature_L3 >= 1 && p2:Alarm_L1 == 0";

/// The cells of the page's answer: `(predicate or place, t, value)`, `t` = `steady` for the
/// steady state.
async fn answer_cells(b: &Browser) -> Vec<(String, String, String, f64)> {
    let v = b
        .js(
            "return [...document.querySelectorAll('#query-result td[data-value]')]\
               .map(td => [td.dataset.prob !== undefined ? 'prob' : 'tokens',\
                           td.dataset.prob !== undefined ? td.dataset.prob : td.dataset.tokens,\
                           td.dataset.t, Number(td.dataset.value)]);",
            vec![],
        )
        .await;
    serde_json::from_value(v).unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_panel_answers_predicates_and_transient_tokens_with_the_numbers_of_analyze() {
    let _one = BROWSER.lock().await;
    let cli = analyze_json_with(
        &patrol_plan_path(),
        &[
            "--transient",
            "0.5,2,10",
            "--prob",
            WAIT_L1,
            "--prob",
            TWO_CHECKING,
        ],
    );
    assert_eq!(cli["analysed"], "net under plan policy");
    let (addr, server) = start_server(plan_state(patrol_plan())).await;
    let b = Browser::start(1280, 900).await;
    open(&b, addr).await;
    // At 1280 px the token game's header, with the longest set of controls, is one row.
    crate::replay_world::assert_header_one_row(&b).await;
    analyse_on_page(&b).await;
    b.js(
        "document.getElementById('query-times').value = '0.5, 2, 10';\
         document.getElementById('query-prob').value = arguments[0];\
         document.getElementById('query').click();",
        vec![json!(format!("{WAIT_L1}\n{TWO_CHECKING}\n"))],
    )
    .await;
    b.wait_js(
        "return document.querySelectorAll('#query-result td[data-value]').length > 0;",
        WAIT,
        "the answer",
    )
    .await;
    let cells = answer_cells(&b).await;
    let places = patrol_plan().net.place_count();
    // 2 predicates × (steady + 3 times) + every place × 3 times.
    assert_eq!(cells.len(), 2 * 4 + places * 3, "{cells:?}");
    let close = |page: f64, cli: &Value, what: &str| {
        let c = cli
            .as_f64()
            .unwrap_or_else(|| panic!("{what}: no number in {cli}"));
        assert!((page - c).abs() < 1e-9, "{what}: page {page}, analyze {c}");
    };
    for (kind, name, t, v) in &cells {
        let what = format!("{kind} {name} at {t}");
        if t == "steady" {
            close(*v, &cli["steady_state"]["probability"][name], &what);
            continue;
        }
        let point = cli["transient"]
            .as_array()
            .unwrap()
            .iter()
            .find(|p| p["t"].as_f64().unwrap().to_string() == *t)
            .unwrap_or_else(|| panic!("{what}: no such time in analyze's output"));
        match kind.as_str() {
            "prob" => close(*v, &point["probability"][name], &what),
            _ => close(*v, &point["mean_tokens"][name], &what),
        }
    }
    // Not a vacuous comparison: the predicates' probabilities move with time.
    let wait: Vec<f64> = cells
        .iter()
        .filter(|c| c.1 == WAIT_L1 && c.2 != "steady")
        .map(|c| c.3)
        .collect();
    assert_eq!(wait.len(), 3);
    assert!(wait[0] != wait[2], "{wait:?}");
    b.js(
        "document.querySelector('#analysis .query').scrollIntoView({block: 'start'});",
        vec![],
    )
    .await;
    b.screenshot(&screenshot_path("analysis-questions.png"))
        .await;

    // A bad predicate: the panel says what is wrong, naming the place.
    b.js(
        "document.getElementById('query-prob').value = 'Nowhere > 0';\
         document.getElementById('query').click();",
        vec![],
    )
    .await;
    let err = b
        .wait_js(
            "const e = document.querySelector('#query-result .error'); return e && e.textContent;",
            WAIT,
            "the error",
        )
        .await;
    let err = err.as_str().unwrap();
    assert!(
        err.starts_with("prob `Nowhere > 0`: ") && err.contains("Nowhere"),
        "{err}"
    );
    b.close().await;
    server.abort();
}

#[tokio::test]
async fn questions_need_a_finished_analysis_and_valid_times_and_predicates() {
    let state = plan_state(patrol_plan());
    let ask = |body: Value| {
        let state = state.clone();
        async move { call(&state, "POST", "/api/analysis/query", Some(body)).await }
    };
    let (status, v) = ask(json!({ "prob": [WAIT_L1] })).await;
    assert_eq!(status, StatusCode::CONFLICT, "{v}");
    assert!(v["error"].as_str().unwrap().starts_with("analyse first"));
    let (status, _) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK);
    let (status, v) = ask(json!({ "transient": [-1.0] })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(v["error"], "transient: -1 is not a time ≥ 0");
    let (status, v) = ask(json!({ "prob": ["p4:Wait_L1 >"] })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert!(
        v["error"]
            .as_str()
            .unwrap()
            .starts_with("prob `p4:Wait_L1 >`: "),
        "{v}"
    );
    // At time 0 the state is the initial marking: P(p4:Wait_L1 > 0) = 0, and its tokens 0.
    let (status, v) = ask(json!({ "transient": [0.0], "prob": [WAIT_L1] })).await;
    assert_eq!(status, StatusCode::OK, "{v}");
    assert_eq!(v["transient"][0]["t"], 0.0);
    assert_eq!(v["transient"][0]["probability"][WAIT_L1], 0.0);
    assert_eq!(
        v["transient"][0]["mean_tokens"]["p1:Check_Temperature_L1"],
        1.0
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_dead_marking_in_the_panel_replays_its_firing_sequence_on_the_net() {
    let _one = BROWSER.lock().await;
    // go → left or right; both end dead, right after two firings.
    let mut nb = NetBuilder::new("fork");
    let start = nb.place("start", 1);
    let mid = nb.place("mid", 0);
    let left = nb.place("left", 0);
    let right = nb.place("right", 0);
    let go = nb.exponential("go", 1.0, Servers::Single);
    let l = nb.exponential("to_left", 1.0, Servers::Single);
    let r = nb.exponential("to_right", 2.0, Servers::Single);
    nb.input(start, go, 1);
    nb.output(go, mid, 1);
    nb.input(mid, l, 1);
    nb.output(l, left, 1);
    nb.input(mid, r, 1);
    nb.output(r, right, 1);
    let net = nb.build().unwrap();
    let (addr, server) = start_server(WebState::new(net.clone(), None, 1)).await;
    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    analyse_on_page(&b).await;
    let dead = b
        .js(
            "return [...document.querySelectorAll('#analysis [data-dead]')].map(li => li.textContent);",
            vec![],
        )
        .await;
    let dead: Vec<String> = serde_json::from_value(dead).unwrap();
    assert_eq!(dead.len(), 2, "{dead:?}");
    let i = dead.iter().position(|d| d.starts_with("right=1")).unwrap();
    assert_eq!(dead[i], "right=1 ← go to_right");
    b.js(
        "document.querySelectorAll('#analysis [data-dead]')[arguments[0]].click();",
        vec![json!(i)],
    )
    .await;
    let want = [0u32, 0, 0, 1];
    let deadline = tokio::time::Instant::now() + WAIT;
    loop {
        let m = marking_of(&net, &page_marking(&b).await);
        if m == want {
            break;
        }
        assert!(
            tokio::time::Instant::now() < deadline,
            "the page stays at {m:?}"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    b.screenshot(&screenshot_path("analysis-dead-replayed.png"))
        .await;
    b.close().await;
    server.abort();
}
