//! Regression (issue 32, item 2): `replay` and `conform` read the whole journal, then every
//! event of it, into memory — about 17 times the file (a 100 MB robot journal took 1.7 GB,
//! a 605 MB one aborted under a 4 GB limit). They now read it a line at a time: `replay`
//! holds one line, `conform` the firings it compares. Measured here on a robot journal of a
//! few megabytes (the 100 MB figures are in docs/benchmarks.md): the peak resident memory
//! of each process (its `VmHWM`) stays far below the file's size times 17.
#![cfg(feature = "sim")]

use std::path::Path;
use std::process::{Command, Stdio};

/// Runs `cmd` with stdout to /dev/null; its exit code and peak RSS in kB: the largest
/// `VmHWM` of its own address space, read from /proc every millisecond until it exits.
/// Not `wait4`'s `ru_maxrss`: that counts the address space the child was spawned from,
/// i.e. this test binary with its other tests running (206 MB, reported for both
/// `replay` and `conform`, on a fresh machine).
fn peak_rss_kb(mut cmd: Command) -> (i32, u64) {
    let mut child = cmd
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let status_file = format!("/proc/{}/status", child.id());
    let mut peak = 0u64;
    loop {
        if let Ok(text) = std::fs::read_to_string(&status_file)
            && let Some(kb) = text
                .lines()
                .find_map(|l| l.strip_prefix("VmHWM:"))
                .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<u64>().ok())
        {
            peak = peak.max(kb);
        }
        if let Some(status) = child.try_wait().unwrap() {
            return (status.code().unwrap_or(-1), peak);
        }
        std::thread::sleep(std::time::Duration::from_millis(1));
    }
}

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

#[test]
fn replay_and_conform_of_a_robot_journal_hold_a_fraction_of_it() {
    let dir = tempfile::tempdir().unwrap();
    let journal = dir.path().join("robots.jsonl");
    crate::support::journal_of_patrol_on_robots(&journal, 16, 5, 20_000);
    let short = dir.path().join("short.jsonl");
    crate::support::journal_of_patrol_on_robots(&short, 16, 5, 200);
    let bytes = std::fs::metadata(&journal).unwrap().len();
    assert!(bytes > 4 << 20, "only {bytes} bytes");
    let plan = Path::new(env!("CARGO_MANIFEST_DIR")).join("plans/temperature-patrol/plan.toml");

    let mut replay = bin();
    replay.arg("replay").arg(&journal).arg("--net").arg(&plan);
    let (code, replay_kb) = peak_rss_kb(replay);
    assert_eq!(code, 0);
    // `conform` analyses the plan's net first (the same memory for any journal): what the
    // journal adds is the difference with a journal of 200 firings.
    let conform = |j: &Path| {
        let mut c = bin();
        c.arg("conform").arg(j).arg("--plan").arg(&plan);
        let (code, kb) = peak_rss_kb(c);
        assert_eq!(code, 0);
        kb
    };
    let (conform_kb, conform_short_kb) = (conform(&journal), conform(&short));
    eprintln!(
        "journal {} kB: replay peak {replay_kb} kB, conform peak {conform_kb} kB \
         ({conform_short_kb} kB with 200 firings)",
        bytes >> 10
    );
    // Read whole, the journal alone would be `bytes`, its events ~17 times that.
    assert!(replay_kb < 48 << 10, "replay held {replay_kb} kB");
    assert!(
        replay_kb < bytes >> 10,
        "replay held {replay_kb} kB of a {bytes} B journal"
    );
    let added = conform_kb.saturating_sub(conform_short_kb);
    assert!(
        added < (bytes >> 10) / 2,
        "conform held {added} kB more for a {bytes} B journal"
    );
}
