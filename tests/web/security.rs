//! No stranger controls a run (issue 14, defect 7): a page on another site could stop a live
//! run or drive the token game through the visitor's browser (a cross-origin form post to
//! `/api/live/stop` answered `{"stopping":true}`), a DNS-rebinding page could read the API,
//! and the live websocket accepted any `Origin`. Now, over a real socket: a foreign `Host`
//! is 421, a foreign `Origin` 403, a non-JSON `POST` 415, every response says `nosniff` and
//! `no-referrer`, and a non-loopback address needs `--allow-remote`.
#![cfg(feature = "web")]

use crate::support as common;

use std::net::SocketAddr;
use std::sync::Arc;
use std::time::Duration;

use assert_cmd::Command;
use gspn::net::Servers;
use gspn::runtime::Runtime;
use gspn::web::{LiveRun, WebState, serve};
use serde_json::Value;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite;
use tokio_tungstenite::tungstenite::client::IntoClientRequest;

/// One HTTP/1.1 request over TCP; the status, the lower-cased head, the body as JSON.
pub(crate) async fn request(
    addr: SocketAddr,
    method: &str,
    path: &str,
    headers: &[(&str, &str)],
    body: &str,
) -> (u16, String, Value) {
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let mut req = format!("{method} {path} HTTP/1.1\r\nConnection: close\r\n");
    if !headers.iter().any(|(k, _)| k.eq_ignore_ascii_case("host")) {
        req.push_str(&format!("Host: {addr}\r\n"));
    }
    for (k, v) in headers {
        req.push_str(&format!("{k}: {v}\r\n"));
    }
    req.push_str(&format!("Content-Length: {}\r\n\r\n{body}", body.len()));
    stream.write_all(req.as_bytes()).await.unwrap();
    let mut res = String::new();
    stream.read_to_string(&mut res).await.unwrap();
    let (head, body) = res.split_once("\r\n\r\n").unwrap();
    let status = head[9..12].parse().unwrap();
    (
        status,
        head.to_ascii_lowercase(),
        serde_json::from_str(body).unwrap_or(Value::String(body.into())),
    )
}

pub(crate) const JSON: (&str, &str) = ("Content-Type", "application/json");
const FORM: (&str, &str) = ("Content-Type", "application/x-www-form-urlencoded");

/// A token-game viewer on a free loopback port.
async fn token_game() -> (SocketAddr, tokio::task::JoinHandle<std::io::Result<()>>) {
    let state = WebState::new(common::cyc3(Servers::Single), None, 3);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    (addr, tokio::spawn(serve(listener, state)))
}

async fn firings(addr: SocketAddr) -> u64 {
    let (status, _, v) = request(addr, "GET", "/api/sim/state", &[], "").await;
    assert_eq!(status, 200, "{v}");
    v["firings"].as_u64().unwrap()
}

#[tokio::test]
async fn a_cross_origin_form_post_cannot_stop_a_live_run() {
    // A run in real time that would go on for ever.
    let mut handle = Runtime::builder(common::cyc3(Servers::Single))
        .seed(2)
        .time_scale(1.0)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events);
    let (addr, server) = common::start_server(WebState::for_live(live)).await;

    // What the attacking page's `<form method=post action=http://127.0.0.1:PORT/...>` sends.
    let evil = ("Origin", "http://evil.example");
    let (status, head, v) = request(addr, "POST", "/api/live/stop", &[evil, FORM], "a=1").await;
    assert_eq!(status, 403, "{v}");
    assert!(v["error"].as_str().unwrap().contains("evil.example"), "{v}");
    assert!(head.contains("x-content-type-options: nosniff"), "{head}");
    // The same form from a page that sends no Origin, and a `no-cors` text/plain fetch.
    let (status, _, _) = request(addr, "POST", "/api/live/stop", &[FORM], "a=1").await;
    assert_eq!(status, 415);
    let text = ("Content-Type", "text/plain");
    let (status, _, _) = request(addr, "POST", "/api/live/stop", &[text], "{}").await;
    assert_eq!(status, 415);
    // A rebinding page: the right port, the attacker's name.
    let rebound = ("Host", "rebind.example:80");
    let (status, _, _) = request(addr, "POST", "/api/live/stop", &[rebound, JSON], "{}").await;
    assert_eq!(status, 421);
    // None of them stopped it.
    assert!(
        tokio::time::timeout(Duration::from_millis(300), handle.wait())
            .await
            .is_err(),
        "the run stopped"
    );
    let (_, _, snap) = request(addr, "GET", "/api/live/state", &[], "").await;
    assert!(snap["stopped"].is_null(), "{snap}");

    // The viewer's own page (same origin, JSON) still stops it.
    let own = format!("http://{addr}");
    let (status, _, v) = request(
        addr,
        "POST",
        "/api/live/stop",
        &[("Origin", own.as_str()), JSON],
        "{}",
    )
    .await;
    assert_eq!(status, 200, "{v}");
    assert_eq!(v["stopping"], true);
    let summary = tokio::time::timeout(Duration::from_secs(10), handle.wait())
        .await
        .expect("the run stops");
    assert_eq!(summary.stopped, gspn::runtime::StopReason::Requested);
    server.abort();
}

