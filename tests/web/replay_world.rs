//! `plan-runner replay JOURNAL --net PLAN --web` of a run with `--robots 8`: the run is
//! recognised (its scaled initial marking made the hash differ from the plan's net), the
//! page shows the map with the 8 robots where the journal's world records put them, and the
//! slider is in model seconds.
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
struct Serving(Child);

impl Drop for Serving {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `plan-runner replay JOURNAL --net PLAN --web 127.0.0.1:0`: the child and the viewer's
/// address (from its "replay of … at" line).
fn replay_with_viewer(journal: &Path, plan: &Path) -> (Serving, SocketAddr) {
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
    assert_eq!(b.text("#timeline-end").await, format!("{end} s"));

    // A time between two firings: the marking of the earlier one, the robots where the last
    // world record before it put them.
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
    let want = poses.iter().rev().find(|w| w.time <= t).unwrap();
    let on_page = b
        .js(
            "return [...document.querySelectorAll('#map [data-robot]')]\
               .map(g => [g.dataset.robot, Number(g.dataset.x), Number(g.dataset.y)]);",
            vec![],
        )
        .await;
    let mut on_page: Vec<(String, f64, f64)> = serde_json::from_value(on_page).unwrap();
    on_page.sort_by(|a, b| a.0.cmp(&b.0));
    let mut expected = crate::follow::poses(&want.data);
    expected.sort_by(|a, b| a.0.cmp(&b.0));
    assert_eq!(on_page, expected);
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
