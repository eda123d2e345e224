//! Regression (issue 32, item 2): `replay --web` held 4.9 GB for a 100 MB robot journal — the
//! page got the whole run at once (every frame, every pose). The viewer now reads the journal
//! once for an index of windows, and each window from the file when the page asks. Here, on
//! a robot journal of ~20 MB (16 robots, ~7,300 firings), with the real `plan-runner`: the
//! windows put together are the journal's frames, each window's poses cover its time, and the
//! server's own peak resident memory (its `VmHWM`, read from /proc, after the index pass and
//! every window served) stays below 64 MB, the journal adding less than a quarter of its size
//! to what the same viewer of a 200-firing journal needs. The 100 MB figure is in
//! docs/benchmarks.md.
#![cfg(all(feature = "web", feature = "sim"))]

use std::fs::File;
use std::io::BufReader;
use std::path::PathBuf;

use gspn::io::ReadOptions;
use gspn::runtime::journal::{Entry, JournalReader};

use crate::browser::http_get;
use crate::replay_world::replay_with_viewer;

/// The peak resident memory of process `pid` in kB (`VmHWM`: the high-water mark over its
/// life, so one read after the work is done sees the peak).
fn peak_rss_kb(pid: u32) -> u64 {
    std::fs::read_to_string(format!("/proc/{pid}/status"))
        .unwrap()
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
        .unwrap()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_viewers_replay_serves_windows_read_from_the_journal_in_bounded_memory() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("robots.jsonl");
    let plan = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");
    crate::support::journal_of_patrol_on_robots(&journal, 16, 5, 20_000);
    let bytes = std::fs::metadata(&journal).unwrap().len();
    assert!(bytes > 16 << 20, "only {bytes} bytes");
    // The frames as the journal has them (read a line at a time here too).
    let net = gspn::plan::open(&plan, &ReadOptions::default())
        .unwrap()
        .into_plan()
        .net;
    // (`--robots 16` scaled the initial marking: the header says which.)
    let reader = JournalReader::new(BufReader::new(File::open(&journal).unwrap()), &net).unwrap();
    let ran = reader.net().clone();
    let mut times = vec![0.0];
    let mut markings = vec![ran.initial_marking().into_vec()];
    let mut poses = Vec::new();
    // Per frame, the poses recorded before its line.
    let mut poses_before = vec![0];
    for e in reader {
        match e.unwrap() {
            Entry::Event(e) => {
                if let Some(f) = e.firing() {
                    times.push(f.time);
                    markings.push(f.marking.to_vec());
                    poses_before.push(poses.len());
                }
            }
            Entry::Record(r) if &*r.record == "world" => poses.push(r.time),
            Entry::Record(_) => {}
        }
    }
    assert!(times.len() > 4 * 256, "{} frames", times.len());

    let (child, addr) = replay_with_viewer(&journal, &plan);
    let outline = http_get(addr, "/api/replay").await;
    assert_eq!(outline["firings"], times.len() - 1);
    let size = outline["window"].as_u64().unwrap() as usize;
    let starts = outline["starts"].as_array().unwrap();
    assert_eq!(starts.len(), times.len().div_ceil(size));
    let mut served = 0;
    for (k, start) in starts.iter().enumerate() {
        let w = http_get(addr, &format!("/api/replay/window?k={k}")).await;
        assert_eq!(w["first"], k * size);
        let frames = w["frames"].as_array().unwrap();
        assert_eq!(frames.len(), size.min(times.len() - k * size), "window {k}");
        for (j, f) in frames.iter().enumerate() {
            let i = k * size + j;
            assert_eq!(f["time"].as_f64().unwrap(), times[i], "frame {i}");
            let tokens: Vec<u32> = serde_json::from_value(f["tokens"].clone()).unwrap();
            assert_eq!(tokens, markings[i], "frame {i}");
        }
        assert_eq!(start.as_f64().unwrap(), times[k * size]);
        // The poses: from the last one at or before the window's start to the first one at
        // or after the next window's.
        let got: Vec<f64> = w["poses"]
            .as_array()
            .unwrap()
            .iter()
            .map(|p| p["time"].as_f64().unwrap())
            .collect();
        // From the last pose before the window's first firing to the first one after the
        // next window's first firing, in the journal's order.
        let from = poses_before[k * size].saturating_sub(1);
        let to = poses_before
            .get((k + 1) * size)
            .map_or(poses.len(), |&n| (n + 1).min(poses.len()));
        assert_eq!(got, poses[from..to], "window {k}");
        served += frames.len();
    }
    assert_eq!(served, times.len());
    assert_eq!(
        http_get_status(addr, &format!("/api/replay/window?k={}", starts.len())).await,
        404
    );
    let kb = peak_rss_kb(child.0.id());
    drop(child);
    // The same viewer of a journal of 200 firings: what the viewer needs whatever the
    // journal (the net of 16 robots, the server); the difference is what the journal adds.
    let short = dir.path().join("short.jsonl");
    crate::support::journal_of_patrol_on_robots(&short, 16, 5, 200);
    let (child, addr) = replay_with_viewer(&short, &plan);
    http_get(addr, "/api/replay").await;
    http_get(addr, "/api/replay/window?k=0").await;
    let short_kb = peak_rss_kb(child.0.id());
    let added = kb.saturating_sub(short_kb);
    eprintln!(
        "journal {} kB, {} windows: the viewer's peak {kb} kB ({short_kb} kB with 200 firings)",
        bytes >> 10,
        starts.len()
    );
    // Held whole, the page's answer alone was about 2.5 times the file (4.9 GB for 100 MB
    // as `Value`s): here a fraction of it.
    assert!(kb < 64 << 10, "the viewer held {kb} kB");
    // The outline (the robot timeline) still grows with the run: 3.6–5.4 MB here for a
    // 20 MB journal, so the bound is half the file, where holding it whole was ~2.5 times.
    assert!(
        added < (bytes >> 10) / 2,
        "the viewer held {added} kB more for a {bytes} B journal"
    );
}

/// The status code of a GET.
async fn http_get_status(addr: std::net::SocketAddr, path: &str) -> u16 {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut stream = tokio::net::TcpStream::connect(addr).await.unwrap();
    let req = format!("GET {path} HTTP/1.1\r\nHost: {addr}\r\nConnection: close\r\n\r\n");
    stream.write_all(req.as_bytes()).await.unwrap();
    let mut res = String::new();
    stream.read_to_string(&mut res).await.unwrap();
    res.split(' ').nth(1).unwrap().parse().unwrap()
}
