//! The viewer follows a running plan: a browser that joins late gets the net first, then the
//! run so far (the marking after every firing), then the current marking, clock and event
//! log; the HTTP snapshot agrees with the run's summary.
#![cfg(feature = "web")]

use crate::support as common;

use std::sync::Arc;

use futures_util::StreamExt;
use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::Runtime;
use gspn::web::{LiveRun, WebState, serve};
use serde_json::{Value, json};
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio_tungstenite::tungstenite::Message;

fn cyc3() -> Net {
    common::cyc3(Servers::Single)
}

async fn http_get(addr: std::net::SocketAddr, path: &str) -> Value {
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    stream.write_all(req.as_bytes()).await.unwrap();
    let mut res = String::new();
    stream.read_to_string(&mut res).await.unwrap();
    let (head, body) = res.split_once("\r\n\r\n").unwrap();
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    serde_json::from_str(body).unwrap()
}

#[tokio::test]
async fn a_late_joiner_gets_the_net_then_the_final_state_of_the_run() {
    let mut handle = Runtime::builder(cyc3())
        .seed(5)
        .max_firings(30)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events);
    let summary = handle.wait().await;
    assert_eq!(summary.firings, 30);

    let (addr, server) = common::start_server(WebState::for_live(live)).await;

    assert_eq!(http_get(addr, "/api/mode").await["live"], true);
    // The fold may still be draining the bus: poll until it has seen the end.
    let mut snap = Value::Null;
    for _ in 0..200 {
        snap = http_get(addr, "/api/live/state").await;
        if snap["stopped"].is_string() && snap["firings"] == 30 {
            break;
        }
        tokio::time::sleep(std::time::Duration::from_millis(10)).await;
    }
    assert_eq!(snap["firings"], 30, "{snap}");
    let tokens: Vec<u32> = serde_json::from_value(snap["tokens"].clone()).unwrap();
    assert_eq!(tokens, summary.marking.as_slice());
    assert_eq!(snap["time"].as_f64().unwrap(), summary.time);
    let fired = snap["log"]
        .as_array()
        .unwrap()
        .iter()
        .filter(|e| e["event"] == "fired")
        .count();
    assert_eq!(fired, 30);

    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/live/ws"))
        .await
        .unwrap();
    let text = |m: Message| -> Value {
        match m {
            Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            other => panic!("expected text, got {other:?}"),
        }
    };
    let first = text(ws.next().await.unwrap().unwrap());
    assert_eq!(first["type"], "net");
    assert_eq!(first["places"].as_array().unwrap().len(), 3);
    // The run so far: the initial marking at 0, then the marking after each firing.
    let history = text(ws.next().await.unwrap().unwrap());
    assert_eq!(history["type"], "history");
    let frames = history["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 31);
    assert_eq!(frames[0]["time"].as_f64(), Some(0.0));
    assert_eq!(
        frames[0]["tokens"],
        json!(cyc3().initial_marking().as_slice())
    );
    assert_eq!(frames[30]["tokens"], snap["tokens"]);
    assert_eq!(frames[30]["time"].as_f64().unwrap(), summary.time);
    assert_eq!(history["robots"], json!([]));
    let second = text(ws.next().await.unwrap().unwrap());
    assert_eq!(second["type"], "state");
    assert_eq!(second["firings"], 30);
    assert_eq!(second["tokens"], snap["tokens"]);
    assert_eq!(second["stopped"], snap["stopped"]);
    server.abort();
}

