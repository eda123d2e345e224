//! The viewer in a real browser: headless Chromium driven through chromedriver (WebDriver).
//!
//! The page's token game gives the marking of `plan-runner simulate` with the same seed; a
//! live run's numbers (and its robots on the map) change on the page; a reload mid-run shows
//! the current marking; a large net is drawn on a canvas with the same hooks; every resource
//! comes from the server, and the browser has no way out (its proxy is a closed port).
//! Screenshots of each view go to `target/screenshots/` — look at them after a change.
//!
//! Needs chromedriver and Chromium (Debian: `chromium`, `chromium-driver`; `.ci/run`
//! installs them): without them these tests fail, saying so.
#![cfg(feature = "web")]

use crate::support as common;
use crate::support::browser;

use std::net::SocketAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

use assert_cmd::Command;
use browser::Browser;
use fantoccini::Locator;
use gspn::analysis::state_space::{Options, StateSpace};
use gspn::io::{ReadOptions, read_net};
use gspn::net::{Net, Servers};
use gspn::runtime::Runtime;
use gspn::sim::Simulator;
use gspn::web::{CONTENT_SECURITY_POLICY, LiveRun, WebState};
use serde_json::{Value, json};
use tokio::io::{AsyncReadExt, AsyncWriteExt};

pub(crate) const PATROL: &str =
    "thesis/caldeira_2020_package/ros_TemperaturePatrolV2/gspn_temperature_patrol.xml";

/// One browser at a time: the machine has two cores.
pub(crate) static BROWSER: tokio::sync::Mutex<()> = tokio::sync::Mutex::const_new(());

/// Generous: a loaded CI machine may be slow, and a wait that runs out fails the test.
pub(crate) const WAIT: Duration = Duration::from_secs(60);

pub(crate) fn screenshot_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .parent()
        .expect("target dir")
        .join("screenshots")
        .join(name)
}

use crate::support::start_server;

/// `GET path` over plain TCP: the head and the body.
async fn http_get_raw(addr: SocketAddr, path: &str) -> (String, String) {
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    stream.write_all(req.as_bytes()).await.unwrap();
    let mut res = String::new();
    stream.read_to_string(&mut res).await.unwrap();
    let (head, body) = res.split_once("\r\n\r\n").unwrap();
    (head.to_string(), body.to_string())
}

pub(crate) async fn http_get(addr: SocketAddr, path: &str) -> Value {
    let (head, body) = http_get_raw(addr, path).await;
    assert!(head.starts_with("HTTP/1.1 200"), "{head}");
    serde_json::from_str(&body).unwrap()
}

/// The analysis panel's cancel button is hidden (nothing runs).
pub(crate) async fn assert_cancel_hidden(b: &Browser) {
    let hidden = b
        .js(
            "return document.getElementById('analysis-cancel').classList.contains('hidden');",
            vec![],
        )
        .await;
    assert_eq!(hidden, json!(true));
}

/// Clicks `analyse` and waits for the panel's result.
pub(crate) async fn analyse_on_page(b: &Browser) {
    b.click("#analyze").await;
    b.wait_js(
        "return document.getElementById('analysis').textContent.includes('reachable markings');",
        WAIT,
        "the analysis",
    )
    .await;
}

/// The replay cursor's time, every digit (`#timeline-time`'s `data-t`; it says `t = … s`
/// to the microsecond; a range input keeps about 15 digits of its value, so compare to
/// 1e-12).
pub(crate) async fn cursor_time(b: &Browser) -> f64 {
    let cursor = b.text("#timeline-time").await;
    let said: f64 = cursor
        .strip_prefix("t = ")
        .and_then(|c| c.strip_suffix(" s"))
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("{cursor}"));
    let t = b
        .js(
            "return Number(document.getElementById('timeline-time').dataset.t);",
            vec![],
        )
        .await
        .as_f64()
        .unwrap();
    assert!(
        (said - t).abs() <= 5e-7 * t.abs().max(1.0),
        "{cursor} for {t}"
    );
    t
}

/// Opens the page and waits until its first drawing is on the screen.
pub(crate) async fn open(b: &Browser, addr: SocketAddr) {
    b.client.goto(&format!("http://{addr}/")).await.unwrap();
    wait_drawn(b).await;
}

async fn wait_drawn(b: &Browser) {
    b.wait_js(
        "return window.gspnPerf && window.gspnPerf.drawn;",
        WAIT,
        "the first drawing",
    )
    .await;
}

