//! Regression (issue 32, item 3): a journal on a full disk failed to write (ENOSPC), the run
//! went on with exit 0, the only trace one line in the stdout summary, and the journal ended
//! mid-line. Now the write error stops the run at once with exit 1 and
//! `journal: No space left on device` on stderr, the journal is cut back to its last whole
//! line and ends with the run's `stopped` event, and a target that cannot be written at all
//! refuses the run before it starts.
//!
//! The full disk is a 64 KiB tmpfs mounted in a mount namespace this test makes with
//! `unshare --mount --map-root-user` (util-linux; root or unprivileged user namespaces).

use crate::support as common;

use std::process::Command;

use serde_json::Value;

#[test]
fn a_full_disk_ends_the_run_with_exit_1_and_a_journal_of_whole_lines() {
    let dir = tempfile::tempdir().unwrap();
    let mnt = dir.path().join("disk");
    let out = dir.path().join("journal.jsonl");
    std::fs::create_dir(&mnt).unwrap();
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    // Inside the namespace: a 64 KiB disk, a run of a million firings journalled to it,
    // then the journal copied out (the disk goes away with the namespace).
    let script = r#"mount -t tmpfs -o size=64k tmpfs "$1" || exit 90
"$2" run "$3" --time-scale 0 --seed 1 --max-firings 1000000 --journal "$1/j.jsonl" \
    > /dev/null
code=$?
cp "$1/j.jsonl" "$4" || exit 91
exit $code"#;
    let ran = Command::new("unshare")
        .args(["--mount", "--map-root-user", "sh", "-c", script, "sh"])
        .arg(&mnt)
        .arg(env!("CARGO_BIN_EXE_plan-runner"))
        .arg(&net)
        .arg(&out)
        .output()
        .expect("unshare (util-linux) runs");
    let stderr = String::from_utf8_lossy(&ran.stderr);
    assert_ne!(
        ran.status.code(),
        Some(90),
        "could not mount a tmpfs in a new namespace: {stderr}"
    );
    assert_eq!(ran.status.code(), Some(1), "stderr: {stderr}");
    assert!(
        stderr
            .lines()
            .any(|l| l == "journal: No space left on device"),
        "stderr: {stderr}"
    );
    let text = std::fs::read_to_string(&out).unwrap();
    assert!(text.len() <= 64 << 10, "{} bytes", text.len());
    assert!(text.ends_with('\n'), "the journal ends mid-line");
    let lines: Vec<Value> = text
        .lines()
        .map(|l| serde_json::from_str(l).expect("every line is whole JSON"))
        .collect();
    assert!(lines.len() > 100, "{} lines", lines.len());
    let last = lines.last().unwrap();
    assert_eq!(last["event"], "stopped", "last line: {last}");
    assert_eq!(last["reason"], "journal", "last line: {last}");
    // The events before it are the run's first ones, none missing.
    let seqs: Vec<u64> = lines[1..lines.len() - 1]
        .iter()
        .map(|l| l["seq"].as_u64().unwrap())
        .collect();
    assert!(
        seqs.windows(2).all(|w| w[1] == w[0] + 1),
        "a gap in {seqs:?}"
    );
    assert_eq!(seqs[0], 0);
}

#[test]
fn a_journal_that_cannot_be_written_refuses_the_run_before_it_starts() {
    let net = common::fixture("greatspn/cyc3/cyc3_ss.PNPRO");
    let ran = Command::new(env!("CARGO_BIN_EXE_plan-runner"))
        .args(["run", net.to_str().unwrap(), "--time-scale", "0"])
        .args(["--max-firings", "10", "--journal", "/dev/full"])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&ran.stderr);
    assert_eq!(ran.status.code(), Some(2), "stderr: {stderr}");
    assert!(
        stderr.contains("journal /dev/full: No space left on device"),
        "stderr: {stderr}"
    );
    assert!(ran.stdout.is_empty(), "the run started");
}
