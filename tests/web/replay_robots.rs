//! Who did what, at 1280×800: a replay of the patrol on 8 robots shows robot ids on places,
//! a robot timeline with one row per robot, and clicking robot r1 at the slider's 40 % names
//! its agent and place (the place the journal's last firing of r1 put it in); playback at
//! ×10 runs model time ten times faster than wall time; the conformance table's every
//! column can be scrolled into view. A page that joins a live run late gets the run's
//! history: its plot and timeline start at model time 0.
#![cfg(all(feature = "web", feature = "sim"))]

use crate::browser::{BROWSER, WAIT, http_get, open, screenshot_path};
use crate::follow::{patrol_net, run_with_viewer};
use crate::support::browser::Browser;
use crate::support::start_server;

use std::time::Duration;

use gspn::net::{ArcKind, Net};
use gspn::runtime::EventKind;
use gspn::runtime::journal::{Recording, read_recording};
use gspn::web::WebState;
use serde_json::{Value, json};

/// Robot `id`'s agent and place at time `t` by the journal: spawned with its agent in a
/// place; each firing that consumed it (its robot listed) put it in the transition's one
/// output place (every transition of the patrol has one).
fn robot_at(net: &Net, rec: &Recording, id: &str, t: f64) -> (u64, String) {
    let mut agent = None;
    let mut place = None;
    for e in rec.events.iter().take_while(|e| e.time <= t) {
        match &e.kind {
            EventKind::AgentSpawned {
                agent: a,
                place: p,
                robot: Some(r),
            } if &**r == id => {
                agent = Some(a.0);
                place = Some(net.place(*p).name.clone());
            }
            EventKind::Fired {
                transition, robots, ..
            } if robots.iter().any(|r| &**r == id) => {
                let outputs: Vec<&str> = net
                    .arcs()
                    .iter()
                    .filter(|a| a.transition == *transition && a.kind == ArcKind::Output)
                    .map(|a| net.place(a.place).name.as_str())
                    .collect();
                assert_eq!(outputs.len(), 1);
                place = Some(outputs[0].to_string());
            }
            _ => {}
        }
    }
    (agent.unwrap(), place.unwrap())
}

