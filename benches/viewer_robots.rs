//! The viewer following a live run on N simulated robots in headless Chromium: the first
//! draw of the page and, per state frame (net and map), the time from the WebSocket message
//! to the paint after it — what `plan-runner run PLAN --robots N --time-scale 1 --web` serves.
//!
//! ```text
//! cargo bench --bench viewer_robots -- [--robots 64 --seconds 10]
//! ```
//!
//! The thesis's temperature patrol (`plans/temperature-patrol/plan.toml`) with its tokens
//! scaled to `robots`, in real time. "open": navigation start → the first paint after the net
//! is drawn (`window.gspnPerf.drawn`); "frames": `window.gspnPerf.frames` over `seconds`
//! seconds. Needs chromedriver (Debian: `chromium`, `chromium-driver`).

#[path = "support/args.rs"]
mod bench_args;

#[path = "../tests/support/browser.rs"]
mod browser;

use std::path::Path;
use std::sync::Arc;
use std::time::Duration;

use browser::Browser;
use gspn::io::ReadOptions;
use gspn::web::{LiveRun, WebState, serve};
use gspn::world::{Fleet, WorldView};

fn arg(name: &str, default: u64) -> u64 {
    let args: Vec<String> = bench_args::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1))
        .map(|v| v.parse().expect("a number"))
        .unwrap_or(default)
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
    let frames = browser.live_frames(seconds).await;
    println!(
        "open (patrol, {robots} robots, live): {:.0} ms",
        drawn.as_f64().unwrap_or(f64::NAN)
    );
    println!("live {robots} robots: {}", frames.summary(seconds));
    handle.stop();
    server.abort();
    browser.close().await;
}
