//! The live page's conformance table (`run --monitor` in the viewer): a run of cyc3 watched by
//! a monitor whose model says T3 fires at rate 0.5 (it fires at 2) shows, per transition and
//! place, what the run shows beside what the model predicts — the numbers the server sends —
//! and highlights T3 (drifting), not T1.
#![cfg(feature = "web")]

use std::sync::Arc;

use gspn::conform::{Monitor, MonitorOptions, SharedMonitor, steady_predictions};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::Runtime;
use gspn::web::{LiveRun, WebState};
use serde_json::Value;

use crate::browser::{BROWSER, WAIT, http_get, open, screenshot_path};
use crate::support::browser::Browser;
use crate::support::start_server;

/// cyc3 (two tokens, P1 -T1-> P2 -t2-> P3 -T3-> P1) with T3 at `t3`.
fn cyc3_with(t3: f64) -> Net {
    let mut b = NetBuilder::new("cyc3");
    let (p1, p2, p3) = (b.place("P1", 2), b.place("P2", 0), b.place("P3", 0));
    let t1 = b.exponential("T1", 1.0, Servers::Single);
    let t2 = b.immediate("t2", 1.0, 1);
    let t3 = b.exponential("T3", t3, Servers::Single);
    b.moves(p1, t1, p2);
    b.moves(p2, t2, p3);
    b.moves(p3, t3, p1);
    b.build().unwrap()
}

fn row<'a>(rows: &'a Value, kind: &str, item: &str) -> &'a Value {
    rows.as_array()
        .unwrap()
        .iter()
        .find(|r| r["kind"] == kind && r["item"] == item)
        .unwrap_or_else(|| panic!("no {kind} row for {item}: {rows}"))
}

/// The text of column `col` of the page's row for `item`.
async fn cell(b: &Browser, item: &str, col: &str) -> String {
    let v = b
        .js(
            "return document.querySelector(`#conform tr[data-item=\"${arguments[0]}\"] \
             td[data-col=\"${arguments[1]}\"]`).textContent;",
            vec![item.into(), col.into()],
        )
        .await;
    v.as_str().unwrap().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_live_page_shows_observed_beside_predicted_and_highlights_drifting_items() {
    let _one = BROWSER.lock().await;
    let model = cyc3_with(0.5);
    let steady = steady_predictions(&model, None, 1000).unwrap();
    let opts = MonitorOptions {
        min_firings: 20,
        batch_firings: 20,
        batches: 10,
        ..MonitorOptions::default()
    };
    let monitor = SharedMonitor::new(
        Monitor::new(&model, model.initial_marking().into_vec(), opts)
            .with_mean_tokens(steady.mean_tokens.unwrap()),
    );
    // 300 time units at 100 times real time: 3 s.
    let mut handle = Runtime::builder(cyc3_with(2.0))
        .seed(7)
        .time_scale(0.01)
        .until(300.0)
        .watch(monitor.clone())
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events).with_monitor(monitor);
    let (addr, server) = start_server(WebState::for_live(live)).await;
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    b.wait_js(
        "return document.getElementById('clock').textContent.includes('stopped') \
         && !!document.querySelector('#conform tr[data-item=\"T3\"]');",
        WAIT,
        "the run to stop with T3 in the table",
    )
    .await;
    handle.wait().await;
    // Past the end of the run the server's rows no longer change: the page shows them.
    let rows = http_get(addr, "/api/live/state").await["conform"].clone();
    b.wait_js(
        "return document.getElementById('conform-count').textContent.length > 0;",
        WAIT,
        "the table's count",
    )
    .await;

    let t3 = row(&rows, "rate", "T3");
    let observed = t3["observed"].as_f64().unwrap();
    assert!((1.6..2.5).contains(&observed), "{t3}");
    assert_eq!(t3["predicted"], 0.5);
    assert_eq!(t3["n"], 200);
    assert_eq!(t3["drifting"], true, "{t3}");
    let t1 = row(&rows, "rate", "T1");
    assert_eq!(t1["predicted"], 1.0);
    assert_eq!(t1["drifting"], false, "{t1}");
    // The model keeps tokens in P3 (T3 slow); the run does not.
    let p3 = row(&rows, "mean_tokens", "P3");
    assert!(p3["predicted"].as_f64().unwrap() > 1.0, "{p3}");
    assert!(p3["interval"][1].as_f64().unwrap() < 1.0, "{p3}");
    assert_eq!(p3["n"], 10);
    // No row for the immediate t2.
    assert!(rows.as_array().unwrap().iter().all(|r| r["item"] != "t2"));

    // The page: the server's numbers, drifting rows highlighted.
    assert_eq!(cell(&b, "T3", "observed").await, format!("{observed:.4}"));
    assert_eq!(cell(&b, "T3", "predicted").await, "0.5000");
    let [lo, hi] = [0, 1].map(|i| t3["interval"][i].as_f64().unwrap());
    assert_eq!(
        cell(&b, "T3", "interval").await,
        format!("[{lo:.4}, {hi:.4}]")
    );
    assert_eq!(cell(&b, "T3", "n").await, "200");
    assert_eq!(cell(&b, "T1", "predicted").await, "1.0000");
    let drifting = b
        .js(
            "return [...document.querySelectorAll('#conform tr.drifting')]\
               .map(r => r.dataset.kind + ' ' + r.dataset.item);",
            vec![],
        )
        .await;
    let drifting: Vec<String> = serde_json::from_value(drifting).unwrap();
    let expected: Vec<String> = rows
        .as_array()
        .unwrap()
        .iter()
        .filter(|r| r["drifting"] == true)
        .map(|r| {
            format!(
                "{} {}",
                r["kind"].as_str().unwrap(),
                r["item"].as_str().unwrap()
            )
        })
        .collect();
    assert_eq!(drifting, expected);
    assert!(drifting.contains(&"rate T3".to_string()));
    assert!(!drifting.contains(&"rate T1".to_string()));
    let background = b
        .js(
            "return getComputedStyle(document.querySelector('#conform tr[data-item=\"T3\"]'))\
               .backgroundColor;",
            vec![],
        )
        .await;
    assert_eq!(background, "rgb(255, 221, 221)");
    b.screenshot(&screenshot_path("conform.png")).await;
    b.close().await;
    server.abort();
}

