//! Runs recorded to MCAP (issue 25): `run … --journal run.mcap` and `plan-runner export
//! run.jsonl out.mcap` write firings, markings and the simulated robots' poses as ROS 2
//! messages (ros2msg schemas, CDR), and the PyPI `mcap` + `mcap-ros2-support` readers — not
//! ours — decode them: 200 `gspn_msgs/msg/Firing` with the journal's transitions, the
//! `geometry_msgs/msg/PoseStamped` poses of 4 robots in frame `map`.

use crate::ros2_support as support;

use std::path::Path;
use std::process::Command;

use support::{python, repo};

fn plan_runner() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

/// What `tests/ros2/mcap_reader.py` read from `file`.
fn read_mcap(file: &Path) -> serde_json::Value {
    let out = Command::new(python())
        .arg(repo("tests/ros2/mcap_reader.py"))
        .arg(file)
        .output()
        .expect("python runs");
    assert!(
        out.status.success(),
        "mcap_reader.py: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("JSON from mcap_reader.py")
}

#[test]
fn a_run_and_an_export_are_read_back_by_the_mcap_ros2_readers() {
    let dir = tempfile::tempdir().unwrap();
    let mcap = dir.path().join("run.mcap");
    let out = plan_runner()
        .current_dir(repo(""))
        .args(["run", "plans/temperature-patrol/plan.toml", "--robots", "4"])
        .args(["--max-firings", "200", "--quiet", "--journal"])
        .arg(&mcap)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("200 firings"), "{stderr}");
    let journal = dir.path().join("run.mcap.jsonl");
    let lines = std::fs::read_to_string(&journal).expect("the JSON Lines journal beside it");
    let header: serde_json::Value = serde_json::from_str(lines.lines().next().unwrap()).unwrap();
    let fired: Vec<String> = lines
        .lines()
        .skip(1)
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|e| e["event"] == "fired")
        .map(|e| {
            header["transitions"][e["transition"].as_u64().unwrap() as usize]
                .as_str()
                .unwrap()
                .to_string()
        })
        .collect();
    assert_eq!(fired.len(), 200);

    let exported = dir.path().join("exported.mcap");
    let out = plan_runner()
        .arg("export")
        .arg(&journal)
        .arg(&exported)
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );

    let run = read_mcap(&mcap);
    for got in [&run, &read_mcap(&exported)] {
        let topics = &got["topics"];
        assert_eq!(topics["/gspn/firings"]["schema"], "gspn_msgs/msg/Firing");
        assert_eq!(topics["/gspn/firings"]["encoding"], "cdr");
        assert_eq!(topics["/gspn/firings"]["count"], 200);
        // The initial marking, then one per firing.
        assert_eq!(topics["/gspn/marking"]["count"], 201);
        let firings = got["firings"].as_array().unwrap();
        let seqs: Vec<u64> = firings.iter().map(|f| f[0].as_u64().unwrap()).collect();
        assert_eq!(seqs, (1..=200).collect::<Vec<_>>());
        let names: Vec<&str> = firings.iter().map(|f| f[1].as_str().unwrap()).collect();
        assert_eq!(names, fired);
        // Model time, increasing, and the header stamp says the same in nanoseconds.
        let mut last = 0.0;
        for f in firings {
            let t = f[3].as_f64().unwrap();
            assert!(t >= last, "{f}");
            last = t;
            assert_eq!(f[4].as_u64().unwrap(), (t * 1e9).round() as u64, "{f}");
            assert_eq!(f[2].as_array().unwrap().len(), 1, "one robot moves: {f}");
        }
        let poses = got["poses"].as_object().unwrap();
        let robots: Vec<&str> = poses.keys().map(String::as_str).collect();
        assert_eq!(robots, ["/r1/pose", "/r2/pose", "/r3/pose", "/r4/pose"]);
        for (topic, p) in poses {
            assert_eq!(
                topics[topic]["schema"], "geometry_msgs/msg/PoseStamped",
                "{topic}"
            );
            assert_eq!(p["frames"], serde_json::json!(["map"]), "{topic}");
            assert!(p["count"].as_u64().unwrap() > 100, "{topic}: {p}");
            // Heading unknown: the identity quaternion.
            assert_eq!(p["first"][3], 1.0, "{topic}");
        }
    }
    // The run's MCAP and the export of its journal hold the same messages.
    assert_eq!(run, read_mcap(&exported));
}

#[test]
fn a_journal_that_is_not_one_is_refused_naming_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("bad.jsonl");
    std::fs::write(&journal, "{\"net\": \"n\"}\n").unwrap();
    let out = plan_runner()
        .arg("export")
        .arg(&journal)
        .arg(dir.path().join("out.mcap"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains(&format!(
            "{}: journal line 1: missing field",
            journal.display()
        )),
        "{stderr}"
    );
    let out = plan_runner()
        .arg("export")
        .arg(&journal)
        .arg(dir.path().join("out.json"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("out.json: the output must be an .mcap file")
    );
}