async fn slide_to(b: &Browser, t: f64) {
    b.js(
        "const s = document.getElementById('slider'); s.value = String(arguments[0]);\
         s.dispatchEvent(new Event('input'));",
        vec![json!(t)],
    )
    .await;
    // The run comes a window of 256 firings at a time: the one at t may still be on its way.
    b.wait_js(
        "return window.gspnReplay.settled();",
        crate::browser::WAIT,
        "the replay's window at the slider's time",
    )
    .await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_replay_shows_which_robot_did_what_and_plays_in_model_time() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    crate::support::journal_of_patrol_on_robots(&journal, 8, 5, 1000);
    let plan_net = patrol_net();
    let rec = read_recording(&std::fs::read_to_string(&journal).unwrap(), &plan_net).unwrap();
    let net = rec.net.clone();
    let end = rec.frames().last().unwrap().time;
    let (addr, server) = start_server(WebState::for_recording(rec.clone())).await;
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    b.wait_js(
        "return document.querySelectorAll('#map [data-robot]').length === 8;",
        WAIT,
        "the map with 8 robots",
    )
    .await;
    let slider_end = b
        .js(
            "return Number(document.getElementById('slider').max);",
            vec![],
        )
        .await
        .as_f64()
        .unwrap();
    assert!(slider_end >= end);

    // At 40 %: click r1 on the map.
    let t = 0.4 * slider_end;
    slide_to(&b, t).await;
    b.js(
        "document.querySelector('#map [data-robot=\"r1\"]').dispatchEvent(new MouseEvent('click', {bubbles: true}));",
        vec![],
    )
    .await;
    let (agent, place) = robot_at(&net, &rec, "r1", t);
    let selection = b.text("#selection").await;
    assert!(
        selection.starts_with(&format!("robot r1: agent {agent} in {place},")),
        "{selection} (want agent {agent} in {place})"
    );
    assert!(selection.contains(" stays"), "{selection}");
    let selected = b
        .js(
            "return [...document.querySelectorAll('[data-place][data-selected=\"true\"]')].map(g => g.dataset.place);",
            vec![],
        )
        .await;
    assert_eq!(selected, json!([place]));
    // Robot ids on the places that hold them: r1 on its place.
    let on_place = b
        .js(
            "const g = document.querySelector('[data-place=\"' + arguments[0] + '\"] text.agents');\
             return g ? g.textContent.split(' ') : [];",
            vec![json!(place)],
        )
        .await;
    assert!(
        on_place.as_array().unwrap().contains(&json!("r1")),
        "{on_place}"
    );
    // The robot timeline: one row per robot, a legend of the places.
    let rows = b
        .wait_js(
            "const rows = [...document.querySelectorAll('#gantt [data-robot-row]')].map(e => e.dataset.robotRow);\
             return rows.length === 8 && [rows, new Set([...document.querySelectorAll('#gantt rect[data-robot]')].map(r => r.dataset.robot)).size,\
                     document.querySelectorAll('#gantt-legend .legend-item').length];",
            WAIT,
            "the robot timeline",
        )
        .await;
    assert_eq!(
        rows[0],
        json!(["r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8"])
    );
    assert_eq!(rows[1], json!(8));
    assert!(rows[2].as_u64().unwrap() >= 2, "{rows}");
    b.screenshot(&screenshot_path("replay-robot-r1.png")).await;

    // Every column of the conformance table (which has statistics from about two thirds of
    // this run on) can be brought into view inside the panel.
    slide_to(&b, slider_end).await;
    let columns = b
        .wait_js(
            "const ths = [...document.querySelectorAll('#conform thead th')];\
             if (!ths.length) return null;\
             const side = document.getElementById('side').getBoundingClientRect();\
             return ths.map(th => {\
               th.scrollIntoView({block: 'nearest', inline: 'nearest'});\
               const r = th.getBoundingClientRect();\
               return [th.textContent, r.left >= side.left - 0.5 && r.right <= Math.min(side.right, innerWidth) + 0.5];\
             });",
            WAIT,
            "the conformance table",
        )
        .await;
    assert_eq!(
        columns,
        json!([
            ["item", true],
            ["observed", true],
            ["predicted", true],
            ["95% interval", true],
            ["n", true],
            ["p", true]
        ])
    );

    // Playback at ×10 from the start: model time runs ten times as fast as wall time.
    slide_to(&b, 0.0).await;
    b.js(
        "const s = document.getElementById('replay-speed'); s.value = '10';\
         s.dispatchEvent(new Event('change'));\
         document.getElementById('play').click();",
        vec![],
    )
    .await;
    // Both read at one animation frame: its timestamp and the model time it set. The page
    // moves model time by ×10 the wall time between frames, whatever the frame rate (a
    // loaded machine drops frames; the ratio is not timed from outside).
    let sample = "return [window.gspnReplay.tick(), window.gspnReplay.time()];";
    tokio::time::sleep(Duration::from_millis(300)).await;
    let a = b.js(sample, vec![]).await;
    tokio::time::sleep(Duration::from_millis(1500)).await;
    let z = b.js(sample, vec![]).await;
    let f = |v: &Value, i: usize| v[i].as_f64().unwrap();
    let wall = (f(&z, 0) - f(&a, 0)) / 1000.0;
    let model = f(&z, 1) - f(&a, 1);
    assert!(f(&z, 1) < slider_end, "the replay ended while measured");
    assert!(wall > 0.0, "no animation frame in 1.5 s");
    let ratio = model / wall;
    eprintln!("replay at ×10: {model} model s in {wall} wall s (×{ratio:.6})");
    assert!((ratio - 10.0).abs() <= 1e-6, "×{ratio}");
    b.click("#play").await;
    b.close().await;
    server.abort();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_page_that_joins_a_live_run_late_gets_its_history() {
    let _one = BROWSER.lock().await;
    let (child, addr) = run_with_viewer(8);
    // Let the run go on for 3 model seconds (real time) before the page opens.
    let deadline = std::time::Instant::now() + WAIT;
    loop {
        let s = http_get(addr, "/api/live/state").await;
        if s["time"].as_f64().unwrap() > 3.0 && s["firings"].as_u64().unwrap() > 0 {
            break;
        }
        assert!(
            std::time::Instant::now() < deadline,
            "the run never got to 3 s"
        );
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    let history = b
        .wait_js(
            "return follow.segments.size === 8\
               && document.querySelectorAll('#gantt [data-robot-row]').length === 8 && [follow.times[0],\
               [...follow.segments.values()].map(s => s[0].t0),\
               document.querySelectorAll('#gantt [data-robot-row]').length];",
            WAIT,
            "the history of the run",
        )
        .await;
    assert_eq!(history[0].as_f64(), Some(0.0), "the plot starts at 0");
    let starts: Vec<f64> = serde_json::from_value(history[1].clone()).unwrap();
    assert_eq!(starts, vec![0.0; 8], "every robot's timeline starts at 0");
    assert_eq!(history[2], json!(8));
    // The net readable beside the map: names at 10 px at least.
    let px = b
        .js(
            "const ls = [...document.querySelectorAll('#nodes text.label')].filter(t => getComputedStyle(t).display !== 'none');\
             return ls.length && Math.min(...ls.map(t => parseFloat(getComputedStyle(t).fontSize) * t.getScreenCTM().a));",
            vec![],
        )
        .await;
    assert!(px.as_f64().unwrap() >= 9.99, "{px}");
    b.screenshot(&screenshot_path("live-8-robots-1280.png"))
        .await;
    // For docs/viewer.md, the page as it opened before: a 320 px side panel, the map at 28 %,
    // the whole net fitted.
    b.js(
        "document.getElementById('side').style.width = '320px';\
         document.getElementById('map-panel').style.width = '28%';\
         fit(true);",
        vec![],
    )
    .await;
    tokio::time::sleep(Duration::from_millis(300)).await;
    b.screenshot(&screenshot_path("live-8-robots-1280-as-before.png"))
        .await;
    b.close().await;
    drop(child);
}
