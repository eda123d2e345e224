//! `plan-runner replay` of a run with `--robots N`: the journal records the robots, the
//! marking the run started from and the world (map once, robot poses as the viewer sees
//! them), so the run is recognised as a run of its plan's net (its scaled initial marking
//! made the hash differ) and a journal of another net is refused naming both nets by file
//! and hash, exit code 2.
#![cfg(feature = "sim")]

use std::path::{Path, PathBuf};
use std::process::Command;

use gspn::io::ReadOptions;
use gspn::runtime::journal::{net_hash, read_recording};
use serde_json::Value;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

/// `plan-runner replay JOURNAL --net NET`.
fn replay(journal: &Path, net: &Path) -> std::process::Output {
    bin()
        .args(["replay", journal.to_str().unwrap(), "--net"])
        .arg(net)
        .output()
        .unwrap()
}

fn repo(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// `plan-runner run PLAN --robots 8 --seed 3 --max-firings 40 --journal DIR/run.jsonl`.
fn journal_of_8_robots(dir: &Path) -> PathBuf {
    let path = dir.join("run.jsonl");
    crate::support::journal_of_patrol_on_robots(&path, 8, 3, 40);
    path
}

#[test]
fn a_run_with_8_robots_replays_on_its_plan_and_keeps_its_world() {
    let dir = tempfile::tempdir().unwrap();
    let journal = journal_of_8_robots(dir.path());
    let plan = repo("plans/temperature-patrol/plan.toml");
    let text = std::fs::read_to_string(&journal).unwrap();
    let header: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    let robots: Vec<&str> = header["robots"]
        .as_array()
        .unwrap()
        .iter()
        .map(|r| r.as_str().unwrap())
        .collect();
    assert_eq!(robots, ["r1", "r2", "r3", "r4", "r5", "r6", "r7", "r8"]);
    assert!(
        header["file"].as_str().unwrap().ends_with("plan.toml"),
        "{header}"
    );

    // The plan's own net has 3 robots: the run's net is it with 8, and hashes differently.
    let net = gspn::plan::open(&plan, &ReadOptions::default())
        .unwrap()
        .into_plan()
        .net;
    assert_eq!(net.initial_marking().iter().sum::<u32>(), 3);
    assert_ne!(header["hash"], net_hash(&net));
    let rec = read_recording(&text, &net).unwrap();
    assert!(rec.remarked);
    assert_eq!(net_hash(&rec.net), header["hash"]);
    assert_eq!(rec.net.initial_marking().iter().sum::<u32>(), 8);
    assert_eq!(rec.frames().len(), 41);
    // The world: the map once, then poses of all 8 robots, in time order.
    assert_eq!(rec.records("map").count(), 1);
    let map = &rec.records("map").next().unwrap().data;
    assert_eq!(map["map"]["locations"].as_array().unwrap().len(), 8);
    let poses: Vec<_> = rec.records("world").collect();
    assert!(poses.len() > 10, "{} world records", poses.len());
    for w in &poses {
        assert_eq!(w.data.as_array().unwrap().len(), 8);
    }
    assert!(poses.windows(2).all(|w| w[0].time <= w[1].time));
    let last_firing = rec.frames().last().unwrap().time;
    assert!(poses.last().unwrap().time > last_firing - 1.0);

    // `replay` prints the initial marking and the 40 firings, exit code 0.
    let out = replay(&journal, &plan);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stdout = String::from_utf8(out.stdout).unwrap();
    assert_eq!(stdout.lines().count(), 41);
    assert!(stdout.lines().next().unwrap().contains("(initial)"));
}

#[test]
fn a_journal_of_another_net_is_refused_naming_both_nets_by_file_and_hash() {
    let dir = tempfile::tempdir().unwrap();
    let journal = journal_of_8_robots(dir.path());
    // The thesis's standalone plan: the same net name, `Net-One`, another net.
    let other = repo("plans/thesis-standalone/plan.toml");
    let net = gspn::plan::open(&other, &ReadOptions::default())
        .unwrap()
        .into_plan()
        .net;
    let text = std::fs::read_to_string(&journal).unwrap();
    let header: Value = serde_json::from_str(text.lines().next().unwrap()).unwrap();
    let out = replay(&journal, &other);
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8(out.stderr).unwrap();
    let expected = format!(
        "error: {}: the journal is of net `Net-One` from {} (hash {}), not of this net `Net-One` (hash {}), read from --net {}\n",
        journal.display(),
        header["file"].as_str().unwrap(),
        header["hash"].as_str().unwrap(),
        net_hash(&net),
        other.display()
    );
    assert_eq!(stderr, expected);
}
