//! Throughput over time: a replay's firings per transition per window of model time, as
//! curves with a readout and CSV, beside the exact steady-state throughput once the
//! analysis panel has it. The CSV's values are the journal's firings counted per window
//! here, divided by the window.
#![cfg(feature = "web")]

use crate::browser::{BROWSER, WAIT, analyse_on_page, open, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;
use crate::support::start_server;

use std::collections::BTreeMap;

use gspn::net::Servers;
use gspn::runtime::journal::Frame;
use gspn::web::WebState;
use serde_json::json;

/// A two-place ring's run: firing j (t0, t1, t0, …) at 0.05 j + 0.001 (j mod 7) s.
fn frames(firings: usize) -> Vec<Frame> {
    let mut out = vec![Frame {
        time: 0.0,
        transition: None,
        tokens: vec![1, 0],
    }];
    for j in 0..firings {
        out.push(Frame {
            time: 0.05 * j as f64 + 0.001 * (j % 7) as f64,
            transition: Some(format!("t{}", j % 2)),
            tokens: if j % 2 == 0 { vec![0, 1] } else { vec![1, 0] },
        });
    }
    out
}

/// A CSV row: its time and its cells (`None`: empty).
type Row = (f64, Vec<Option<f64>>);

/// The CSV's header and rows.
fn rows(csv: &str) -> (Vec<String>, Vec<Row>) {
    let mut lines = csv.lines();
    let head: Vec<String> = lines
        .next()
        .unwrap()
        .split(',')
        .map(str::to_string)
        .collect();
    let body = lines
        .map(|l| {
            let mut cells = l.split(',');
            let t = cells.next().unwrap().parse().unwrap();
            (t, cells.map(|c| c.parse().ok()).collect())
        })
        .collect();
    (head, body)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_draws_firings_per_window_beside_the_exact_throughput() {
    let _one = BROWSER.lock().await;
    let net = common::ring(2, |i| u32::from(i == 0), |_| 1.0, Servers::Single).0;
    let run = frames(600);
    let (addr, server) = start_server(WebState::for_replay(net, run.clone())).await;
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    b.wait_js(
        "return !document.getElementById('tput-panel').classList.contains('hidden');",
        WAIT,
        "the throughput panel",
    )
    .await;
    // The run ends at 29.95 s: 128 windows of 2⁻² s hold it, 128 of 2⁻³ do not.
    let width = b
        .js("return window.gspnThroughput.width();", vec![])
        .await
        .as_f64()
        .unwrap();
    assert_eq!(width, 0.25);
    b.js("window.gspnThroughput.pick(['t0', 't1']);", vec![])
        .await;
    let csv = b.js("return window.gspnThroughput.csv();", vec![]).await;
    let (head, body) = rows(csv.as_str().unwrap());
    assert_eq!(head, ["time", "t0", "t1"]);
    // Counted here: firings of each transition per window.
    let mut counts: BTreeMap<(String, usize), u32> = BTreeMap::new();
    for f in &run[1..] {
        let k = (f.time / width).floor() as usize;
        *counts
            .entry((f.transition.clone().unwrap(), k))
            .or_default() += 1;
    }
    assert_eq!(body.len(), 120, "windows up to the last firing (29.95 s)");
    for (k, (t, cells)) in body.iter().enumerate() {
        assert_eq!(*t, k as f64 * width);
        for (c, name) in ["t0", "t1"].iter().enumerate() {
            let want = f64::from(counts.get(&(name.to_string(), k)).copied().unwrap_or(0)) / width;
            let got = cells[c].unwrap();
            assert!(
                (got - want).abs() < 1e-9,
                "{name} window {k}: {got} vs {want}"
            );
        }
    }
    // Every firing in some window: 300 of each.
    for c in 0..2 {
        let total: f64 = body
            .iter()
            .map(|(_, cells)| cells[c].unwrap() * width)
            .sum();
        assert!((total - 300.0).abs() < 1e-9, "{total}");
    }
    // The readout under the pointer: every curve's value at its time.
    let readout = b
        .js(
            "const s = document.getElementById('tput'); const r = s.getBoundingClientRect();\
             s.dispatchEvent(new MouseEvent('mousemove', {clientX: r.left + r.width / 2, clientY: r.top + 20}));\
             return document.getElementById('tput-readout').textContent;",
            vec![],
        )
        .await;
    let readout = readout.as_str().unwrap();
    assert!(
        readout.starts_with("t = ") && readout.contains("t0 ") && readout.contains("t1 "),
        "{readout}"
    );

    // Analysed: the exact throughput (1/2 per second each: the ring's two rates are 1) beside.
    analyse_on_page(&b).await;
    let csv = b.js("return window.gspnThroughput.csv();", vec![]).await;
    let (head, body) = rows(csv.as_str().unwrap());
    assert_eq!(head, ["time", "t0", "t1", "t0 (exact)", "t1 (exact)"]);
    let exact: Vec<f64> = body.iter().filter_map(|(_, c)| c[2]).collect();
    assert_eq!(exact.len(), 2, "a line from 0 to the end");
    assert!(exact.iter().all(|v| (v - 0.5).abs() < 1e-9), "{exact:?}");
    let drawn = b
        .js(
            "return [...document.querySelectorAll('#tput polyline')].map(p => p.dataset.series);",
            vec![],
        )
        .await;
    assert_eq!(drawn, json!(["t0", "t1", "t0 (exact)", "t1 (exact)"]));
    b.screenshot(&screenshot_path("throughput.png")).await;
    b.close().await;
    server.abort();
}
