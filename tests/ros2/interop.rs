//! Interoperability with a DDS peer not written by us (feature `ros2`): Eclipse Cyclone DDS
//! through the PyPI `cyclonedds` package subscribes to `rt/gspn/firings` with the IDL of
//! `gspn_msgs/msg/Firing` (tests/ros2/firings_listener.py) and must receive every firing of a
//! 1 + 3 process run with the fields the supervisor's journal recorded.
//!
//! Needs the Python venv that `.ci/run` creates: `target/venv-ros2` (or `$GSPN_ROS2_VENV`)
//! with `cyclonedds` installed. The test fails, saying so, when it is missing.
#![cfg(feature = "ros2")]

use crate::ros2_support as support;

use std::process::Stdio;
use std::time::Duration;

use gspn::io::{ReadOptions, read_net};
use support::{CYCLONE_CONFIG, domain, finish, python, repo, robot, supervisor};
use tokio::io::{AsyncBufReadExt, BufReader};

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cyclone_dds_in_python_receives_every_firing_with_its_fields() {
    const N: usize = 40;
    let py = python();
    let dir = tempfile::tempdir().unwrap();
    let d = domain(10);
    let mut listener = tokio::process::Command::new(&py)
        .arg(repo("tests/ros2/firings_listener.py"))
        .args([d.to_string(), N.to_string(), "90".into()])
        .env("CYCLONEDDS_URI", CYCLONE_CONFIG)
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .kill_on_drop(true)
        .spawn()
        .expect("python starts");
    // Wait for the Cyclone reader to exist.
    let mut err = BufReader::new(listener.stderr.take().unwrap()).lines();
    let ready = tokio::time::timeout(Duration::from_secs(60), async {
        let mut seen = String::new();
        while let Ok(Some(l)) = err.next_line().await {
            if l.trim() == "ready" {
                return Ok(());
            }
            seen.push_str(&l);
            seen.push('\n');
        }
        Err(seen)
    })
    .await;
    match ready {
        Ok(Ok(())) => {}
        Ok(Err(e)) => panic!("the Cyclone listener failed:\n{e}"),
        Err(_) => panic!("the Cyclone listener did not start within 60 s"),
    }
    // The rest of its stderr (a Python traceback, Cyclone's own errors), read as it comes so
    // a full pipe never blocks it, and shown if it fails.
    let stderr = tokio::spawn(async move {
        let mut rest = String::new();
        while let Ok(Some(l)) = err.next_line().await {
            rest.push_str(&l);
            rest.push('\n');
        }
        rest
    });

    let journal = dir.path().join("journal.jsonl");
    let _robots: Vec<_> = ["r1", "r2", "r3"]
        .iter()
        .map(|r| robot(dir.path(), r, d))
        .collect();
    // The 3 robots and the Cyclone reader subscribe to /gspn/firings.
    let sup = supervisor(
        dir.path(),
        d,
        &[
            "--max-firings",
            &N.to_string(),
            "--ros2-wait-subscribers",
            "4",
            "--journal",
            journal.to_str().unwrap(),
        ],
    );
    let log = sup.log.clone();
    let (code, out) = finish(sup, Duration::from_secs(120)).await;
    assert_eq!(
        code,
        Some(0),
        "{out}\n{}",
        std::fs::read_to_string(&log).unwrap_or_default()
    );
    let got = tokio::time::timeout(Duration::from_secs(30), listener.wait_with_output())
        .await
        .expect("the Cyclone listener ends")
        .expect("its output");
    let lines: Vec<serde_json::Value> = String::from_utf8_lossy(&got.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).expect("one JSON firing per line"))
        .collect();
    let stderr = stderr.await.unwrap_or_default();
    assert_eq!(
        got.status.code(),
        Some(0),
        "received {}; its stderr:\n{stderr}",
        lines.len()
    );
    assert_eq!(lines.len(), N);

    // What the supervisor recorded, firing by firing.
    let net = read_net(
        &repo("plans/nets/temperature_patrol.xml"),
        &ReadOptions::default(),
    )
    .unwrap()
    .net;
    let fired: Vec<serde_json::Value> = std::fs::read_to_string(&journal)
        .unwrap()
        .lines()
        .map(|l| serde_json::from_str::<serde_json::Value>(l).unwrap())
        .filter(|e| e["event"] == "fired")
        .collect();
    assert_eq!(fired.len(), N);
    for (k, (py, rs)) in lines.iter().zip(&fired).enumerate() {
        assert_eq!(py["seq"], k as u64 + 1);
        let t = rs["transition"].as_u64().unwrap() as usize;
        assert_eq!(
            py["transition"],
            net.transitions()[t].name,
            "firing {}",
            k + 1
        );
        assert_eq!(py["marking"], rs["marking"], "firing {}", k + 1);
        assert_eq!(py["robots"], rs["robots"], "firing {}", k + 1);
        assert_eq!(py["robots"].as_array().unwrap().len(), 1);
        assert!(py["stamp_ns"].as_u64().unwrap() > 1_700_000_000_000_000_000);
    }
}
