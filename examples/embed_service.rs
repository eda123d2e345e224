//! Embedding the runtime in a running service. axum is not a dependency of this crate (the
//! viewer behind feature `web` brings it later), so this is a plain tokio TCP service: the
//! plan runs in the background in real time, and each connection gets the current marking
//! and progress as one JSON line. `stop` on a connection stops the plan.
//!
//! ```text
//! cargo run --example embed_service          # then: nc 127.0.0.1 7878
//! ```

use std::sync::Arc;

use gspn::net::{NetBuilder, Servers};
use gspn::runtime::Runtime;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpListener;

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

    // Real time, twice as fast; no user actions: every place is net-timed.
    let handle = Arc::new(
        Runtime::builder(net)
            .time_scale(0.5)
            .seed(1)
            .spawn()
            .expect("spawn"),
    );
    let listener = TcpListener::bind("127.0.0.1:7878").await?;
    println!("listening on 127.0.0.1:7878 (send `stop` to stop the plan)");
    loop {
        tokio::select! {
            accepted = listener.accept() => {
                let (mut sock, _) = accepted?;
                let h = Arc::clone(&handle);
                tokio::spawn(async move {
                    let mut buf = [0u8; 16];
                    let n = sock.read(&mut buf).await.unwrap_or(0);
                    if buf[..n].starts_with(b"stop") {
                        h.stop();
                    }
                    let m = h.marking().await;
                    let p = h.progress();
                    let line = serde_json::json!({
                        "marking": h.net().format_marking(&m),
                        "firings": p.firings(),
                        "time": p.time(),
                    });
                    let _ = sock.write_all(format!("{line}\n").as_bytes()).await;
                });
            }
            s = handle.wait() => {
                println!("plan stopped: {} after {} firings", s.stopped, s.firings);
                return Ok(());
            }
        }
    }
}
