//! The page among others: a step in one tab shows in another; when the server goes away a
//! banner says so and the last analysis stays on the page; the current view exports as SVG
//! (with its style inside) and PNG.
#![cfg(feature = "web")]

use crate::browser::{BROWSER, PATROL, WAIT, analyse_on_page, http_get, open, screenshot_path};
use crate::support as common;
use crate::support::browser::Browser;

use std::net::SocketAddr;

use gspn::io::{ReadOptions, read_net};
use gspn::web::{WebState, serve};
use serde_json::{Value, json};

/// Serves `state` on its own runtime in a thread, so that stopping it (sending on the
/// returned channel) closes every connection too, as a server that went away does.
fn server_that_can_go_away(state: WebState) -> (SocketAddr, std::sync::mpsc::Sender<()>) {
    let (addr_tx, addr_rx) = std::sync::mpsc::channel();
    let (stop_tx, stop_rx) = std::sync::mpsc::channel::<()>();
    std::thread::spawn(move || {
        let rt = tokio::runtime::Builder::new_multi_thread()
            .worker_threads(1)
            .enable_all()
            .build()
            .unwrap();
        rt.block_on(async move {
            let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
            addr_tx.send(listener.local_addr().unwrap()).unwrap();
            let stop = tokio::task::spawn_blocking(move || stop_rx.recv());
            tokio::select! {
                _ = serve(listener, state) => {}
                _ = stop => {}
            }
        });
        // Dropping the runtime drops every connection's task: the sockets close.
        drop(rt);
    });
    (addr_rx.recv().unwrap(), stop_tx)
}

/// Standard base64 (with `=` padding) to bytes.
fn decode_base64(text: &str) -> Vec<u8> {
    const ALPHABET: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = Vec::with_capacity(text.len() * 3 / 4);
    let (mut acc, mut bits) = (0u32, 0);
    for c in text.bytes().filter(|&c| c != b'=') {
        let v = ALPHABET.iter().position(|&a| a == c).expect("base64") as u32;
        acc = (acc << 6) | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
        }
    }
    out
}

fn patrol_state() -> WebState {
    let net = read_net(&common::fixture(PATROL), &ReadOptions::default())
        .unwrap()
        .net;
    WebState::new(net, None, 3)
}

async fn firings_shown(b: &Browser) -> String {
    b.text("#clock").await
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_step_in_one_tab_shows_in_the_other() {
    let _one = BROWSER.lock().await;
    let (addr, stop) = server_that_can_go_away(patrol_state());
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    let first = b.client.window().await.unwrap();
    let second = b.client.new_window(true).await.unwrap().handle;
    b.client.switch_to_window(second).await.unwrap();
    open(&b, addr).await;
    for n in 1..=3 {
        b.click("#step").await;
        let script = format!(
            "return document.getElementById('clock').textContent.includes(', {n} firings');"
        );
        b.wait_js(&script, WAIT, &format!("{n} firings in the second tab"))
            .await;
    }
    b.client.switch_to_window(first).await.unwrap();
    b.wait_js(
        "return document.getElementById('clock').textContent.includes(', 3 firings');",
        WAIT,
        "the first tab to show the second tab's steps",
    )
    .await;
    let s = http_get(addr, "/api/sim/state").await;
    let shown = b
        .js(
            "return [...document.querySelectorAll('[data-place]')].map(e => Number(e.dataset.tokens));",
            vec![],
        )
        .await;
    assert_eq!(shown, s["tokens"]);
    let trace = b
        .js(
            "return [...document.querySelectorAll('#trace li')].map(li => li.textContent);",
            vec![],
        )
        .await;
    assert_eq!(trace.as_array().unwrap().len(), 3, "{trace}");
    assert_eq!(s["firings"], 3);
    b.screenshot(&screenshot_path("cross-tab.png")).await;

    // The server goes away: a banner, and the last analysis stays.
    analyse_on_page(&b).await;
    let before = b.text("#analysis").await;
    let hidden = b
        .js(
            "return document.getElementById('offline').classList.contains('hidden');",
            vec![],
        )
        .await;
    assert_eq!(hidden, json!(true));
    stop.send(()).unwrap();
    b.wait_js(
        "return !document.getElementById('offline').classList.contains('hidden');",
        WAIT,
        "the banner",
    )
    .await;
    // A click that needs the server keeps what is shown.
    b.click("#analyze").await;
    b.click("#step").await;
    tokio::time::sleep(std::time::Duration::from_millis(500)).await;
    assert_eq!(b.text("#analysis").await, before);
    assert!(firings_shown(&b).await.contains(", 3 firings"));
    let banner = b.text("#offline").await;
    assert!(
        banner.starts_with("The server cannot be reached"),
        "{banner}"
    );
    b.screenshot(&screenshot_path("server-unreachable.png"))
        .await;
    b.close().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_view_exports_as_svg_and_png() {
    let _one = BROWSER.lock().await;
    let (addr, _stop) = server_that_can_go_away(patrol_state());
    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    let svg = b.js("return window.gspnExport.svg();", vec![]).await;
    let svg = svg.as_str().unwrap();
    assert!(svg.starts_with("<svg"), "{}", &svg[..80]);
    assert_eq!(svg.matches("data-place=").count(), 16);
    assert_eq!(svg.matches("data-transition=").count(), 24);
    assert!(
        svg.contains(":root:root:root{--bg:"),
        "the colours are inside"
    );
    assert!(svg.contains(".arc.inhibitor"), "the style is inside");
    let size = b
        .js(
            "const r = document.getElementById('net').getBoundingClientRect();\
             return [Math.round(r.width), Math.round(r.height), window.devicePixelRatio || 1];",
            vec![],
        )
        .await;
    assert!(
        svg.contains(&format!("width=\"{}\"", size[0])),
        "{}",
        &svg[..200]
    );
    let png: Value = b.js("return window.gspnExport.png();", vec![]).await;
    let png = png.as_str().unwrap();
    let data = png
        .strip_prefix("data:image/png;base64,")
        .expect("a PNG data URL");
    let bytes = decode_base64(data);
    assert_eq!(&bytes[..8], b"\x89PNG\r\n\x1a\n");
    let width = u32::from_be_bytes(bytes[16..20].try_into().unwrap());
    let k = size[2].as_f64().unwrap();
    assert_eq!(
        f64::from(width),
        (size[0].as_f64().unwrap() * k).floor(),
        "PNG width"
    );
    // Not blank: the PNG of a drawn net is far larger than an empty one.
    assert!(bytes.len() > 10_000, "{} bytes", bytes.len());
    std::fs::write(screenshot_path("export.png"), &bytes).unwrap();
    b.close().await;
}
