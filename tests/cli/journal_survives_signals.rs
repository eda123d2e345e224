//! Regressions (issue 14, defects 1 and 2): the journal sat in a 64 KiB buffer until the run
//! ended, so a SIGKILL lost everything and SIGTERM (not handled) left it empty; `replay`
//! refused a whole journal whose last line was cut. Now events are written through within
//! 100 ms or 100 events, SIGTERM and SIGHUP stop a run like Ctrl-C (exit 143 and 129, final
//! `stopped` line), and `replay` skips a cut last line with a warning.

use crate::support as common;

use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

/// `run` of cyc3 in real time at 100× speed (about a hundred firings a second), forever.
fn start(journal: &Path) -> Child {
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    bin()
        .args([
            "run",
            net.to_str().unwrap(),
            "--time-scale",
            "0.01",
            "--seed",
            "1",
            "--json",
        ])
        .arg("--journal")
        .arg(journal)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

fn signal(child: &Child, name: &str) {
    let status = Command::new("kill")
        .args([&format!("-{name}"), &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
}

/// Waits until the journal has `lines` newlines (the run is firing), at most 20 s.
fn wait_for_lines(journal: &Path, lines: usize) {
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(20) {
        let text = std::fs::read(journal).unwrap_or_default();
        if text.iter().filter(|&&b| b == b'\n').count() >= lines {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    panic!("the journal never reached {lines} lines");
}

#[test]
fn after_sigkill_the_journal_holds_the_events_so_far_in_whole_lines() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let mut child = start(&journal);
    // Events reach the file while the run goes on, not at its end.
    wait_for_lines(&journal, 5);
    std::thread::sleep(Duration::from_millis(1000));
    child.kill().unwrap(); // SIGKILL: no handler, no flush.
    child.wait().unwrap();
    let text = std::fs::read_to_string(&journal).unwrap();
    let (whole, torn) = match text.rfind('\n') {
        Some(i) => (&text[..=i], &text[i + 1..]),
        None => ("", text.as_str()),
    };
    let lines: Vec<Value> = whole
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|e| panic!("{e}: {l}")))
        .collect();
    assert!(lines.len() > 5, "{} lines", lines.len());
    assert_eq!(lines[0]["seed"], 1);
    for (i, e) in lines[1..].iter().enumerate() {
        assert_eq!(e["seq"], i as u64, "no gaps");
    }
    assert!(lines.iter().any(|l| l["event"] == "fired"));
    // At most one line cut short, at the end.
    assert!(!torn.contains('\n'));
}

#[test]
fn sigterm_stops_the_run_like_ctrl_c_with_exit_143() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let child = start(&journal);
    wait_for_lines(&journal, 5);
    signal(&child, "TERM");
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(143),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "interrupted");
    let text = std::fs::read_to_string(&journal).unwrap();
    assert!(text.ends_with('\n'));
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    let last = lines.last().unwrap();
    assert_eq!(last["event"], "stopped");
    assert_eq!(last["reason"], "interrupted");
    let fired = lines.iter().filter(|l| l["event"] == "fired").count() as u64;
    assert_eq!(fired, summary["firings"].as_u64().unwrap());
}

#[test]
fn sighup_stops_the_run_like_ctrl_c_with_exit_129() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let child = start(&journal);
    wait_for_lines(&journal, 5);
    signal(&child, "HUP");
    let out = child.wait_with_output().unwrap();
    assert_eq!(out.status.code(), Some(129));
    let text = std::fs::read_to_string(&journal).unwrap();
    let last: Value = serde_json::from_str(text.lines().last().unwrap()).unwrap();
    assert_eq!(last["event"], "stopped");
}

#[test]
fn replay_skips_a_cut_last_line_with_a_warning() {
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let out = bin()
        .args([
            "run",
            net.to_str().unwrap(),
            "--seed",
            "4",
            "--max-firings",
            "20",
        ])
        .arg("--journal")
        .arg(&journal)
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let text = std::fs::read_to_string(&journal).unwrap();
    let lines = text.lines().count();
    // Cut the last line (the `stopped` event) in the middle, as a SIGKILL would.
    let cut = &text[..text.len() - 12];
    std::fs::write(&journal, cut).unwrap();
    let replay = |path: &Path| {
        bin()
            .args(["replay"])
            .arg(path)
            .args(["--net", net.to_str().unwrap()])
            .output()
            .unwrap()
    };
    let out = replay(&journal);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(0), "{stderr}");
    assert!(
        stderr.contains(&format!("run.jsonl: line {lines}: cut short")),
        "{stderr}"
    );
    // The initial marking and the 20 firings, all before the cut line.
    assert_eq!(String::from_utf8_lossy(&out.stdout).lines().count(), 21);
    // A bad line that is not the last one is still refused, with its number.
    let mut broken: Vec<&str> = text.lines().collect();
    broken[3] = "{\"seq\": ";
    std::fs::write(&journal, broken.join("\n") + "\n").unwrap();
    let out = replay(&journal);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("line 4:"));
}
