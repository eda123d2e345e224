//! `plan-runner convert` with GreatSPN projects: pages and parameters from the command line,
//! the written project reads back as the same net, and bad input exits 2 with its position.

use std::path::{Path, PathBuf};

use assert_cmd::Command;
use gspn::io::{ReadOptions, read_net};

fn greatspn(rel: &str) -> PathBuf {
    let beside = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/fixtures/greatspn");
    let root = if beside.is_dir() {
        beside
    } else {
        PathBuf::from("/work/shared/fixtures/greatspn")
    };
    root.join(rel)
}

fn plan_runner() -> Command {
    Command::cargo_bin("plan-runner").expect("binary builds")
}

#[test]
fn convert_with_param_writes_the_bound_net() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("fms5.PNPRO");
    let input = greatspn("greatspn_examples/fms.PNPRO");
    plan_runner()
        .arg("convert")
        .arg(&input)
        .arg(&out)
        .args(["--param", "N=5"])
        .assert()
        .success();
    let back = read_net(&out, &ReadOptions::default()).unwrap().net;
    let original = read_net(
        &input,
        &ReadOptions {
            page: None,
            params: vec![("N".into(), "5".into())],
        },
    )
    .unwrap()
    .net;
    assert_eq!(back.diff(&original), Vec::<String>::new());
    assert_eq!(back.initial_tokens(), 12);
}

#[test]
fn convert_reads_the_page_named_on_the_command_line() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("team.PNPRO");
    plan_runner()
        .arg("convert")
        .arg(greatspn("gspnr_toolbox/test_executable_with_result.PNPRO"))
        .arg(&out)
        .args(["--page", "cooperation_test"])
        .assert()
        .success();
    let back = read_net(&out, &ReadOptions::default()).unwrap().net;
    assert_eq!(back.name(), "cooperation_test");
    assert_eq!((back.place_count(), back.transition_count()), (8, 3));
}

#[test]
fn convert_refuses_coloured_nets_and_unknown_pages_with_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.PNPRO");
    let assert = plan_runner()
        .arg("convert")
        .arg(greatspn("greatspn_examples/polling.PNPRO"))
        .arg(&out)
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(stderr.contains("polling.PNPRO:6:22"), "{stderr}");
    assert!(stderr.contains("TokIn_C"), "{stderr}");

    let assert = plan_runner()
        .arg("convert")
        .arg(greatspn("gspnr_toolbox/creating_GSPNs.PNPRO"))
        .arg(&out)
        .args(["--page", "Model3"])
        .assert()
        .code(2);
    let stderr = String::from_utf8_lossy(&assert.get_output().stderr).into_owned();
    assert!(stderr.contains("`Model`, `Model2`"), "{stderr}");
    assert!(!out.exists());
}
