//! `plan-runner replay JOURNAL --net PLAN --web` of a run with `--robots 8`: the run is
//! recognised (its scaled initial marking made the hash differ from the plan's net), the
//! page shows the map with the 8 robots where the journal's world records put them, and the
//! slider is in model seconds. At 1280 px the header holds one row, the net keeps almost half
//! the width beside the map and the side panel, and no two robot names on the map overlap.
#![cfg(all(feature = "web", feature = "sim"))]

use crate::browser::{BROWSER, WAIT, cursor_time, open, screenshot_path};
use crate::support::browser::Browser;

use std::io::{BufRead, BufReader};
use std::net::SocketAddr;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};

use gspn::io::ReadOptions;
use gspn::runtime::journal::read_recording;
use serde_json::json;

fn bin() -> Command {
    Command::new(assert_cmd::cargo::cargo_bin("plan-runner"))
}

/// The `plan-runner replay --web` child, killed when the test ends (it serves until Ctrl-C).
pub(crate) struct Serving(pub(crate) Child);

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `plan-runner replay JOURNAL --net PLAN --web 127.0.0.1:0`: the child and the viewer's
/// address (from its "replay of … at" line).
pub(crate) fn replay_with_viewer(journal: &Path, plan: &Path) -> (Serving, SocketAddr) {
    let mut child = bin()
        .args(["replay", journal.to_str().unwrap(), "--net"])
        .arg(plan)
        .args(["--web", "127.0.0.1:0"])
        .stdout(Stdio::piped())
        .stderr(Stdio::inherit())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let child = Serving(child);
    let mut out = BufReader::new(stdout);
    let mut line = String::new();
    assert!(out.read_line(&mut line).unwrap() > 0, "no viewer address");
    let url = line.trim().rsplit(" at http://").next().unwrap();
    let addr = url.trim_end_matches('/').parse().unwrap();
    std::thread::spawn(move || for _ in out.lines() {});
    (child, addr)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_journal_of_8_robots_replays_with_the_map_on_a_slider_in_model_seconds() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let plan = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    crate::support::journal_of_patrol_on_robots(&journal, 8, 5, 60);
    let net = gspn::plan::open(&plan, &ReadOptions::default())
        .unwrap()
        .into_plan()
        .net;
    let text = std::fs::read_to_string(&journal).unwrap();
    let rec = read_recording(&text, &net).unwrap();
    let frames = rec.frames();
    let poses: Vec<_> = rec.records("world").collect();
    assert_eq!(frames.len(), 61);

    let (child, addr) = replay_with_viewer(&journal, &plan);
    let b = Browser::start(1400, 900).await;
    open(&b, addr).await;
    b.wait_js(
        "return document.querySelectorAll('#map [data-robot]').length === 8\
           && !document.getElementById('map-panel').classList.contains('hidden');",
        WAIT,
        "the map with 8 robots",
    )
    .await;
    // The slider runs over model seconds, to the end of the recording.
    let end = frames.last().unwrap().time.max(poses.last().unwrap().time);
    let max = b
        .js(
            "return Number(document.getElementById('slider').max);",
            vec![],
        )
        .await;
    assert_eq!(max.as_f64().unwrap(), end);
    let said = b.text("#timeline-end").await;
    let said: f64 = said.strip_suffix(" s").unwrap().parse().unwrap();
    assert!((said - end).abs() < 5e-7, "{said} for {end}");
    let full = b
        .js(
            "return Number(document.getElementById('timeline-end').dataset.t);",
            vec![],
        )
        .await;
    assert_eq!(full.as_f64().unwrap(), end);

    // A time between two firings: the marking of the earlier one, the robots on their way
    // between the world records before and after it.
    let t = (frames[30].time + frames[31].time) / 2.0;
    b.js(
        "const s = document.getElementById('slider'); s.value = String(arguments[0]);\
         s.dispatchEvent(new Event('input'));",
        vec![json!(t)],
    )
    .await;
    assert_eq!(b.text("#frame").await, "30/60");
    let shown = cursor_time(&b).await;
    assert!((shown - t).abs() < 1e-12, "cursor at {shown} for {t}");
    let k = poses.iter().rposition(|w| w.time <= t).unwrap();
    let (before, after) = (&poses[k], &poses[k + 1]);
    let u = (t - before.time) / (after.time - before.time);
    let on_page = b
        .js(
            "return [...document.querySelectorAll('#map [data-robot]')]\
               .map(g => [g.dataset.robot, Number(g.dataset.x), Number(g.dataset.y)]);",
            vec![],
        )
        .await;
    let mut on_page: Vec<(String, f64, f64)> = serde_json::from_value(on_page).unwrap();
    on_page.sort_by(|a, b| a.0.cmp(&b.0));
    let mut expected = crate::follow::poses(&before.data);
    let next = crate::follow::poses(&after.data);
    for r in &mut expected {
        let q = next.iter().find(|q| q.0 == r.0).unwrap();
        r.1 += (q.1 - r.1) * u;
        r.2 += (q.2 - r.2) * u;
    }
    expected.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(on_page.len(), expected.len());
    for (p, e) in on_page.iter().zip(&expected) {
        assert_eq!(p.0, e.0);
        assert!(
            (p.1 - e.1).abs() < 1e-9 && (p.2 - e.2).abs() < 1e-9,
            "{p:?} vs {e:?}"
        );
    }
    // The robots drove meanwhile: r1 is not where it started.
    let start = &poses[0].data[0];
    assert_eq!(start["id"], "r1");
    let r1_now = expected.iter().find(|r| r.0 == "r1").unwrap();
    assert!(
        (r1_now.1 - start["x"].as_f64().unwrap()).abs()
            + (r1_now.2 - start["y"].as_f64().unwrap()).abs()
            > 0.1,
        "r1 at {r1_now:?} and at the start {start}"
    );
    // Earlier, the robots stood elsewhere: the map follows the slider.
    b.js(
        "const s = document.getElementById('slider'); s.value = '0';\
         s.dispatchEvent(new Event('input'));",
        vec![],
    )
    .await;
    let r1 = b
        .js(
            "const g = document.querySelector('#map [data-robot=\"r1\"]');\
             return [Number(g.dataset.x), Number(g.dataset.y)];",
            vec![],
        )
        .await;
    let first = &poses[0].data[0];
    assert_eq!(first["id"], "r1");
    let r1: (f64, f64) = serde_json::from_value(r1).unwrap();
    assert_eq!(
        r1,
        (first["x"].as_f64().unwrap(), first["y"].as_f64().unwrap())
    );
    b.js(
        "const s = document.getElementById('slider'); s.value = String(arguments[0]);\
         s.dispatchEvent(new Event('input'));",
        vec![json!(t)],
    )
    .await;
    b.screenshot(&screenshot_path("replay-robots.png")).await;
    b.close().await;
    drop(child);
}

