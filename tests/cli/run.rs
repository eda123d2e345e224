//! `plan-runner run`: a bare net runs net-timed; the JSON summary has exactly the documented
//! keys; Ctrl-C (SIGINT) stops the run with exit code 130 and a complete journal.

use crate::support as common;

use std::process::{Command, Stdio};
use std::time::Duration;

use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

#[test]
fn a_bare_net_runs_net_timed_and_prints_the_json_summary() {
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let args = [
        "run",
        net.to_str().unwrap(),
        "--seed",
        "5",
        "--max-firings",
        "300",
        "--json",
    ];
    let out = bin().args(args).output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: Value = serde_json::from_slice(&out.stdout).unwrap();
    let mut keys: Vec<&str> = v.as_object().unwrap().keys().map(|k| k.as_str()).collect();
    keys.sort();
    assert_eq!(
        keys,
        [
            "agents_ended",
            "agents_spawned",
            "errors",
            "final_marking",
            "firings",
            "mean_tokens",
            "stopped",
            "throughput",
            "time"
        ]
    );
    assert_eq!(v["stopped"], "max_firings");
    assert_eq!(v["firings"], 300);
    let m = &v["final_marking"];
    let tokens = m["P1"].as_u64().unwrap() + m["P2"].as_u64().unwrap() + m["P3"].as_u64().unwrap();
    assert_eq!(tokens, 2, "cyc3 keeps its two tokens");
    // The same seed gives the same run.
    let again = bin().args(args).output().unwrap();
    assert_eq!(out.stdout, again.stdout);
}

#[test]
fn a_missing_file_is_bad_input() {
    let out = bin().args(["run", "no/such/net.xml"]).output().unwrap();
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn ctrl_c_leaves_a_complete_journal_and_exits_130() {
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("run.jsonl");
    let child = bin()
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
        .arg(&journal)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Real time at 100× speed: it would run forever; interrupt it once it has fired.
    let mut waited = 0;
    while waited < 200 {
        std::thread::sleep(Duration::from_millis(50));
        waited += 1;
        let n = std::fs::read_to_string(&journal)
            .map(|s| s.len())
            .unwrap_or(0);
        if n > 0 && waited > 20 {
            break;
        }
    }
    let status = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(status.success());
    let out = child.wait_with_output().unwrap();
    assert_eq!(
        out.status.code(),
        Some(130),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary: Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(summary["stopped"], "interrupted");
    let text = std::fs::read_to_string(&journal).unwrap();
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    assert_eq!(lines[0]["seed"], 1);
    let last = lines.last().unwrap();
    assert_eq!(last["event"], "stopped");
    assert_eq!(last["reason"], "interrupted");
    let fired = lines.iter().filter(|l| l["event"] == "fired").count() as u64;
    assert_eq!(fired, summary["firings"].as_u64().unwrap());
    assert!(fired > 0);
}

/// The keys of the JSON object `key` of `text`, in the order they are written (a parsed
/// `Value` would sort them).
fn written_keys(text: &str, key: &str) -> Vec<String> {
    let start = text.find(&format!("\"{key}\": {{")).expect("the object") + key.len() + 5;
    let body = &text[start..start + text[start..].find('}').expect("its end")];
    body.split(',')
        .map(|entry| {
            entry
                .split(':')
                .next()
                .unwrap()
                .trim()
                .trim_matches('"')
                .to_string()
        })
        .collect()
}

/// Issue 30, snag 7: `run --json` wrote `p10` before `p2` (name order); the summary keeps
/// the net's order, like the text summary and the net file.
#[test]
fn the_json_summary_keeps_places_and_transitions_in_net_order() {
    let net = common::fixture("mcc/Eratosthenes-PT-010/model.pnml");
    let out = bin()
        .args([
            "run",
            net.to_str().unwrap(),
            "--seed",
            "1",
            "--max-firings",
            "3",
            "--json",
        ])
        .output()
        .unwrap();
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let places = ["p2", "p3", "p6", "p7", "p4", "p5", "p8", "p9", "p10"];
    assert_eq!(written_keys(&text, "final_marking"), places);
    assert_eq!(written_keys(&text, "mean_tokens"), places);
    assert_eq!(
        written_keys(&text, "throughput"),
        [
            "t10.2", "t6.2", "t6.3", "t8.2", "t10.5", "t9.3", "t8.4", "t4.2"
        ]
    );
}
