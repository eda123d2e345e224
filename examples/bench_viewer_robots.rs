//! The viewer following a live run on N simulated robots in headless Chromium: the first
//! draw of the page and, per state frame (net and map), the time from the WebSocket message
//! to the paint after it — what `plan-runner run PLAN --robots N --time-scale 1 --web` serves.
//!
//! ```text
//! cargo run --release --example bench_viewer_robots [-- --robots 64 --seconds 10]
//! ```
//!
//! The thesis's temperature patrol (`plans/temperature-patrol/plan.toml`) with its tokens
//! scaled to `robots`, in real time. "open": navigation start → the first paint after the net
//! is drawn (`window.gspnPerf.drawn`); "frames": `window.gspnPerf.frames` over `seconds`
//! seconds. Needs chromedriver (Debian: `chromium`, `chromium-driver`).

#[path = "../tests/support/browser.rs"]
mod browser;

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use browser::Browser;
use gspn::io::ReadOptions;
use gspn::web::{LiveRun, WebState, serve};
use gspn::world::{Fleet, WorldView};
use serde_json::Value;

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("a number"))
        .unwrap_or(default)
}

fn quantile(mut v: Vec<f64>, q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    if v.is_empty() {
        return f64::NAN;
    }
    v[((v.len() - 1) as f64 * q).round() as usize]
}

#[tokio::main(flavor = "multi_thread", worker_threads = 2)]
async fn main() {
    let robots = arg("--robots", 64) as usize;
    let seconds = arg("--seconds", 10);
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    let mut plan = gspn::plan::open(&path, &ReadOptions::default())
        .expect("the patrol plan")
        .into_plan();
    plan.time_scale = Some(1.0);
    plan.seed = Some(1);
    let fleet = Fleet::new(plan, Some(robots)).expect("the fleet");
    let feed = WorldView::json_feed(fleet.world.view());
    let mut handle = fleet.builder.subscribe_at_start(true).spawn().expect("run");
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events).with_world(feed);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(serve(listener, WebState::for_live(live)));
    let browser = Browser::start(1400, 900).await;
    browser
        .client
        .goto(&format!("http://{addr}/"))
        .await
        .expect("goto");
    let drawn = browser
        .wait_js(
            "return window.gspnPerf && window.gspnPerf.drawn;",
            Duration::from_secs(120),
            "the live page",
        )
        .await;
    browser
        .wait_js(
            &format!("return document.querySelectorAll('#map [data-robot]').length === {robots};"),
            Duration::from_secs(60),
            "every robot on the map",
        )
        .await;
    browser
        .js(
            "window.gspnPerf.frames = []; window.gspnPerf.handler = [];",
            vec![],
        )
        .await;
    tokio::time::sleep(Duration::from_secs(seconds)).await;
    let perf = browser
        .js(
            "return {frames: window.gspnPerf.frames, handler: window.gspnPerf.handler, \
             clock: document.getElementById('clock').textContent};",
            vec![],
        )
        .await;
    let list = |v: &Value| -> Vec<f64> {
        v.as_array()
            .map(|a| a.iter().filter_map(Value::as_f64).collect())
            .unwrap_or_default()
    };
    let frames = list(&perf["frames"]);
    let handler = list(&perf["handler"]);
    println!(
        "open (patrol, {robots} robots, live): {:.0} ms",
        drawn.as_f64().unwrap_or(f64::NAN)
    );
    println!(
        "live {robots} robots: {} frames in {seconds} s; message → paint median {:.1} ms, p90 {:.1} ms, \
         max {:.1} ms; script per frame median {:.1} ms ({})",
        frames.len(),
        quantile(frames.clone(), 0.5),
        quantile(frames.clone(), 0.9),
        frames.iter().copied().fold(0.0, f64::max),
        quantile(handler, 0.5),
        perf["clock"].as_str().unwrap_or(""),
    );
    handle.stop();
    server.abort();
    browser.close().await;
}
