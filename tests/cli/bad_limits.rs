//! Regressions (issue 14, defects 5 and 11): long durations panicked ("cannot convert float
//! seconds to Duration") and the run hung, while `check` accepted them; an invalid UTF-8
//! byte or a bad `[params]` entry in a plan was refused without the plan's line and column;
//! a marking of 2³² was reported as "must be a whole number ≥ 0". Now each is refused at
//! load with exit code 2, the file, line and column, and the limit it broke.

use std::path::{Path, PathBuf};
use std::process::Command;

fn bin() -> Command {
    Command::new(env!("CARGO_BIN_EXE_plan-runner"))
}

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(rel)
}

/// A directory with `patrol.xml` (the quickstart's net, `edit` applied to its text) and
/// `plan.toml` holding `plan`.
fn plan_dir(plan: &[u8], edit: impl Fn(String) -> String) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let net = std::fs::read_to_string(repo("plans/nets/two_robot_patrol.xml")).unwrap();
    std::fs::write(dir.path().join("patrol.xml"), edit(net)).unwrap();
    let path = dir.path().join("plan.toml");
    std::fs::write(&path, plan).unwrap();
    (dir, path)
}

/// Runs `plan-runner ARGS`, expects exit code 2 and returns stderr.
fn refused(args: &[&str], file: &Path) -> String {
    let out = bin().args(args).arg(file).output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
    stderr
}

fn check_refuses(plan: &str, at: &str, message: &str) {
    let (_dir, path) = plan_dir(plan.as_bytes(), |n| n);
    for cmd in [
        ["check"].as_slice(),
        ["run", "--max-firings", "5"].as_slice(),
    ] {
        let stderr = refused(cmd, &path);
        assert!(stderr.contains(&format!("plan.toml:{at}: ")), "{stderr}");
        assert!(stderr.contains(message), "{stderr}");
    }
}

#[test]
fn a_timeout_of_1e300_seconds_is_refused_at_its_position() {
    check_refuses(
        "net = \"patrol.xml\"\n[places.Patrol_A]\naction = \"patrol\"\ntimeout = 1e300\n",
        "4:11",
        "timeout of `Patrol_A` is 1e300: must be a finite number of seconds > 0 and ≤ 315576000 (10 years)",
    );
}

#[test]
fn a_ros2_heartbeat_of_1e300_seconds_is_refused_at_its_position() {
    check_refuses(
        "net = \"patrol.xml\"\n[ros2]\nheartbeat = 1e300\n",
        "3:13",
        "heartbeat of `ros2` is 1e300: must be a finite number of seconds",
    );
}

#[test]
fn a_time_scale_of_1e300_is_refused_in_the_plan_and_on_the_command_line() {
    check_refuses(
        "net = \"patrol.xml\"\ntime_scale = 1e300\n",
        "2:14",
        "time_scale of `plan` is 1e300: must be a finite number ≥ 0 and ≤ 315576000",
    );
    let (_dir, path) = plan_dir(b"net = \"patrol.xml\"\n", |n| n);
    let out = bin()
        .arg("run")
        .arg(&path)
        .args(["--time-scale", "1e300"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr)
            .contains("--time-scale 1e300: must be a finite number ≥ 0 and ≤ 315576000")
    );
}