/// Every visible control of the header on the same line, the header one line high.
pub(crate) async fn assert_header_one_row(b: &Browser) {
    let rows = b
        .js(
            "const tops = [...document.querySelectorAll('header h1, .controls > *')]\
               .filter(e => e.getClientRects().length > 0)\
               .map(e => { const r = e.getBoundingClientRect(); return Math.round(r.top + r.height / 2); });\
             return [Math.min(...tops), Math.max(...tops), document.querySelector('header').getBoundingClientRect().height];",
            vec![],
        )
        .await;
    let rows: [f64; 3] = serde_json::from_value(rows).unwrap();
    assert!(
        rows[1] - rows[0] <= 4.0,
        "controls on several rows: {rows:?}"
    );
    assert!(rows[2] < 40.0, "header {} px high", rows[2]);
}

/// Client rectangles `[x0, y0, x1, y1]` of the robots' names on the map.
async fn robot_name_boxes(b: &Browser) -> Vec<(String, [f64; 4])> {
    let v = b
        .js(
            "return [...document.querySelectorAll('#map [data-robot] text')].map(t => {\
               const r = t.getBoundingClientRect();\
               return [t.textContent, [r.left, r.top, r.right, r.bottom]];\
             });",
            vec![],
        )
        .await;
    serde_json::from_value(v).unwrap()
}

/// Pairs of names whose boxes overlap by more than half a pixel each way.
fn overlapping(boxes: &[(String, [f64; 4])]) -> Vec<(String, String)> {
    let mut out = Vec::new();
    for (i, (a, p)) in boxes.iter().enumerate() {
        for (b, q) in &boxes[i + 1..] {
            let w = p[2].min(q[2]) - p[0].max(q[0]);
            let h = p[3].min(q[3]) - p[1].max(q[1]);
            if w > 0.5 && h > 0.5 {
                out.push((a.clone(), b.clone()));
            }
        }
    }
    out
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn at_1280_px_the_header_is_one_row_the_net_half_the_width_and_no_robot_names_overlap() {
    let _one = BROWSER.lock().await;
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let plan = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    crate::support::journal_of_patrol_on_robots(&journal, 8, 5, 60);
    let (child, addr) = replay_with_viewer(&journal, &plan);
    let b = Browser::start(1280, 800).await;
    open(&b, addr).await;
    b.wait_js(
        "return document.querySelectorAll('#map [data-robot]').length === 8;",
        WAIT,
        "the map with 8 robots",
    )
    .await;
    assert_header_one_row(&b).await;
    // The net keeps nearly half the window beside the map and the side panel.
    let net_width = b
        .js(
            "return document.getElementById('canvas').getBoundingClientRect().width;",
            vec![],
        )
        .await;
    let net_width = net_width.as_f64().unwrap();
    assert!(
        net_width >= 0.45 * 1280.0,
        "the net pane is {net_width} px wide"
    );
    // At the start three robots queue side by side at L1 (0.5 m apart), and at every time
    // after: no two names overlap.
    let end = b
        .js(
            "return Number(document.getElementById('slider').max);",
            vec![],
        )
        .await
        .as_f64()
        .unwrap();
    for k in 0..=10 {
        let t = end * f64::from(k) / 10.0;
        b.js(
            "const s = document.getElementById('slider'); s.value = String(arguments[0]);\
             s.dispatchEvent(new Event('input'));",
            vec![json!(t)],
        )
        .await;
        let boxes = robot_name_boxes(&b).await;
        assert_eq!(boxes.len(), 8);
        assert_eq!(
            overlapping(&boxes),
            Vec::<(String, String)>::new(),
            "at t = {t}: {boxes:?}"
        );
        if k == 0 {
            b.screenshot(&screenshot_path("replay-robots-1280-start.png"))
                .await;
        }
    }
    b.screenshot(&screenshot_path("replay-robots-1280.png"))
        .await;
    b.close().await;
    drop(child);
}
