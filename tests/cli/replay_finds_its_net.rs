//! `plan-runner replay JOURNAL` without `--net` (issue 30, snag 2): the journal records the
//! file its run read the net from, so replay opens that one (checked by hash) and prints
//! what `--net` would; a recorded file that is not there is bad input naming it, exit 2.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn ok(out: Output) -> String {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).unwrap()
}

/// The quickstart run, started in the repository with a relative plan path.
fn quickstart_journal(dir: &Path) -> PathBuf {
    let journal = dir.join("run.jsonl");
    ok(bin()
        .current_dir(repo())
        .args([
            "run",
            "plans/quickstart.toml",
            "--max-firings",
            "40",
            "--journal",
        ])
        .arg(&journal)
        .output()
        .unwrap());
    journal
}

#[test]
fn replay_without_net_uses_the_recorded_file_and_prints_what_net_prints() {
    let dir = tempfile::tempdir().unwrap();
    let journal = quickstart_journal(dir.path());
    let with = ok(bin()
        .arg("replay")
        .arg(&journal)
        .arg("--net")
        .arg(repo().join("plans/quickstart.toml"))
        .output()
        .unwrap());
    let without = ok(bin()
        .current_dir(repo())
        .arg("replay")
        .arg(&journal)
        .output()
        .unwrap());
    // The initial marking and 40 firings.
    assert_eq!(with.lines().count(), 41, "{with}");
    assert_eq!(without, with);
}

#[test]
fn a_recorded_net_that_is_not_there_is_named_with_exit_code_2() {
    let dir = tempfile::tempdir().unwrap();
    let journal = quickstart_journal(dir.path());
    // From another directory the relative path leads nowhere (nor beside the journal).
    let out = bin()
        .current_dir(dir.path())
        .arg("replay")
        .arg(&journal)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{err}");
    assert!(
        err.contains("the journal's net file `plans/quickstart.toml` is not there"),
        "{err}"
    );
    assert!(err.contains("--net FILE"), "{err}");
}
