//! Embedding the runtime in an axum service: the plan runs in the background in real time
//! (twice as fast), `GET /marking` returns the current marking and progress as JSON, and
//! `POST /stop` stops the plan; the service exits when the plan has stopped.
//!
//! ```text
//! cargo run --example embed_service     # then: curl 127.0.0.1:7878/marking
//!                                       #       curl -X POST 127.0.0.1:7878/stop
//! ```

use std::sync::Arc;

use axum::{Json, Router, extract::State, routing::get, routing::post};
use gspn::net::{NetBuilder, Servers};
use gspn::runtime::{Runtime, RuntimeHandle};
use serde_json::{Value, json};

#[tokio::main]
async fn main() -> std::io::Result<()> {
    // Two robots share one charger: work → (charger) charge → work.
    let mut b = NetBuilder::new("charging");
    let work = b.place("Working", 2);
    let queue = b.place("WantsCharge", 0);
    let charger = b.place("Charger", 1);
    let charging = b.place("Charging", 0);
    let tired = b.exponential("tired", 0.5, Servers::Infinite);
    let plug = b.immediate("plug", 1.0, 1);
    let full = b.exponential("full", 1.0, Servers::Single);
    b.input(work, tired, 1);
    b.output(tired, queue, 1);
    b.input(queue, plug, 1);
    b.input(charger, plug, 1);
    b.output(plug, charging, 1);
    b.input(charging, full, 1);
    b.output(full, work, 1);
    b.output(full, charger, 1);
    let net = b.build().expect("valid net");

    // No user actions: every place is net-timed. The runtime lives in this tokio runtime.
    let handle = Arc::new(
        Runtime::builder(net)
            .time_scale(0.5)
            .seed(1)
            .spawn()
            .expect("spawn"),
    );

    let app = Router::new()
        .route("/marking", get(marking))
        .route("/stop", post(stop))
        .with_state(Arc::clone(&handle));
    let listener = tokio::net::TcpListener::bind("127.0.0.1:7878").await?;
    println!("listening on http://127.0.0.1:7878 (GET /marking, POST /stop)");
    let served = axum::serve(listener, app).with_graceful_shutdown({
        let h = Arc::clone(&handle);
        async move {
            let s = h.wait().await;
            println!("plan stopped: {} after {} firings", s.stopped, s.firings);
        }
    });
    served.await
}

async fn marking(State(h): State<Arc<RuntimeHandle>>) -> Json<Value> {
    let m = h.marking().await;
    let p = h.progress();
    Json(json!({
        "marking": h.net().format_marking(&m),
        "firings": p.firings(),
        "time": p.time(),
    }))
}

async fn stop(State(h): State<Arc<RuntimeHandle>>) -> &'static str {
    h.stop();
    "stopping\n"
}