#[tokio::test]
async fn a_journal_plays_back_as_the_markings_of_the_run() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.jsonl");
    let handle = Runtime::builder(cyc3())
        .seed(9)
        .max_firings(12)
        .journal(&path)
        .spawn()
        .unwrap();
    let summary = handle.wait().await;
    let text = std::fs::read_to_string(&path).unwrap();
    let frames = gspn::runtime::journal::read_journal(&text, &cyc3()).unwrap();
    assert_eq!(frames.len(), 13);
    assert_eq!(frames[0].tokens, vec![2, 0, 0]);
    assert_eq!(frames[12].tokens, summary.marking.as_slice());
    // Every frame follows from the one before by firing its transition.
    let net = cyc3();
    for w in frames.windows(2) {
        let t = net
            .transition_by_name(w[1].transition.as_deref().unwrap())
            .unwrap();
        let mut m = w[0].tokens.clone();
        net.fire(&mut m, t).unwrap();
        assert_eq!(m, w[1].tokens);
        assert!(w[1].time >= w[0].time);
    }

    // Another net's journal is refused, naming both nets.
    let mut b = NetBuilder::new("other");
    b.place("x", 1);
    let err = gspn::runtime::journal::read_journal(&text, &b.build().unwrap()).unwrap_err();
    assert!(err.to_string().contains("`cyc3`"), "{err}");

    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(serve(listener, WebState::for_replay(cyc3(), frames)));
    assert_eq!(http_get(addr, "/api/mode").await["replay"], true);
    let v = http_get(addr, "/api/replay").await;
    assert_eq!(v["firings"], 12);
    assert_eq!(v["starts"], json!([0.0]));
    let w = http_get(addr, "/api/replay/window?k=0").await;
    assert_eq!(w["frames"].as_array().unwrap().len(), 13);
    assert_eq!(w["frames"][0]["transition"], Value::Null);
    server.abort();
}

#[tokio::test]
async fn a_world_feed_is_served_and_sent_in_the_state_frames() {
    let mut handle = Runtime::builder(cyc3())
        .seed(3)
        .max_firings(10)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let world = |x: f64| {
        serde_json::json!({
            "time": x,
            "map": {
                "locations": [{"name": "L1", "x": 0.0, "y": 0.0}, {"name": "L2", "x": 8.0, "y": 0.0}],
                "edges": [["L1", "L2"]],
                "walls": [[-1.0, -1.0, 9.0, -1.0]],
                "obstacles": [{"x": 3.0, "y": 1.0, "w": 1.0, "h": 0.5}],
            },
            "robots": [{"id": "r1", "agent": 0, "x": x, "y": 0.0, "radius": 0.3}],
        })
    };
    let (tx, rx) = tokio::sync::watch::channel(world(0.5));
    let live = LiveRun::start(handle.clone(), events).with_world(rx);
    handle.wait().await;

    let (addr, server) = common::start_server(WebState::for_live(live)).await;
    assert_eq!(http_get(addr, "/api/live/world").await, world(0.5));
    assert_eq!(http_get(addr, "/api/live/state").await["world"], world(0.5));

    let (mut ws, _) = tokio_tungstenite::connect_async(format!("ws://{addr}/api/live/ws"))
        .await
        .unwrap();
    let mut next = async || -> Value {
        match ws.next().await.unwrap().unwrap() {
            Message::Text(t) => serde_json::from_str(t.as_str()).unwrap(),
            other => panic!("expected text, got {other:?}"),
        }
    };
    assert_eq!(next().await["type"], "net");
    assert_eq!(next().await["type"], "history");
    // The run may still be folding its last events: skip to a frame with the first world.
    let first = next().await;
    assert_eq!(first["world"]["robots"][0]["x"], 0.5, "{first}");
    // A new world value alone (the run is over, no event comes) wakes a frame.
    tx.send(world(2.0)).unwrap();
    let mut moved = next().await;
    for _ in 0..20 {
        if moved["world"]["robots"][0]["x"] == 2.0 {
            break;
        }
        moved = next().await;
    }
    assert_eq!(moved["type"], "state");
    assert_eq!(moved["world"], world(2.0));
    assert_eq!(
        http_get(addr, "/api/live/world").await["robots"][0]["x"],
        2.0
    );
    // The feed ends: the last value stays.
    drop(tx);
    assert_eq!(http_get(addr, "/api/live/world").await, world(2.0));
    server.abort();
}

#[tokio::test]
async fn a_run_without_a_world_feed_has_no_world() {
    let mut handle = Runtime::builder(cyc3())
        .seed(1)
        .max_firings(3)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events);
    handle.wait().await;
    let (addr, server) = common::start_server(WebState::for_live(live)).await;
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET /api/live/world HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    stream.write_all(req.as_bytes()).await.unwrap();
    let mut res = String::new();
    stream.read_to_string(&mut res).await.unwrap();
    assert!(res.starts_with("HTTP/1.1 404"), "{res}");
    assert!(
        http_get(addr, "/api/live/state")
            .await
            .get("world")
            .is_none()
    );
    server.abort();
}