/// `[(place, tokens)]` as the page's hooks say, in the page's order.
pub(crate) async fn page_marking(b: &Browser) -> Vec<(String, u32)> {
    let v = b
        .js(
            "return [...document.querySelectorAll('[data-place]')]\
               .map(e => [e.getAttribute('data-place'), e.getAttribute('data-tokens')]);",
            vec![],
        )
        .await;
    v.as_array()
        .unwrap()
        .iter()
        .map(|e| {
            let tokens = e[1].as_str().unwrap();
            let k = tokens
                .parse()
                .unwrap_or_else(|_| panic!("data-tokens={tokens:?} of {}", e[0]));
            (e[0].as_str().unwrap().to_string(), k)
        })
        .collect()
}

/// Names of the transitions whose hook says `data-enabled="true"`.
async fn page_enabled(b: &Browser) -> Vec<String> {
    let v = b
        .js(
            "return [...document.querySelectorAll('[data-transition][data-enabled=\"true\"]')]\
               .map(e => e.getAttribute('data-transition'));",
            vec![],
        )
        .await;
    serde_json::from_value(v).unwrap()
}

/// The firing count in the page's clock line (`time T, N firings…`).
async fn page_firings(b: &Browser) -> u64 {
    let clock = b.text("#clock").await;
    clock
        .split(", ")
        .nth(1)
        .and_then(|s| s.split(' ').next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| panic!("no firing count in {clock:?}"))
}

async fn wait_firings(b: &Browser, n: u64) {
    let script =
        format!("return document.getElementById('clock').textContent.includes(', {n} firings');");
    b.wait_js(&script, WAIT, &format!("{n} firings")).await;
}

pub(crate) fn marking_of(net: &Net, page: &[(String, u32)]) -> Vec<u32> {
    assert_eq!(page.len(), net.place_count(), "one hook per place");
    net.places()
        .iter()
        .zip(page)
        .map(|(p, (name, k))| {
            assert_eq!(&p.name, name);
            *k
        })
        .collect()
}

