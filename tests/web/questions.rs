//! Questions in the analysis panel: `--prob`-style predicates (steady state and at times t)
//! and expected tokens at times t, on the analysed state space (for a plan: the net under its
//! policy) — the numbers of `plan-runner analyze PLAN --json --transient … --prob …` to
//! 1e-9; bad questions refused naming what is wrong; a long question shows its progress and
//! is cancelled (409 `cancelled`), and the next one is answered. And the panel's dead
//! markings replay their firing sequences on the net.
#![cfg(feature = "web")]

use crate::analysis::{analyze_json_with, patrol_plan, patrol_plan_path, plan_state};
use crate::api::call;
use crate::browser::{
    BROWSER, WAIT, analyse_on_page, marking_of, open, page_marking, screenshot_path,
};
use crate::support::browser::Browser;
use crate::support::start_server;

use std::time::{Duration, Instant};

use axum::http::StatusCode;
use gspn::analysis::measures::Solver;
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
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
            "--steady",
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
    // A time no uniformisation could reach (Λ·t iterations) is refused before it starts.
    let (status, v) = ask(json!({ "transient": [1.0, 1e300] })).await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
    let e = v["error"].as_str().unwrap();
    assert!(
        e.starts_with("transient: t = 1e300 needs about ") && e.contains("at most 1e11"),
        "{e}"
    );
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