/// A journal played back: the table follows the slider — the monitor's rows after the last
/// firing at the slider's time (transitions' rates only: a journal does not say which policy
/// ran it), the same as a monitor fed the journal's firings; none before enough firings.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_shows_the_monitors_table_at_the_sliders_time() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.jsonl");
    Runtime::builder(cyc3_with(2.0))
        .seed(9)
        .time_scale(0.001)
        .until(400.0)
        .journal(&path)
        .spawn()
        .unwrap()
        .wait()
        .await;
    let text = std::fs::read_to_string(&path).unwrap();
    let frames = gspn::runtime::journal::read_journal(&text, &cyc3_with(2.0)).unwrap();
    // The same firings through a monitor of the model (T3 at 0.5).
    let model = cyc3_with(0.5);
    let mut monitor = Monitor::new(&model, frames[0].tokens.clone(), Default::default());
    for f in &frames[1..] {
        let t = model
            .transition_by_name(f.transition.as_deref().unwrap())
            .unwrap();
        monitor.fired(f.time, t, &f.tokens);
    }
    let expected = monitor.statistics();
    assert_eq!(expected.len(), 2, "{expected:?}");
    let t3 = expected[1].clone();
    assert!(t3.drifting && t3.figures.n == 200, "{t3:?}");

    let (addr, server) = start_server(WebState::for_replay(model, frames.clone())).await;
    let snapshots = http_get(addr, "/api/replay").await["conform"].clone();
    let last = snapshots.as_array().unwrap().last().unwrap();
    assert_eq!(last["time"], frames.last().unwrap().time);
    let served = row(&last["rows"], "rate", "T3");
    assert_eq!(served["observed"].as_f64().unwrap(), t3.figures.observed);
    assert_eq!(served["drifting"], true);
    assert_eq!(row(&last["rows"], "rate", "T1")["drifting"], false);

    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    let rows_shown = "return document.querySelectorAll('#conform tbody tr').length;";
    // At time 0 nothing has fired: an empty table.
    assert_eq!(b.js(rows_shown, vec![]).await, 0);
    b.js(
        "const s = document.getElementById('slider'); s.value = s.max;\
         s.dispatchEvent(new Event('input'));",
        vec![],
    )
    .await;
    assert_eq!(b.js(rows_shown, vec![]).await, 2);
    assert_eq!(
        cell(&b, "T3", "observed").await,
        format!("{:.4}", t3.figures.observed)
    );
    assert_eq!(cell(&b, "T3", "predicted").await, "0.5000");
    let classes = b
        .js(
            "return [...document.querySelectorAll('#conform tbody tr')]\
               .map(r => r.dataset.item + ':' + r.classList.contains('drifting'));",
            vec![],
        )
        .await;
    assert_eq!(classes, serde_json::json!(["T1:false", "T3:true"]));
    b.screenshot(&screenshot_path("conform-replay.png")).await;
    b.close().await;
    server.abort();
}
