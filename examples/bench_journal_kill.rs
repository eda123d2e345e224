//! Measures the journal's durability under load (issue 32, item 7): a real-time run of cyc3
//! (`--time-scale 0.01`: about 200 events a second) is killed with SIGKILL at a seeded
//! random moment, KILLS times, beside BUSY busy loops; after each kill the events that were
//! lost are found by running the same seed again in virtual time (a run repeats from its
//! seed) and the age of the oldest lost one at the kill is printed — the journal's promise is
//! that an event reaches the file at most `FLUSH_AFTER` (100 ms) after it happened.
//!
//! ```text
//! cargo build --release --bin plan-runner
//! cargo run --release --example bench_journal_kill -- target/release/plan-runner [KILLS] [BUSY]
//! ```

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

const SCALE: f64 = 0.01;

fn lines(path: &Path) -> Vec<Value> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    text.lines()
        .filter_map(|l| serde_json::from_str(l).ok())
        .collect()
}

fn busy() -> Child {
    Command::new("sh")
        .args(["-c", "while :; do :; done"])
        .spawn()
        .unwrap()
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .unwrap_or_default()
        .split(' ')
        .next()
        .unwrap_or("?")
        .to_string()
}

fn main() {
    let mut args = std::env::args().skip(1);
    let bin = args.next().expect("the plan-runner binary");
    let kills: u64 = args.next().and_then(|s| s.parse().ok()).unwrap_or(20);
    let busy_loops: usize = args.next().and_then(|s| s.parse().ok()).unwrap_or(2);
    let fixtures = std::env::var("GSPN_FIXTURES")
        .unwrap_or_else(|_| concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/fixtures").into());
    let net = format!("{fixtures}/greatspn/cyc3/cyc3.PNPRO");
    let dir = tempfile::tempdir().unwrap();
    let mut loops: Vec<Child> = (0..busy_loops).map(|_| busy()).collect();
    std::thread::sleep(Duration::from_secs(2));
    let mut worst: f64 = 0.0;
    let mut over = 0;
    for k in 0..kills {
        let seed = 100 + k;
        let journal = dir.path().join(format!("run{k}.jsonl"));
        let mut child = Command::new(&bin)
            .args(["run", &net, "--time-scale", &SCALE.to_string(), "--quiet"])
            .args(["--seed", &seed.to_string()])
            .arg("--journal")
            .arg(&journal)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        // The header is written just before the run's clock starts.
        while std::fs::metadata(&journal).map_or(0, |m| m.len()) == 0 {
            std::thread::sleep(Duration::from_micros(200));
        }
        let started = Instant::now();
        // 0.5 to 1.5 s into the run (a fixed sequence, not wall-clock chance).
        let wait = 0.5 + ((seed * 7919) % 1000) as f64 / 1000.0;
        std::thread::sleep(Duration::from_secs_f64(wait));
        let _ = child.kill();
        let killed = started.elapsed().as_secs_f64();
        let _ = child.wait();
        let on_disk = lines(&journal);
        let kept = on_disk.len().saturating_sub(1); // the header
        // The same run in virtual time: its events, the first `kept` of which are on disk.
        let full = dir.path().join(format!("full{k}.jsonl"));
        let out = Command::new(&bin)
            .args(["run", &net, "--time-scale", "0", "--quiet"])
            .args(["--seed", &seed.to_string(), "--until"])
            .arg(format!("{}", killed / SCALE + 100.0))
            .arg("--journal")
            .arg(&full)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .status()
            .unwrap();
        assert!(out.success());
        let all = lines(&full);
        let same = on_disk
            .iter()
            .zip(&all)
            .skip(1)
            .all(|(a, b)| a["event"] == b["event"] && a["transition"] == b["transition"]);
        let first_lost = all
            .get(kept + 1)
            .and_then(|e| e["time"].as_f64())
            .filter(|&t| t * SCALE <= killed);
        let age_ms = first_lost.map_or(0.0, |t| (killed - t * SCALE) * 1e3);
        let lost = all[1..]
            .iter()
            .filter(|e| e["time"].as_f64().is_some_and(|t| t * SCALE <= killed))
            .count()
            .saturating_sub(kept);
        worst = worst.max(age_ms);
        if age_ms > 100.0 {
            over += 1;
        }
        println!(
            "kill {k:>2} at {killed:.3} s, load {}: {kept} events on disk{}, {lost} lost, \
             oldest lost {age_ms:.1} ms old",
            load(),
            if same { "" } else { " (NOT the seed's run)" }
        );
    }
    for l in &mut loops {
        let _ = l.kill();
        let _ = l.wait();
    }
    println!("worst: {worst:.1} ms; {over} of {kills} kills lost an event older than 100 ms");
}
