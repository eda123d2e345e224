//! Runs that never end say so: `check` names unbounded places with the transitions that pump
//! them and plans with no stop condition whose net never stops; `run` warns once before such
//! a run in virtual time and prints progress lines on a stderr that is not a terminal
//! (`--quiet`: none); `max_firings = 0` and other stop values no run can use are refused.

use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use crate::program_actions::{bin, interrupt, repo};

/// A plan over the quickstart's patrol (bounded, never dead) with `stop` as its `[stop]`.
fn patrol(dir: &Path, stop: &str) -> PathBuf {
    let net = repo("plans/nets/two_robot_patrol.xml");
    let plan = dir.join("plan.toml");
    std::fs::write(
        &plan,
        format!("net = {:?}\nseed = 1\n{stop}", net.display().to_string()),
    )
    .unwrap();
    plan
}

/// A producer net: `make` puts a token in `made` at every firing, forever.
fn producer(dir: &Path) -> PathBuf {
    use gspn::net::{NetBuilder, Servers};
    let mut b = NetBuilder::new("producer");
    let idle = b.place("idle", 1);
    let made = b.place("made", 0);
    let make = b.exponential("make", 1.0, Servers::Single);
    b.input(idle, make, 1);
    b.output(make, idle, 1);
    b.output(make, made, 1);
    let path = dir.join("producer.xml");
    gspn::io::write_net(&b.build().unwrap(), &path, gspn::io::Format::Pipe).unwrap();
    path
}

fn stderr_of(args: &[&str]) -> (Option<i32>, String) {
    let out = bin().args(args).output().unwrap();
    (
        out.status.code(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn check_names_unbounded_places_and_their_pumps() {
    let dir = tempfile::tempdir().unwrap();
    let net = producer(dir.path());
    let out = bin()
        .args(["check", net.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        report["warnings"],
        serde_json::json!(["place `made` can grow without limit (coverability): pumped by `make`"])
    );
}

#[test]
fn check_says_when_a_plan_without_stop_never_ends() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol(dir.path(), "");
    let out = bin()
        .args(["check", plan.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(
        report["warnings"],
        serde_json::json!([
            "the plan has no stop condition and no dead marking is reachable: the net never stops firing: `run` goes on until Ctrl-C (add [stop] max_firings, time_limit or when)"
        ])
    );
    // With a stop condition: nothing to say.
    let plan = patrol(dir.path(), "[stop]\ntime_limit = 5.0\n");
    let out = bin()
        .args(["check", plan.to_str().unwrap(), "--json"])
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(report["warnings"], serde_json::json!([]));
    // A net that stops on its own (a chain into a dead marking): nothing either.
    let out = bin()
        .args([
            "check",
            repo("plans/immediate_chain.toml").to_str().unwrap(),
            "--json",
        ])
        .output()
        .unwrap();
    let report: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert!(
        !report["warnings"].to_string().contains("stop condition"),
        "{report}"
    );
}

#[test]
fn max_firings_0_and_other_useless_stops_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol(dir.path(), "[stop]\nmax_firings = 0\n");
    for cmd in ["check", "run"] {
        let (code, err) = stderr_of(&[cmd, plan.to_str().unwrap()]);
        assert_eq!(code, Some(2), "{cmd}: {err}");
        assert!(
            err.contains(&format!(
                "{}:4:15: max_firings of `stop` is 0: must be at least 1",
                plan.display()
            )),
            "{cmd}: {err}"
        );
    }
    let plan = patrol(dir.path(), "");
    for (flag, value, says) in [
        ("--max-firings", "0", "--max-firings 0: must be at least 1"),
        ("--until", "0", "--until 0: must be a finite model time > 0"),
        (
            "--until",
            "-3",
            "--until -3: must be a finite model time > 0",
        ),
        (
            "--until",
            "NaN",
            "--until NaN: must be a finite model time > 0",
        ),
    ] {
        let arg = format!("{flag}={value}");
        let (code, err) = stderr_of(&["run", plan.to_str().unwrap(), &arg]);
        assert_eq!(code, Some(2), "{flag} {value}: {err}");
        assert!(err.contains(says), "{flag} {value}: {err}");
    }
}

/// Runs `plan` with `extra` flags for about `secs` seconds, then Ctrl-C; its stderr.
fn run_then_interrupt(plan: &Path, extra: &[&str], secs: f64) -> String {
    let child = bin()
        .arg("run")
        .arg(plan)
        .args(extra)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_secs_f64(secs));
    let out = interrupt(child);
    assert_eq!(out.status.code(), Some(130));
    String::from_utf8_lossy(&out.stderr).into_owned()
}

#[test]
fn an_endless_run_warns_once_and_shows_progress_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let plan = patrol(dir.path(), "");
    let err = run_then_interrupt(&plan, &[], 3.6);
    let warning = "warning: this run has no stop condition and no dead marking is reachable: the net never stops firing: it goes on until Ctrl-C (add --max-firings N or --until T, or [stop] in the plan)";
    assert_eq!(err.matches(warning).count(), 1, "{err}");
    let progress: Vec<&str> = err
        .lines()
        .filter(|l| l.starts_with("progress: "))
        .collect();
    assert_eq!(progress.len(), 1, "{err}");
    assert!(progress[0].ends_with(", 3 s"), "{err}");
    let quiet = run_then_interrupt(&plan, &["--quiet"], 3.6);
    assert_eq!(quiet.matches(warning).count(), 1, "{quiet}");
    assert!(!quiet.contains("progress: "), "{quiet}");

    // A run with a stop condition (the flag counts): no warning.
    let (code, err) = stderr_of(&["run", plan.to_str().unwrap(), "--max-firings", "50"]);
    assert_eq!(code, Some(0), "{err}");
    assert!(!err.contains("warning"), "{err}");
}