#[test]
fn a_rate_of_1e_minus_30_in_real_time_is_refused_at_the_time_scale() {
    let plan = "net = \"patrol.xml\"\ntime_scale = 1.0\n";
    let (_dir, path) = plan_dir(plan.as_bytes(), |n| {
        n.replacen(
            "<rate>\n<value>1.0</value>",
            "<rate>\n<value>1e-30</value>",
            1,
        )
    });
    let stderr = refused(&["check"], &path);
    assert!(
        stderr.contains(
            "plan.toml:2:14: time_scale = 1: transition `T_A_done` (rate 1e-30) would wait 1.0e30 s of real time on average, more than the maximum 315576000 s (10 years)"
        ),
        "{stderr}"
    );
    // The same net in virtual time is fine: the rate is only a number there.
    std::fs::write(&path, "net = \"patrol.xml\"\ntime_scale = 0.0\n").unwrap();
    let out = bin()
        .arg("run")
        .arg(&path)
        .args(["--max-firings", "3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn a_rate_of_1e_minus_30_in_a_bare_net_is_refused_at_the_transition_for_time_scale_1() {
    let (dir, _) = plan_dir(b"", |n| {
        n.replacen(
            "<rate>\n<value>1.0</value>",
            "<rate>\n<value>1e-30</value>",
            1,
        )
    });
    let net = dir.path().join("patrol.xml");
    let stderr = refused(&["run", "--time-scale", "1"], &net);
    // Line 108 is `<transition id="T_A_done">`; the column is its id's value.
    assert!(
        stderr.contains(
            "patrol.xml:108:17: --time-scale 1: transition `T_A_done` (rate 1e-30) would wait 1.0e30 s of real time on average, more than the maximum 315576000 s (10 years)"
        ),
        "{stderr}"
    );
    // In virtual time the same net runs.
    let out = bin()
        .arg("run")
        .arg(&net)
        .args(["--time-scale", "0", "--max-firings", "3"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn a_slow_rate_in_a_bare_pnpro_net_is_refused_at_the_transition() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(crate::support::fixture("greatspn/cyc3/cyc3.PNPRO"))
        .unwrap()
        .replace("delay=\"2.0\"", "delay=\"1e-30\"");
    let net = dir.path().join("cyc3.PNPRO");
    std::fs::write(&net, text).unwrap();
    let stderr = refused(&["run", "--time-scale", "2"], &net);
    // Line 10 is T3's `<transition …/>`, from column 7.
    assert!(
        stderr.contains(
            "cyc3.PNPRO:10:7: --time-scale 2: transition `T3` (rate 1e-30) would wait 2.0e30 s"
        ),
        "{stderr}"
    );
}

#[test]
fn an_invalid_utf8_byte_in_a_plan_is_refused_at_its_line_and_column() {
    let (_dir, path) = plan_dir(b"net = \"patrol.xml\"\n# caf\xe9\n", |n| n);
    let stderr = refused(&["check"], &path);
    assert!(
        stderr.contains(
            "plan.toml:2:6: the file is not UTF-8: byte 0xe9 cannot start a character here"
        ),
        "{stderr}"
    );
}

#[test]
fn a_bad_params_entry_is_refused_at_the_plan_not_the_net() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(repo("plans/nets/fms.PNPRO"), dir.path().join("fms.PNPRO")).unwrap();
    let path = dir.path().join("plan.toml");
    for (params, at, message) in [
        (
            "N = 2.5",
            "4:1",
            "template parameter `N` = 2.5: 2.5 is not a whole number, but the parameter is INTEGER",
        ),
        ("M = 2", "4:1", "template parameter `M` does not exist"),
        (
            "t = \"x\"",
            "4:1",
            "template parameter of `t`: `x` is not a number",
        ),
    ] {
        std::fs::write(
            &path,
            format!("net = \"fms.PNPRO\"\npage = \"FMS\"\n[params]\n{params}\n"),
        )
        .unwrap();
        let stderr = refused(&["check"], &path);
        assert!(
            stderr.contains(&format!("plan.toml:{at}: {message}")),
            "{stderr}"
        );
    }
    // On the command line the same mistake names the flag's parameter and the net file.
    std::fs::write(&path, "net = \"fms.PNPRO\"\npage = \"FMS\"\n").unwrap();
    let out = bin()
        .arg("check")
        .arg(&path)
        .args(["--param", "N=2.5"])
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(2));
    assert!(
        String::from_utf8_lossy(&out.stderr).contains("fms.PNPRO: template parameter `N` = 2.5")
    );
}

#[test]
fn a_marking_of_two_to_the_32_names_the_maximum_token_count() {
    let (_dir, path) = plan_dir(b"net = \"patrol.xml\"\n", |n| {
        n.replacen(
            "<initialMarking>\n<value>Default,1</value>",
            "<initialMarking>\n<value>Default,4294967296</value>",
            1,
        )
    });
    let net = path.with_file_name("patrol.xml");
    let stderr = refused(&["check"], &net);
    assert!(
        stderr.contains("initial marking of `Patrol_A` is 4294967296: exceeds the maximum token count 4294967295"),
        "{stderr}"
    );
    assert!(stderr.contains("patrol.xml:"), "{stderr}");
}
