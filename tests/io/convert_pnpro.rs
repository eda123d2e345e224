//! `plan-runner convert` with GreatSPN projects: pages and parameters from the command line,
//! the written project reads back as the same net, and bad input exits 2 with its position.

use std::path::PathBuf;

use assert_cmd::Command;
use gspn::io::{ReadOptions, read_net};

fn greatspn(rel: &str) -> PathBuf {
    crate::support::fixtures::root().join("greatspn").join(rel)
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

#[test]
fn convert_pnpro_to_pnml_keeps_the_net() {
    let dir = tempfile::tempdir().unwrap();
    let input = greatspn("cyc3/cyc3.PNPRO");
    let out = dir.path().join("cyc3.pnml");
    plan_runner()
        .arg("convert")
        .arg(&input)
        .arg(&out)
        .assert()
        .success();
    let back = read_net(&out, &ReadOptions::default()).unwrap().net;
    let original = read_net(&input, &ReadOptions::default()).unwrap().net;
    assert_eq!(original.diff(&back), Vec::<String>::new());
    assert_eq!(
        back.transition(back.transition_by_name("T1").unwrap())
            .timing,
        gspn::net::Timing::Exponential {
            rate: 1.0,
            servers: gspn::net::Servers::Infinite
        }
    );
    // And back to PNPRO, through the command again.
    let again = dir.path().join("again.PNPRO");
    plan_runner()
        .arg("convert")
        .arg(&out)
        .arg(&again)
        .assert()
        .success();
    let again = read_net(&again, &ReadOptions::default()).unwrap().net;
    assert_eq!(original.diff(&again), Vec::<String>::new());
}