#[tokio::test]
async fn every_state_changing_route_refuses_strangers_and_serves_its_page() {
    let (addr, server) = token_game().await;
    let own = format!("http://{addr}");
    let routes = [
        ("/api/sim/reset", r#"{"seed": 7}"#),
        ("/api/sim/step", r#"{"n": 3}"#),
        ("/api/sim/fire", r#"{"transition": "T1"}"#),
        ("/api/analysis/start", "{}"),
        ("/api/analysis/cancel", "{}"),
        ("/api/analysis/query", r#"{"transient": [1]}"#),
        ("/api/analysis/query/cancel", "{}"),
        ("/api/layout", r#"{"places": [], "transitions": []}"#),
    ];
    for (route, body) in routes {
        let cases: [(&[(&str, &str)], u16); 5] = [
            (&[("Origin", "http://evil.example"), JSON], 403),
            (&[("Origin", "null"), JSON], 403),
            (&[("Origin", "http://evil.example"), FORM], 403),
            (&[FORM], 415),
            (&[("Host", "evil.example"), JSON], 421),
        ];
        for (headers, want) in cases {
            let (status, head, v) = request(addr, "POST", route, headers, body).await;
            assert_eq!(status, want, "{route} {headers:?}: {v}");
            assert!(head.contains("referrer-policy: no-referrer"), "{head}");
            assert!(head.contains("content-security-policy:"), "{head}");
        }
    }
    // Nothing moved the token game, and the analysis was never started.
    assert_eq!(firings(addr).await, 0);
    let (_, _, p) = request(addr, "GET", "/api/analysis/progress", &[], "").await;
    assert_eq!(p["state"], "idle", "{p}");
    let (_, _, p) = request(addr, "GET", "/api/analysis/query/progress", &[], "").await;
    assert_eq!(p["state"], "idle", "{p}");

    // The page itself: same origin, JSON.
    let same = [("Origin", own.as_str()), JSON];
    let (status, _, v) = request(addr, "POST", "/api/sim/step", &same, r#"{"n": 3}"#).await;
    assert_eq!(status, 200, "{v}");
    assert_eq!(v["fired"], 3);
    // `localhost` names the same server, with a charset parameter on the type.
    let port = addr.port();
    let host = format!("localhost:{port}");
    let origin = format!("http://localhost:{port}");
    let (status, _, v) = request(
        addr,
        "POST",
        "/api/sim/reset",
        &[
            ("Host", host.as_str()),
            ("Origin", origin.as_str()),
            ("Content-Type", "application/json; charset=utf-8"),
        ],
        r#"{"seed": 9}"#,
    )
    .await;
    assert_eq!(status, 200, "{v}");
    assert_eq!(
        (v["seed"].as_u64(), v["firings"].as_u64()),
        (Some(9), Some(0))
    );
    server.abort();
}

#[tokio::test]
async fn a_rebinding_page_cannot_read_the_api_and_every_response_is_marked() {
    let (addr, server) = token_game().await;
    let (status, _, v) = request(addr, "GET", "/api/net", &[("Host", "rebind.example")], "").await;
    assert_eq!(status, 421, "{v}");
    let wrong_port = format!("127.0.0.1:{}", addr.port().wrapping_add(1));
    let (status, _, _) = request(
        addr,
        "GET",
        "/api/net",
        &[("Host", wrong_port.as_str())],
        "",
    )
    .await;
    assert_eq!(status, 421);
    for path in ["/", "/app.js", "/api/net", "/api/nothing"] {
        let (status, head, _) = request(addr, "GET", path, &[], "").await;
        assert!(matches!(status, 200 | 404), "{path}: {status}");
        for h in [
            "x-content-type-options: nosniff",
            "referrer-policy: no-referrer",
            "content-security-policy: default-src 'self'",
        ] {
            assert!(head.contains(h), "{path}: {h} missing from {head}");
        }
    }
    server.abort();
}

#[tokio::test]
async fn the_live_websocket_refuses_a_foreign_origin() {
    let mut handle = Runtime::builder(common::cyc3(Servers::Single))
        .seed(4)
        .max_firings(5)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events);
    handle.wait().await;
    let (addr, server) = common::start_server(WebState::for_live(live)).await;

    let url = format!("ws://{addr}/api/live/ws");
    let with_origin = |origin: &str| {
        let mut req = url.as_str().into_client_request().unwrap();
        req.headers_mut().insert("Origin", origin.parse().unwrap());
        req
    };
    match tokio_tungstenite::connect_async(with_origin("http://evil.example")).await {
        Err(tungstenite::Error::Http(res)) => assert_eq!(res.status().as_u16(), 403),
        Err(e) => panic!("expected an HTTP refusal, got {e}"),
        Ok(_) => panic!("a foreign origin opened the live websocket"),
    }
    // The viewer's own page opens it.
    let (mut ws, res) = tokio_tungstenite::connect_async(with_origin(&format!("http://{addr}")))
        .await
        .unwrap();
    assert_eq!(res.status().as_u16(), 101);
    use futures_util::StreamExt;
    let first = match ws.next().await.unwrap().unwrap() {
        tungstenite::Message::Text(t) => serde_json::from_str::<Value>(t.as_str()).unwrap(),
        other => panic!("expected text, got {other:?}"),
    };
    assert_eq!(first["type"], "net");
    server.abort();
}

/// The net file the CLI tests serve.
fn cyc3_file() -> std::path::PathBuf {
    common::fixture("greatspn/cyc3/cyc3.PNPRO")
}

#[test]
fn a_non_loopback_address_needs_allow_remote() {
    let net = cyc3_file();
    for args in [
        vec!["serve", net.to_str().unwrap(), "--addr", "0.0.0.0:0"],
        vec![
            "run",
            net.to_str().unwrap(),
            "--max-firings",
            "1",
            "--web",
            "0.0.0.0:0",
        ],
    ] {
        let out = Command::cargo_bin("plan-runner")
            .unwrap()
            .args(&args)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {stderr}");
        assert!(
            stderr.contains("0.0.0.0:0 is not a loopback address")
                && stderr.contains("--allow-remote"),
            "{stderr}"
        );
    }
}

#[test]
fn allow_remote_serves_with_a_warning() {
    use std::io::{BufRead, BufReader};
    let mut child = std::process::Command::new(assert_cmd::cargo::cargo_bin("plan-runner"))
        .args(["serve", cyc3_file().to_str().unwrap()])
        .args(["--addr", "0.0.0.0:0", "--allow-remote"])
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut err = BufReader::new(child.stderr.take().unwrap());
    let mut warning = String::new();
    err.read_line(&mut warning).unwrap();
    let mut out = BufReader::new(child.stdout.take().unwrap());
    let mut url = String::new();
    out.read_line(&mut url).unwrap();
    child.kill().unwrap();
    child.wait().unwrap();
    assert!(
        warning.starts_with("warning: the viewer listens on 0.0.0.0:0, reachable from other"),
        "{warning}"
    );
    assert!(url.contains("at http://0.0.0.0:"), "{url}");
}