/// The panel takes `analyze --query` queries too: the same values as the CLI's JSON to 1e-9,
/// a bad one refused with its column, `max`/`min` sent to the CLI.
#[tokio::test]
async fn the_panel_answers_storm_queries_with_the_numbers_of_analyze() {
    let queries = [
        "P=? [F<=5 `p4:Wait_L1`=1]",
        "P=? [F p4:Wait_L1>0]",
        "T=? [F p4:Wait_L1 > 0]",
        "S=? [p4:Wait_L1>0 | p2:Alarm_L1>0]",
    ];
    let mut args = Vec::new();
    for q in queries {
        args.extend(["--query", q]);
    }
    let cli = analyze_json_with(&patrol_plan_path(), &args);
    let state = plan_state(patrol_plan());
    let (status, _) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK);
    let (status, v) = call(
        &state,
        "POST",
        "/api/analysis/query",
        Some(json!({ "query": queries })),
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{v}");
    for (i, q) in queries.iter().enumerate() {
        assert_eq!(v["queries"][i]["query"], *q);
        assert_eq!(cli["queries"][i]["query"], *q);
        let (page, ours) = (
            v["queries"][i]["value"].as_f64().unwrap(),
            cli["queries"][i]["value"].as_f64().unwrap(),
        );
        assert!((page - ours).abs() < 1e-9, "{q}: page {page}, cli {ours}");
    }
    // Reached surely, within 5 with some probability, and a steady fraction in (0, 1).
    assert!(
        (cli["queries"][1]["value"].as_f64().unwrap() - 1.0).abs() < 1e-9,
        "{cli}"
    );
    let within = cli["queries"][0]["value"].as_f64().unwrap();
    assert!(within > 0.0 && within < 1.0, "{cli}");
    let (status, v) = call(
        &state,
        "POST",
        "/api/analysis/query",
        Some(json!({ "query": ["P=? [F<=5 p4:Wait_L9=1]"] })),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST);
    assert_eq!(
        v["error"],
        "query `P=? [F<=5 p4:Wait_L9=1]`: column 11: place `p4:Wait_L9` does not exist"
    );
    let (status, v) = call(
        &state,
        "POST",
        "/api/analysis/query",
        Some(json!({ "query": ["Pmax=? [F p4:Wait_L1>0]"] })),
    )
    .await;
    assert_eq!(status, StatusCode::BAD_REQUEST, "{v}");
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

const KANBAN2: &str = "kanban/kanban_gspn_N2.pnml";

/// A time so large that the transient solver's work (iterations planned × the chain's
/// entries, one multiply-add each) is far beyond a second: asserted from the numbers, not
/// from a clock.
const LONG_T: f64 = 1e6;

/// The viewer of Kanban N = 2 (4,600 tangible markings), and the work of one iteration of
/// the transient solver on it (the generator's entries).
fn kanban2() -> (WebState, usize) {
    let net = read_net(&crate::support::fixture(KANBAN2), &ReadOptions::default())
        .unwrap()
        .net;
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    assert_eq!(ss.tangible_count(), 4600);
    let nnz = Solver::new(&net, &ss).chain().nnz();
    (WebState::new(net, None, 0), nnz)
}

/// Polls `/api/analysis/query/progress` until `ok` holds.
async fn question_progress(state: &WebState, ok: impl Fn(&Value) -> bool) -> Value {
    let deadline = Instant::now() + WAIT;
    loop {
        let (_, p) = call(state, "GET", "/api/analysis/query/progress", None).await;
        if ok(&p) {
            return p;
        }
        assert!(
            Instant::now() < deadline,
            "the question's progress stays {p}"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

fn assert_same_question(page: &Value, cli: &Value, exprs: &[&str]) {
    let (page, cli) = (
        page["transient"].as_array().unwrap(),
        cli["transient"].as_array().unwrap(),
    );
    assert_eq!(page.len(), cli.len());
    for (a, b) in page.iter().zip(cli) {
        assert_eq!(a["t"], b["t"]);
        let tokens = b["mean_tokens"].as_object().unwrap();
        assert!(!tokens.is_empty());
        for (name, v) in tokens {
            let (x, y) = (
                a["mean_tokens"][name].as_f64().unwrap(),
                v.as_f64().unwrap(),
            );
            assert!(
                (x - y).abs() < 1e-9,
                "E[{name}] at {}: page {x}, analyze {y}",
                b["t"]
            );
        }
        for e in exprs {
            let (x, y) = (
                a["probability"][e].as_f64().unwrap(),
                b["probability"][e].as_f64().unwrap(),
            );
            assert!(
                (x - y).abs() < 1e-9,
                "P({e}) at {}: page {x}, analyze {y}",
                b["t"]
            );
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_long_question_shows_its_progress_is_cancelled_and_the_next_is_answered() {
    let (state, nnz) = kanban2();
    let (status, a) = call(&state, "GET", "/api/analysis", None).await;
    assert_eq!(status, StatusCode::OK, "{a}");
    let asking = tokio::spawn({
        let state = state.clone();
        async move {
            call(
                &state,
                "POST",
                "/api/analysis/query",
                Some(json!({ "transient": [LONG_T], "prob": ["P1 > 0"] })),
            )
            .await
        }
    });
    let p = question_progress(&state, |p| {
        p["state"] == "running" && p["iterations"].as_u64().unwrap_or(0) > 0
    })
    .await;
    assert_eq!(p["phase"], format!("transient t={LONG_T}"), "{p}");
    assert_eq!(
        (p["point"].clone(), p["points"].clone()),
        (json!(1), json!(1))
    );
    // Uniformisation: about Λ·t iterations (Λ the largest exit rate), each a pass over the
    // generator's entries: over 10^10 multiply-adds, many seconds on any machine.
    let planned = p["of"].as_u64().unwrap();
    assert!(planned >= 1_000_000, "{p}");
    assert!(
        planned as f64 * nnz as f64 > 1e10,
        "{planned} iterations × {nnz} entries"
    );
    let sent = Instant::now();
    let (status, c) = call(&state, "POST", "/api/analysis/query/cancel", None).await;
    assert_eq!(status, StatusCode::OK, "{c}");
    assert!(
        c["state"] == "cancelling" || c["state"] == "cancelled",
        "{c}"
    );
    let (status, v) = asking.await.unwrap();
    let latency = sent.elapsed();
    println!(
        "question cancelled {:.1} ms after the cancel was sent (test profile), at {} of {planned} \
         iterations",
        latency.as_secs_f64() * 1e3,
        v["progress"]["iterations"]
    );
    assert_eq!(status, StatusCode::CONFLICT, "{v}");
    assert_eq!(v["kind"], "cancelled", "{v}");
    assert_eq!(v["progress"]["state"], "cancelled", "{v}");
    assert!(
        v["progress"]["iterations"].as_u64().unwrap() < planned,
        "{v}"
    );
    let (_, p) = call(&state, "GET", "/api/analysis/query/progress", None).await;
    assert_eq!(p, v["progress"]);

    // The next question is answered, with the numbers of `analyze --transient`.
    let exprs = ["P1 > 0", "Pout4 >= 1 && P2 == 0"];
    let (status, v) = call(
        &state,
        "POST",
        "/api/analysis/query",
        Some(json!({ "transient": [2.0, 0.5], "prob": exprs })),
    )
    .await;
    assert_eq!(status, StatusCode::OK, "{v}");
    let cli = analyze_json_with(
        &crate::support::fixture(KANBAN2),
        &[
            "--transient",
            "2,0.5",
            "--prob",
            exprs[0],
            "--prob",
            exprs[1],
        ],
    );
    assert_same_question(&v, &cli, &exprs);
    let (_, p) = call(&state, "GET", "/api/analysis/query/progress", None).await;
    assert_eq!(p["state"], "done", "{p}");
}

/// Asks `LONG_T` on the page and waits for its progress in the element `progress`.
async fn ask_long(b: &Browser, progress: &str) -> String {
    b.js(
        "document.getElementById('query-times').value = arguments[0];\
         document.getElementById('query-prob').value = 'P1 > 0';\
         document.getElementById('query').click();",
        vec![json!(LONG_T.to_string())],
    )
    .await;
    let shown = b
        .wait_js(
            &format!(
                "const t = document.getElementById('{progress}').textContent;\
                 return /^question running \\(transient t=1000000\\), [1-9][0-9,]* of \
                 [0-9,]+ iterations, /.test(t) && t;"
            ),
            WAIT,
            "the question's progress",
        )
        .await;
    shown.as_str().unwrap().to_string()
}

/// Waits for the panel to say the question was cancelled (a finished question: the result
/// is no longer stale and `ask` works again), as the server says; its text and the
/// server's progress.
async fn cancelled_on_page(b: &Browser, addr: std::net::SocketAddr) -> (String, Value) {
    let shown = b
        .wait_js(
            "const e = document.querySelector('#query-result:not(.stale) [data-cancelled]');\
             return e && !document.getElementById('query').disabled && e.textContent;",
            WAIT,
            "the cancel",
        )
        .await;
    let shown = shown.as_str().unwrap().to_string();
    assert!(
        shown.starts_with("question cancelled (transient t=1000000) after "),
        "{shown}"
    );
    let p = crate::browser::http_get(addr, "/api/analysis/query/progress").await;
    assert_eq!(p["state"], "cancelled");
    (shown, p)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_cancel_button_stops_a_question_on_the_page() {
    let _one = BROWSER.lock().await;
    let (state, _) = kanban2();
    let (addr, server) = start_server(state).await;
    let b = Browser::start(1280, 900).await;
    open(&b, addr).await;
    analyse_on_page(&b).await;
    // The form's own cancel button, beside the progress shown there.
    b.js(
        "document.querySelector('#analysis .query').scrollIntoView({block: 'start'});",
        vec![],
    )
    .await;
    let progress = ask_long(&b, "query-progress").await;
    assert!(progress.ends_with(" s"), "{progress}");
    b.screenshot(&screenshot_path("analysis-question-progress.png"))
        .await;
    b.click("#query-cancel").await;
    let (shown, p) = cancelled_on_page(&b, addr).await;
    assert!(
        shown.ends_with(&format!(" of {} iterations", fmt_thousands(&p["of"]))),
        "{shown} vs {p}"
    );
    crate::browser::assert_cancel_hidden(&b).await;
    b.screenshot(&screenshot_path("analysis-question-cancelled.png"))
        .await;

    // The panel header's cancel button stops a question too.
    ask_long(&b, "analysis-progress").await;
    b.click("#analysis-cancel").await;
    cancelled_on_page(&b, addr).await;
    b.close().await;
    server.abort();
}

/// `1234567` as the page writes it, `1,234,567`.
fn fmt_thousands(v: &Value) -> String {
    let digits = v.as_u64().unwrap().to_string();
    let mut out = String::new();
    for (i, c) in digits.chars().enumerate() {
        if i > 0 && (digits.len() - i).is_multiple_of(3) {
            out.push(',');
        }
        out.push(c);
    }
    out
}