fn firable_names(net: &Net, m: &[u32]) -> Vec<String> {
    let mut v: Vec<String> = net
        .firable(m)
        .into_iter()
        .map(|t| net.transition(t).name.clone())
        .collect();
    v.sort();
    v
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn five_steps_in_the_browser_give_the_marking_of_plan_runner_simulate() {
    let _one = BROWSER.lock().await;
    let path = common::fixture(PATROL);
    let net = read_net(&path, &ReadOptions::default()).unwrap().net;
    let (addr, server) = start_server(WebState::new(net.clone(), None, 0)).await;
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    assert_eq!(page_marking(&b).await.len(), net.place_count());

    // Seed 11 typed into the seed field, then reset and five presses of `step`.
    let seed = 11u64;
    let field = b.client.find(Locator::Id("seed")).await.unwrap();
    field.clear().await.unwrap();
    field.send_keys(&seed.to_string()).await.unwrap();
    b.click("#reset").await;
    for _ in 0..200 {
        if http_get(addr, "/api/sim/state").await["seed"] == seed {
            break;
        }
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
    assert_eq!(http_get(addr, "/api/sim/state").await["seed"], seed);
    for k in 1..=5 {
        b.click("#step").await;
        wait_firings(&b, k).await;
    }
    let shown = marking_of(&net, &page_marking(&b).await);

    // The library's token game with that seed.
    let mut sim = Simulator::new(net.clone(), seed);
    sim.run_steps(5).unwrap();
    assert_eq!(shown, sim.marking().as_slice());
    // `plan-runner simulate` with that seed.
    let out = Command::cargo_bin("plan-runner")
        .unwrap()
        .args(["simulate", path.to_str().unwrap(), "--seed", "11"])
        .args(["--steps", "5", "--json"])
        .output()
        .unwrap();
    assert!(out.status.success());
    let cli: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(cli["trace"][4]["marking"], net.format_marking(&shown));
    // The transitions drawn as firable are the ones that may fire.
    let mut enabled = page_enabled(&b).await;
    enabled.sort();
    assert_eq!(enabled, firable_names(&net, &shown));
    // The trace lists the five firings of the command line, in order.
    let trace = b
        .js(
            "return [...document.querySelectorAll('#trace li')].map(li => li.textContent);",
            vec![],
        )
        .await;
    let trace = trace.as_array().unwrap();
    assert_eq!(trace.len(), 5);
    for (line, step) in trace.iter().zip(cli["trace"].as_array().unwrap()) {
        let name = step["transition"].as_str().unwrap();
        assert!(line.as_str().unwrap().contains(name), "{line} vs {name}");
    }
    b.screenshot(&screenshot_path("token-game.png")).await;

    // The analysis panel: the library's counts, of the bare net (no plan).
    analyse_on_page(&b).await;
    let ss = StateSpace::build(&net, &Options::default()).unwrap();
    let text = b.text("#analysis").await;
    assert!(
        text.starts_with(&format!(
            "bare net{} reachable markings ({} tangible, {} vanishing)",
            ss.reachable_count(),
            ss.tangible_count(),
            ss.vanishing_count()
        )),
        "{text}"
    );
    let bars = b
        .js(
            "return document.querySelectorAll('#analysis .bar').length;",
            vec![],
        )
        .await;
    assert_eq!(
        bars,
        json!(net.place_count() + net.transition_count()),
        "a bar per place and per transition"
    );
    b.screenshot(&screenshot_path("analysis.png")).await;
    b.close().await;
    server.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_page_loads_everything_from_its_own_server() {
    let _one = BROWSER.lock().await;
    let net = read_net(&common::fixture(PATROL), &ReadOptions::default())
        .unwrap()
        .net;
    let (addr, server) = start_server(WebState::new(net, None, 0)).await;
    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    let origin = format!("http://{addr}/");
    let loaded = b
        .js(
            "return [location.href].concat(performance.getEntriesByType('resource')\
               .map(e => e.name));",
            vec![],
        )
        .await;
    let loaded: Vec<String> = serde_json::from_value(loaded).unwrap();
    for url in &loaded {
        assert!(url.starts_with(&origin), "{url} is not from {origin}");
    }
    for asset in [
        "style.css",
        "canvas.js",
        "map.js",
        "analysis.js",
        "conform.js",
        "live.js",
        "follow.js",
        "share.js",
        "navigate.js",
        "app.js",
        "api/net",
    ] {
        assert!(
            loaded.contains(&format!("{origin}{asset}")),
            "{asset} not loaded: {loaded:?}"
        );
    }
    // Every response forbids other origins.
    for path in ["/", "/app.js", "/api/net"] {
        let (head, _) = http_get_raw(addr, path).await;
        let want = format!("content-security-policy: {CONTENT_SECURITY_POLICY}").to_lowercase();
        assert!(head.to_lowercase().contains(&want), "{path}: {head}");
    }
    // And the browser has no way out: any other host goes to a proxy that is not there.
    let away = b.client.goto("http://example.com/").await;
    let why = match away {
        Err(e) => e.to_string(),
        Ok(()) => b.text("body").await,
    };
    assert!(
        why.contains("ERR_PROXY_CONNECTION_FAILED"),
        "a request to another host did not end at the closed proxy: {why}"
    );
    b.close().await;
    server.abort();
}

fn cyc3() -> Net {
    common::cyc3(Servers::Single)
}

/// A fake simulated world: robot r1 drives from L1 to L3 and back while the test runs.
fn world(t: f64) -> Value {
    let x = 1.0 + 6.0 * (0.5 - 0.5 * (t * 0.8).cos());
    json!({
        "time": t,
        "map": {
            "locations": [
                {"name": "L1", "x": 1.0, "y": 1.0}, {"name": "L2", "x": 7.0, "y": 1.0},
                {"name": "L3", "x": 7.0, "y": 5.0}, {"name": "L4", "x": 1.0, "y": 5.0},
            ],
            "edges": [["L1", "L2"], ["L2", "L3"], ["L3", "L4"], ["L4", "L1"]],
            "walls": [[0.0, 0.0, 8.0, 0.0], [8.0, 0.0, 8.0, 6.0], [8.0, 6.0, 0.0, 6.0],
                      [0.0, 6.0, 0.0, 0.0], [4.0, 0.0, 4.0, 2.0]],
            "obstacles": [{"x": 3.0, "y": 3.0, "w": 2.0, "h": 1.0}],
        },
        "robots": [
            {"id": "r1", "agent": 0, "x": x, "y": 1.0, "radius": 0.3},
            {"id": "r2", "agent": 1, "x": 1.0, "y": 5.0, "radius": 0.3},
        ],
    })
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_live_run_moves_on_the_page_and_a_reload_shows_the_current_marking() {
    let _one = BROWSER.lock().await;
    // cyc3 at half real-time speed: about one firing a second.
    let mut handle = Runtime::builder(cyc3())
        .seed(7)
        .time_scale(2.0)
        .subscribe_at_start(true)
        .spawn()
        .unwrap();
    let events = handle.events();
    let handle = Arc::new(handle);
    let (tx, rx) = tokio::sync::watch::channel(world(0.0));
    let feed = tokio::spawn(async move {
        let mut t = 0.0;
        loop {
            tokio::time::sleep(Duration::from_millis(100)).await;
            t += 0.1;
            if tx.send(world(t)).is_err() {
                return;
            }
        }
    });
    let live = LiveRun::start(handle.clone(), events).with_world(rx);
    let (addr, server) = start_server(WebState::for_live(live)).await;
    let b = Browser::start(1400, 800).await;
    open(&b, addr).await;
    let net = cyc3();

    // The numbers change: the firing count grows, the robot moves.
    let f0 = page_firings(&b).await;
    let x0 = b
        .js(
            "return Number(document.querySelector('[data-robot=\"r1\"]').dataset.x);",
            vec![],
        )
        .await;
    wait_firings_above(&b, f0 + 2).await;
    let x1 = b
        .js(
            "return Number(document.querySelector('[data-robot=\"r1\"]').dataset.x);",
            vec![],
        )
        .await;
    assert_ne!(x0, x1, "the robot did not move");
    let locations = b
        .js(
            "return [...document.querySelectorAll('[data-location]')].map(e => e.dataset.location);",
            vec![],
        )
        .await;
    assert_eq!(locations, json!(["L1", "L2", "L3", "L4"]));
    // Two tokens circulate: every marking the page shows has two.
    let total: u32 = page_marking(&b).await.iter().map(|(_, k)| k).sum();
    assert_eq!(total, 2);
    b.screenshot(&screenshot_path("live.png")).await;

    // Reload mid-run: the page shows the run's current marking (read between two identical
    // snapshots of the server, so the run did not move meanwhile).
    b.client.refresh().await.unwrap();
    wait_drawn(&b).await;
    assert!(!http_get(addr, "/api/live/state").await["stopped"].is_string());
    let mut checked = false;
    for _ in 0..60 {
        let before = http_get(addr, "/api/live/state").await;
        tokio::time::sleep(Duration::from_millis(300)).await;
        let shown = marking_of(&net, &page_marking(&b).await);
        let firings = page_firings(&b).await;
        let after = http_get(addr, "/api/live/state").await;
        if before["firings"] != after["firings"] {
            continue;
        }
        let tokens: Vec<u32> = serde_json::from_value(after["tokens"].clone()).unwrap();
        assert_eq!(shown, tokens);
        assert_eq!(json!(firings), after["firings"]);
        let mut enabled = page_enabled(&b).await;
        enabled.sort();
        assert_eq!(enabled, firable_names(&net, &tokens));
        checked = true;
        break;
    }
    assert!(checked, "the run never stood still for 300 ms");

    // `stop` stops the run.
    b.click("#stop").await;
    b.wait_js(
        "return document.getElementById('clock').textContent.includes('stopped');",
        WAIT,
        "the run to stop",
    )
    .await;
    let summary = handle.wait().await;
    assert_eq!(json!(page_firings(&b).await), json!(summary.firings));
    b.close().await;
    feed.abort();
    server.abort();
}

async fn wait_firings_above(b: &Browser, n: u64) {
    let script = format!(
        "const m = document.getElementById('clock').textContent.match(/, (\\d+) firings/);\
         return m !== null && Number(m[1]) >= {n};"
    );
    b.wait_js(&script, WAIT, &format!("at least {n} firings"))
        .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_journal_plays_back_on_the_time_slider() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("run.jsonl");
    let summary = Runtime::builder(cyc3())
        .seed(9)
        .max_firings(12)
        .journal(&path)
        .spawn()
        .unwrap()
        .wait()
        .await;
    let text = std::fs::read_to_string(&path).unwrap();
    let frames = gspn::runtime::journal::read_journal(&text, &cyc3()).unwrap();
    let (addr, server) = start_server(WebState::for_replay(cyc3(), frames.clone())).await;
    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    let net = cyc3();
    assert_eq!(marking_of(&net, &page_marking(&b).await), frames[0].tokens);
    // Click the 7th firing in the trace, then drag the slider to the end.
    b.click("#trace li:nth-child(7)").await;
    assert_eq!(b.text("#frame").await, "7/12");
    assert_eq!(marking_of(&net, &page_marking(&b).await), frames[7].tokens);
    b.js(
        "const s = document.getElementById('slider'); s.value = s.max;\
         s.dispatchEvent(new Event('input'));",
        vec![],
    )
    .await;
    assert_eq!(b.text("#frame").await, "12/12");
    assert_eq!(
        marking_of(&net, &page_marking(&b).await),
        summary.marking.as_slice()
    );
    // The slider is in model seconds: its end is the last firing's time, a time between two
    // firings shows the earlier one.
    let max = b
        .js(
            "return Number(document.getElementById('slider').max);",
            vec![],
        )
        .await;
    assert_eq!(max.as_f64().unwrap(), frames[12].time);
    let between = (frames[3].time + frames[4].time) / 2.0;
    b.js(
        "const s = document.getElementById('slider'); s.value = String(arguments[0]);\
         s.dispatchEvent(new Event('input'));",
        vec![json!(between)],
    )
    .await;
    assert_eq!(b.text("#frame").await, "3/12");
    // The cursor says the time it is at; the state, the firing it shows.
    let shown = cursor_time(&b).await;
    assert!(
        (shown - between).abs() < 1e-12,
        "cursor at {shown} for {between}"
    );
    let clock = b.text("#clock").await;
    let said: f64 = clock
        .strip_prefix("time ")
        .and_then(|c| c.split(',').next())
        .and_then(|c| c.parse().ok())
        .unwrap_or_else(|| panic!("{clock}"));
    assert!((said - frames[3].time).abs() < 5e-7, "{clock}");
    assert!(clock.contains(", 3 firings"), "{clock}");
    // Keys: → and ← step one firing; the trace marks the current one.
    let key = |k: &'static str| {
        format!(
            "document.body.dispatchEvent(new KeyboardEvent('keydown', {{key: '{k}', bubbles: true}}));"
        )
    };
    b.js(&(key("ArrowRight") + &key("ArrowRight")), vec![])
        .await;
    assert_eq!(b.text("#frame").await, "5/12");
    b.js(&key("ArrowLeft"), vec![]).await;
    assert_eq!(b.text("#frame").await, "4/12");
    assert_eq!(b.text("#trace li.current .seq").await, "4");
    // Play in model time at ×0.1, then at ×1000: the new speed applies while playing; with
    // `loop` it starts again after the end.
    b.js(
        "const s = document.getElementById('replay-speed'); s.value = '0.1'; s.dispatchEvent(new Event('change'));\
         document.getElementById('loop').checked = true;",
        vec![],
    )
    .await;
    b.js(&key(" "), vec![]).await;
    b.js(
        "const s = document.getElementById('replay-speed'); s.value = '1000'; s.dispatchEvent(new Event('change'));",
        vec![],
    )
    .await;
    b.wait_js(
        "return window.gspnReplay.at() < 4 && window.gspnReplay.playing();",
        Duration::from_secs(10),
        "the replay to loop round at the new speed",
    )
    .await;
    b.js(&key(" "), vec![]).await;
    let playing = b.js("return window.gspnReplay.playing();", vec![]).await;
    assert_eq!(playing, json!(false));
    b.screenshot(&screenshot_path("replay.png")).await;
    b.close().await;
    server.abort();
}

/// A ring of `n` places, one token in every tenth.
fn ring(n: usize) -> Net {
    common::ring(n, |i| u32::from(i % 10 == 0), |_| 1.0, Servers::Single).0
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_large_net_is_drawn_on_a_canvas_with_the_same_hooks() {
    let _one = BROWSER.lock().await;
    let net = ring(2000);
    let (addr, server) = start_server(WebState::new(net.clone(), None, 3)).await;
    let b = Browser::start(1200, 800).await;
    open(&b, addr).await;
    let drawn = b
        .js(
            "return [getComputedStyle(document.getElementById('net-canvas')).display,\
                     getComputedStyle(document.getElementById('net')).display];",
            vec![],
        )
        .await;
    assert_eq!(drawn, json!(["block", "none"]));
    assert_eq!(
        marking_of(&net, &page_marking(&b).await),
        net.initial_marking().as_slice()
    );
    assert_eq!(
        page_enabled(&b).await.len(),
        200,
        "one firable transition per token"
    );
    // `step n` with n = 25.
    let n = b.client.find(Locator::Id("n")).await.unwrap();
    n.clear().await.unwrap();
    n.send_keys("25").await.unwrap();
    b.click("#step-n").await;
    wait_firings(&b, 25).await;
    let mut sim = Simulator::new(net.clone(), 3);
    sim.run_steps(25).unwrap();
    let shown = marking_of(&net, &page_marking(&b).await);
    assert_eq!(shown, sim.marking().as_slice());
    let mut enabled = page_enabled(&b).await;
    enabled.sort();
    assert_eq!(enabled, firable_names(&net, &shown));
    // Something was painted: the canvas is not blank.
    let inked = b
        .js(
            "const c = document.getElementById('net-canvas');\
             const d = c.getContext('2d').getImageData(0, 0, c.width, c.height).data;\
             let n = 0; for (let i = 0; i < d.length; i += 4) if (d[i] < 128) n++; return n;",
            vec![],
        )
        .await;
    assert!(inked.as_u64().unwrap() > 1000, "blank canvas: {inked}");
    b.screenshot(&screenshot_path("large-net.png")).await;
    // Zoomed in on p0 (the wheel, as a user would): names and token dots.
    b.js(
        "const c = document.getElementById('canvas'); const r = c.getBoundingClientRect();\
         const p = net.places[0]; const x = r.left + p.x * view.k + view.x;\
         const y = r.top + p.y * view.k + view.y;\
         for (let i = 0; i < 2; i++) c.dispatchEvent(new WheelEvent('wheel', \
           {deltaY: -1100, clientX: x, clientY: y, bubbles: true, cancelable: true}));",
        vec![],
    )
    .await;
    b.wait_js(
        "return new Promise(r => requestAnimationFrame(() => setTimeout(() => r(true))));",
        WAIT,
        "a frame",
    )
    .await;
    b.screenshot(&screenshot_path("large-net-zoomed.png")).await;
    // Click a green transition in the window: it fires (hit-testing on the canvas).
    let target = b
        .js(
            "const c = document.getElementById('net-canvas'); const r = c.getBoundingClientRect();\
             for (let i = 0; i < net.transitions.length; i++) {\
               const t = net.transitions[i];\
               const x = r.left + t.x * view.k + view.x, y = r.top + t.y * view.k + view.y;\
               if (!transEnabled[i] || x < r.left + 10 || x > r.right - 10 || y < r.top + 10 \
                   || y > r.bottom - 10) continue;\
               const o = {clientX: x, clientY: y, bubbles: true};\
               c.dispatchEvent(new MouseEvent('mousedown', o));\
               window.dispatchEvent(new MouseEvent('mouseup', o));\
               return t.name;\
             }\
             return null;",
            vec![],
        )
        .await;
    let target = target.as_str().expect("a green transition in the window");
    wait_firings(&b, 26).await;
    let s = http_get(addr, "/api/sim/state").await;
    let last = s["trace"].as_array().unwrap().last().unwrap().clone();
    assert_eq!(last["transition"], target);
    assert_eq!(last["manual"], true);
    b.close().await;
    server.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_long_analysis_shows_its_progress_on_the_page_and_can_be_cancelled() {
    let _one = BROWSER.lock().await;
    // Kanban N = 4: 454,475 tangible markings, seconds of work.
    let net = read_net(
        &common::fixture("kanban/kanban_gspn_N4.pnml"),
        &ReadOptions::default(),
    )
    .unwrap()
    .net;
    let (addr, server) = start_server(WebState::new(net, None, 0)).await;
    let b = Browser::start(1400, 800).await;
    open(&b, addr).await;
    b.click("#analyze").await;
    let progress = b
        .wait_js(
            "const t = document.getElementById('analysis-progress').textContent;\
             return /running \\([a-z ]+\\), [1-9][0-9,]* markings/.test(t) && t;",
            WAIT,
            "the analysis progress",
        )
        .await;
    assert!(
        progress.as_str().unwrap().ends_with(" s"),
        "{progress} (seconds shown)"
    );
    b.screenshot(&screenshot_path("analysis-progress.png"))
        .await;
    b.click("#analysis-cancel").await;
    b.wait_js(
        "return document.getElementById('analysis').textContent.startsWith('cancelled after');",
        WAIT,
        "the cancel",
    )
    .await;
    let p = http_get(addr, "/api/analysis/progress").await;
    assert_eq!(p["state"], "cancelled");
    let shown = b.text("#analysis").await;
    assert!(
        shown.starts_with(&format!("cancelled after {} markings", p["markings"])),
        "{shown} vs {p}"
    );
    assert_cancel_hidden(&b).await;
    b.close().await;
    server.abort();
}
