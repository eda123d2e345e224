//! Finding one's way in a net: search by name zooms to the node, the zoom stays within its
//! limits, names show only when they can be read, and a click in the minimap moves the view
//! there.
#![cfg(feature = "web")]

use crate::browser::{BROWSER, PATROL, WAIT, open, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;
use crate::support::start_server;

use gspn::io::{ReadOptions, read_net};
use gspn::web::WebState;
use serde_json::{Value, json};

async fn view(b: &Browser) -> Value {
    b.js("return window.gspnView();", vec![]).await
}

async fn search(b: &Browser, text: &str) {
    b.js(
        "const s = document.getElementById('search'); s.value = arguments[0];\
         s.dispatchEvent(new KeyboardEvent('keydown', {key: 'Enter', bubbles: true}));",
        vec![json!(text)],
    )
    .await;
}

/// Wheel events over the middle of the net pane.
async fn wheel(b: &Browser, delta: f64, times: u32) {
    b.js(
        "const c = document.getElementById('canvas'); const r = c.getBoundingClientRect();\
         for (let i = 0; i < arguments[1]; i++) c.dispatchEvent(new WheelEvent('wheel',\
           {deltaY: arguments[0], clientX: r.x + r.width / 2, clientY: r.y + r.height / 2, bubbles: true, cancelable: true}));",
        vec![json!(delta), json!(times)],
    )
    .await;
}

async fn label_shown(b: &Browser, name: &str) -> bool {
    let v = b
        .js(
            "const g = document.querySelector('[data-transition=\"' + arguments[0] + '\"]');\
             return getComputedStyle(g.querySelector('text.label')).display !== 'none';",
            vec![json!(name)],
        )
        .await;
    v.as_bool().unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn search_zoom_limits_labels_and_the_minimap() {
    let _one = BROWSER.lock().await;
    let net = read_net(&common::fixture(PATROL), &ReadOptions::default())
        .unwrap()
        .net;
    let (addr, server) = start_server(WebState::new(net, None, 0)).await;
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;

    // A part of a name finds the node; the view centres it at a zoom where it reads.
    search(&b, "t13").await;
    let name = "t13:Temperature_High_L3";
    let found = b
        .js(
            "return [...document.querySelectorAll('[data-found=\"true\"]')].map(g => g.dataset.transition);",
            vec![],
        )
        .await;
    assert_eq!(found, json!([name]));
    let offset = b
        .js(
            "const g = document.querySelector('[data-transition=\"' + arguments[0] + '\"] rect').getBoundingClientRect();\
             const c = document.getElementById('canvas').getBoundingClientRect();\
             return [g.x + g.width / 2 - (c.x + c.width / 2), g.y + g.height / 2 - (c.y + c.height / 2)];",
            vec![json!(name)],
        )
        .await;
    for d in offset.as_array().unwrap() {
        assert!(d.as_f64().unwrap().abs() < 2.0, "{offset}");
    }
    let v = view(&b).await;
    assert!(v["k"].as_f64().unwrap() >= 1.5, "{v}");
    assert!(label_shown(&b, name).await);
    b.screenshot(&screenshot_path("search.png")).await;
    search(&b, "zzz").await;
    assert_eq!(
        b.text("#status").await,
        "no place or transition named “zzz”"
    );

    // The zoom stops at its limits; names hide when they would be too small to read.
    wheel(&b, -2000.0, 40).await;
    let v = view(&b).await;
    assert_eq!(v["k"], v["max"], "{v}");
    wheel(&b, 2000.0, 60).await;
    let v = view(&b).await;
    assert_eq!(v["k"], v["min"], "{v}");
    let k = v["k"].as_f64().unwrap();
    assert!(
        (k - v["fitK"].as_f64().unwrap() * 0.25).abs() < 1e-12,
        "{v}"
    );
    assert_eq!(label_shown(&b, name).await, 11.0 * k >= 4.5);
    assert!(!label_shown(&b, name).await, "names at the least zoom");
    b.screenshot(&screenshot_path("zoomed-out.png")).await;

    // The minimap: a click in its middle centres the view on the middle of the net.
    b.click("#fit").await;
    wheel(&b, -1500.0, 1).await;
    let centre = b
        .js(
            "const c = document.getElementById('minimap'); const r = c.getBoundingClientRect();\
             const o = {clientX: r.x + r.width / 2, clientY: r.y + r.height / 2, bubbles: true};\
             c.dispatchEvent(new MouseEvent('mousedown', o));\
             window.dispatchEvent(new MouseEvent('mouseup', o));\
             const v = window.gspnView(); const box = document.getElementById('canvas');\
             const all = net.places.concat(net.transitions);\
             const xs = all.map(n => n.x), ys = all.map(n => n.y);\
             const mid = [(Math.min(...xs) + Math.max(...xs)) / 2, (Math.min(...ys) + Math.max(...ys)) / 2];\
             const seen = [(box.clientWidth / 2 - v.x) / v.k, (box.clientHeight / 2 - v.y) / v.k];\
             const unit = (Math.max(...xs) - Math.min(...xs) + 80) / 180;\
             return [mid, seen, unit];",
            vec![],
        )
        .await;
    let unit = centre[2].as_f64().unwrap();
    for axis in 0..2 {
        let (mid, seen) = (
            centre[0][axis].as_f64().unwrap(),
            centre[1][axis].as_f64().unwrap(),
        );
        assert!((mid - seen).abs() <= 2.0 * unit, "{centre}");
    }
    b.wait_js(
        "return !document.getElementById('minimap-box').classList.contains('hidden');",
        WAIT,
        "the minimap",
    )
    .await;
    b.screenshot(&screenshot_path("minimap.png")).await;
    b.close().await;
    server.abort();
}
