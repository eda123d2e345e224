//! Following a live run with robots, as `plan-runner run PLAN --robots 8 --web` serves it:
//! robot ids on the places that hold them; the transition that fired last is highlighted;
//! clicking robot `r3` on the map selects the place the last `Fired` event put it in (and
//! clicking a place marks its robots); a tokens-over-time plot of the selected place and a
//! timeline per robot; `stop` halts the world (robot positions do not change for 2 s) and
//! marks the map stopped; the panes resize and collapse.
#![cfg(all(feature = "web", feature = "sim"))]

use crate::browser::{BROWSER, WAIT, http_get, open, screenshot_path};
use crate::support::browser::Browser;

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::{Child, Command, Stdio};
use std::time::Duration;

use gspn::io::ReadOptions;
use gspn::net::{ArcKind, Net};
use serde_json::{Value, json};

/// `plan-runner run plans/temperature-patrol/plan.toml --robots N --time-scale 1 --web
/// 127.0.0.1:0` (real time, as a user watches it): the child and the viewer's address (from
/// its "watch the run at" line).
pub(crate) fn run_with_viewer(robots: usize) -> (RunningPlan, SocketAddr) {
    let plan = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    let mut child = Command::new(assert_cmd::cargo::cargo_bin("plan-runner"))
        .args([
            "run",
            plan.to_str().unwrap(),
            "--robots",
            &robots.to_string(),
        ])
        .args(["--time-scale", "1", "--web", "127.0.0.1:0"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stderr = child.stderr.take().unwrap();
    let child = RunningPlan(child);
    let mut err = BufReader::new(stderr);
    let mut line = String::new();
    loop {
        line.clear();
        assert!(err.read_line(&mut line).unwrap() > 0, "no viewer address");
        if let Some(url) = line.trim().strip_prefix("watch the run at http://") {
            let addr = url.trim_end_matches('/').parse().unwrap();
            // Keep reading stderr so the child never blocks on a full pipe.
            std::thread::spawn(move || for _ in err.lines() {});
            return (child, addr);
        }
    }
}

/// The `plan-runner` child, killed when the test ends (it serves until Ctrl-C), even on a
/// failed assertion.
pub(crate) struct RunningPlan(Child);

impl Drop for RunningPlan {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

pub(crate) fn patrol_net() -> Net {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    gspn::plan::open(&path, &ReadOptions::default())
        .unwrap()
        .into_plan()
        .net
}

/// Where the run's own log says robot `id` is: the output place of the last transition that
/// consumed it (every transition of the patrol has one output place), else its start place.
fn place_of_robot_in_log(net: &Net, log: &[Value], id: &str) -> String {
    for e in log.iter().rev() {
        let robots = e["robots"].as_array().cloned().unwrap_or_default();
        if e["event"] == "fired" && robots.contains(&json!(id)) {
            let t = e["transition"].as_u64().unwrap() as usize;
            let outputs: Vec<usize> = net
                .arcs()
                .iter()
                .filter(|a| a.transition.index() == t && a.kind == ArcKind::Output)
                .map(|a| a.place.index())
                .collect();
            assert_eq!(outputs.len(), 1, "transition {t}");
            return net.places()[outputs[0]].name.clone();
        }
        if e["event"] == "agent_spawned" && e["robot"] == id {
            let p = e["place"].as_u64().unwrap() as usize;
            return net.places()[p].name.clone();
        }
    }
    panic!("robot {id} is not in the log");
}

/// Robot positions from the server: `[[id, x, y]]` and the world's time.
async fn robot_positions(addr: SocketAddr) -> (Vec<(String, f64, f64)>, f64) {
    let w = http_get(addr, "/api/live/world").await;
    (poses(&w["robots"]), w["time"].as_f64().unwrap())
}

/// `[[id, x, y]]` of a JSON list of robots (`[{"id", "x", "y", …}]`).
pub(crate) fn poses(robots: &Value) -> Vec<(String, f64, f64)> {
    robots
        .as_array()
        .unwrap()
        .iter()
        .map(|r| {
            (
                r["id"].as_str().unwrap().to_string(),
                r["x"].as_f64().unwrap(),
                r["y"].as_f64().unwrap(),
            )
        })
        .collect()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_live_run_with_8_robots_can_be_followed_and_stopped() {
    let _one = BROWSER.lock().await;
    let net = patrol_net();
    let (child, addr) = run_with_viewer(8);
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    b.wait_js(
        "return document.querySelectorAll('#map [data-robot]').length === 8;",
        WAIT,
        "8 robots on the map",
    )
    .await;
    // Some firings, with robots: ids appear on the places that hold them.
    b.wait_js(
        "return [...document.querySelectorAll('#log li')].filter(li => li.textContent.includes(' fired (r')).length >= 6;",
        WAIT,
        "six firings by robots",
    )
    .await;
    let s = http_get(addr, "/api/live/state").await;
    let list = s["agent_list"].as_array().unwrap();
    assert_eq!(
        list.iter().filter(|a| a["robot"].is_string()).count(),
        8,
        "{list:?}"
    );
    let on_places = b
        .js(
            "return Object.fromEntries([...document.querySelectorAll('#nodes [data-place]')]\
               .map(g => [g.dataset.place, (g.querySelector('text.agents') || {}).textContent || '']));",
            vec![],
        )
        .await;
    // Every robot id is on the place that holds it (the page may be one frame behind the
    // request: allow a robot that moved meanwhile, but not most of them).
    b.screenshot(&screenshot_path("follow-live.png")).await;
    let mut found = 0;
    for a in list {
        let text = on_places[a["place"].as_str().unwrap()].as_str().unwrap();
        if text.split(' ').any(|w| w == a["robot"].as_str().unwrap()) {
            found += 1;
        }
    }
    assert!(
        found >= 6,
        "{found} of 8 robot ids on their places: {on_places}"
    );
    b.screenshot(&screenshot_path("follow-live.png")).await;

    // Stop: the run ends, the map says so, and the robots stand still.
    b.click("#stop").await;
    b.wait_js(
        "return document.getElementById('clock').textContent.includes('stopped')\
           && document.getElementById('map-panel').classList.contains('stopped');",
        WAIT,
        "the run and the map to stop",
    )
    .await;
    // The world stops after the run has ended: give it a moment to do so.
    tokio::time::sleep(Duration::from_millis(500)).await;
    let (before, t_before) = robot_positions(addr).await;
    tokio::time::sleep(Duration::from_secs(2)).await;
    let (after, t_after) = robot_positions(addr).await;
    assert_eq!(before.len(), 8);
    assert_eq!(before, after, "robots moved after stop");
    assert_eq!(t_before, t_after, "the world's clock ran on after stop");
    let map_time = b.text("#map-time").await;
    assert!(map_time.ends_with("— stopped"), "{map_time}");

    // The transition that fired last is the highlighted one.
    let s = http_get(addr, "/api/live/state").await;
    let log = s["log"].as_array().unwrap();
    let last_fired = log.iter().rev().find(|e| e["event"] == "fired").unwrap();
    let t = last_fired["transition"].as_u64().unwrap() as usize;
    let fired = b
        .js(
            "return [...document.querySelectorAll('.transition.fired')].map(g => g.dataset.transition);",
            vec![],
        )
        .await;
    assert_eq!(fired, json!([net.transitions()[t].name]));

    // Clicking robot r3 on the map selects the place the last Fired event put it in.
    let want = place_of_robot_in_log(&net, log, "r3");
    b.js(
        "document.querySelector('#map [data-robot=\"r3\"]').dispatchEvent(new MouseEvent('click', {bubbles: true}));",
        vec![],
    )
    .await;
    let selected = b
        .js(
            "return [...document.querySelectorAll('[data-place][data-selected=\"true\"]')].map(g => g.dataset.place);",
            vec![],
        )
        .await;
    assert_eq!(selected, json!([want]));
    let selection = b.text("#selection").await;
    assert!(
        selection.starts_with("robot r3: agent ") && selection.contains(&want),
        "{selection}"
    );
    let robot_selected = b
        .js(
            "return [...document.querySelectorAll('#map [data-selected=\"true\"]')].map(g => g.dataset.robot);",
            vec![],
        )
        .await;
    assert_eq!(robot_selected, json!(["r3"]));
    // Its tokens over time: the plot ends at the place's tokens now.
    let plot = b
        .wait_js(
            "const l = document.querySelector('#plot polyline');\
             return l && [l.dataset.place, l.dataset.points];",
            WAIT,
            "the plot",
        )
        .await;
    assert_eq!(plot[0], json!(want));
    let p = net.place_by_name(&want).unwrap();
    let last_k: u32 = plot[1]
        .as_str()
        .unwrap()
        .rsplit(' ')
        .next()
        .unwrap()
        .split(',')
        .nth(1)
        .unwrap()
        .parse()
        .unwrap();
    assert_eq!(json!(last_k), s["tokens"][p.index()]);
    // The timeline: a row per robot, r3's last bar in that place.
    let gantt = b
        .js(
            "const rs = [...document.querySelectorAll('#gantt rect[data-robot]')];\
             const r3 = rs.filter(r => r.dataset.robot === 'r3');\
             return [new Set(rs.map(r => r.dataset.robot)).size, r3[r3.length - 1].dataset.place];",
            vec![],
        )
        .await;
    assert_eq!(gantt, json!([8, want]));
    b.screenshot(&screenshot_path("follow-robot-selected.png"))
        .await;

    // The reverse: clicking a place marks the robots in it on the map.
    let marked = b
        .js(
            "const g = document.querySelector('[data-place=\"' + arguments[0] + '\"]');\
             const r = g.getBoundingClientRect();\
             const o = {clientX: r.x + r.width / 2, clientY: r.y + r.height / 2, bubbles: true};\
             g.querySelector('circle').dispatchEvent(new MouseEvent('mousedown', o));\
             window.dispatchEvent(new MouseEvent('mouseup', o));\
             g.querySelector('circle').dispatchEvent(new MouseEvent('mousedown', o));\
             window.dispatchEvent(new MouseEvent('mouseup', o));\
             return [...document.querySelectorAll('#map [data-selected=\"true\"]')].map(g => g.dataset.robot);",
            vec![json!(want)],
        )
        .await;
    let marked: Vec<String> = serde_json::from_value(marked).unwrap();
    assert!(marked.contains(&"r3".to_string()), "{marked:?}");
    for id in &marked {
        assert_eq!(place_of_robot_in_log(&net, log, id), want, "{id}");
    }

    // Panes: dragging the bar left of the side panel widens it by the distance dragged;
    // collapsing the map gives its room to the net.
    let widths = b
        .js(
            "const side = document.getElementById('side');\
             const bar = document.querySelector('.splitter[data-pane=\"side\"]');\
             const w0 = side.getBoundingClientRect().width;\
             const r = bar.getBoundingClientRect();\
             const x = r.x + 2, y = r.y + 50;\
             bar.dispatchEvent(new MouseEvent('mousedown', {clientX: x, clientY: y, bubbles: true}));\
             window.dispatchEvent(new MouseEvent('mousemove', {clientX: x - 100, clientY: y, bubbles: true}));\
             window.dispatchEvent(new MouseEvent('mouseup', {clientX: x - 100, clientY: y, bubbles: true}));\
             const c0 = document.getElementById('canvas').getBoundingClientRect().width;\
             document.querySelector('[data-collapse=\"map-panel\"]').click();\
             const c1 = document.getElementById('canvas').getBoundingClientRect().width;\
             return [w0, side.getBoundingClientRect().width, c0, c1,\
                     getComputedStyle(document.getElementById('map-panel')).display];",
            vec![],
        )
        .await;
    let w = |i: usize| widths[i].as_f64().unwrap();
    assert!((w(1) - w(0) - 100.0).abs() < 1.0, "{widths}");
    assert!(w(3) > w(2) + 100.0, "{widths}");
    assert_eq!(widths[4], "none");
    b.screenshot(&screenshot_path("follow-panes.png")).await;
    b.close().await;
    drop(child);
}
