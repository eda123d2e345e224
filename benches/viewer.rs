//! The viewer in headless Chromium on a large ring: how long until the page has drawn the net,
//! and how long each live update takes to reach the screen.
//!
//! ```text
//! cargo bench --bench viewer -- [--places 10000 --runs 5 --seconds 10 --svg]
//! cargo bench --bench viewer -- --net FILE --runs 5 --seconds 0
//! ```
//!
//! `--net FILE` opens that net (or plan) instead of the ring (the thesis's temperature
//! patrol: `plans/temperature-patrol/temperature_patrol.xml`, drawn with the layered layout).
//!
//! `--svg` forces the SVG renderer (`/?renderer=svg`), which the page otherwise uses only up
//! to 1,500 nodes, to compare it with the canvas.
//!
//! A ring of `places` places (one token in every tenth), no positions (the server computes
//! the layout). "open": from navigation start to the first paint after the net and its
//! marking are drawn, as the page measures it (`performance.now()` in a frame callback,
//! `window.gspnPerf.drawn`), over `runs` page loads. "live": the ring runs in real time
//! (rate 1 per transition: about `places / 10` firings a second) behind `LiveRun`; per state
//! frame, the time from the WebSocket message to the first paint after it
//! (`window.gspnPerf.frames`), for `seconds` seconds. Needs chromedriver (Debian:
//! `chromium`, `chromium-driver`).

#[path = "support/args.rs"]
mod bench_args;

#[path = "../tests/support/browser.rs"]
mod browser;

use std::sync::Arc;
use std::time::{Duration, Instant};

use browser::{Browser, quantile};
use gspn::net::{Net, NetBuilder, Servers};
use gspn::runtime::Runtime;
use gspn::web::{LiveRun, WebState, serve};

fn ring(n: usize) -> Net {
    let mut b = NetBuilder::new(format!("ring{n}"));
    let places: Vec<_> = (0..n)
        .map(|i| b.place(format!("p{i}"), u32::from(i % 10 == 0)))
        .collect();
    for i in 0..n {
        let t = b.exponential(format!("t{i}"), 1.0, Servers::Single);
        b.input(places[i], t, 1);
        b.output(t, places[(i + 1) % n], 1);
    }
    b.build().expect("ring")
}

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
    let n = arg("--places", 10_000) as usize;
    let runs = arg("--runs", 5);
    let seconds = arg("--seconds", 10);
    let query = if bench_args::args().any(|a| a == "--svg") {
        "?renderer=svg"
    } else {
        ""
    };
    let browser = Browser::start(1400, 900).await;

    // ---- open: the token game's page, loaded `runs` times
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let args: Vec<String> = bench_args::args().collect();
    let file = args
        .iter()
        .position(|a| a == "--net")
        .and_then(|i| args.get(i + 1));
    let net = match file {
        Some(f) => {
            gspn::plan::open(std::path::Path::new(f), &gspn::io::ReadOptions::default())
                .expect("the net")
                .into_plan()
                .net
        }
        None => ring(n),
    };
    let n = net.place_count();
    let server = tokio::spawn(serve(listener, WebState::new(net, None, 1)));
    let mut opens = Vec::new();
    let mut walls = Vec::new();
    for _ in 0..runs {
        let start = Instant::now();
        browser
            .client
            .goto(&format!("http://{addr}/{query}"))
            .await
            .expect("goto");
        let drawn = browser
            .wait_js(
                "return window.gspnPerf && window.gspnPerf.drawn;",
                Duration::from_secs(120),
                "the first drawing",
            )
            .await;
        walls.push(start.elapsed().as_secs_f64() * 1000.0);
        opens.push(drawn.as_f64().unwrap());
        let places = browser
            .js(
                "return document.querySelectorAll('[data-place]').length;",
                vec![],
            )
            .await;
        assert_eq!(places, n as u64, "every place carries its data-place hook");
    }
    let renderer = browser
        .js(
            "return document.getElementById('net-canvas').classList.contains('hidden') \
             ? 'svg' : 'canvas';",
            vec![],
        )
        .await;
    println!("renderer: {}", renderer.as_str().unwrap_or("?"));
    println!(
        "open {n} places: median {:.0} ms (page: navigation start → first paint; runs {:?}); \
         wall from goto {:.0} ms",
        quantile(&opens, 0.5),
        opens.iter().map(|x| x.round()).collect::<Vec<_>>(),
        quantile(&walls, 0.5),
    );
    server.abort();
    if file.is_some() || seconds == 0 {
        browser.close().await;
        return;
    }

    // ---- live: the ring running in real time
    let mut handle = Runtime::builder(ring(n))
        .seed(1)
        .time_scale(1.0)
        .subscribe_at_start(true)
        .spawn()
        .expect("run");
    let events = handle.events();
    let handle = Arc::new(handle);
    let live = LiveRun::start(handle.clone(), events);
    let listener = tokio::net::TcpListener::bind("127.0.0.1:0").await.unwrap();
    let addr = listener.local_addr().unwrap();
    let server = tokio::spawn(serve(listener, WebState::for_live(live)));
    browser
        .client
        .goto(&format!("http://{addr}/{query}"))
        .await
        .expect("goto");
    browser
        .wait_js(
            "return window.gspnPerf && window.gspnPerf.drawn;",
            Duration::from_secs(120),
            "the live page",
        )
        .await;
    let frames = browser.live_frames(seconds).await;
    println!("live {n} places: {}", frames.summary(seconds));
    handle.stop();
    server.abort();
    browser.close().await;
}
